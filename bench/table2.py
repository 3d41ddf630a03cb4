#!/usr/bin/env python3
"""bench/table2.py: the paper's Table 2 and Fig. 8/9 on this machine, plus the ablations.

For each preset x scene (closeup, weave, knit; `weft scene` with the shipped
models/<preset>.json) it renders, each in its own `weft render` process:
  - a converged fiber-mode reference and a converged neural render (REF spp);
  - for each mode, renders at REF/16 and REF/4 spp with other seeds, whose
    relative MSE against the mode's own converged image gives the time to
    reach relative MSE 0.01 (equal quality, below);
  - an equal-time fiber render: fiber mode given the neural time to 0.01;
and compares (weft compare): neural vs fiber reference (SSIM, relative MSE,
heatmap) and the equal-time fiber render vs its reference. Memory: Embree
geometry + BVH bytes and peak resident bytes of the reference renders.

Time to relative MSE 0.01. Two independent renders at n and N spp of the
same mode differ by relMSE ~ c (1/n + 1/N) (Monte Carlo variance falls as
1/spp; the converged image's own noise is the 1/N term), so
c = relMSE / (1/n + 1/N) and a render reaches relative MSE 0.01 against the
true image at n* = c / 0.01 spp, i.e. after n* x (seconds per spp) seconds
(scene build excluded, reported separately). Both ladder levels are
reported: their c agree when the 1/spp law holds.

Ablations (paper Fig. 5), on fleece with one gather and one fit
configuration for all variants: the full model, (a) one naive network over
the whole RDM (`weft fit --ablation naive`), (b) no analytic R lobe
(`--ablation no-r-lobe`), (c) the full model with cosine sampling
(`weft render --yarn-sampling cosine`); each as SSIM against the fiber
reference and equal-quality time against the full model.

Everything is cached under the work folder (scene folders, renders, their
JSON statistics, comparisons, gathers and fits); a step is redone only when
its parameters change, so an interrupted run resumes where it stopped.

    bench/table2.py [--quick] [--work DIR] [--weft build/release/weft]
                    [--presets fleece,...] [--scenes closeup,weave,knit] [--threads 0]

--quick: 128 x 128, 256 spp references, 3 x 3 patches, ablations on the
close-up from a 2M-path gather with a shortened fit: 42 minutes on 2 cores
(measured; the equal-time renders of the slowly converging cotton and
gabardine patches take a third of it). The full version: 256 x 256, 1024 spp (4096 for silk and cotton, as
the paper), 4 x 4 patches, ablations on all three scenes from a 16M-path
gather with the default fit: hours.
Writes bench/results/table2.md (table2-quick.md) and .json, and one figure per
scene in bench/results/table2/ (table2-quick/): reference | neural | heatmap
(1 - SSIM) | equal-time fiber.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRESETS = ["fleece", "silk", "polyester", "cotton", "gabardine"]
SCENES = ["closeup", "weave", "knit"]
TARGET_REL_MSE = 0.01


class Bench:
    def __init__(self, args):
        self.args = args
        self.weft = os.path.abspath(args.weft)
        self.work = os.path.abspath(args.work)
        os.makedirs(self.work, exist_ok=True)
        self.log = open(os.path.join(self.work, "log.txt"), "a")
        self.started = time.time()

    def say(self, text):
        line = "[table2 %6.0fs] %s" % (time.time() - self.started, text)
        print(line, flush=True)
        self.log.write(line + "\n")
        self.log.flush()

    def run(self, cmd):
        self.log.write("$ " + " ".join(cmd) + "\n")
        self.log.flush()
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit("table2: command failed (%d): %s\n%s" % (r.returncode, " ".join(cmd), r.stderr))
        return r.stdout

    def cached(self, folder, params, make):
        """Runs make(folder) unless folder/params.json already records `params`."""
        stamp = os.path.join(folder, "params.json")
        if os.path.exists(stamp):
            with open(stamp) as f:
                if json.load(f) == params:
                    return
        if os.path.isdir(folder):
            shutil.rmtree(folder)
        os.makedirs(folder)
        make(folder)
        with open(stamp + ".tmp", "w") as f:
            json.dump(params, f, indent=1)
        os.replace(stamp + ".tmp", stamp)

    def render(self, scene, out_dir, name, mode, seed, spp=None, seconds=None, extra=()):
        """weft render -> (stats dict, exr path); cached by its command line."""
        folder = os.path.join(out_dir, name)
        budget = ["--spp", str(spp)] if spp is not None else ["--time", "%.3f" % seconds]
        cmd = [self.weft, "render", scene, "--mode", mode, "--seed", str(seed), "--quiet",
               "--threads", str(self.args.threads)] + budget + list(extra)
        exr = os.path.join(folder, "image.exr")

        def make(folder):
            self.say("render %s %s %s" % (os.path.relpath(scene, self.work), mode,
                                          " ".join(budget + list(extra))))
            self.run(cmd + ["--out", exr])

        self.cached(folder, {"cmd": cmd[1:]}, make)
        with open(os.path.join(folder, "image.json")) as f:
            return json.load(f), exr

    def compare(self, a, b, heatmap=None):
        cmd = [self.weft, "compare", a, b] + (["--heatmap", heatmap] if heatmap else [])
        return json.loads(self.run(cmd))


def convergence(bench, scene, folder, mode, ref_exr, ref_spp, extra=()):
    """Ladder renders at ref/16 and ref/4 spp: c, spp and seconds to relMSE 0.01."""
    levels = []
    for i, spp in enumerate([max(1, ref_spp // 16), max(1, ref_spp // 4)]):
        stats, exr = bench.render(scene, folder, "%s-%dspp" % (mode, spp), mode, 10 + i, spp=spp,
                                  extra=extra)
        rel = bench.compare(exr, ref_exr)["rel_mse"]
        c = rel / (1.0 / spp + 1.0 / ref_spp)
        levels.append({"spp": spp, "rel_mse": rel, "c": c,
                       "seconds_per_spp": stats["seconds_per_spp"]})
    last = levels[-1]
    spp_target = last["c"] / TARGET_REL_MSE
    seconds_per_spp = sum(l["seconds_per_spp"] * l["spp"] for l in levels) / sum(
        l["spp"] for l in levels)
    return {"levels": levels, "spp_to_target": spp_target,
            "seconds_per_spp": seconds_per_spp,
            "seconds_to_target": spp_target * seconds_per_spp}


def scene_cell(bench, cfg, preset, kind):
    folder = os.path.join(bench.work, preset, kind)
    model = os.path.join(ROOT, "models", preset + ".json")
    scene_dir = os.path.join(folder, "scene")
    cmd = [bench.weft, "scene", kind, "--model", model, "--width", str(cfg["size"]),
           "--height", str(cfg["size"]), "--spp", "1"]
    if kind != "closeup":
        cmd += ["--size", str(cfg["patch"])]

    def make(d):
        bench.run(cmd + ["--out", os.path.join(d, "s")])

    bench.cached(scene_dir, {"cmd": cmd[1:]}, make)
    scene = os.path.join(scene_dir, "s", "scene.json")
    ref_spp = cfg["ref_spp_hard"] if preset in ("silk", "cotton") else cfg["ref_spp"]

    fiber_stats, fiber_ref = bench.render(scene, folder, "fiber-ref", "fiber", 1, spp=ref_spp)
    neural_stats, neural_ref = bench.render(scene, folder, "neural-ref", "neural", 1, spp=ref_spp)
    fiber_eq = convergence(bench, scene, folder, "fiber", fiber_ref, ref_spp)
    neural_eq = convergence(bench, scene, folder, "neural", neural_ref, ref_spp)
    heatmap = os.path.join(folder, "heatmap.png")
    quality = bench.compare(neural_ref, fiber_ref, heatmap)
    # Equal time: fiber mode given the time the neural render needs for relMSE 0.01.
    eq_seconds = max(neural_eq["seconds_to_target"], 0.01)
    eq_stats, eq_exr = bench.render(scene, folder, "fiber-equal-time", "fiber", 3,
                                    seconds=eq_seconds)
    eq_quality = bench.compare(eq_exr, fiber_ref)
    neural_eq_stats, neural_eq_exr = bench.render(
        scene, folder, "neural-equal-time", "neural", 3,
        spp=max(1, int(round(neural_eq["spp_to_target"]))))
    neural_eq_quality = bench.compare(neural_eq_exr, fiber_ref)

    figure = os.path.join(cfg["figures"], "%s-%s.png" % (preset, kind))
    bench.run([bench.weft, "montage", fiber_ref, neural_ref, heatmap, eq_exr, "--out", figure])
    return {
        "preset": preset, "scene": kind, "ref_spp": ref_spp, "size": cfg["size"],
        "scene_stats": {"fiber": fiber_stats["scene"], "neural": neural_stats["scene"]},
        "ssim": quality["ssim"], "rel_mse": quality["rel_mse"],
        # relMSE of two converged renders = their difference + each one's noise
        # (c / N): what is left after the noise is the neural model's error.
        "rel_mse_minus_noise": quality["rel_mse"] - (fiber_eq["levels"][-1]["c"] +
                                                     neural_eq["levels"][-1]["c"]) / ref_spp,
        "fiber": {"seconds_per_spp": fiber_stats["seconds_per_spp"],
                  "build_seconds": fiber_stats["scene"]["build_seconds"],
                  "embree_bytes": fiber_stats["scene"]["geometry_bvh_bytes"],
                  "peak_resident_bytes": fiber_stats["peak_resident_bytes"],
                  "equal_quality": fiber_eq},
        "neural": {"seconds_per_spp": neural_stats["seconds_per_spp"],
                   "build_seconds": neural_stats["scene"]["build_seconds"],
                   "embree_bytes": neural_stats["scene"]["geometry_bvh_bytes"],
                   "peak_resident_bytes": neural_stats["peak_resident_bytes"],
                   "equal_quality": neural_eq},
        "equal_time": {"seconds": eq_stats["seconds"], "fiber_spp": eq_stats["spp"],
                       "fiber_ssim": eq_quality["ssim"], "fiber_rel_mse": eq_quality["rel_mse"],
                       "neural_spp": neural_eq_stats["spp"],
                       "neural_ssim": neural_eq_quality["ssim"],
                       "neural_rel_mse": neural_eq_quality["rel_mse"]},
        "speedup": fiber_eq["seconds_to_target"] / neural_eq["seconds_to_target"],
        "memory_ratio": fiber_stats["scene"]["geometry_bvh_bytes"] /
                        neural_stats["scene"]["geometry_bvh_bytes"],
        "rss_ratio": fiber_stats["peak_resident_bytes"] / neural_stats["peak_resident_bytes"],
        "figure": os.path.relpath(figure, ROOT),
    }


def ablations(bench, cfg, cells):
    """Fig. 5 ablations on fleece: one gather, one fit configuration for every variant."""
    folder = os.path.join(bench.work, "ablation")
    rdm = os.path.join(folder, "rdm")
    gather = [bench.weft, "gather", "--preset", "fleece", "--paths", str(cfg["ablation_paths"]),
              "--seed", "1", "--quiet", "--threads", str(bench.args.threads)]

    def make_gather(d):
        bench.say("gather fleece, %d paths" % cfg["ablation_paths"])
        bench.run(gather + ["--out", os.path.join(d, "rdm")])

    bench.cached(rdm + "-step", {"cmd": gather[1:]}, make_gather)
    rdm = os.path.join(rdm + "-step", "rdm")
    config = os.path.join(folder, "fit-config.json")
    os.makedirs(folder, exist_ok=True)
    base = json.loads(bench.run([bench.weft, "fit", "--print-config"]))
    for net, steps in cfg["ablation_steps"].items():
        if steps:
            base[net]["steps"] = steps
    with open(config, "w") as f:
        json.dump(base, f, indent=1)

    models = {}
    for variant, flags in [("full", []), ("naive", ["--ablation", "naive"]),
                           ("no_r_lobe", ["--ablation", "no-r-lobe"])]:
        fit = [bench.weft, "fit", "--rdm", rdm, "--config", config, "--seed", "1", "--quiet",
               "--no-report"] + flags

        def make_fit(d, fit=fit, variant=variant):
            bench.say("fit %s" % variant)
            bench.run(fit + ["--out", os.path.join(d, "model.json")])

        step = os.path.join(folder, "fit-" + variant)
        bench.cached(step, {"cmd": fit[1:], "config": base}, make_fit)
        models[variant] = os.path.join(step, "model.json")

    rows = []
    for cell in cells:
        if cell["preset"] != "fleece" or cell["scene"] not in cfg["ablation_scenes"]:
            continue
        kind = cell["scene"]
        cell_dir = os.path.join(bench.work, "fleece", kind)
        fiber_ref = os.path.join(cell_dir, "fiber-ref", "image.exr")
        with open(os.path.join(cell_dir, "scene", "s", "scene.json")) as f:
            scene_json = json.load(f)
        scene_json["yarns"][0]["curves"] = os.path.join(cell_dir, "scene", "s", "yarns.txt")
        variants = [("full", "full", []), ("naive", "naive", []),
                    ("no_r_lobe", "no_r_lobe", []),
                    ("cosine_sampling", "full", ["--yarn-sampling", "cosine"])]
        results = {}
        for name, model, extra in variants:
            vdir = os.path.join(folder, kind, name)
            os.makedirs(vdir, exist_ok=True)
            scene_json["yarns"][0]["model"] = models[model]
            scene = os.path.join(vdir, "scene.json")
            text = json.dumps(scene_json, indent=1)
            if not os.path.exists(scene) or open(scene).read() != text:
                with open(scene, "w") as f:
                    f.write(text)
            stats, ref = bench.render(scene, vdir, "ref", "neural", 1, spp=cell["ref_spp"],
                                      extra=extra)
            eq = convergence(bench, scene, vdir, "neural", ref, cell["ref_spp"], extra=extra)
            quality = bench.compare(ref, fiber_ref, os.path.join(vdir, "heatmap.png"))
            results[name] = {"ssim": quality["ssim"], "rel_mse": quality["rel_mse"],
                             "seconds_per_spp": stats["seconds_per_spp"], "equal_quality": eq,
                             "image": ref}
        full_time = results["full"]["equal_quality"]["seconds_to_target"]
        for name, r in results.items():
            r["time_ratio_to_full"] = r["equal_quality"]["seconds_to_target"] / full_time
            rows.append(dict(scene=kind, variant=name, **{k: v for k, v in r.items()
                                                          if k != "image"}))
        figure = os.path.join(cfg["figures"], "ablation-fleece-%s.png" % kind)
        bench.run([bench.weft, "montage", fiber_ref] + [results[n]["image"] for n in
                  ("full", "naive", "no_r_lobe", "cosine_sampling")] + ["--out", figure])
    return rows


def mb(n):
    return "%.3g" % (n / 1e6)


def write_tables(cfg, cells, ablation_rows, out_md):
    lines = ["# Table 2 on this machine%s" % (" (--quick)" if cfg["quick"] else ""), "",
             "Written by `bench/table2.py%s` in one run (%s, %d threads). Renders of %d x %d "
             "pixels; references at %d spp (%d for silk and cotton). relMSE minus noise: "
             "the relative MSE of the two converged renders less both renders' own noise "
             "(c / N, from the ladder), an estimate of the model's error alone. Times are render "
             "seconds at equal quality: the time for each mode to reach relative MSE %.2f "
             "against its own converged image (estimated from renders at 1/16 and 1/4 of the "
             "reference spp, see the script). Memory: Embree geometry + BVH (and peak RSS "
             "of the whole process)." % (cfg["arguments"], cfg["machine"],
                                         cfg["threads"], cfg["size"], cfg["size"],
                                         cfg["ref_spp"], cfg["ref_spp_hard"], TARGET_REL_MSE),
             "",
             "| material | scene | SSIM neural vs fiber ref | relMSE neural vs ref (minus "
             "noise) | fiber s (EQ) "
             "| neural s (EQ) | speed-up | fiber s/spp | neural s/spp | fiber build s "
             "| fiber MB | neural MB | memory ratio | RSS ratio | equal-time fiber SSIM / relMSE "
             "| equal-time neural SSIM / relMSE |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in cells:
        f, n, e = c["fiber"], c["neural"], c["equal_time"]
        lines.append(
            "| %s | %s | %.3f | %.4f (%.4f) | %.1f | %.2f | **%.1fx** | %.3f | %.3f | %.1f | %s | %s | "
            "**%.0fx** | %.1fx | %.3f / %.4f | %.3f / %.4f |" % (
                c["preset"], c["scene"], c["ssim"], c["rel_mse"], c["rel_mse_minus_noise"],
                f["equal_quality"]["seconds_to_target"], n["equal_quality"]["seconds_to_target"],
                c["speedup"], f["seconds_per_spp"], n["seconds_per_spp"], f["build_seconds"],
                mb(f["embree_bytes"]), mb(n["embree_bytes"]), c["memory_ratio"], c["rss_ratio"],
                e["fiber_ssim"], e["fiber_rel_mse"], e["neural_ssim"], e["neural_rel_mse"]))
    lines += ["", "Convergence check (c = relMSE / (1/n + 1/N) at the two ladder levels; equal "
              "when variance falls as 1/spp):", "",
              "| material | scene | fiber c (n1, n2) | neural c (n1, n2) | fiber spp to 0.01 "
              "| neural spp to 0.01 |", "|---|---|---|---|---|---|"]
    for c in cells:
        fl, nl = c["fiber"]["equal_quality"], c["neural"]["equal_quality"]
        lines.append("| %s | %s | %.3g, %.3g | %.3g, %.3g | %.0f | %.0f |" % (
            c["preset"], c["scene"], fl["levels"][0]["c"], fl["levels"][1]["c"],
            nl["levels"][0]["c"], nl["levels"][1]["c"], fl["spp_to_target"],
            nl["spp_to_target"]))
    if ablation_rows:
        lines += ["", "## Ablations (paper Fig. 5), fleece, one gather (%d paths) and one fit "
                  "configuration for all variants" % cfg["ablation_paths"], "",
                  "| scene | variant | SSIM vs fiber ref | relMSE vs fiber ref | s/spp "
                  "| s to relMSE 0.01 | time / full |", "|---|---|---|---|---|---|---|"]
        for r in ablation_rows:
            lines.append("| %s | %s | %.3f | %.4f | %.3f | %.2f | %.2fx |" % (
                r["scene"], r["variant"], r["ssim"], r["rel_mse"], r["seconds_per_spp"],
                r["equal_quality"]["seconds_to_target"], r["time_ratio_to_full"]))
    lines += ["", "Figures (reference | neural | heatmap of 1 - SSIM | equal-time fiber): "
              "`%s/`." % os.path.relpath(cfg["figures"], ROOT)]
    if ablation_rows:
        lines.append("Ablation figures: fiber reference | full | naive | no R lobe | cosine "
                     "sampling.")
    text = "\n".join(lines) + "\n"
    with open(out_md + ".tmp", "w") as f:
        f.write(text)
    os.replace(out_md + ".tmp", out_md)
    out_json = os.path.splitext(out_md)[0] + ".json"
    with open(out_json + ".tmp", "w") as f:
        json.dump({"config": cfg, "cells": cells, "ablations": ablation_rows}, f, indent=1)
    os.replace(out_json + ".tmp", out_json)
    return text


def shown_arguments(argv):
    """The command's flags for the table's caption, without machine-local paths."""
    shown, skip = [], False
    for a in argv:
        if skip:
            skip = False
        elif a in ("--weft", "--work"):
            skip = True
        elif not a.startswith(("--weft=", "--work=")):
            shown.append(" " + a)
    return "".join(shown)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="the ~30 minute version")
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--work", default=None, help="cache folder (default bench/work/table2[-quick])")
    p.add_argument("--presets", default=",".join(PRESETS))
    p.add_argument("--scenes", default=",".join(SCENES))
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--no-ablations", action="store_true")
    p.add_argument("--size", type=int, default=None, help="image side in pixels (overrides)")
    p.add_argument("--ref-spp", type=int, default=None,
                   help="spp of the converged renders, every preset (overrides)")
    p.add_argument("--name", default=None,
                   help="results name: bench/results/NAME.md, .json and NAME/ (default table2 "
                        "or table2-quick)")
    args = p.parse_args()
    name = args.name or ("table2-quick" if args.quick else "table2")
    if not name.replace("-", "").replace("_", "").isalnum():
        sys.exit("table2: --name %r: use letters, digits, '-' and '_'" % name)
    if args.work is None:
        args.work = os.path.join(ROOT, "bench", "work", name)
    if not os.access(args.weft, os.X_OK):
        sys.exit("table2: %s is not an executable weft (build first, or pass --weft)" % args.weft)
    presets = [s for s in args.presets.split(",") if s]
    scenes = [s for s in args.scenes.split(",") if s]
    for s in presets:
        if s not in PRESETS:
            sys.exit("table2: --presets: unknown preset %r (allowed %s)" % (s, ", ".join(PRESETS)))
    for s in scenes:
        if s not in SCENES:
            sys.exit("table2: --scenes: unknown scene %r (allowed %s)" % (s, ", ".join(SCENES)))
    cfg = {
        "quick": args.quick, "size": 128 if args.quick else 256, "patch": 3 if args.quick else 4,
        "ref_spp": 256 if args.quick else 1024, "ref_spp_hard": 256 if args.quick else 4096,
        "ablation_paths": 2000000 if args.quick else 16000000,
        "ablation_steps": {"t_net": 20000, "m_net": 40000} if args.quick else {},
        "ablation_scenes": ["closeup"] if args.quick else SCENES,
        "threads": args.threads or os.cpu_count(),
        "machine": "%s, %d cores" % (os.uname().machine, os.cpu_count()),
        "figures": os.path.join(ROOT, "bench", "results", name),
        "arguments": shown_arguments(sys.argv[1:]),
    }
    if args.size is not None:
        cfg["size"] = args.size
    if args.ref_spp is not None:
        cfg["ref_spp"] = cfg["ref_spp_hard"] = args.ref_spp
    for key, lo, hi in (("size", 16, 4096), ("ref_spp", 16, 1 << 20)):
        if not lo <= cfg[key] <= hi:
            sys.exit("table2: --%s %d is out of range [%d, %d]" % (key.replace("_", "-"), cfg[key],
                                                                   lo, hi))
    os.makedirs(cfg["figures"], exist_ok=True)
    bench = Bench(args)
    cells = []
    for preset in presets:
        for kind in scenes:
            bench.say("%s %s" % (preset, kind))
            cells.append(scene_cell(bench, cfg, preset, kind))
            write_tables(cfg, cells, [], os.path.join(ROOT, "bench", "results", name + ".md"))
    rows = []
    if not args.no_ablations and "fleece" in presets:
        rows = ablations(bench, cfg, cells)
    text = write_tables(cfg, cells, rows, os.path.join(ROOT, "bench", "results", name + ".md"))
    print(text)


if __name__ == "__main__":
    main()
