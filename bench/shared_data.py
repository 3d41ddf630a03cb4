#!/usr/bin/env python3
"""bench/shared_data.py: the real knit and woven swatches of data/curves
rendered with every fitted material in fiber, neural and dual mode.

For each model of models/ (the five Table 3 materials) and each swatch
(knit-stockinette-tiny.bcc, woven-satin-small.bcc; yarn radius 1 in the files
by their README, scaled here by 0.01), drawn at the smaller of that radius and
the largest radius without interpenetration that `weft curves info` measures
(the knit's yarns overlap at radius 1: docs/curves.md), renders a fiber-mode reference at REF_SPP and the
neural model and the dual-scattering baseline (after ZMA23) at SPP, each with
`weft render` in its own process, then compares both with the reference
(`weft compare`: SSIM, relative MSE). Writes a table (seconds per spp of each
mode, SSIM and relative MSE of neural and dual against the fiber reference)
to bench/results/shared-data.md (.json beside it) and one figure per swatch,
bench/results/shared-data-<swatch>.png: a row per material, fiber | neural |
dual. The reference is not converged at the default settings: the SSIM of two
equal-spp fiber renders would sit below 1 too; compare the two columns with
each other rather than with 1.

    bench/shared_data.py [--weft build/release/weft] [--size 160] [--spp 32]
                         [--ref-spp 128] [--materials fleece,...] [--threads 0]
"""
import argparse
import json
import os
import struct
import sys
import tempfile

import benchlib
from benchlib import write_results

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.join(ROOT, "data", "curves")
SWATCHES = [("knit", "knit-stockinette-tiny.bcc"), ("woven", "woven-satin-small.bcc")]
MATERIALS = ["fleece", "silk", "polyester", "cotton", "gabardine"]
SCALE = 0.01  # file units (yarn radius 1) -> scene units (yarn radius 0.01)


def bcc_bounds(path):
    """Bounding box of a BCC file's points (the format of core/curves.h)."""
    with open(path, "rb") as f:
        data = f.read()
    curves = struct.unpack_from("<Q", data, 8)[0]
    lo, hi = [float("inf")] * 3, [-float("inf")] * 3
    offset = 64
    for _ in range(curves):
        n = abs(struct.unpack_from("<i", data, offset)[0])
        offset += 4
        for k in range(n):
            p = struct.unpack_from("<3f", data, offset + 12 * k)
            lo = [min(a, b) for a, b in zip(lo, p)]
            hi = [max(a, b) for a, b in zip(hi, p)]
        offset += 12 * n
    return lo, hi


def swatch_radius(weft, bcc, folder):
    """The yarn radius in scene units: min(1, the largest radius without
    overlap) in file units, times SCALE."""
    report = os.path.join(folder, os.path.basename(bcc) + ".report.json")
    run([weft, "curves", "info", bcc, "--json", report])
    with open(report) as f:
        largest = json.load(f)["largest_radius_without_overlap"]
    return SCALE * (1.0 if largest is None else min(1.0, largest))


def swatch_scene(folder, name, bcc, model, size, spp, radius):
    lo, hi = bcc_bounds(bcc)
    centre = [SCALE * 0.5 * (a + b) for a, b in zip(lo, hi)]
    extent = SCALE * max(b - a for a, b in zip(lo, hi))
    scene = {
        "camera": {"from": [centre[0], centre[1] - 0.35 * extent, centre[2] + 1.5 * extent],
                   "to": centre, "up": [0, 1, 0], "fov_deg": 40},
        "film": {"width": size, "height": size},
        "render": {"spp": spp, "max_depth": 1000, "seed": 0},
        "lights": [
            {"type": "sky"},
            {"type": "sphere", "center": [centre[0] + extent, centre[1] + extent, extent],
             "radius": 0.2 * extent, "radiance": [10, 10, 10]},
        ],
        "yarns": [{"curves": os.path.abspath(bcc), "scale": SCALE, "radius": radius, "plies": 3,
                   "ply_twist": 0.3, "model": os.path.abspath(model)}],
    }
    path = os.path.join(folder, "%s.json" % name)
    with open(path, "w") as f:
        json.dump(scene, f, indent=2)
    return path


