#!/usr/bin/env python3
"""bench/family.py: one family model against models fitted for one yarn alone
(issue 42, docs/family.md).

For a family model (`weft fit family`), measured in one run with `weft yarn
check` (M and R relative L2 on the coarse grid, fit/metrics.h, and the mean
absolute relative error of the directional albedo):
  - at the five presets: the family's yarn (`weft yarn at --preset`) against
    the preset's shipped dedicated model, both checked against an independent
    16M-path any-colour gather of the preset (the colour models' gathers,
    seed 1: the shipped models were fitted to other walks of the same ply), at
    the preset's C_TT clamped into the family's colour range (polyester's
    green 0 is below it: that preset is compared at green 0.3, its dedicated
    model then the shipped polyester colour model at that colour);
  - at held-out yarns of the box (a family gather with another seed, so no
    training yarn), each with a test colour: a gather of --held-paths paths
    of that yarn, a model fitted to it alone (`weft fit`, default config), and
    the family's yarn; both checked against that gather (the dedicated model
    was fitted to it, which favours it).
Targets: family / dedicated <= 1.3 at the presets, <= 1.5 at held-out yarns.
Resumable: steps cache under bench/work/family/. Writes bench/results/family.md
and .json.

    bench/family.py --family FAMILY.json --preset-gathers DIR
                    [--weft build/release/weft] [--held 8] [--held-paths 4000000]
                    [--threads 0]
"""
import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from any_colour import PRESETS  # noqa: E402  (Table 3)
from benchlib import now, write_results  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HELD_SEED = 1001
# The held-out yarns' test colours: Table 3's C_TT in turn.
HELD_COLOURS = [PRESETS[m][1] for m in ("fleece", "silk", "polyester", "cotton", "gabardine")]


def run_json(cmd):
    """Runs a weft command; returns its last stdout line as JSON."""
    r = subprocess.run([str(c) for c in cmd], check=True, stdout=subprocess.PIPE, text=True)
    lines = [l for l in r.stdout.splitlines() if l.strip()]
    return json.loads(lines[-1]) if lines else {}


def cached(path, compute):
    """The JSON at `path`, or compute() written there first."""
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    value = compute()
    with open(path + ".tmp", "w") as f:
        json.dump(value, f)
    os.replace(path + ".tmp", path)
    return value


def scalar(value):
    """A check's number (a per-channel list: its mean)."""
    return sum(value) / len(value) if isinstance(value, list) else value


def csv(values):
    return ",".join(format(v, ".6g") for v in values)


