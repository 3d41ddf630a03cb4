#!/usr/bin/env python3
"""bench/model_bias.py: each shipped model against a fresh gather of its own
ply (issue 47, item 1 (c): the model's own error, apart from the renders).

For each preset: `weft gather` of the ply the model was fitted on (the
fit's ply seed, fiber and ply parameters of the preset) with another walk
seed, then `weft yarn check` of models/PRESET.json against it. Writes, per
channel, the model's mean directional albedo of each component (M, R, and T)
over the gather's, the incident bins checked (those with >= 1000 paths),
averaged as `weft yarn check` averages them (check.json albedo.components_mean),
the share of bins whose albedo is within 3 %, and the coarse-grid relative L2
errors of M and R. A ratio above 1 is light the model adds at every
incidence: it shows in a render as a channel too bright.

Then the same against gathers of --other-plies other arrangements of the
same fibers (ply seeds S + 1, S + 2, ...): a fiber render draws every ply in
its own arrangement (render/scene.h fiberSeed), so what it averages is the
arrangements' mean, while the model learnt the one arrangement it was
gathered on. The spread of those ratios is what one arrangement's RDM
differs by; their mean against the fit's own ply, the model's bias against
the fibers a render draws.

    bench/model_bias.py [--weft build/release/weft] [--presets polyester silk fleece
        gabardine cotton] [--paths 4000000] [--other-plies 3] [--out bench/results/model-bias.md]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from benchlib import binary_digest, now, write_results  # noqa: E402


def gather_check(a, work, preset, model_path, ply_seed):
    """check.json of the model against a gather of the preset's ply `ply_seed`."""
    gather = os.path.join(work, f"{preset}-rdm-{ply_seed}")
    check = os.path.join(work, f"{preset}-check-{ply_seed}")
    subprocess.run([a.weft, "gather", "--preset", preset, "--paths", str(a.paths), "--seed",
                    str(a.seed), "--ply-seed", str(ply_seed), "--quiet", "--out", gather],
                   check=True, stdout=subprocess.DEVNULL)
    subprocess.run([a.weft, "yarn", "check", "--model", model_path, "--rdm", gather, "--out",
                    check], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(check, "check.json")) as f:
        return json.load(f)


def m_ratio(check):
    mean = check["albedo"]["components_mean"]
    return ratios(mean["model_m"], mean["rdm_m"])


def ratios(model, rdm):
    return [m / r if r > 0 else None for m, r in zip(model, rdm)]


def fmt(values):
    return " / ".join("-" if v is None else f"{v:.3f}" for v in values)


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--presets", nargs="+",
                   default=["polyester", "silk", "fleece", "gabardine", "cotton"])
    p.add_argument("--paths", type=int, default=4000000)
    p.add_argument("--seed", type=int, default=101, help="walk seed (the fit's ply seed is kept)")
    p.add_argument("--other-plies", type=int, default=3)
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "model-bias.md"))
    a = p.parse_args()
    results = {"date": now(), "paths": a.paths, "seed": a.seed, "weft": binary_digest(a.weft),
               "rows": []}
    lines = [
        "# The shipped models against a fresh gather of their ply",
        "",
        f"`bench/model_bias.py --paths {a.paths}` ({results['date']}): `weft gather --preset "
        f"P --paths {a.paths} --seed {a.seed} --ply-seed S` (S: the ply seed the model was "
        "fitted on, from its fit.rdm) and `weft yarn check` of models/P.json against it. "
        "Model / gather mean directional albedo per component and channel (r / g / b) over "
        "the incident bins with at least 1000 paths; *within 3 %*: the share of those bins "
        "whose total albedo is; m and r rel L2: the coarse-grid relative L2 error of each "
        "lobe.",
        "",
        "| preset | M model / gather | R model / gather | T | total | within 3 % | m rel L2 | r rel L2 |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    with tempfile.TemporaryDirectory(prefix="weft-model-bias-") as work:
        for preset in a.presets:
            model_path = os.path.join(ROOT, "models", preset + ".json")
            with open(model_path) as f:
                fit = json.load(f).get("fit", {})
            ply_seed = fit.get("rdm", {}).get("ply_seed", 0)
            c = gather_check(a, work, preset, model_path, ply_seed)
            others = [gather_check(a, work, preset, model_path, ply_seed + k)
                      for k in range(1, a.other_plies + 1)]
            mean = c["albedo"]["components_mean"]
            total_model = [m + r + mean["model_t"] for m, r in zip(mean["model_m"], mean["model_r"])]
            total_rdm = [m + r + mean["rdm_t"] for m, r in zip(mean["rdm_m"], mean["rdm_r"])]
            row = {"preset": preset, "ply_seed": ply_seed,
                   "m": ratios(mean["model_m"], mean["rdm_m"]),
                   "r": ratios(mean["model_r"], mean["rdm_r"]),
                   "t": mean["model_t"] / mean["rdm_t"] if mean["rdm_t"] > 0 else None,
                   "total": ratios(total_model, total_rdm),
                   "within_3_percent": c["albedo"]["within_3_percent"],
                   "m_rel_l2": c["m_rel_l2"], "r_rel_l2": c["r_rel_l2"],
                   "bins_checked": c["bins_checked"],
                   "other_plies_m": [m_ratio(o) for o in others]}
            results["rows"].append(row)
            t = "-" if row["t"] is None else f"{row['t']:.3f}"
            lines.append(f"| {preset} | {fmt(row['m'])} | {fmt(row['r'])} | {t} | "
                         f"{fmt(row['total'])} | {row['within_3_percent']:.2f} | "
                         f"{row['m_rel_l2']:.3f} | {row['r_rel_l2']:.3f} |")
            print(f"[model_bias] {preset}: M {fmt(row['m'])}", flush=True)
    lines += [
        "",
        f"M model / gather on {a.other_plies} other arrangements of each ply (ply seeds S + 1, "
        "S + 2, ...; r / g / b), and their mean: the model against the fibers a render draws.",
        "",
        "| preset | fit's ply | other plies | their mean |",
        "| --- | --- | --- | --- |",
    ]
    for row in results["rows"]:
        others = row["other_plies_m"]
        mean = [sum(o[c] for o in others) / len(others) for c in range(3)] if others else None
        row["other_plies_m_mean"] = mean
        lines.append(f"| {row['preset']} | {fmt(row['m'])} | "
                     + "; ".join(fmt(o) for o in others)
                     + f" | {fmt(mean) if mean else '-'} |")
    write_results(a.out, lines + [""], results)


if __name__ == "__main__":
    main()