def run(cmd):
    print("bench/shared_data:", " ".join(cmd), file=sys.stderr)
    return benchlib.run(cmd, "bench/shared_data")


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--size", type=int, default=160)
    p.add_argument("--spp", type=int, default=32)
    p.add_argument("--ref-spp", type=int, default=128)
    p.add_argument("--materials", default=",".join(MATERIALS))
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "shared-data.md"))
    a = p.parse_args()
    materials = a.materials.split(",")
    for m in materials:
        if m not in MATERIALS:
            sys.exit("bench/shared_data: unknown material %r (%s)" % (m, ", ".join(MATERIALS)))
    if not os.path.isdir(SHARED):
        sys.exit("bench/shared_data: %s is missing" % SHARED)

    results = {"settings": vars(a), "rows": []}
    lines = ["# The shared knit and woven swatches in fiber, neural and dual mode", "",
             "%d x %d; fiber reference %d spp, neural and dual %d spp; %s threads; scale %g "
             "(below: the radius of each swatch). SSIM and relative MSE against the "
             "fiber reference (itself noisy: compare the columns with each other). "
             "Seconds per spp include no scene build." % (a.size, a.size, a.ref_spp, a.spp,
                                                          a.threads or "all", SCALE), "",
             "| swatch | material | fiber s/spp | neural s/spp | dual s/spp | SSIM neural | "
             "SSIM dual | relMSE neural | relMSE dual |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    captions, radii = [], {}
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="weft-bench-shared-") as tmp:
        for swatch, file_name in SWATCHES:
            images = []
            bcc = os.path.join(SHARED, file_name)
            radius = swatch_radius(a.weft, bcc, tmp)
            radii[swatch] = radius
            for m in materials:
                model = os.path.join(ROOT, "models", "%s.json" % m)
                scene = swatch_scene(tmp, "%s-%s" % (swatch, m), bcc, model, a.size, a.spp, radius)
                stats, exr = {}, {}
                for mode, spp in (("fiber", a.ref_spp), ("neural", a.spp), ("dual", a.spp)):
                    exr[mode] = os.path.join(tmp, "%s-%s-%s.exr" % (swatch, m, mode))
                    run([a.weft, "render", scene, "--mode", mode, "--spp", str(spp),
                         "--threads", str(a.threads), "--quiet", "--out", exr[mode]])
                    with open(os.path.splitext(exr[mode])[0] + ".json") as f:
                        stats[mode] = json.load(f)
                cmp = {mode: json.loads(run([a.weft, "compare", exr[mode], exr["fiber"]]))
                       for mode in ("neural", "dual")}
                row = {"swatch": swatch, "material": m,
                       "seconds_per_spp": {k: v["seconds_per_spp"] for k, v in stats.items()},
                       "ssim": {k: v["ssim"] for k, v in cmp.items()},
                       "rel_mse": {k: v["rel_mse"] for k, v in cmp.items()}}
                results["rows"].append(row)
                s = row["seconds_per_spp"]
                lines.append("| %s | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.4f | %.4f |" % (
                    swatch, m, s["fiber"], s["neural"], s["dual"], row["ssim"]["neural"],
                    row["ssim"]["dual"], row["rel_mse"]["neural"], row["rel_mse"]["dual"]))
                images += [exr["fiber"], exr["neural"], exr["dual"]]
            figure = os.path.join(os.path.dirname(os.path.abspath(a.out)),
                                  "shared-data-%s.png" % swatch)
            made = os.path.join(tmp, os.path.basename(figure))
            run([a.weft, "montage", *images, "--columns", "3", "--out", made])
            benchlib.publish_png(made, figure)  # written only when its pixels change
            captions.append("- `%s`: rows %s; columns fiber reference | neural | dual." % (
                os.path.basename(figure), ", ".join(materials)))
    lines += ["", "Yarn radius (scene units): %s." % ", ".join(
        "%s %.4g" % kv for kv in radii.items()), "", "Figures:", ""] + captions
    results["radius"] = radii
    write_results(a.out, lines, results)


if __name__ == "__main__":
    main()
