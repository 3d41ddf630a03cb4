#!/usr/bin/env python3
"""bench/sampler.py: what the sobol sampler buys each mode, and the speed-up.

`weft render --sampler sobol` draws each pixel's samples from Owen-scrambled
Sobol' points (core/sample_stream.h, docs/render.md) instead of independent
random numbers. This program measures, on Table 2's weave and knit scenes
(`weft scene weave|knit --size 3`), for fiber and neural mode and both
samplers in one run:

  - c = relMSE x spp at each ladder level n, against that mode's converged
    render at N spp (independent sampler): c = relMSE / (1/n + 1/N), as in
    bench/table2.py;
  - seconds per spp, and seconds to relative MSE 0.01 (c of the top level /
    0.01 x seconds per spp);
  - the equal-quality speed-up (fiber seconds / neural seconds) with each
    sampler, and the ratios independent / sobol of c per mode.

Writes bench/results/sampler.md and .json (or --out).

    bench/sampler.py [--weft build/release/weft] [--presets polyester]
                     [--scenes weave,knit] [--size 128] [--ref-spp 1024]
                     [--ladder 16,64,256] [--threads 0] [--work DIR]

About 5 minutes per material and scene on 2 cores at the defaults (the fiber
reference is most of it). Renders are cached in --work by their command line.
"""
import argparse
import datetime
import json
import os
import platform
import sys
import tempfile

import benchlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TARGET_REL_MSE = 0.01
SAMPLERS = ("independent", "sobol")
MODES = ("fiber", "neural")
REF_SEED, LADDER_SEED = 1, 10


def run(cmd):
    return benchlib.run(cmd, "sampler")


def cached(folder, cmd):
    benchlib.cached_run(folder, cmd, "sampler")


def render(args, scene, folder, mode, sampler, seed, spp):
    exr = os.path.join(folder, "image.exr")
    cmd = [args.weft, "render", scene, "--mode", mode, "--sampler", sampler, "--seed",
           str(seed), "--spp", str(spp), "--threads", str(args.threads), "--quiet", "--out", exr]
    print("sampler: %s %s %s %d spp" % (os.path.relpath(scene, args.work), mode, sampler, spp),
          flush=True)
    cached(folder, cmd)
    with open(os.path.join(folder, "image.json")) as f:
        return json.load(f), exr


def rel_mse(args, a, b):
    return json.loads(run([args.weft, "compare", a, b]))["rel_mse"]


def measure(args, preset, kind):
    folder = os.path.join(args.work, "%s-%s" % (preset, kind))
    scene_dir = os.path.join(folder, "scene")
    scene_cmd = [args.weft, "scene", kind, "--model", os.path.join(ROOT, "models",
                                                                     preset + ".json"),
                 "--width", str(args.size), "--height", str(args.size), "--spp", "1", "--size",
                 "3", "--out", os.path.join(scene_dir, "s")]
    cached(scene_dir, scene_cmd)
    scene = os.path.join(scene_dir, "s", "scene.json")
    row = {"preset": preset, "scene": kind, "modes": {}}
    for mode in MODES:
        _, ref = render(args, scene, os.path.join(folder, mode + "-ref"), mode, "independent",
                        REF_SEED, args.ref_spp)
        row["modes"][mode] = {}
        for sampler in SAMPLERS:
            levels = []
            for i, spp in enumerate(args.ladder):
                stats, exr = render(args, scene,
                                    os.path.join(folder, "%s-%s-%d" % (mode, sampler, spp)),
                                    mode, sampler, LADDER_SEED + i, spp)
                rel = rel_mse(args, exr, ref)
                levels.append({"spp": spp, "rel_mse": rel,
                               "c": rel / (1.0 / spp + 1.0 / args.ref_spp),
                               "seconds_per_spp": stats["seconds_per_spp"]})
            seconds_per_spp = sum(l["seconds_per_spp"] * l["spp"] for l in levels) / sum(
                l["spp"] for l in levels)
            c = levels[-1]["c"]
            row["modes"][mode][sampler] = {
                "levels": levels, "c": c, "seconds_per_spp": seconds_per_spp,
                "seconds_to_target": c / TARGET_REL_MSE * seconds_per_spp}
    m = row["modes"]
    row["speedup"] = {s: m["fiber"][s]["seconds_to_target"] / m["neural"][s]["seconds_to_target"]
                      for s in SAMPLERS}
    row["c_ratio"] = {mode: m[mode]["independent"]["c"] / m[mode]["sobol"]["c"] for mode in MODES}
    return row


def write(args, rows):
    lines = [
        "# The sobol sampler against the independent one",
        "",
        "Made by `bench/sampler.py` on %s (%s, %d threads given; 0 = all cores), %d x %d px, "
        "`weft scene KIND --size 3`, references at %d spp (independent sampler). c = relMSE / "
        "(1/n + 1/N) at each ladder level n; time to relMSE %.2g = c of the top level / %.2g x "
        "seconds per spp. Every number of a row comes from this one run."
        % (datetime.date.today().isoformat(), platform.processor() or platform.machine(),
           args.threads, args.size, args.size, args.ref_spp, TARGET_REL_MSE, TARGET_REL_MSE),
        "",
        "| material | scene | mode | c independent (n: c) | c sobol (n: c) | c ratio ind / sobol "
        "| s/spp ind / sobol | speed-up independent | speed-up sobol |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        for mode in MODES:
            a, b = r["modes"][mode]["independent"], r["modes"][mode]["sobol"]
            lv = lambda e: ", ".join("%d: %.3g" % (l["spp"], l["c"]) for l in e["levels"])
            speed = ("**%.1fx**" % r["speedup"]["independent"],
                     "**%.1fx**" % r["speedup"]["sobol"]) if mode == "neural" else ("", "")
            lines.append("| %s | %s | %s | %s | %s | %.2f | %.4f / %.4f | %s | %s |" % (
                r["preset"], r["scene"], mode, lv(a), lv(b), r["c_ratio"][mode],
                a["seconds_per_spp"], b["seconds_per_spp"], speed[0], speed[1]))
    out_json = benchlib.write_md_and_json(args.out, "\n".join(lines) + "\n",
                                          {"size": args.size, "ref_spp": args.ref_spp,
                                           "ladder": args.ladder, "threads": args.threads,
                                           "rows": rows})
    print("sampler: wrote %s and %s" % (args.out, out_json))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--presets", default="polyester")
    p.add_argument("--scenes", default="weave,knit")
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--ref-spp", type=int, default=1024)
    p.add_argument("--ladder", default="16,64,256")
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "weft-bench-sampler"))
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "sampler.md"))
    args = p.parse_args()
    args.ladder = [int(x) for x in args.ladder.split(",")]
    if not os.path.exists(args.weft):
        sys.exit("sampler: no weft binary at %s (build first, or give --weft)" % args.weft)
    if args.size < 16 or args.ref_spp < max(args.ladder) or min(args.ladder) < 1:
        sys.exit("sampler: --size >= 16 and 1 <= ladder <= --ref-spp")
    rows = [measure(args, preset, kind) for preset in args.presets.split(",")
            for kind in args.scenes.split(",")]
    write(args, rows)


if __name__ == "__main__":
    main()
