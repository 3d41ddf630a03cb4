#!/usr/bin/env python3
"""bench/memory_scale.py: Table 2's memory ratio as the cloth grows.

Table 2 renders 3 x 3 patches (`weft scene weave|knit --size 3`: 3 warp and
3 weft yarns, or 3 courses of 3 loops), the size that keeps a chunk under an
hour; `weft scene`'s default is 6. Their memory ratio (fiber / neural:
Embree geometry + BVH plus the materials' BSDFs) mixes two things: the
geometry, which grows with the cloth in both modes, and the neural
material (the networks and the sampling table, about 1 MB per yarn model),
which does not. This program builds the same scenes at larger patch sizes
in both modes and reports, per material and scene kind and size:

  - fiber and neural geometry + BVH bytes, the neural material bytes;
  - the memory ratio (as Table 2 counts it) and the geometry-only ratio;
  - peak resident memory of each `weft render` process and its ratio.

Every number comes from `weft render`'s JSON statistics of a 1-spp render
at 32 x 32 pixels (the build is what costs; rendering is a few ms), each
mode in its own process, in one run. Writes bench/results/memory-scale.md
and .json.

    bench/memory_scale.py [--weft build/release/weft] [--sizes 3,6,12]
                          [--presets fleece,silk,polyester,cotton,gabardine]
                          [--scenes weave,knit] [--out bench/results/memory-scale.md]

About 10 minutes on 2 cores at the default sizes (most of it the fiber
builds of the 12 x 12 patches, a few GB resident).
"""
import argparse
import datetime
import json
import os
import sys
import tempfile

import benchlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MB = 1e6


def run(cmd):
    return benchlib.run(cmd, "memory_scale")


def measure(weft, preset, kind, size, folder):
    """Both modes' statistics for one scene: {mode: image.json of the render}."""
    scene_dir = os.path.join(folder, "%s-%s-%d" % (preset, kind, size))
    run([weft, "scene", kind, "--model", os.path.join(ROOT, "models", preset + ".json"),
         "--width", "32", "--height", "32", "--spp", "1", "--size", str(size), "--out", scene_dir])
    stats = {}
    for mode in ("fiber", "neural"):
        exr = os.path.join(scene_dir, mode + ".exr")
        run([weft, "render", os.path.join(scene_dir, "scene.json"), "--mode", mode, "--spp", "1",
             "--quiet", "--out", exr])
        with open(os.path.join(scene_dir, mode + ".json")) as f:
            stats[mode] = json.load(f)
    return stats


def row(preset, kind, size, stats):
    f, n = stats["fiber"]["scene"], stats["neural"]["scene"]
    fiber_bytes = f["geometry_bvh_bytes"] + f["material_bytes"]
    neural_bytes = n["geometry_bvh_bytes"] + n["material_bytes"]
    return {
        "preset": preset, "scene": kind, "patch": size,
        "fiber_tubes": f["tubes"], "neural_tubes": n["tubes"],
        "fiber_geometry_bytes": f["geometry_bvh_bytes"],
        "neural_geometry_bytes": n["geometry_bvh_bytes"],
        "neural_material_bytes": n["material_bytes"],
        "fiber_material_bytes": f["material_bytes"],
        "memory_ratio": fiber_bytes / neural_bytes,
        "geometry_ratio": f["geometry_bvh_bytes"] / n["geometry_bvh_bytes"],
        "fiber_rss_bytes": stats["fiber"]["peak_resident_bytes"],
        "neural_rss_bytes": stats["neural"]["peak_resident_bytes"],
        "rss_ratio": stats["fiber"]["peak_resident_bytes"] / stats["neural"]["peak_resident_bytes"],
        "fiber_build_seconds": f["build_seconds"],
    }


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--sizes", default="3,6,12")
    p.add_argument("--presets", default="fleece,silk,polyester,cotton,gabardine")
    p.add_argument("--scenes", default="weave,knit")
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "memory-scale.md"))
    args = p.parse_args()
    if not os.path.exists(args.weft):
        sys.exit("memory_scale: no weft binary at %s (build first, or pass --weft)" % args.weft)
    try:
        sizes = [int(s) for s in args.sizes.split(",")]
    except ValueError:
        sys.exit("memory_scale: --sizes %r: expected integers like 3,6,12" % args.sizes)
    if not sizes or min(sizes) < 1:
        sys.exit("memory_scale: --sizes %r: every size must be >= 1" % args.sizes)

    rows = []
    with tempfile.TemporaryDirectory(prefix="weft-memory-scale-") as folder:
        for preset in args.presets.split(","):
            for kind in args.scenes.split(","):
                for size in sizes:
                    r = row(preset, kind, size, measure(args.weft, preset, kind, size, folder))
                    rows.append(r)
                    print("%s %s %dx%d: memory ratio %.0fx (geometry %.0fx), RSS %.1fx"
                          % (preset, kind, size, size, r["memory_ratio"], r["geometry_ratio"],
                             r["rss_ratio"]), flush=True)

    version = run([args.weft, "--version"]).strip()
    lines = [
        "# Memory ratio as the cloth grows",
        "",
        "Made by `bench/memory_scale.py` (%s, %s). Each row builds `weft scene KIND --size "
        "N` (weave: N warp and N weft yarns; knit: N courses of N loops) with models/MATERIAL.json and renders it at 32 x 32 px, 1 spp, in fiber and "
        "in neural mode (one process each). Memory as Table 2 counts it: Embree geometry + "
        "BVH plus the materials' BSDFs (neural: the networks, energy guard and sampling table "
        "of the one yarn model, the same at every size). Table 2's rows are the 3 x 3 patches."
        % (version, datetime.date.today().isoformat()),
        "",
        "| material | scene | --size | fiber tubes | fiber MB | neural geometry MB | neural "
        "material MB | memory ratio | geometry ratio | RSS fiber / neural MB | RSS ratio |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append("| %s | %s | %d x %d | %d | %.1f | %.2f | %.2f | **%.0fx** | %.0fx | "
                     "%.0f / %.0f | %.1fx |" % (
                         r["preset"], r["scene"], r["patch"], r["patch"], r["fiber_tubes"],
                         (r["fiber_geometry_bytes"] + r["fiber_material_bytes"]) / MB,
                         r["neural_geometry_bytes"] / MB, r["neural_material_bytes"] / MB,
                         r["memory_ratio"], r["geometry_ratio"], r["fiber_rss_bytes"] / MB,
                         r["neural_rss_bytes"] / MB, r["rss_ratio"]))
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    benchlib.write_text(args.out, "\n".join(lines) + "\n")
    benchlib.write_text(os.path.splitext(args.out)[0] + ".json", json.dumps(benchlib.portable(
        {"weft_version": version, "date": datetime.date.today().isoformat(), "rows": rows}),
        indent=1) + "\n")
    print("wrote %s" % os.path.relpath(args.out, ROOT))


if __name__ == "__main__":
    main()
