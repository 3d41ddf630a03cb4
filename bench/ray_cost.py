#!/usr/bin/env python3
"""bench/ray_cost.py: where a neural-mode ray's time goes, from perf (issue 45's "before" and "after").

Renders Table 2 scenes (`weft scene weave|knit`, sky and two sphere lights) in
neural mode under `perf record --call-graph dwarf` and sorts the samples taken
inside the path tracer (pathRadiance on the stack; the scene build is left
out) by the innermost frame that names a part:
  Embree     librtcore / libembree3 frames, TubeAccel::intersect and ::occluded
  networks   the T and M networks (FixedMlp, the Highway dense layers)
  tables     the tabulated sampler, the energy guard and calibration (SamplingTable,
             TabulatedYarnSampler, EnergyGuard, EnergyCalibration)
  lights     the lights' sample, pdf, radiance and intersect, and the light pick
  BSDF rest  the rest of the yarn BSDF: the R lobe, frames and angles, evalAndPdf
  the rest   the path tracer itself, the sample streams, the film
A libm frame (atan2, exp, ...) counts for the part that called it. The CPU time
per ray is the render's seconds x threads / rays, split by those shares.
Writes bench/results/ray-cost.md and .json (--out).

    bench/ray_cost.py [--materials polyester,silk] [--size 128] [--spp 64] [--threads 2]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from benchlib import write_results  # noqa: E402

PARTS = [
    ("Embree", ("libembree", "librtcore", "TubeAccel::intersect", "TubeAccel::occluded", "rtcIntersect", "rtcOccluded")),
    ("networks", ("FixedMlp", "denseLayer", "N_AVX", "N_SSE", "N_AVX3", "hwy::")),
    ("tables", ("SamplingTable", "TabulatedYarnSampler", "EnergyGuard", "EnergyCalibration")),
    ("lights", ("EnvironmentLight", "SphereLight", "ConstantLight", "nearestFiniteLight", "LightSampler",
                "skyRadiance")),
    ("BSDF rest", ("RLobe", "YarnEvaluator", "YarnBsdf", "SurfaceFiberFrame", "TruncatedGaussian",
                   "YarnSampler", "yarnFrame", "ShadingPoint", "BsdfSlice")),
]
ORDER = [p for p, _ in PARTS] + ["the rest"]


def part_of(stack):
    """The part of a sample: its innermost frame that names one; None outside the path tracer."""
    if not any("pathRadiance" in f for f in stack):
        return None
    for frame in stack:  # leaf first
        for part, keys in PARTS:
            if any(k in frame for k in keys):
                return part
    return "the rest"


def samples(perf_data):
    out = subprocess.run(["perf", "script", "-i", perf_data, "-F", "ip,sym,dso"],
                         capture_output=True, text=True, check=True).stdout
    stack = []
    for line in out.splitlines() + [""]:
        if line.strip():
            stack.append(line.strip())
        elif stack:
            yield stack
            stack = []


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    ap.add_argument("--materials", default="polyester,silk")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "ray-cost.md"))
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for material in a.materials.split(","):
            for kind in ("weave", "knit"):
                folder = os.path.join(tmp, material + "-" + kind)
                subprocess.run([a.weft, "scene", kind, "--model",
                                os.path.join(ROOT, "models", material + ".json"), "--width",
                                str(a.size), "--height", str(a.size), "--out", folder],
                               check=True, capture_output=True)
                data = os.path.join(folder, "perf.data")
                image = os.path.join(folder, "neural.exr")
                subprocess.run(["perf", "record", "--call-graph", "dwarf,16384", "-F", "499", "-o",
                                data, a.weft, "render", os.path.join(folder, "scene.json"), "--mode",
                                "neural", "--spp", str(a.spp), "--threads", str(a.threads), "--seed",
                                "1", "--quiet", "--out", image],
                               check=True, capture_output=True)
                with open(os.path.join(folder, "neural.json")) as f:
                    stats = json.load(f)
                counts = {p: 0 for p in ORDER}
                for stack in samples(data):
                    part = part_of(stack)
                    if part:
                        counts[part] += 1
                total = sum(counts.values())
                ns_per_ray = stats["seconds"] * stats["threads"] / stats["rays"] * 1e9
                row = {"material": material, "scene": kind, "samples": total,
                       "ns_per_ray": ns_per_ray,
                       "shares": {p: counts[p] / total for p in ORDER}}
                rows.append(row)
                print(material, kind, round(ns_per_ray), {p: round(100 * v, 1) for p, v in row["shares"].items()}, flush=True)
    lines = ["# Where a neural-mode ray's time goes (bench/ray_cost.py)", "",
             f"Table 2 scenes, neural mode, {a.size} x {a.size}, {a.spp} spp, {a.threads} threads; "
             "perf samples inside the path tracer sorted by the innermost frame that names a part "
             "(a libm call counts for its caller). CPU ns per ray = render seconds x threads / rays "
             "(closest-hit and shadow rays), split by the shares.", "",
             "| material | scene | ns per ray | " + " | ".join(ORDER) + " | perf samples |",
             "| --- | --- | --- | " + " | ".join("---" for _ in ORDER) + " | --- |"]
    for r in rows:
        cells = [f"{100 * r['shares'][p]:.0f} % ({r['ns_per_ray'] * r['shares'][p]:.0f} ns)" for p in ORDER]
        lines.append(f"| {r['material']} | {r['scene']} | {r['ns_per_ray']:.0f} | " + " | ".join(cells) +
                     f" | {r['samples']} |")
    lines += ["", f"Command: `bench/ray_cost.py --materials {a.materials} --size {a.size} --spp {a.spp}`", ""]
    write_results(a.out, lines, {"size": a.size, "spp": a.spp, "threads": a.threads, "rows": rows})


if __name__ == "__main__":
    main()
