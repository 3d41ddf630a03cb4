#!/usr/bin/env python3
"""bench/colour_scenes.py: a colour-conditioned model against the fibers in
colours it was never fitted for (issue 21, docs/colour.md).

With one conditioned model (`weft fit --colour-range`, e.g. the one
bench/colour_fit.py leaves in bench/work/colour-fit/), each case is a
generated scene (`weft scene`) rendered in fiber mode (the ground truth: the
same colours on the explicit fibers) and in neural mode, each in its own
process:
  - the close-up and the knit in two colours outside Table 3,
  - the striped knit in both colours (`--colours C1 C2`),
  - the close-up at the model's own gathered colour, conditioned and, with
    --dedicated, the ordinary model fitted at that colour (how much of the
    difference to the fibers is the model's own, not the conditioning's; the
    knit at gabardine's own colour is left out: its near-white red channel
    makes a 1024-spp fiber render of it take 12 minutes).
Per case: SSIM and relative MSE of neural against the fiber reference, and of
a second fiber render (another seed, same spp) against the reference: the
reference's own noise, so that a reader sees how much of the SSIM gap is
noise. Also seconds per spp of each mode. Resumable (renders cached under
bench/work/colour-scenes/). Writes bench/results/colour-scenes.md, .json and
a figure, bench/results/colour-scenes.png (a row per case: fiber | neural).

    bench/colour_scenes.py --model ANY.json [--dedicated MODEL.json]
                           [--weft build/release/weft] [--size 128] [--spp 256]
                           [--ref-spp 256] [--threads 0]
"""
import argparse
import json
import os
import subprocess
import sys
import time

import benchlib
from benchlib import portable_path, write_results

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Two colours that are not Table 3's (docs/design.md 3), inside [0.3, 0.999].
OCHRE = (0.85, 0.55, 0.3)
SAGE = (0.4, 0.62, 0.5)


