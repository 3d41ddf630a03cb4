#!/usr/bin/env python3
"""bench/render.py: the same scenes in neural and fiber mode, one run.

Writes a small close-up scene (one 3-ply yarn segment filling the frame, lit
by the procedural sky and two sphere lights) and a real knit swatch (when
data/curves is there), renders each with `weft render`
in both modes at the same samples per pixel, each in its own process (so
that peak resident memory is per mode), and writes a table of the measured
values and the ratios fiber / neural to bench/results/render.md (and .json).

    bench/render.py [--weft build/release/weft] [--model tests/data/fleece-small.json]
                    [--size 256] [--spp 16] [--threads 0] [--out bench/results/render.md]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

from benchlib import portable_path, write_results

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def closeup_scene(folder, model, size):
    # A slightly bent yarn along x, radius 0.1, seen from the front; 3 plies.
    points = []
    for i in range(33):
        x = -1.2 + 2.4 * i / 32
        points.append("%.6f %.6f 0" % (x, 0.03 * (1 - (x / 1.2) ** 2)))
    with open(os.path.join(folder, "yarn.txt"), "w") as f:
        f.write("\n".join(points) + "\n")
    scene = {
        "camera": {"from": [0, 0.25, 1.6], "to": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 12},
        "film": {"width": size, "height": size},
        "render": {"spp": 16, "max_depth": 1000, "seed": 0},
        "lights": [
            {"type": "sky", "scale": 0.5},
            {"type": "sphere", "center": [1.5, 1.5, 1.5], "radius": 0.3, "radiance": [20, 20, 20]},
            {"type": "sphere", "center": [-1.5, -1.0, 1.0], "radius": 0.3, "radiance": [8, 8, 10]},
        ],
        "yarns": [{"curves": "yarn.txt", "radius": 0.1, "plies": 3, "ply_twist": 0.3,
                   "model": os.path.abspath(model)}],
    }
    path = os.path.join(folder, "scene.json")
    with open(path, "w") as f:
        json.dump(scene, f, indent=2)
    return path


def knit_scene(folder, model, size):
    # The real stockinette swatch of data/curves (yarn radius 1 in the file),
    # scaled to a yarn radius of 0.01, seen from the front at a slant.
    bcc = os.path.join(ROOT, "data", "curves", "knit-stockinette-tiny.bcc")
    if not os.path.exists(bcc):
        return None
    s = 0.01
    centre, extent = [0.2498, 0.1562, 0.0], 0.568  # of the file's points times s
    scene = {
        "camera": {"from": [centre[0], centre[1] + 0.3 * extent, centre[2] + 1.6 * extent],
                   "to": centre, "up": [0, 1, 0], "fov_deg": 40},
        "film": {"width": size, "height": size},
        "render": {"spp": 16, "max_depth": 1000, "seed": 0},
        "lights": [
            {"type": "sky"},
            {"type": "sphere", "center": [centre[0] + extent, centre[1] + extent, extent],
             "radius": 0.2 * extent, "radiance": [10, 10, 10]},
        ],
        "yarns": [{"curves": os.path.abspath(bcc), "scale": s, "radius": 0.01, "plies": 3,
                   "ply_twist": 0.3, "model": os.path.abspath(model)}],
    }
    path = os.path.join(folder, "knit.json")
    with open(path, "w") as f:
        json.dump(scene, f, indent=2)
    return path


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--model", default=os.path.join(ROOT, "tests", "data", "fleece-small.json"))
    p.add_argument("--size", type=int, default=256)
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "render.md"))
    a = p.parse_args()

    rows = [
        ("segments handed to Embree", lambda s: s["scene"]["segments"], "%d"),
        ("tubes (plies or fibers)", lambda s: s["scene"]["tubes"], "%d"),
        ("geometry + BVH bytes (Embree)", lambda s: s["scene"]["geometry_bvh_bytes"], "%d"),
        ("peak resident bytes (process)", lambda s: s["peak_resident_bytes"], "%d"),
        ("scene build seconds", lambda s: s["scene"]["build_seconds"], "%.3f"),
        ("render seconds per spp", lambda s: s["seconds_per_spp"], "%.4f"),
        ("rays per second", lambda s: s["rays_per_second"], "%.4g"),
        ("rays per sample", lambda s: s["rays"] / (s["spp"] * s["width"] * s["height"]), "%.2f"),
    ]
    lines = ["# Render: fiber mode vs neural mode, one run", ""]
    results = {"settings": vars(a), "scenes": {}}
    with tempfile.TemporaryDirectory(prefix="weft-bench-render-") as tmp:
        scenes = [("close-up of one 3-ply yarn", closeup_scene(tmp, a.model, a.size)),
                  ("knit swatch, data/curves/knit-stockinette-tiny.bcc (22 curves)",
                   knit_scene(tmp, a.model, a.size))]
        for title, scene in scenes:
            if scene is None:
                continue
            stem = os.path.splitext(os.path.basename(scene))[0]
            stats = {}
            for mode in ("neural", "fiber"):
                out = os.path.join(tmp, "%s-%s.exr" % (stem, mode))
                cmd = [a.weft, "render", scene, "--mode", mode, "--spp", str(a.spp),
                       "--threads", str(a.threads), "--quiet", "--out", out]
                print("bench/render:", " ".join(cmd), file=sys.stderr)
                subprocess.run(cmd, check=True)
                with open(os.path.splitext(out)[0] + ".json") as f:
                    stats[mode] = json.load(f)
            n, f = stats["neural"], stats["fiber"]
            lines += [
                "## %s" % title,
                "",
                "%dx%d, %d spp, %d threads, model `%s`."
                % (a.size, a.size, a.spp, n["threads"], portable_path(os.path.abspath(a.model))),
                "",
                "| quantity | neural | fiber | fiber / neural |",
                "| --- | --- | --- | --- |",
            ]
            table = {}
            for name, get, fmt in rows:
                vn, vf = get(n), get(f)
                ratio = vf / vn if vn else float("nan")
                table[name] = {"neural": vn, "fiber": vf, "ratio": ratio}
                lines.append("| %s | %s | %s | %.3g |" % (name, fmt % vn, fmt % vf, ratio))
            lines.append("")
            results["scenes"][stem] = {"title": title, "table": table, "neural": n, "fiber": f}

    write_results(a.out, lines, results)


if __name__ == "__main__":
    main()