def calibration_text(fit):
    """The family's energy calibration, as its fit record gives it."""
    cal = fit.get("calibration")
    if not cal:
        return "no energy calibration"
    m = "R and M" if cal.get("m") else "R only"
    text = f"energy calibration of degree {cal['degree']} ({m}, {cal['yarns']} yarns"
    if fit.get("recalibrated"):
        text += f"; refitted by --recalibrate in {fit['recalibration_seconds']:.0f} s"
    return text + ")"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--family", required=True)
    ap.add_argument("--preset-gathers", required=True,
                    help="folder of MATERIAL-any-rdm: weft gather --preset MATERIAL --paths 16000000 "
                         "--seed 1 --any-colour")
    ap.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    ap.add_argument("--held", type=int, default=8)
    ap.add_argument("--held-paths", type=int, default=4000000)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--work", default=os.path.join(ROOT, "bench", "work", "family"))
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "family.md"))
    a = ap.parse_args()
    weft, work = a.weft, a.work
    os.makedirs(work, exist_ok=True)
    with open(a.family) as f:
        family = json.load(f)
    lo, hi = family["colour"]["c_tt_range"]
    threads = ["--threads", str(a.threads)]

    def check(model, rdm, out, colour=None):
        extra = ["--c-tt", csv(colour)] if colour is not None else []
        return cached(out + ".json", lambda: run_json(
            [weft, "yarn", "check", "--model", model, "--rdm", rdm, "--out", out] + threads + extra))

    rows = []
    # The five presets.
    for m in ("fleece", "silk", "polyester", "cotton", "gabardine"):
        gathered = PRESETS[m][1]
        colour = [min(max(c, lo), hi) for c in gathered]
        ref = os.path.join(a.preset_gathers, f"{m}-any-rdm")
        if colour != gathered:
            recoloured = os.path.join(work, f"{m}-ref-rdm")
            if not os.path.isdir(recoloured):
                subprocess.run([weft, "gather", "recolour", ref, "--c-tt", csv(colour),
                                "--out", recoloured], check=True, stdout=subprocess.DEVNULL)
            ref = recoloured
        yarn = os.path.join(work, f"{m}-family.json")
        if not os.path.exists(yarn):
            run_json([weft, "yarn", "at", "--family", a.family, "--preset", m, "--out", yarn])
        fam = check(yarn, ref, os.path.join(work, f"check-family-{m}"), colour)
        if colour == gathered:
            ded = check(os.path.join(ROOT, "models", f"{m}.json"), ref,
                        os.path.join(work, f"check-dedicated-{m}"))
            dedicated = f"models/{m}.json"
        else:
            ded = check(os.path.join(ROOT, "models", f"{m}-colour.json"), ref,
                        os.path.join(work, f"check-dedicated-{m}"), colour)
            dedicated = f"models/{m}-colour.json"
        rows.append({"point": m, "c_tt": colour, "dedicated": dedicated, "family": fam,
                     "dedicated_check": ded, "target": 1.3})

    # Held-out yarns: a family gather with another seed.
    held = os.path.join(work, "held")
    if a.held > 0 and (not os.path.isdir(os.path.join(held, "points")) or
                       len(os.listdir(os.path.join(held, "points"))) < a.held):
        subprocess.run([weft, "gather", "family", "--points", str(a.held), "--paths", str(a.held_paths),
                        "--seed", str(HELD_SEED), "--quiet", "--out", held] + threads, check=True,
                       stdout=subprocess.DEVNULL)
    points = []
    if a.held > 0:
        with open(os.path.join(held, "family.json")) as f:
            points = json.load(f)["yarns"]
    for k, p in enumerate(points[:a.held]):
        colour = [min(max(c, lo), hi) for c in HELD_COLOURS[k % len(HELD_COLOURS)]]
        rdm = os.path.join(work, f"held-{k}-rdm")
        if not os.path.isdir(rdm):
            subprocess.run([weft, "gather", "recolour", os.path.join(held, p["folder"]), "--c-tt",
                            csv(colour), "--out", rdm], check=True, stdout=subprocess.DEVNULL)
        dedicated = os.path.join(work, f"held-{k}-dedicated.json")
        fit_seconds = cached(os.path.join(work, f"held-{k}-fit-seconds.json"), lambda: (
            run_json([weft, "fit", "--rdm", rdm, "--seed", "1", "--quiet", "--no-report",
                      "--out", dedicated] + threads)["seconds"]))
        yarn_json = {key: p[key] for key in ("fibers", "density", "twist", "beta_r_deg",
                                             "beta_tt_deg", "gamma_tt_deg", "c_r")}
        yarn = os.path.join(work, f"held-{k}-family.json")
        if not os.path.exists(yarn):
            run_json([weft, "yarn", "at", "--family", a.family, "--yarn", json.dumps(yarn_json),
                      "--out", yarn])
        fam = check(yarn, rdm, os.path.join(work, f"check-family-held-{k}"), colour)
        ded = check(dedicated, rdm, os.path.join(work, f"check-dedicated-held-{k}"))
        rows.append({"point": f"held-out {k}", "yarn": yarn_json, "c_tt": colour,
                     "dedicated": f"weft fit of its own gather ({fit_seconds:.0f} s)",
                     "family": fam, "dedicated_check": ded, "target": 1.5})

    def ratio(r, key):
        d = scalar(r["dedicated_check"][key])
        return scalar(r["family"][key]) / d if d else float("nan")

    fit = family["fit"]
    lines = [
        "# One family model against models fitted for one yarn alone",
        "",
        f"`bench/family.py --family {os.path.basename(a.family)} --held {a.held} --held-paths "
        f"{a.held_paths}`, {now()}. The family: {fit['gather']['yarns']} yarns of "
        f"{fit['gather']['paths_per_yarn']} paths (`weft gather family`), fitted in "
        f"{fit['seconds']:.0f} s (`weft fit family`, M network "
        f"{'-'.join(str(len(l['bias'])) for l in family['m_net']['layers'])}, "
        f"{fit['m_samples_per_second'] / 1e6:.2f} M samples/s), colour range [{lo}, {hi}], "
        f"{calibration_text(fit)}. "
        "Both models of a row are checked by `weft yarn check` against the same gather: at the "
        "presets an independent 16M-path gather of the preset; at held-out yarns (a family "
        f"gather with seed {HELD_SEED}: none is a training yarn) the {a.held_paths}-path gather "
        "the dedicated model was fitted to. Targets: ratio <= 1.3 at the presets, <= 1.5 held out.",
        "",
        "| point | C_TT | M: family | M: dedicated | M ratio | R: family | R: dedicated | R ratio "
        "| albedo err.: family | albedo err.: dedicated | albedo ratio | dedicated model |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |",
    ]
    for r in rows:
        f, d = r["family"], r["dedicated_check"]
        lines.append(
            f"| {r['point']} | {', '.join(format(c, '.3g') for c in r['c_tt'])} | "
            f"{f['m_rel_l2']:.4f} | {d['m_rel_l2']:.4f} | {ratio(r, 'm_rel_l2'):.2f} | "
            f"{f['r_rel_l2']:.4f} | {d['r_rel_l2']:.4f} | {ratio(r, 'r_rel_l2'):.2f} | "
            f"{scalar(f['albedo_relative_error_mean_abs']):.4f} | "
            f"{scalar(d['albedo_relative_error_mean_abs']):.4f} | "
            f"{ratio(r, 'albedo_relative_error_mean_abs'):.2f} | {r['dedicated']} |")
    write_results(a.out, lines, {"family": os.path.basename(a.family), "fit": fit, "rows": rows})


if __name__ == "__main__":
    main()
