#!/usr/bin/env python3
"""bench/exit_table2.py: Table 2's weave and knit rows with the exit models
(issue 47, item 3), quality at Table 2's own settings, one run.

For each chunk given whose Table 2 renders are still in the work folder
(bench/table2.py's, default bench/work/table2/PRESET/KIND: its scene and
its converged fiber reference), renders the same scene in neural mode with
models/PRESET-exit.json (docs/exit-point.md) at the chunk's size and
reference spp, as two halves (seeds 21 and 22, ref_spp / 2 each; their mean
is the converged render), and scores it against the chunk's fiber
reference exactly as Table 2 scores today's model (`weft compare`: SSIM at
full resolution and over 4 x 4 px blocks, per-channel mean ratio, relative
MSE minus both references' noise). The exit render's noise comes from its
halves: with weights w = 1 / (F^2 + 0.01), F the fiber reference (the
weights of weft compare's relative MSE), D(a, b) = mean(w (a - b)^2) and
the noise of their mean D(a, b) / 4; the fiber reference's noise is the
chunk's (table2.json). Today's columns are the chunk's in
bench/results/table2.json, or with --today rendered here (Table 2's neural
reference made again: seed 1, the row's reference spp) and scored against
the same fiber reference by the same binary. No time is measured here (s/spp: bench/
exit_spread.md). An exit render is cached beside its scene with the digest
of the binary that made it (exit-SEED.exr.made-by) and made again by
another binary (--reuse-unstamped keeps those cached before the digest was
recorded); each row records its renders' binary, and the table is written
after every row.

    bench/exit_table2.py --chunks silk,weave polyester,knit ...
        [--work bench/work/table2] [--weft build/release/weft] [--spp N]
        [--today] [--reuse-unstamped] [--out bench/results/exit-table2.md]
"""
import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from benchlib import binary_digest, now, write_results  # noqa: E402
from exit_spread import compare, made_by_of, render, with_model  # noqa: E402
from fidelity_budget import REL_MSE_EPSILON  # noqa: E402

SEEDS = (21, 22)


def mean_noise(a, b, reference, np):
    """The noise (relative MSE against the truth, weights from `reference`) of
    the mean of two independent renders a and b of the same image."""
    w = 1.0 / (reference * reference + REL_MSE_EPSILON)
    return float(np.mean(w * (a - b) ** 2)) / 4.0


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--chunks", nargs="+", required=True, metavar="PRESET,KIND")
    p.add_argument("--work", default=os.path.join(ROOT, "bench", "work", "table2"))
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--python", default=os.path.join(ROOT, "build", "release", "python"))
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--spp", type=int, default=None,
                   help="spp of the exit render (default: the row's reference spp; less for a "
                        "quick look, more to see what of a difference is the exit render's "
                        "noise; the noise column subtracts it either way)")
    p.add_argument("--today", action="store_true",
                   help="render today's model here too (Table 2's neural reference: seed 1, "
                        "the row's reference spp) and score it against the same fiber reference "
                        "with the same binary, instead of taking today's columns from "
                        "table2.json (whose rows were made by several binaries)")
    p.add_argument("--reuse-unstamped", action="store_true",
                   help="reuse exit renders cached before renders recorded their binary "
                        "(their rows say so) instead of rendering them again")
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "exit-table2.md"))
    a = p.parse_args()
    sys.path.insert(0, a.python)
    import numpy as np
    import weft

    with open(os.path.join(ROOT, "bench", "results", "table2.json")) as f:
        cells = {(c["preset"], c["scene"]): c for c in json.load(f)["cells"]}
    rows, made_by = [], binary_digest(a.weft)
    for chunk in a.chunks:
        preset, _, kind = chunk.partition(",")
        cell = cells.get((preset, kind))
        folder = os.path.join(a.work, preset, kind)
        scene = os.path.join(folder, "scene", "s", "scene.json")
        fiber = os.path.join(folder, "fiber-ref", "image.exr")
        model = os.path.join(ROOT, "models", preset + "-exit.json")
        missing = [x for x in (scene, fiber, model) if not os.path.exists(x)]
        if cell is None or missing:
            sys.exit(f"bench/exit_table2: {chunk}: needs its Table 2 row and " +
                     ", ".join(missing or ["bench/results/table2.json's cell"]))
        ref_spp = a.spp or cell["ref_spp"]
        exit_scene = with_model(scene, model, os.path.join(folder, "scene", "s", "exit.json"))
        # Renders at another spp than the row's own are cached under names of their own.
        tag = "" if ref_spp == cell["ref_spp"] else f"{ref_spp}spp-"
        halves, stamps = [], set()
        for seed in SEEDS:
            out = os.path.join(folder, f"exit-{tag}{seed}.exr")
            reuse = a.reuse_unstamped and os.path.exists(out) and made_by_of(out) is None
            render(a.weft, exit_scene, "neural", ref_spp // 2, seed, a.threads, out,
                   None if reuse else made_by)
            stamps.add(made_by_of(out) or "unstamped")
            halves.append(np.asarray(weft.read_image(out), dtype=np.float64))
            print(f"[exit_table2] {preset} {kind} seed {seed}", flush=True)
        mean = os.path.join(folder, f"exit-{tag}ref.exr")
        weft.save_image(mean, ((halves[0] + halves[1]) / 2).astype(np.float32))
        reference = np.asarray(weft.read_image(fiber), dtype=np.float64)
        exit_noise = mean_noise(halves[0], halves[1], reference, np)
        fiber_noise = cell["fiber"]["equal_quality"]["reference_noise"]

        def score(image, noise):
            """Table 2's scores of `image` against the fiber reference, its own noise given."""
            full, blocks = compare(a.weft, image, fiber, 1), compare(a.weft, image, fiber, 4)
            return {"mean_ratio": full["mean_ratio"], "ssim": full["ssim"],
                    "ssim_4": blocks["ssim"], "rel_mse": full["rel_mse"], "noise": noise,
                    "rel_mse_minus_noise": full["rel_mse"] - fiber_noise - noise}

        today = {"mean_ratio": cell["mean_ratio"], "ssim": cell["ssim"],
                 "ssim_4": cell["ssim_scales"]["4"],
                 "rel_mse_minus_noise": cell["rel_mse_minus_noise"], "source": "table2.json"}
        if a.today:
            # Table 2's own neural reference, made again: its noise is the chunk's.
            out = os.path.join(folder, f"today-{cell['ref_spp']}spp.exr")
            render(a.weft, scene, "neural", cell["ref_spp"], 1, a.threads, out, made_by)
            today = dict(score(out, cell["neural"]["equal_quality"]["reference_noise"]),
                         source="rendered")
        rows.append({
            "preset": preset, "scene": kind, "size": cell["size"], "ref_spp": ref_spp,
            "exit_made_by": " + ".join(sorted(stamps)),
            "today": today, "exit": score(mean, exit_noise)})

        write_table(a, rows, made_by)


