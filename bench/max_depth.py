#!/usr/bin/env python3
"""bench/max_depth.py: how much light a render's max_depth cuts, per material and scene.

A path still carrying light after render.max_depth scattering events is cut
(docs/render.md#integrator): the image lacks its further light and is darker,
not noisier. In fiber mode a path scatters about 13 times per visit of a
near-white ply (the gather's mean depth of cotton), so the old default of 100
events cut part of a cloth's light. This program renders Table 2's scenes
(`weft scene KIND --size 3` with each shipped model, 128 x 128) in fiber mode
at max_depth 100 and 1000 with the same seed, and in neural mode at 100, and
reports per row, in one run:

  - the share of paths cut (the render's truncated_fraction) at 100 and 1000;
  - the mean of each channel at 1000 over the mean at 100 (the light the
    shallow limit lost; the same samples up to the cut, so the ratio is far
    less noisy than either mean);
  - seconds per spp at 1000 over 100 (what the deep limit costs);
  - neural mode's cut share at 100 (a ply visit is one event there).

Writes bench/results/max-depth.md and .json (or --out). bench/table2.py reads
the json to mark the Table 2 rows whose fiber reference was made at 100.

    bench/max_depth.py [--weft build/release/weft] [--spp 16]
                       [--presets fleece,silk,polyester,cotton,gabardine]

About 5 minutes on 2 cores at the default.
"""
import argparse
import datetime
import json
import os
import sys
import tempfile

import benchlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRESETS = ("fleece", "silk", "polyester", "cotton", "gabardine")
SCENES = ("closeup", "weave", "knit")
SHALLOW, DEEP = 100, 1000
SIZE = 128


def run(cmd):
    return benchlib.run(cmd, "max_depth")


def render(weft, scene, mode, spp, out):
    run([weft, "render", scene, "--mode", mode, "--seed", "1", "--spp", str(spp), "--quiet",
         "--threads", "0", "--out", out])
    with open(os.path.splitext(out)[0] + ".json") as f:
        return json.load(f)


def row(weft, preset, kind, spp, work):
    folder = os.path.join(work, "%s-%s" % (preset, kind))
    cmd = [weft, "scene", kind, "--model", os.path.join(ROOT, "models", preset + ".json"),
           "--width", str(SIZE), "--height", str(SIZE), "--spp", "1", "--out", folder]
    if kind != "closeup":
        cmd += ["--size", "3"]
    run(cmd)
    scene = os.path.join(folder, "scene.json")
    with open(scene) as f:
        desc = json.load(f)
    scenes = {}
    for depth in (SHALLOW, DEEP):
        desc.setdefault("render", {})["max_depth"] = depth
        scenes[depth] = os.path.join(folder, "scene-depth%d.json" % depth)
        with open(scenes[depth], "w") as f:
            json.dump(desc, f, indent=1)
    out = {d: os.path.join(folder, "fiber-%d.exr" % d) for d in (SHALLOW, DEEP)}
    stats = {d: render(weft, scenes[d], "fiber", spp, out[d]) for d in (SHALLOW, DEEP)}
    neural = render(weft, scenes[SHALLOW], "neural", spp, os.path.join(folder, "neural-100.exr"))
    # weft compare's mean_ratio: per channel mean of the deep render over the shallow one's.
    light = json.loads(run([weft, "compare", out[DEEP], out[SHALLOW]]))["mean_ratio"]
    return {
        "preset": preset, "scene": kind, "size": SIZE, "spp": spp,
        "fiber_cut": {str(d): stats[d]["truncated_fraction"] for d in (SHALLOW, DEEP)},
        "fiber_light_ratio": light,
        "fiber_seconds_ratio": stats[DEEP]["seconds_per_spp"] / stats[SHALLOW]["seconds_per_spp"],
        "neural_cut": {str(SHALLOW): neural["truncated_fraction"]},
    }


def write(rows, args, out_md):
    lines = ["# Light cut by render.max_depth, fiber mode", "",
             "Made by `bench/max_depth.py` (one run, %s): Table 2's scenes at %d x %d px, %d spp, "
             "fiber mode at max_depth %d and %d with the same seed. Cut share: the render's "
             "`truncated_fraction` (paths still carrying light when the limit ended them). Light "
             "ratio: mean of each channel at %d over the mean at %d (the light the shallow limit "
             "lost). Time ratio: seconds per spp at %d over %d. Neural mode scatters once per "
             "ply visit: its cut share at %d is beside." % (
                 datetime.date.today().isoformat(), SIZE, SIZE, args.spp, SHALLOW, DEEP, DEEP,
                 SHALLOW, DEEP, SHALLOW, SHALLOW), "",
             "| material | scene | fiber cut at %d | fiber cut at %d | light ratio R / G / B | "
             "time ratio | neural cut at %d |" % (SHALLOW, DEEP, SHALLOW),
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %s | %s | %.3f %% | %.4f %% | %s | %.2f | %.4f %% |" % (
            r["preset"], r["scene"], 100 * r["fiber_cut"][str(SHALLOW)],
            100 * r["fiber_cut"][str(DEEP)],
            " / ".join("-" if v is None else "%.3f" % v for v in r["fiber_light_ratio"]),
            r["fiber_seconds_ratio"], 100 * r["neural_cut"][str(SHALLOW)]))
    text = "\n".join(lines) + "\n"
    benchlib.write_md_and_json(out_md, text, {"shallow": SHALLOW, "deep": DEEP, "rows": rows})
    return text


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--presets", default=",".join(PRESETS))
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "max-depth.md"))
    args = p.parse_args()
    if not os.path.exists(args.weft):
        sys.exit("max_depth: no weft binary at %s (--weft)" % args.weft)
    if args.spp < 1:
        sys.exit("max_depth: --spp must be >= 1")
    presets = args.presets.split(",")
    for name in presets:
        if name not in PRESETS:
            sys.exit("max_depth: unknown preset '%s' (allowed: %s)" % (name, ", ".join(PRESETS)))
    rows = []
    with tempfile.TemporaryDirectory(prefix="weft-max-depth-") as work:
        for preset in presets:
            for kind in SCENES:
                rows.append(row(args.weft, preset, kind, args.spp, work))
                r = rows[-1]
                print("%s %s: cut %.4f -> %.6f, light x %s" % (
                    preset, kind, r["fiber_cut"][str(SHALLOW)], r["fiber_cut"][str(DEEP)],
                    " ".join("%.3f" % v for v in r["fiber_light_ratio"])), flush=True)
    print(write(rows, args, args.out))


if __name__ == "__main__":
    main()