def colour_arg(c):
    return ",".join(f"{v:g}" for v in c)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", required=True, help="a colour-conditioned MODEL.json")
    ap.add_argument("--dedicated", help="an ordinary model fitted at the conditioned model's own colour")
    ap.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--ref-spp", type=int, default=256)
    ap.add_argument("--knit-size", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--work", default=os.path.join(ROOT, "bench", "work", "colour-scenes"))
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "colour-scenes"))
    a = ap.parse_args()
    weft = os.path.abspath(a.weft)
    model = os.path.abspath(a.model)
    os.makedirs(a.work, exist_ok=True)

    def run(args):
        r = subprocess.run([str(x) for x in args], check=True, stdout=subprocess.PIPE, text=True)
        lines = [l for l in r.stdout.splitlines() if l.strip()]
        return json.loads(lines[-1]) if lines else {}

    def log(message):
        print(f"[colour-scenes] {time.strftime('%H:%M:%S')} {message}", file=sys.stderr, flush=True)

    def render(scene, mode, spp, seed, name):
        exr = os.path.join(a.work, name + ".exr")
        stats_file = os.path.join(a.work, name + ".json")
        if not os.path.exists(stats_file):
            log(f"{name}: {mode}, {spp} spp")
            run([weft, "render", scene, "--mode", mode, "--spp", spp, "--seed", seed,
                 "--threads", a.threads, "--quiet", "--out", exr])
        with open(stats_file) as f:
            stats = json.load(f)
        return exr, stats["seconds"] / stats["spp"]

    cases = [
        ("close-up, ochre", "closeup", model, [OCHRE]),
        ("close-up, sage", "closeup", model, [SAGE]),
        ("knit, ochre", "knit", model, [OCHRE]),
        ("knit, sage", "knit", model, [SAGE]),
        ("striped knit, ochre / sage", "knit", model, [OCHRE, SAGE]),
        ("close-up, own colour (conditioned)", "closeup", model, []),
    ]
    if a.dedicated:
        cases.append(("close-up, own colour (dedicated model)", "closeup", os.path.abspath(a.dedicated), []))

    def fiber_and_ply(path):
        with open(path) as f:
            m = json.load(f)
        return json.dumps([m["fiber"], m["ply"]], sort_keys=True)

    rows, figure = [], []
    references = {}  # (scene kind, colours, fiber and ply) -> tag of the case whose fiber renders serve
    for label, kind, case_model, colours in cases:
        tag = "".join(ch if ch.isalnum() else "-" for ch in label).strip("-")
        # Fiber mode sees only the model's fiber and ply blocks: cases that
        # share them (the conditioned and the dedicated model at its colour)
        # share the fiber renders.
        ref_tag = references.setdefault((kind, str(colours), fiber_and_ply(case_model)), tag)
        scene_dir = os.path.join(a.work, "scene-" + tag)
        args = [weft, "scene", kind, "--model", case_model, "--width", a.size, "--height", a.size,
                "--quiet", "--out", scene_dir]
        if kind == "knit":
            args += ["--size", a.knit_size]
        if colours:
            args += ["--colours", *map(colour_arg, colours)]
        if len(colours) == 2:
            args += ["--stripe", 1]
        run(args)
        scene = os.path.join(scene_dir, "scene.json")
        ref, fiber_spp = render(scene, "fiber", a.ref_spp, 1, ref_tag + "-fiber")
        ref2, _ = render(scene, "fiber", a.ref_spp, 2, ref_tag + "-fiber2")
        neural, neural_spp = render(scene, "neural", a.spp, 3, tag + "-neural")
        versus = run([weft, "compare", neural, ref, "--heatmap", os.path.join(a.work, tag + "-ssim.png")])
        noise = run([weft, "compare", ref2, ref])
        # The same over 2 x 2 and 4 x 4 pixel blocks (weft compare --scale, docs/compare.md):
        # structure finer than a block, single fibers that a ply-level model averages, no longer counts.
        scales = {str(k): {"ssim": run([weft, "compare", neural, ref, "--scale", k])["ssim"],
                           "reference_ssim": run([weft, "compare", ref2, ref, "--scale", k])["ssim"]}
                  for k in (2, 4)}
        rows.append({"case": label, "scene": kind, "model": case_model, "colours": colours,
                     "ssim": versus["ssim"], "rel_mse": versus["rel_mse"],
                     "reference_ssim": noise["ssim"], "reference_rel_mse": noise["rel_mse"],
                     "ssim_scales": scales,
                     "fiber_seconds_per_spp": fiber_spp, "neural_seconds_per_spp": neural_spp})
        figure += [ref, neural]
    result = {"model": model, "dedicated": a.dedicated, "size": a.size, "spp": a.spp,
              "ref_spp": a.ref_spp, "knit_size": a.knit_size, "threads": a.threads, "rows": rows,
              "date": time.strftime("%Y-%m-%d %H:%M"), "nproc": os.cpu_count()}
    lines = [
        "# A colour-conditioned model against the fibers in new colours",
        "",
        f"`bench/colour_scenes.py`, {result['date']}, {os.cpu_count()} cores. Model "
        f"`{portable_path(model)}`; {a.size} x {a.size}, neural {a.spp} spp against a fiber "
        f"reference of {a.ref_spp} spp (seed 1); \"reference noise\" compares a second fiber render "
        "(seed 2, same spp) with it. Colours: ochre "
        f"{colour_arg(OCHRE)}, sage {colour_arg(SAGE)} (C_TT; not Table 3 colours).",
        "",
        "SSIM at 2x2 / 4x4 px: both images averaged over 2 x 2 and 4 x 4 pixel blocks first "
        "(`weft compare --scale`), for neural vs fiber and for the reference's noise.",
        "",
        "| case | SSIM neural vs fiber | rel. MSE | reference noise: SSIM | rel. MSE "
        "| SSIM at 2x2 / 4x4 px: neural | reference noise "
        "| fiber s/spp | neural s/spp | speed-up per spp |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        sc = r["ssim_scales"]
        lines.append(
            f"| {r['case']} | {r['ssim']:.4f} | {r['rel_mse']:.4f} | {r['reference_ssim']:.4f} | "
            f"{r['reference_rel_mse']:.4f} | {sc['2']['ssim']:.4f} / {sc['4']['ssim']:.4f} | "
            f"{sc['2']['reference_ssim']:.4f} / {sc['4']['reference_ssim']:.4f} | "
            f"{r['fiber_seconds_per_spp']:.3f} | "
            f"{r['neural_seconds_per_spp']:.3f} | "
            f"{r['fiber_seconds_per_spp'] / r['neural_seconds_per_spp']:.1f} |")
    lines += ["", "Figure `colour-scenes.png`: a row per case, fiber reference | neural.", ""]
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    made = os.path.join(a.work, "figure.png")
    run([weft, "montage", *figure, "--columns", 2, "--out", made])
    benchlib.publish_png(made, a.out + ".png")  # written only when its pixels change
    write_results(a.out + ".md", lines, result)


if __name__ == "__main__":
    main()
