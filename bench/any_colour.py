#!/usr/bin/env python3
"""bench/any_colour.py: one any-colour gather against dedicated gathers of
each colour (docs/gather.md, "Any colour from one gather").

For one material's ply (default fleece), measured in one run:
  - the cost of `weft gather --any-colour` against an ordinary gather of the
    same paths (seconds, ratio) and the size of its recorded paths;
  - for each target C_TT (the five Table 3 colours and two greys): the time
    of `weft gather recolour`, and the noise of the recoloured RDM: its
    coarse-grid relative L2 (fit/metrics.h: 11 x 45 x 15 x 30, solid-angle
    weighted) against a dedicated gather of that colour (other walks, same
    ply), beside the same error between two dedicated gathers of that colour
    (the noise of a dedicated gather with as many paths). A ratio near 1
    means the recolouring costs no accuracy; above 1, how much noisier the
    colour-blind lobe choice and per-lobe weights are for that colour.
Writes bench/results/any-colour.md and .json.

    bench/any_colour.py [--weft build/release/weft] [--material fleece]
                        [--paths 2000000] [--threads 0]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

from benchlib import write_results

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Table 3 (docs/design.md 3): C_R, C_TT, beta_R, beta_TT, gamma_TT; N, rho, alpha.
PRESETS = {
    "fleece": ([0.040, 0.087, 0.087], [0.452, 0.725, 0.948], 7.238, 10.000, 25.989, (300, 0.30, 0.24)),
    "silk": ([0.745, 0.008, 0.070], [0.620, 0.553, 0.562], 1.000, 10.000, 19.823, (300, 0.20, 0.00)),
    "polyester": ([0.700, 0.700, 0.700], [0.600, 0.000, 0.800], 5.238, 20.000, 25.000, (200, 0.40, 0.20)),
    "cotton": ([0.989, 0.959, 0.874], [0.999, 0.999, 0.999], 1.000, 27.197, 38.269, (600, 0.35, 0.06)),
    "gabardine": ([0.185, 0.047, 0.069], [0.999, 0.330, 0.354], 2.141, 10.000, 23.548, (450, 0.25, 0.12)),
}
COARSE = (11, 45, 15, 30)
PLY_SEED = 7


def run(cmd):
    start = time.monotonic()
    subprocess.run([str(c) for c in cmd], check=True, stdout=subprocess.DEVNULL)
    return time.monotonic() - start


def pool(m, bins):
    """The coarse-grid pooling of fit/metrics.h for a grid that refines COARSE."""
    ti, pi, to, po = bins
    fi, fp, fto, fpo = (a // b for a, b in zip(bins, COARSE))
    edges = np.linspace(0, np.pi, to + 1)
    w = (np.cos(edges[:-1]) - np.cos(edges[1:])) * (2 * np.pi / po)  # per theta_o bin
    v = m.astype(np.float64) * w[None, None, :, None, None]
    v = v.reshape(COARSE[0], fi, COARSE[1], fp, COARSE[2], fto, COARSE[3], fpo, 3)
    summed = v.sum(axis=(1, 3, 5, 7))
    wc = w.reshape(COARSE[2], fto).sum(axis=1) * fpo  # W_O per coarse theta_o row
    return summed / (fi * fp) / wc[None, None, :, None, None], wc


def rel_l2(a, b, bins):
    pa, wc = pool(a, bins)
    pb, _ = pool(b, bins)
    w = wc[None, None, :, None, None]
    return float(np.sqrt((w * (pa - pb) ** 2).sum() / (w * pb ** 2).sum()))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    ap.add_argument("--material", default="fleece", choices=sorted(PRESETS))
    ap.add_argument("--paths", type=int, default=2000000)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "any-colour"))
    args = ap.parse_args()
    c_r, c_tt, beta_r, beta_tt, gamma_tt, (fibers, density, twist) = PRESETS[args.material]
    bins = (22, 90, 45, 90)
    colours = [(name, PRESETS[name][1]) for name in PRESETS] + [
        ("grey 0.3", [0.3] * 3), ("grey 0.9", [0.9] * 3)]
    with tempfile.TemporaryDirectory(prefix="weft-any-colour-") as work:
        def gather(out, seed, params=None, any_colour=False):
            material = ["--preset", args.material] if params is None else [
                "--params", params, "--fibers", fibers, "--density", density, "--twist", twist]
            return run([args.weft, "gather", *material, "--paths", args.paths, "--seed", seed,
                        "--ply-seed", PLY_SEED, "--threads", args.threads, "--quiet", "--out", out]
                       + (["--any-colour"] if any_colour else []))

        def rdm(folder, name):
            return np.load(os.path.join(folder, name))

        print(f"[any-colour] {args.material}: any-colour and ordinary gathers of {args.paths} paths",
              file=sys.stderr)
        t_any = gather(os.path.join(work, "any"), 1, any_colour=True)
        t_plain = gather(os.path.join(work, "plain"), 1)
        meta = json.load(open(os.path.join(work, "any", "meta.json")))
        record_bytes = sum(os.path.getsize(os.path.join(work, "any", f"paths_{n}.npy"))
                           for n in ("bins", "kind", "weight"))
        rows = []
        for name, colour in colours:
            print(f"[any-colour] C_TT of {name}: {colour}", file=sys.stderr)
            tag = name.replace(" ", "")
            params = os.path.join(work, f"{tag}.json")
            with open(params, "w") as f:
                json.dump({"c_r": c_r, "c_tt": colour, "beta_r_deg": beta_r,
                           "beta_tt_deg": beta_tt, "gamma_tt_deg": gamma_tt}, f)
            recoloured = os.path.join(work, f"re-{tag}")
            t_recolour = run([args.weft, "gather", "recolour", os.path.join(work, "any"), "--c-tt",
                              ",".join(map(str, colour)), "--out", recoloured])
            a, b = os.path.join(work, f"a-{tag}"), os.path.join(work, f"b-{tag}")
            gather(a, 2, params)
            gather(b, 3, params)
            row = {"colour": name, "c_tt": colour, "recolour_seconds": t_recolour}
            for comp in ("m", "r"):
                ref = rdm(b, f"rdm_{comp}.npy")
                row[f"{comp}_recoloured"] = rel_l2(rdm(recoloured, f"rdm_{comp}.npy"), ref, bins)
                row[f"{comp}_dedicated"] = rel_l2(rdm(a, f"rdm_{comp}.npy"), ref, bins)
            rows.append(row)
            for folder in (recoloured, a, b):
                shutil.rmtree(folder)
    result = {"material": args.material, "paths": args.paths, "bins": bins, "coarse": COARSE,
              "threads": args.threads, "any_colour_seconds": t_any, "ordinary_seconds": t_plain,
              "colour_paths": meta["colour_paths"], "record_bytes": record_bytes, "rows": rows,
              "date": time.strftime("%Y-%m-%d %H:%M"), "nproc": os.cpu_count()}
    lines = [
        f"# One any-colour gather against dedicated gathers ({args.material} ply)",
        "",
        f"`bench/any_colour.py --material {args.material} --paths {args.paths}`, "
        f"{result['date']}, {os.cpu_count()} cores. Bins 22 x 90 x 45 x 90; errors on the "
        "coarse grid of fit/metrics.h (11 x 45 x 15 x 30), each against a dedicated gather "
        "of that colour with seed 3 (same ply).",
        "",
        f"- gather seconds: any-colour {t_any:.1f}, ordinary {t_plain:.1f} "
        f"(ratio {t_any / t_plain:.2f})",
        f"- recorded paths: {meta['colour_paths']} of {args.paths} "
        f"({record_bytes / 1e6:.1f} MB on disk, {record_bytes / meta['colour_paths']:.1f} bytes each)",
        "",
        "| C_TT of | C_TT | recolour s | M: recoloured | M: dedicated | ratio | R: recoloured | R: dedicated | ratio |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        lines.append(
            f"| {r['colour']} | {', '.join(f'{v:g}' for v in r['c_tt'])} | {r['recolour_seconds']:.2f} | "
            f"{r['m_recoloured']:.4f} | {r['m_dedicated']:.4f} | {r['m_recoloured'] / r['m_dedicated']:.2f} | "
            f"{r['r_recoloured']:.4f} | {r['r_dedicated']:.4f} | {r['r_recoloured'] / r['r_dedicated']:.2f} |")
    lines += ["", "M: recoloured = relative L2 of the recoloured RDM_M against the seed-3 "
              "dedicated gather; M: dedicated = the same for the seed-2 dedicated gather "
              "(the noise of a gather of that many paths); ratio = recoloured / dedicated.", ""]
    write_results(args.out + ".md", lines, result)


if __name__ == "__main__":
    main()
