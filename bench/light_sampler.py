#!/usr/bin/env python3
"""bench/light_sampler.py: next-event estimation's light pick, uniform against by power (issue 45).

On the Table 2 scenes (`weft scene weave|knit`: sky and two sphere lights),
renders each scene K times at S spp with different seeds, neural mode, with
"light_sampler": "uniform" and "power", and compares the per-pixel variance
across the seeds (relative: var / (mean^2 + 0.01), averaged over pixels, as
relative MSE is) and the time per sample, all in one run. The efficiency gain
is (variance x time) uniform / (variance x time) power: how much sooner
"power" reaches the same noise. Writes bench/results/light-sampler.md and .json.

    bench/light_sampler.py [--size 128] [--spp 8] [--seeds 8] [--threads 2]
"""
import argparse
import json
import os
import statistics
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
sys.path.insert(0, os.path.join(ROOT, "build", "release", "python"))
from benchlib import write_results  # noqa: E402

import weft  # noqa: E402


def relative_variance(images):
    stack = np.stack(images)  # (K, H, W, 3)
    mean = stack.mean(axis=0)
    var = stack.var(axis=0, ddof=1)
    return float((var / (mean * mean + 0.01)).mean())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "light-sampler.md"))
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for material in ("silk", "polyester", "fleece"):
            for kind in ("weave", "knit"):
                out = os.path.join(tmp, material + "-" + kind)
                weft.scene(kind, model=os.path.join(ROOT, "models", material + ".json"), out=out,
                           width=a.size, height=a.size, spp=a.spp)
                with open(os.path.join(out, "scene.json")) as f:
                    scene = json.load(f)
                result = {"material": material, "scene": kind, "lights": len(scene["lights"])}
                for sampler in ("uniform", "power"):
                    scene["light_sampler"] = sampler
                    images, seconds = [], []
                    for seed in range(1, a.seeds + 1):
                        image, stats = weft.render(scene, mode="neural", spp=a.spp, seed=seed,
                                                   threads=a.threads, base_dir=out)
                        images.append(image.astype(np.float64))
                        seconds.append(stats["seconds_per_spp"])
                    result[sampler] = {"rel_variance": relative_variance(images),
                                       "seconds_per_spp": statistics.median(seconds)}
                u, p = result["uniform"], result["power"]
                result["variance_ratio"] = p["rel_variance"] / u["rel_variance"]
                result["time_ratio"] = p["seconds_per_spp"] / u["seconds_per_spp"]
                result["efficiency_gain"] = 1.0 / (result["variance_ratio"] * result["time_ratio"])
                rows.append(result)
                print(material, kind, result["variance_ratio"], result["time_ratio"], flush=True)
    lines = ["# Light sampler: uniform against by power (bench/light_sampler.py)", "",
             "Table 2 scenes (`weft scene weave|knit`, sky + two sphere lights), neural mode, "
             f"{a.size} x {a.size}, {a.spp} spp, {a.seeds} seeds each, {a.threads} threads, one run. "
             "Relative variance: per pixel var / (mean^2 + 0.01) across the seeds, averaged. "
             "Gain: (variance x time) uniform / (variance x time) power.", "",
             "| material | scene | rel. variance uniform | power | power / uniform | time per spp power / uniform | gain |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['material']} | {r['scene']} | {r['uniform']['rel_variance']:.4g} | "
                     f"{r['power']['rel_variance']:.4g} | {r['variance_ratio']:.3f} | "
                     f"{r['time_ratio']:.3f} | {r['efficiency_gain']:.2f}x |")
    lines += ["", f"Command: `bench/light_sampler.py --size {a.size} --spp {a.spp} --seeds {a.seeds}`", ""]
    write_results(a.out, lines, {"size": a.size, "spp": a.spp, "seeds": a.seeds, "rows": rows})


if __name__ == "__main__":
    main()
