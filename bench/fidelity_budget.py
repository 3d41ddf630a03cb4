#!/usr/bin/env python3
"""bench/fidelity_budget.py: where the neural render's full-resolution
difference from the fibers comes from (issue 47, item 1), one run.

For each Table 2 scene given (`weft scene KIND`, as bench/table2.py makes
it), renders at the same spp:
  F0a, F0b  fiber mode, the default fiber arrangement, seeds 1 and 2
  F1a, F1b  fiber mode, another arrangement (render.fiber_seed 1), seeds 3, 4
  Na, Nb    neural mode, seeds 1 and 2
and splits, at block sizes of 1, 2, 4 and 8 pixels (both images averaged
over K x K blocks first, as `weft compare --scale K`), the relative MSE of
one neural render against one fiber render into its parts. With one weight
per pixel, 1 / (R^2 + 0.01) where R is the mean of the four fiber renders
(weft compare's relative MSE, with a reference that is the same for every
pair), D(X, Y) = mean(w (X - Y)^2) and
  noise of one render        vF = D(F0a, F0b) / 2 (vF1 likewise), vN = D(Na, Nb) / 2
  sub-ply structure          s2 = D(F0, F1) / 2 - (vF + vF1) / 4, F0 and F1 the seed
                             means of each arrangement: what two arrangements of
                             the same fibers differ by, over 2 (one arrangement
                             against the arrangements' mean)
  the model's own error      e = D(Na, F0a) - vN - vF: the issue's "relMSE minus
                             both references' noise" (Table 2's, at spp here)
  ply-level error            b2 = D(N, F) - vN / 2 - (vF + vF1) / 8 - s2 / 2, N and F
                             the means of all neural and all fiber renders: the
                             part of e no ply-level model need leave (e = b2 + s2)
The per-channel means N / F (all renders) are the bias at every scale;
F1 / F0 shows how far the arrangement alone moves them.

    bench/fidelity_budget.py [--weft build/release/weft]
        [--scenes polyester,weave polyester,knit silk,weave silk,knit fleece,weave fleece,knit]
        (a scene: PRESET,KIND or PRESET,KIND,PLIES: `weft scene KIND --plies PLIES`)
        [--spp 256] [--size 128] [--threads 0] [--out bench/results/fidelity-budget.md]
"""
import argparse
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from benchlib import binary_digest, now, table2_scene, write_results  # noqa: E402

SCALES = (1, 2, 4, 8)
REL_MSE_EPSILON = 0.01  # eval/image_compare.cpp kRelMseEpsilon


def render(weft, scene, mode, spp, seed, fiber_seed, threads, out):
    subprocess.run([weft, "render", scene, "--mode", mode, "--spp", str(spp), "--seed",
                    str(seed), "--fiber-seed", str(fiber_seed), "--threads", str(threads),
                    "--quiet", "--out", out], check=True, stdout=subprocess.DEVNULL)


def blocks(image, k):
    """The image averaged over k x k pixel blocks (edges that do not fill a block dropped)."""
    h, w = (image.shape[0] // k) * k, (image.shape[1] // k) * k
    return image[:h, :w].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))