def write_table(a, rows, made_by):
    """exit-table2.md and .json of the rows measured so far (written after each row, so that a
    run stopped early keeps what it measured)."""
    def means(m):
        return " / ".join(f"{x:.3f}" for x in m)

    others = [f"{r['preset']} {r['scene']} ({r['exit_made_by']})" for r in rows
              if r["exit_made_by"] != made_by]
    lines = ["# Table 2's weave and knit rows with the exit models (bench/exit_table2.py)", "",
             "Each row at its Table 2 size and reference spp, against the row's own converged "
             "fiber reference; today's columns " +
             ("rendered here as Table 2 renders its neural reference (seed 1, the row's "
              "reference spp), by the same binary" if a.today else
              "from bench/results/table2.json") +
             ", the exit model's (models/PRESET-exit.json) rendered here as two halves of "
             "ref_spp / 2 (seeds 21, 22). relMSE - noise: Table 2's relative MSE less both "
             "references' noise (the exit render's from its halves, today's the chunk's). "
             "Commands: `bench/exit_table2.py "
             "--chunks " + " ".join(a.chunks) + (f" --spp {a.spp}" if a.spp else "") +
             (" --today" if a.today else "") + "`.", "",
             "| row | px, ref spp | neural / fiber means r / g / b, today -> exit | "
             "SSIM today -> exit | SSIM 4 x 4 px today -> exit | relMSE - noise today -> exit |",
             "| --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        t, e = r["today"], r["exit"]
        lines.append(
            f"| {r['preset']} {r['scene']} | {r['size']}, {r['ref_spp']} | "
            f"{means(t['mean_ratio'])} -> {means(e['mean_ratio'])} | "
            f"{t['ssim']:.3f} -> {e['ssim']:.3f} | {t['ssim_4']:.3f} -> {e['ssim_4']:.3f} | "
            f"{t['rel_mse_minus_noise']:.4f} -> {e['rel_mse_minus_noise']:.4f} |")
    if others:
        lines += ["", "Exit renders made by another binary than this run's (" + made_by +
                  "; *unstamped*: cached before renders recorded theirs): " +
                  ", ".join(others) + "."]
    results = {"finished": now(), "weft_sha256": made_by, "rows": rows}
    write_results(a.out, lines, results)


if __name__ == "__main__":
    main()
