#!/usr/bin/env python3
"""bench/colour_fit.py: one colour-conditioned model against a dedicated
gather and fit per colour (issue 21, docs/colour.md).

For one material's ply (default gabardine), measured in one run:
  - one any-colour gather (`weft gather --any-colour`) and one conditioned fit
    (`weft fit --colour-range LO,HI`): their seconds (the fit-time target is
    15 minutes on 2 cores);
  - for each test colour (the five Table 3 C_TT, clamped into the range, as
    `weft fit` clamps its own test colours): a dedicated ordinary gather of
    that colour (same ply, other walks) and a dedicated fit to it. Both models
    are checked against that dedicated gather with `weft yarn check` (the
    conditioned one with --c-tt), so both M errors are the same metric
    (coarse-grid relative L2, fit/metrics.h); the target is
    conditioned / dedicated <= 1.3;
  - the render seconds per spp of both models on the same close-up at that
    colour (neural mode, one process each), and the SSIM between the two
    images (how close the conditioned model's picture is to the dedicated one's).
Resumable: every step's result is cached under bench/work/colour-fit/ and a
rerun skips what is done (--redo starts over). Writes
bench/results/colour-fit.md and .json.

    bench/colour_fit.py [--weft build/release/weft] [--material gabardine]
                        [--paths 16000000] [--range 0.3,0.999] [--functions 6]
                        [--size 128] [--spp 64] [--threads 0] [--fit-config FIT.json]
                        [--redo]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from any_colour import PLY_SEED, PRESETS  # noqa: E402  (Table 3, shared with any_colour.py)
from benchlib import write_results  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_json(cmd):
    """Runs a weft command; returns (seconds, its last stdout line as JSON)."""
    start = time.monotonic()
    r = subprocess.run([str(c) for c in cmd], check=True, stdout=subprocess.PIPE, text=True)
    lines = [l for l in r.stdout.splitlines() if l.strip()]
    return time.monotonic() - start, json.loads(lines[-1]) if lines else {}


def fmt(value, spec=".4f"):
    """A number for the table (a list: its mean, as for the per-channel albedo
    errors), or n/a (a check with too few paths per bin gives null)."""
    if isinstance(value, list):
        value = sum(value) / len(value) if value and None not in value else None
    return "n/a" if value is None else format(value, spec)


def cached(path, compute):
    """The JSON at `path`, or compute() written there first (the resumable steps)."""
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    value = compute()
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(value, f, indent=2)
    os.replace(tmp, path)
    return value


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    ap.add_argument("--material", default="gabardine", choices=sorted(PRESETS))
    ap.add_argument("--paths", type=int, default=16000000)
    ap.add_argument("--range", default="0.3,0.999")
    ap.add_argument("--functions", type=int, default=6)
    ap.add_argument("--size", type=int, default=128, help="close-up film width and height")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--work", default=os.path.join(ROOT, "bench", "work", "colour-fit"))
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "colour-fit"))
    ap.add_argument("--fit-config", help="FIT.json for both fits (a short one for a smoke test)")
    ap.add_argument("--redo", action="store_true")
    args = ap.parse_args()
    lo, hi = (float(v) for v in args.range.split(","))
    c_r, c_tt_own, beta_r, beta_tt, gamma_tt, (fibers, density, twist) = PRESETS[args.material]
    work = os.path.join(args.work, f"{args.material}-{args.paths}")
    if args.redo and os.path.isdir(work):
        shutil.rmtree(work)
    os.makedirs(work, exist_ok=True)
    weft = os.path.abspath(args.weft)
    threads = ["--threads", args.threads]
    fit_config = ["--config", os.path.abspath(args.fit_config)] if args.fit_config else []

    def log(message):
        print(f"[colour-fit] {time.strftime('%H:%M:%S')} {message}", file=sys.stderr, flush=True)

    def gather(out, seed, params=None, any_colour=False):
        if os.path.isdir(out):
            shutil.rmtree(out)  # an interrupted step: its cache file was never written
        material = ["--preset", args.material] if params is None else [
            "--params", params, "--fibers", fibers, "--density", density, "--twist", twist]
        seconds, _ = run_json([weft, "gather", *material, "--paths", args.paths, "--seed", seed,
                               "--ply-seed", PLY_SEED, *threads, "--quiet", "--out", out]
                              + (["--any-colour"] if any_colour else []))
        return seconds

    def render(model, colour, name):
        scene = os.path.join(work, f"scene-{name}")
        if os.path.isdir(scene):
            shutil.rmtree(scene)
        run_json([weft, "scene", "closeup", "--model", model, "--width", args.size, "--height",
                  args.size, "--spp", args.spp, "--quiet", "--out", scene]
                 + (["--colours", ",".join(map(str, colour))] if colour else []))
        image = os.path.join(work, f"{name}.exr")
        run_json([weft, "render", os.path.join(scene, "scene.json"), "--mode", "neural", "--spp",
                  args.spp, "--seed", 1, *threads, "--quiet", "--out", image])
        with open(os.path.join(work, f"{name}.json")) as f:
            stats = json.load(f)
        return image, stats["seconds"] / stats["spp"]

    any_dir, any_model = os.path.join(work, "any"), os.path.join(work, "any.json")

    def any_gather():
        log(f"any-colour gather of {args.paths} paths ({args.material})")
        return {"seconds": gather(any_dir, 1, any_colour=True)}

    def conditioned_fit():
        log(f"conditioned fit, range {lo}..{hi}, {args.functions} colour functions")
        seconds, summary = run_json([weft, "fit", "--rdm", any_dir, "--out", any_model,
                                     "--colour-range", f"{lo},{hi}", "--colour-functions",
                                     args.functions, "--seed", 1, *fit_config, *threads, "--quiet"])
        return {"seconds": seconds, "summary": summary}

    any_step = cached(os.path.join(work, "any-gather.json"), any_gather)
    fit_step = cached(os.path.join(work, "conditioned-fit.json"), conditioned_fit)

    rows = []
    for name in PRESETS:
        colour = [min(max(c, lo), hi) for c in PRESETS[name][1]]
        tag = name

        def row():
            log(f"C_TT of {name}: {colour}: dedicated gather")
            params = os.path.join(work, f"{tag}-fiber.json")
            with open(params, "w") as f:
                json.dump({"c_r": c_r, "c_tt": colour, "beta_r_deg": beta_r,
                           "beta_tt_deg": beta_tt, "gamma_tt_deg": gamma_tt}, f)
            ded_dir, ded_model = os.path.join(work, f"ded-{tag}"), os.path.join(work, f"ded-{tag}.json")
            t_gather = gather(ded_dir, 2, params)
            log(f"C_TT of {name}: dedicated fit")
            t_fit, fit_summary = run_json([weft, "fit", "--rdm", ded_dir, "--out", ded_model,
                                           "--seed", 1, *fit_config, *threads, "--quiet"])
            log(f"C_TT of {name}: checks and renders")
            checks = {}
            for which, extra in (("dedicated", []), ("conditioned", ["--c-tt", ",".join(map(str, colour))])):
                model = ded_model if which == "dedicated" else any_model
                check_dir = os.path.join(work, f"check-{tag}-{which}")
                if os.path.isdir(check_dir):
                    shutil.rmtree(check_dir)
                _, checks[which] = run_json([weft, "yarn", "check", "--model", model, "--rdm", ded_dir,
                                             *extra, *threads, "--out", check_dir])
            image_ded, spp_ded = render(ded_model, None, f"render-{tag}-dedicated")
            image_cond, spp_cond = render(any_model, colour, f"render-{tag}-conditioned")
            _, compared = run_json([weft, "compare", image_cond, image_ded])
            shutil.rmtree(ded_dir)  # 16M-path gathers are large; the results are kept
            return {"colour": name, "c_tt": colour, "gather_seconds": t_gather,
                    "dedicated_fit_seconds": t_fit, "dedicated_fit_m_rel_l2": fit_summary["m_rel_l2"],
                    "m_rel_l2_dedicated": checks["dedicated"]["m_rel_l2"],
                    "m_rel_l2_conditioned": checks["conditioned"]["m_rel_l2"],
                    "r_rel_l2_dedicated": checks["dedicated"]["r_rel_l2"],
                    "r_rel_l2_conditioned": checks["conditioned"]["r_rel_l2"],
                    "albedo_error_dedicated": checks["dedicated"]["albedo_relative_error_mean_abs"],
                    "albedo_error_conditioned": checks["conditioned"]["albedo_relative_error_mean_abs"],
                    "seconds_per_spp_dedicated": spp_ded, "seconds_per_spp_conditioned": spp_cond,
                    "ssim_conditioned_vs_dedicated": compared.get("ssim"),
                    "rel_mse_conditioned_vs_dedicated": compared.get("rel_mse")}

        rows.append(cached(os.path.join(work, f"row-{tag}.json"), row))

    result = {"material": args.material, "paths": args.paths, "range": [lo, hi],
              "functions": args.functions, "size": args.size, "spp": args.spp,
              "threads": args.threads, "any_gather_seconds": any_step["seconds"],
              "conditioned_fit_seconds": fit_step["seconds"],
              "conditioned_fit": fit_step["summary"], "rows": rows,
              "date": time.strftime("%Y-%m-%d %H:%M"), "nproc": os.cpu_count()}
    basis = fit_step["summary"].get("colour", {})
    lines = [
        f"# One colour-conditioned model against dedicated fits ({args.material} ply)",
        "",
        f"`bench/colour_fit.py --material {args.material} --paths {args.paths}`, {result['date']}, "
        f"{os.cpu_count()} cores. One any-colour gather and one `weft fit --colour-range {lo},{hi} "
        f"--colour-functions {args.functions}`; per test colour (Table 3 C_TT clamped into the "
        f"range) a dedicated gather of {args.paths} paths (same ply, seed 2) and a dedicated fit. "
        "Both models are checked against the dedicated gather by `weft yarn check` (the "
        "conditioned one with `--c-tt`): M and R relative L2 on the coarse grid of fit/metrics.h.",
        "",
        f"- any-colour gather: {any_step['seconds']:.0f} s; conditioned fit: "
        f"{fit_step['seconds']:.0f} s ({fit_step['seconds'] / 60:.1f} min; target 15 min)",
    ]
    if basis:
        lines.append(f"- colour functions: truncation error mean {basis.get('basis_error_mean', float('nan')):.4f}, "
                     f"worst {basis.get('basis_error_worst', float('nan')):.4f}")
    lines += [
        "",
        "| C_TT of | C_TT | M: conditioned | M: dedicated | ratio (target <= 1.3) | R: conditioned | R: dedicated "
        "| albedo err. (mean of RGB): cond. / ded. | s/spp cond. / ded. | SSIM cond. vs ded. | dedicated fit s |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        lines.append(
            f"| {r['colour']} | {', '.join(f'{v:g}' for v in r['c_tt'])} | {r['m_rel_l2_conditioned']:.4f} | "
            f"{r['m_rel_l2_dedicated']:.4f} | {r['m_rel_l2_conditioned'] / r['m_rel_l2_dedicated']:.2f} | "
            f"{fmt(r['r_rel_l2_conditioned'])} | {fmt(r['r_rel_l2_dedicated'])} | "
            f"{fmt(r['albedo_error_conditioned'])} / {fmt(r['albedo_error_dedicated'])} | "
            f"{r['seconds_per_spp_conditioned'] / r['seconds_per_spp_dedicated']:.2f} | "
            f"{fmt(r['ssim_conditioned_vs_dedicated'])} | {r['dedicated_fit_seconds']:.0f} |")
    lines += ["", f"s/spp: neural render of the close-up at {args.size} x {args.size}, {args.spp} spp, "
              "each in its own process; the ratio is conditioned / dedicated.", ""]
    write_results(args.out + ".md", lines, result)


if __name__ == "__main__":
    main()