def budget(img, np):
    """The split above at each block size, and the channel-mean ratios."""
    rows = {}
    for k in SCALES:
        b = {name: blocks(x, k) for name, x in img.items()}
        reference = (b["F0a"] + b["F0b"] + b["F1a"] + b["F1b"]) / 4
        w = 1.0 / (reference * reference + REL_MSE_EPSILON)

        def d(x, y):
            return float(np.mean(w * (x - y) ** 2))

        f0 = (b["F0a"] + b["F0b"]) / 2
        f1 = (b["F1a"] + b["F1b"]) / 2
        vF = d(b["F0a"], b["F0b"]) / 2
        vF1 = d(b["F1a"], b["F1b"]) / 2
        vN = d(b["Na"], b["Nb"]) / 2
        s2 = d(f0, f1) / 2 - (vF + vF1) / 4
        e = d(b["Na"], b["F0a"]) - vN - vF
        n = (b["Na"] + b["Nb"]) / 2
        b2 = d(n, reference) - vN / 2 - (vF + vF1) / 8 - s2 / 2
        rows[k] = {"noise_fiber": vF, "noise_neural": vN, "structure": s2, "model_error": e,
                   "ply_level": b2, "structure_share": s2 / e if e > 0 else None}
    means = {name: x.reshape(-1, 3).mean(axis=0) for name, x in img.items()}
    fiber = (means["F0a"] + means["F0b"] + means["F1a"] + means["F1b"]) / 4
    neural = (means["Na"] + means["Nb"]) / 2
    arrangement = (means["F1a"] + means["F1b"]) / (means["F0a"] + means["F0b"])
    return rows, [float(x) for x in neural / fiber], [float(x) for x in arrangement]


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--python", default=os.path.join(ROOT, "build", "release", "python"),
                   help="folder of the weft Python module (images are read with it)")
    p.add_argument("--scenes", nargs="+",
                   default=["polyester,weave", "polyester,knit", "silk,weave", "silk,knit",
                            "fleece,weave", "fleece,knit"])
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--patch", type=int, default=3)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "fidelity-budget.md"))
    a = p.parse_args()
    sys.path.insert(0, a.python)
    import numpy as np
    import weft

    results = {"date": now(), "spp": a.spp, "size": a.size, "patch": a.patch,
               "weft": binary_digest(a.weft), "scales": list(SCALES), "rows": []}
    lines = [
        "# Fidelity budget: the neural render's difference from the fibers, by cause",
        "",
        f"`bench/fidelity_budget.py --spp {a.spp} --size {a.size}` ({results['date']}); each "
        f"scene as bench/table2.py makes it (`weft scene KIND --size {a.patch}`), {a.spp} spp "
        "per render: fiber mode in two fiber arrangements (render.fiber_seed 0 and 1) at two "
        "seeds each, neural mode at two seeds. Relative MSE against the mean of the fiber "
        "renders (weights 1 / (R^2 + 0.01)); the split is in the script's header. *model "
        "error*: one neural render against one fiber render less both renders' noise; "
        "*structure*: what one arrangement of the fibers differs from the arrangements' mean "
        "(single fibers and their glints: no ply-level BSDF draws them); *ply-level*: the "
        "rest (the model, the exit spread, light between plies). K: both images averaged "
        "over K x K pixel blocks first.",
        "",
        "| scene | K | model error | structure | ply-level | structure share | noise fiber / neural |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    means_lines = [
        "",
        "Per-channel means (r / g / b), all renders of each mode:",
        "",
        "| scene | neural / fiber | fiber arrangement 1 / 0 |",
        "| --- | --- | --- |",
    ]
    with tempfile.TemporaryDirectory(prefix="weft-budget-") as work:
        for spec in a.scenes:
            preset, kind, *plies = spec.split(",")
            name = f"{preset} {kind}" + (f" ({plies[0]} plies)" if plies else "")
            folder = os.path.join(work, spec.replace(",", "-"))
            scene = table2_scene(a.weft, preset, kind, folder, a.size, a.patch,
                                 ["--plies", plies[0]] if plies else [])
            img = {}
            for key, mode, seed, arrangement in (("F0a", "fiber", 1, 0), ("F0b", "fiber", 2, 0),
                                                 ("F1a", "fiber", 3, 1), ("F1b", "fiber", 4, 1),
                                                 ("Na", "neural", 1, 0), ("Nb", "neural", 2, 0)):
                out = os.path.join(folder, key + ".exr")
                render(a.weft, scene, mode, a.spp, seed, arrangement, a.threads, out)
                img[key] = np.asarray(weft.read_image(out), dtype=np.float64)
                print(f"[fidelity_budget] {spec} {key}", flush=True)
            rows, ratio, arrangement = budget(img, np)
            results["rows"].append({"scene": spec, "by_scale": {str(k): v for k, v in rows.items()},
                                    "neural_over_fiber_means": ratio,
                                    "arrangement_means": arrangement})
            for k, r in rows.items():
                share = "-" if r["structure_share"] is None else f"{r['structure_share']:.2f}"
                lines.append(
                    f"| {name} | {k} | {r['model_error']:.4f} | {r['structure']:.4f} | "
                    f"{r['ply_level']:.4f} | {share} | {r['noise_fiber']:.4f} / "
                    f"{r['noise_neural']:.4f} |")
            means_lines.append(f"| {name} | " + " / ".join(f"{x:.3f}" for x in ratio) +
                               " | " + " / ".join(f"{x:.3f}" for x in arrangement) + " |")
    write_results(a.out, lines + means_lines + [""], results)


if __name__ == "__main__":
    main()
