#!/usr/bin/env python3
"""bench/table2.py: the paper's Table 2 and Fig. 8/9 on this machine, in chunks.

One chunk is one material (preset) and one scene (closeup, weave, knit;
`weft scene` with the shipped models/<preset>.json, a 3 x 3 patch for weave
and knit). A chunk renders, each in its own `weft render` process:
  - a converged fiber-mode reference and a converged neural render (N spp,
    seed 1); neural mode uses the renderer's default --yarn-sampling
    (tabulated), which the chunk records;
  - a ladder per mode: renders at N/64, N/16 and N/4 spp (seeds 10, 11, 12),
    compared with the mode's own converged image (see "Noise" below);
  - an equal-time pair: fiber mode given the time neural mode needs to reach
    relative MSE 0.01, and the neural render at that spp (seed 3);
and compares (weft compare): neural vs fiber reference (SSIM, relative MSE,
heatmap, and the per channel mean ratio, which shows a bias of either mode
apart from noise), the equal-time renders vs the fiber reference. The fiber
reference's render.max_depth and its share of cut paths are recorded: at the
old default of 100 a near-white material's fiber paths were cut and its
reference too dark (bench/max_depth.py measures it per row). Memory: Embree
geometry + BVH bytes and peak resident bytes of the reference renders. It
writes RESULTS/table2/<preset>-<scene>.json (meant to be committed: every
number of the row, the ladder, and the settings: size, spp, patch, seeds,
threads, yarn sampling, sampler, machine, date, weft commit and binary hash) and the
row's figure RESULTS/table2/<preset>-<scene>.png (reference | neural |
heatmap of 1 - SSIM | equal-time fiber), then assembles the table.

Assembling (after every chunk, or alone with --assemble, which renders
nothing and needs no work folder) reads whatever chunk files exist and writes
RESULTS/table2.md and .json, plus one Fig. 8/9-style figure per scene,
RESULTS/table2/fig-<scene>.png (one row per material, from the chunk
figures). Missing rows are listed with the command that makes them, and
chunks made with different settings, commits, machines or days are named.

Noise. Two independent renders at n and N spp of the same mode differ by
relMSE ~ c (1/n + 1/N) (Monte Carlo variance falls as 1/spp), so each ladder
level gives c = relMSE / (1/n + 1/N). When the 1/spp law holds, c is the same
at every level; c growing with spp is a heavy tail (issue 17's target: neural
c equal within 25 % across the ladder; the table reports max/min of c). The
top level's c gives each reference's own noise, c / N, reported beside the
neural vs fiber relative MSE: relMSE(neural ref, fiber ref) ~ model error +
c_fiber / N + c_neural / N, so "relMSE minus noise" is the model's error.
Equal quality: a mode reaches relative MSE 0.01 against the true image at
n* = c / 0.01 spp (c of the top level), i.e. after n* x (seconds per spp of
the ladder) seconds (scene build excluded, reported separately); the
speed-up is the ratio of the two modes' times.

Default settings per chunk (each one an option: --size, --ref-spp,
--fiber-ladder, --neural-ladder, --patch). References at the paper's sample
counts: 1024 spp, 4096 for silk and cotton. The resolution is the largest of
256, 192 and 128 pixels square whose estimated run time stays under 40
minutes on 2 cores (a third of margin under the 60 minute limit for a loaded
machine and timing noise). The estimate (--plan prints it) takes each mode's
seconds per spp at 128 x 128 from bench/results/table2-quick.json (2 threads,
3 x 3 patches, measured before issue 17's sampler and renderer changes, so
it errs long), scales it by the pixel count, and counts the reference, the
ladder, the equal-time pair (from the quick table's neural c) and the scene
builds (the sizes below were chosen so; --plan now starts from a row's last
chunk where that was made at max_depth 1000, else scales the quick table's
fiber seconds per spp, measured at max_depth 100, by bench/results/
max-depth.json's time at 1000 over at 100, which is 1.5-2.0 for cotton):
  256 x 256: every close-up (3-23 min), fleece and polyester weave and knit
             (16-39 min);
  192 x 192: silk weave and knit (25 and 27 min; 44 and 48 at 256),
             gabardine weave (33 min; 58 at 256);
  128 x 128: cotton weave (41 min) and knit, gabardine knit (25 min; 56 at
             192: its neural c of 33 makes the equal-time pair long).
Cotton knit at 4096 spp does not fit at 128 x 128 with the full fiber ladder
(about 59 min): its fiber ladder stops at N/16 (64, 256 spp; about 50 min).
Fiber c of cotton was flat across the quick ladder (10.6, 12.6), so its top
level loses little. At max_depth 1000 with the throughput lobe choice
cotton's fiber references alone take 55 minutes (weave, measured) and about
70 (knit, estimated), so they are rendered in parts (--ref-parts, default 2
for cotton weave and 3 for knit; `weft render --shard K/N`, then `weft
render merge`), each its own run of 25-30 minutes:
    bench/table2.py --chunk cotton,knit --ref-part 0   # then 1 and 2
    bench/table2.py --chunk cotton,knit                # the rest (renders any missing part)
The parts are cached in the work folder; the chunk file records the parts'
count and their seconds summed (fiber_reference).

--sampler sobol renders every image of a chunk with `weft render --sampler
sobol` (Owen-scrambled Sobol' points, docs/render.md#samplers) instead of
independent random numbers; the chunk records it. Use it with --name (for
example table2-sobol) to keep such chunks in their own table: its c then
falls with spp where the integrand is smooth (the ladder's max/min measures
that, not a heavy tail), and the top level's c gives the time to 0.01.

--baseline dual adds the dual-scattering baseline (after ZMA23; `weft render
--mode dual`, docs/dual-scattering.md) to a chunk: its converged render and
ladder (the neural ladder's levels), SSIM and relative MSE against the fiber
reference, time at equal quality, memory, and a Fig. 10 row RESULTS/table2/
<preset>-<scene>-fig10.png (fiber reference | baseline | neural | 1 - SSIM of
each); assembling adds a baseline table and RESULTS/table2/fig10-<preset>.png.
On a chunk already made it renders only the baseline (the chunk's fiber and
neural renders come from the work folder's cache).

Each chunk also scores neural mode (and the baseline) against the fiber
reference after averaging both over 2 x 2 and 4 x 4 pixel blocks (`weft
compare --scale`): single fibers, which a ply-level model averages by design,
then no longer count. --rescore adds these scores to chunk files made before
them, from the cached renders or, where those are gone, from the committed
figures' 8-bit panels (Pillow, Debian python3-pil; marked "figure png").

Everything is cached under the work folder (scene folders, renders, their
JSON statistics, comparisons); a step is redone only when its command line
or the weft binary (its SHA-256) changes, so an interrupted chunk resumes where
it stopped and a rebuilt weft renders everything again. A chunk whose
result file already records the same settings is not run again (--redo).

    bench/table2.py --chunk gabardine,knit [--size PX] [--ref-spp N] [--threads 0]
    bench/table2.py --assemble            # table2.md, .json and figures from the chunk files
    bench/table2.py --plan                # the chunks' command lines and estimated minutes
    bench/table2.py                       # every chunk of --presets x --scenes, then assemble
    bench/table2.py --quick               # the one-run quick table (below)
    bench/table2.py --chunk fleece,weave --baseline dual   # adds the baseline's columns
    bench/table2.py --rescore             # SSIM at 2x2 / 4x4 px blocks for chunks without it
  common: [--work DIR] [--results DIR] [--weft build/release/weft]

--quick (unchanged): 128 x 128, 256 spp references, ladder N/16 and N/4,
3 x 3 patches, all presets and scenes in one run, plus the paper's Fig. 5
ablations (naive network, no R lobe, cosine sampling) on the fleece close-up
from a 2M-path gather with a shortened fit: 42 minutes on 2 cores
(measured). Writes RESULTS/table2-quick.md, .json and RESULTS/table2-quick/.
The chunked table has no ablations.
"""
import argparse
import datetime
import glob
import hashlib
import json
import os
import subprocess
import sys
import time

import benchlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRESETS = ["fleece", "silk", "polyester", "cotton", "gabardine"]
SCENES = ["closeup", "weave", "knit"]
TARGET_REL_MSE = 0.01
# The paper's reference sample counts (Table 2).
PAPER_REF_SPP = {"fleece": 1024, "silk": 4096, "polyester": 1024, "cotton": 4096,
                 "gabardine": 1024}
# Default image side per chunk (see the docstring for the estimates behind it).
DEFAULT_SIZE = {
    ("fleece", "closeup"): 256, ("fleece", "weave"): 256, ("fleece", "knit"): 256,
    ("silk", "closeup"): 256, ("silk", "weave"): 192, ("silk", "knit"): 192,
    ("polyester", "closeup"): 256, ("polyester", "weave"): 256, ("polyester", "knit"): 256,
    ("cotton", "closeup"): 256, ("cotton", "weave"): 128, ("cotton", "knit"): 128,
    ("gabardine", "closeup"): 256, ("gabardine", "weave"): 192, ("gabardine", "knit"): 128,
}
# Ladder levels as divisors of the reference spp.
DEFAULT_LADDER = (64, 16, 4)
DEFAULT_FIBER_LADDER = {("cotton", "knit"): (64, 16)}
# Fiber references rendered in parts (weft render --shard), one process each, so
# that no process outlives a session; the chunk then runs the rest.
DEFAULT_REF_PARTS = {("cotton", "weave"): 2, ("cotton", "knit"): 3}
DEFAULT_PATCH = 3
SEEDS = {"reference": 1, "ladder": 10, "equal_time": 3}
CHUNK_FORMAT = 1
# weft compare --scale: SSIM after averaging both images over K x K pixel blocks,
# so that structure finer than a block (single fibers) no longer counts and what
# remains is the ply-scale appearance a ply-level model is meant to match.
PLY_SCALES = (2, 4)
# weft montage's default gap (pixels between and around the cells of a figure).
MONTAGE_GAP = 4
BUDGET_MINUTES = 60


def chunk_defaults(preset, kind):
    return {"size": DEFAULT_SIZE[(preset, kind)], "ref_spp": PAPER_REF_SPP[preset],
            "patch": DEFAULT_PATCH,
            "fiber_ladder": list(DEFAULT_FIBER_LADDER.get((preset, kind), DEFAULT_LADDER)),
            "neural_ladder": list(DEFAULT_LADDER),
            "ref_parts": DEFAULT_REF_PARTS.get((preset, kind), 1)}


def ladder_spp(ref_spp, divisors):
    """The ladder's spp levels, ascending, without repeats, each below ref_spp."""
    levels = sorted({max(1, ref_spp // d) for d in divisors})
    return [n for n in levels if n < ref_spp] or [1]


class Bench:
    def __init__(self, args):
        self.args = args
        self.weft = os.path.abspath(args.weft)
        # Cached steps are keyed by the binary as well as the command line: a
        # rebuilt weft renders again (its images and timings are its own), while
        # an interrupted chunk with the same binary resumes.
        self.weft_sha256 = binary_digest(self.weft) if os.path.exists(self.weft) else None
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
        """Runs make(folder) unless folder/params.json already records `params` made by this
        weft binary."""
        benchlib.cached(folder, dict(params, weft_sha256=self.weft_sha256), make)

    def render(self, scene, out_dir, name, mode, seed, spp=None, seconds=None, extra=()):
        """weft render -> (stats dict, exr path); cached by its command line and the binary."""
        folder = os.path.join(out_dir, name)
        budget = ["--spp", str(spp)] if spp is not None else ["--time", "%.3f" % seconds]
        cmd = [self.weft, "render", scene, "--mode", mode, "--seed", str(seed), "--quiet",
               "--threads", str(self.args.threads)] + budget + list(extra)
        if self.args.sampler != "independent":
            cmd += ["--sampler", self.args.sampler]
        exr = os.path.join(folder, "image.exr")

        def make(folder):
            self.say("render %s %s %s" % (os.path.relpath(scene, self.work), mode,
                                          " ".join(budget + list(extra))))
            self.run(cmd + ["--out", exr])

        self.cached(folder, {"cmd": cmd[1:]}, make)
        with open(os.path.join(folder, "image.json")) as f:
            return json.load(f), exr

    def reference(self, scene, out_dir, name, mode, seed, spp, parts=1, only_part=None):
        """The converged render of a chunk -> (stats dict, exr path). parts > 1: rendered as
        `weft render --shard K/N` parts (each cached; one process each, so that a part fits a
        session) and joined by `weft render merge`, which sums their seconds and samples: the
        same image, up to float rounding, as one render of spp samples. only_part=K: render
        part K only and return None."""
        if parts <= 1:
            return self.render(scene, out_dir, name, mode, seed, spp=spp)
        part_dirs = []
        for k in range(parts):
            if only_part is not None and k != only_part:
                continue
            part = "%s-part%dof%d" % (name, k, parts)
            self.render(scene, out_dir, part, mode, seed, spp=spp,
                        extra=("--shard", "%d/%d" % (k, parts)))
            part_dirs.append(os.path.join(out_dir, part))
        if only_part is not None:
            return None
        folder = os.path.join(out_dir, name)
        exr = os.path.join(folder, "image.exr")
        part_cmds = []
        for d in part_dirs:
            with open(os.path.join(d, "params.json")) as f:
                part_cmds.append(json.load(f))

        def make(folder):
            self.say("merge %d parts into %s" % (parts, os.path.relpath(folder, self.work)))
            self.run([self.weft, "render", "merge"] +
                     [os.path.join(d, "image.exr") for d in part_dirs] + ["--out", exr])

        self.cached(folder, {"merge": part_cmds}, make)
        with open(os.path.join(folder, "image.json")) as f:
            return json.load(f), exr

    def compare(self, a, b, heatmap=None, scale=1):
        cmd = [self.weft, "compare", a, b] + (["--heatmap", heatmap] if heatmap else [])
        if scale != 1:
            cmd += ["--scale", str(scale)]
        return json.loads(self.run(cmd))

    def ssim_scales(self, a, b):
        """SSIM of a against the reference b at each of PLY_SCALES ({"2": .., "4": ..})."""
        return {str(k): self.compare(a, b, scale=k)["ssim"] for k in PLY_SCALES}


def convergence(bench, scene, folder, mode, ref_exr, ref_spp, divisors, extra=()):
    """Ladder renders at ref_spp / divisor: c per level, spp and seconds to relMSE 0.01."""
    levels = []
    for i, spp in enumerate(ladder_spp(ref_spp, divisors)):
        stats, exr = bench.render(scene, folder, "%s-%dspp" % (mode, spp), mode,
                                  SEEDS["ladder"] + i, spp=spp, extra=extra)
        rel = bench.compare(exr, ref_exr)["rel_mse"]
        c = rel / (1.0 / spp + 1.0 / ref_spp)
        levels.append(dict({"spp": spp, "seed": SEEDS["ladder"] + i, "rel_mse": rel, "c": c,
                            "seconds_per_spp": stats["seconds_per_spp"]}, **ray_costs(stats)))
    last = levels[-1]
    spp_target = last["c"] / TARGET_REL_MSE
    seconds_per_spp = sum(l["seconds_per_spp"] * l["spp"] for l in levels) / sum(
        l["spp"] for l in levels)
    cs = [l["c"] for l in levels]
    return {"levels": levels, "spp_to_target": spp_target,
            "seconds_per_spp": seconds_per_spp,
            "seconds_to_target": spp_target * seconds_per_spp,
            # max / min of c over the ladder: 1 when variance falls as 1/spp.
            "c_spread": max(cs) / min(cs) if min(cs) > 0 else float("inf"),
            # the converged render's own noise: relMSE of it against the true image
            "reference_noise": last["c"] / ref_spp}


def ray_costs(stats):
    """Rays (closest-hit and shadow queries) per sample and thread-microseconds per ray of one
    render (weft render's image.json): a mode's seconds per spp is their product over the
    threads, so the equal-quality speed-up splits into rays ratio x per-ray cost ratio x c
    ratio (the time table's decomposition)."""
    samples = stats["width"] * stats["height"] * stats["spp"]
    return {"rays_per_sample": stats["rays"] / samples,
            "thread_us_per_ray": stats["seconds"] * stats["threads"] / stats["rays"] * 1e6}


def ladder_ray_costs(levels):
    """ray_costs over a ladder, weighted by each level's samples (None where a level lacks them)."""
    if not levels or any("rays_per_sample" not in l for l in levels):
        return None
    spp = sum(l["spp"] for l in levels)
    rays = sum(l["rays_per_sample"] * l["spp"] for l in levels)
    busy = sum(l["rays_per_sample"] * l["spp"] * l["thread_us_per_ray"] for l in levels)
    return {"rays_per_sample": rays / spp, "thread_us_per_ray": busy / rays}


def fiber_reference(stats):
    """The fiber reference's path depth limit and the share of its paths cut there (weft
    render's image.json; docs/render.md#integrator)."""
    return {"max_depth": stats.get("max_depth"),
            "truncated_fraction": stats.get("truncated_fraction"),
            # rendered in N parts (--ref-parts), each its own process; seconds: all of them
            "parts": stats.get("shards", {}).get("count", 1), "seconds": stats.get("seconds")}


# Chunks made before weft's default max_depth became 1000 (commit 74490ee) hold
# no fiber_reference: `weft scene` wrote its then default, 100, into their scenes.
OLD_DEFAULT_MAX_DEPTH = 100


def scene_bytes(stats):
    """Memory of a render's scene: Embree geometry + BVH and the materials' BSDFs."""
    return stats["scene"]["geometry_bvh_bytes"] + stats["scene"].get("material_bytes", 0)


def chunk_scene(bench, s, preset, kind, folder):
    """The chunk's scene (weft scene, cached in folder/scene): the path of its scene.json."""
    model = os.path.join(ROOT, "models", preset + ".json")
    scene_dir = os.path.join(folder, "scene")
    cmd = [bench.weft, "scene", kind, "--model", model, "--width", str(s["size"]),
           "--height", str(s["size"]), "--spp", "1"]
    if kind != "closeup":
        cmd += ["--size", str(s["patch"])]

    def make(d):
        bench.run(cmd + ["--out", os.path.join(d, "s")])

    bench.cached(scene_dir, {"cmd": cmd[1:]}, make)
    return os.path.join(scene_dir, "s", "scene.json")


def scene_cell(bench, s, preset, kind, folder, figure):
    """One Table 2 row: renders, comparisons and the row's figure; s holds its settings."""
    scene = chunk_scene(bench, s, preset, kind, folder)
    ref_spp = s["ref_spp"]
    seed = SEEDS["reference"]

    fiber_stats, fiber_ref = bench.reference(scene, folder, "fiber-ref", "fiber", seed, ref_spp,
                                             s["ref_parts"])
    neural_stats, neural_ref = bench.render(scene, folder, "neural-ref", "neural", seed,
                                            spp=ref_spp)
    fiber_eq = convergence(bench, scene, folder, "fiber", fiber_ref, ref_spp, s["fiber_ladder"])
    neural_eq = convergence(bench, scene, folder, "neural", neural_ref, ref_spp,
                            s["neural_ladder"])
    heatmap = os.path.join(folder, "heatmap.png")
    quality = bench.compare(neural_ref, fiber_ref, heatmap)
    # Equal time: fiber mode given the time the neural render needs for relMSE 0.01.
    eq_seconds = max(neural_eq["seconds_to_target"], 0.01)
    eq_stats, eq_exr = bench.render(scene, folder, "fiber-equal-time", "fiber",
                                    SEEDS["equal_time"], seconds=eq_seconds)
    eq_quality = bench.compare(eq_exr, fiber_ref)
    neural_eq_stats, neural_eq_exr = bench.render(
        scene, folder, "neural-equal-time", "neural", SEEDS["equal_time"],
        spp=max(1, int(round(neural_eq["spp_to_target"]))))
    neural_eq_quality = bench.compare(neural_eq_exr, fiber_ref)

    os.makedirs(os.path.dirname(figure), exist_ok=True)
    bench.run([bench.weft, "montage", fiber_ref, neural_ref, heatmap, eq_exr, "--out", figure])
    noise = fiber_eq["reference_noise"] + neural_eq["reference_noise"]
    return {
        "preset": preset, "scene": kind, "ref_spp": ref_spp, "size": s["size"],
        "yarn_sampling": neural_stats.get("yarn_sampling"),
        "threads_used": fiber_stats.get("threads"),
        "scene_stats": {"fiber": fiber_stats["scene"], "neural": neural_stats["scene"]},
        "ssim": quality["ssim"], "rel_mse": quality["rel_mse"],
        "ssim_scales": bench.ssim_scales(neural_ref, fiber_ref), "ssim_scales_source": "exr",
        # relMSE of two converged renders = their difference + each one's noise
        # (c / N): what is left after the noise is the neural model's error.
        "rel_mse_minus_noise": quality["rel_mse"] - noise,
        # Per channel mean of the neural reference over the fiber one's: a bias
        # (one mode brighter) shows here, noise averages out.
        "mean_ratio": quality["mean_ratio"], "mean_ratio_source": "exr",
        "fiber_reference": fiber_reference(fiber_stats),
        "fiber": {"seconds_per_spp": fiber_stats["seconds_per_spp"],
                  "seconds": fiber_stats["seconds"],
                  "build_seconds": fiber_stats["scene"]["build_seconds"],
                  "embree_bytes": fiber_stats["scene"]["geometry_bvh_bytes"],
                  "material_bytes": fiber_stats["scene"].get("material_bytes", 0),
                  "peak_resident_bytes": fiber_stats["peak_resident_bytes"],
                  "equal_quality": fiber_eq},
        "neural": {"seconds_per_spp": neural_stats["seconds_per_spp"],
                   "seconds": neural_stats["seconds"],
                   "build_seconds": neural_stats["scene"]["build_seconds"],
                   "embree_bytes": neural_stats["scene"]["geometry_bvh_bytes"],
                   "material_bytes": neural_stats["scene"].get("material_bytes", 0),
                   "peak_resident_bytes": neural_stats["peak_resident_bytes"],
                   "equal_quality": neural_eq},
        "equal_time": {"seconds": eq_stats["seconds"], "fiber_spp": eq_stats["spp"],
                       "fiber_ssim": eq_quality["ssim"], "fiber_rel_mse": eq_quality["rel_mse"],
                       "neural_spp": neural_eq_stats["spp"],
                       "neural_ssim": neural_eq_quality["ssim"],
                       "neural_rel_mse": neural_eq_quality["rel_mse"]},
        "speedup": fiber_eq["seconds_to_target"] / neural_eq["seconds_to_target"],
        # Geometry + BVH and the materials' BSDFs (the yarn's networks, energy
        # guard and sampling tables count in the neural memory).
        "memory_ratio": scene_bytes(fiber_stats) / scene_bytes(neural_stats),
        "rss_ratio": fiber_stats["peak_resident_bytes"] / neural_stats["peak_resident_bytes"],
        "figure": os.path.basename(os.path.dirname(figure)) + "/" + os.path.basename(figure),
    }


def dual_baseline(bench, s, preset, kind, folder, cell, figure):
    """The dual-scattering baseline (after ZMA23; docs/dual-scattering.md) for a chunk whose
    fiber and neural renders are done (`cell`): its converged render and ladder, its quality
    against the fiber reference, its time at equal quality and memory, and the Fig. 10 row
    (reference | baseline | neural | 1 - SSIM of the baseline | 1 - SSIM of neural)."""
    t0 = time.time()
    # The same scene as the chunk's (re-made, identically, when the work folder lost it).
    scene = chunk_scene(bench, s, preset, kind, folder)
    ref_spp, seed = s["ref_spp"], SEEDS["reference"]
    fiber_stats, fiber_ref = bench.reference(scene, folder, "fiber-ref", "fiber", seed, ref_spp,
                                             s["ref_parts"])
    _, neural_ref = bench.render(scene, folder, "neural-ref", "neural", seed, spp=ref_spp)
    dual_stats, dual_ref = bench.render(scene, folder, "dual-ref", "dual", seed, spp=ref_spp)
    dual_eq = convergence(bench, scene, folder, "dual", dual_ref, ref_spp, s["neural_ladder"])
    heatmap = os.path.join(folder, "heatmap-dual.png")
    quality = bench.compare(dual_ref, fiber_ref, heatmap)
    neural_heatmap = os.path.join(folder, "heatmap-neural.png")
    bench.compare(neural_ref, fiber_ref, neural_heatmap)
    os.makedirs(os.path.dirname(figure), exist_ok=True)
    bench.run([bench.weft, "montage", fiber_ref, dual_ref, neural_ref, heatmap, neural_heatmap,
               "--out", figure])
    fiber_eq, neural_eq = cell["fiber"]["equal_quality"], cell["neural"]["equal_quality"]
    return {
        "name": "dual-scattering baseline (after ZMA23)",
        "ssim": quality["ssim"], "rel_mse": quality["rel_mse"],
        "mean_ratio": quality["mean_ratio"], "mean_ratio_source": "exr",
        "ssim_scales": bench.ssim_scales(dual_ref, fiber_ref), "ssim_scales_source": "exr",
        "rel_mse_minus_noise": quality["rel_mse"] - fiber_eq["reference_noise"]
        - dual_eq["reference_noise"],
        "seconds_per_spp": dual_stats["seconds_per_spp"], "seconds": dual_stats["seconds"],
        "build_seconds": dual_stats["scene"]["build_seconds"],
        "embree_bytes": dual_stats["scene"]["geometry_bvh_bytes"],
        "material_bytes": dual_stats["scene"].get("material_bytes", 0),
        "peak_resident_bytes": dual_stats["peak_resident_bytes"],
        "equal_quality": dual_eq,
        "speedup_over_fiber": fiber_eq["seconds_to_target"] / dual_eq["seconds_to_target"],
        "neural_speedup_over_dual": dual_eq["seconds_to_target"] / neural_eq["seconds_to_target"],
        "memory_ratio": scene_bytes(fiber_stats) / scene_bytes(dual_stats),
        "figure": os.path.basename(os.path.dirname(figure)) + "/" + os.path.basename(figure),
        "provenance": provenance(bench),
        "run": {"finished": now(), "wall_seconds": time.time() - t0},
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
            eq = convergence(bench, scene, vdir, "neural", ref, cell["ref_spp"], QUICK_LADDER,
                              extra=extra)
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


QUICK_LADDER = (16, 4)


def git_out(args, cwd):
    try:
        r = subprocess.run(["git"] + args, cwd=cwd, capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return r.stdout.strip() if r.returncode == 0 else None


def binary_digest(path):
    """The first 16 hex digits of the file's SHA-256."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()[:16]


def provenance(bench):
    """Which weft made the numbers, and where: recorded in every chunk file."""
    weft = bench.weft
    top = git_out(["rev-parse", "--show-toplevel"], os.path.dirname(os.path.realpath(weft)))
    commit = dirty = None
    if top:
        commit = git_out(["rev-parse", "HEAD"], top)
        dirty = bool(git_out(["status", "--porcelain", "--", "src", "CMakeLists.txt"], top))
    version = subprocess.run([weft, "--version"], capture_output=True, text=True).stdout.strip()
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        # HEAD of the git checkout the binary sits in (the binary may be older:
        # its mtime and hash are beside it); source_dirty: uncommitted changes under src/.
        "weft_commit": commit, "weft_source_dirty": dirty, "weft_version": version,
        "weft_binary_sha256": bench.weft_sha256,
        "weft_binary_mtime": datetime.datetime.fromtimestamp(
            os.path.getmtime(weft), datetime.timezone.utc).isoformat(timespec="seconds"),
        "script_commit": git_out(["rev-parse", "HEAD"], ROOT),
        "script_dirty": bool(git_out(["status", "--porcelain", "--", "bench/table2.py"], ROOT)),
        "machine": "%s, %d cores, %s" % (os.uname().machine, os.cpu_count(), cpu),
    }


def shown_path(path):
    rel = os.path.relpath(path)
    return path if rel.startswith("..") else rel


def now():
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def load_timings(results, name="table2"):
    """Per (preset, scene), the timings the estimates start from: the chunk file
    RESULTS/NAME/<preset>-<scene>.json where it was made with the current default
    max_depth (it records its fiber reference's), else the quick table's cell
    (RESULTS/table2-quick.json: 128 px, max_depth 100), its fiber seconds per spp
    times bench/results/max-depth.json's time at 1000 over at 100 (up to 2x for
    cotton); {} if neither exists."""
    timings = {}
    deeper = max_depth_measured()
    for folder in (results, os.path.join(ROOT, "bench", "results")):
        path = os.path.join(folder, "table2-quick.json")
        if os.path.exists(path):
            with open(path) as f:
                data = json.load(f)
            for c in data["cells"]:
                key = (c["preset"], c["scene"])
                cell = dict(c, source="quick table")
                if key in deeper:
                    cell["fiber"] = dict(c["fiber"], seconds_per_spp=c["fiber"]["seconds_per_spp"]
                                         * deeper[key]["fiber_seconds_ratio"])
                    cell["source"] = "quick table and max-depth.json"
                timings[key] = cell
            break
    for preset in PRESETS:
        for kind in SCENES:
            path = chunk_path(os.path.join(results, name), preset, kind)
            if not os.path.exists(path):
                continue
            with open(path) as f:
                cell = json.load(f)
            if ((cell.get("fiber_reference") or {}).get("max_depth") or 0) > OLD_DEFAULT_MAX_DEPTH:
                timings[(preset, kind)] = dict(cell, source="last chunk")
    return timings


def estimate_minutes(timings, preset, kind, s):
    """Expected minutes of a chunk on 2 cores: (all of it, the fiber reference alone), from
    the seconds per spp and build seconds of load_timings, scaled by the pixel count; None if
    there are no timings for the row."""
    q = timings.get((preset, kind))
    if q is None:
        return None
    scale = (s["size"] / q["size"]) ** 2
    seconds = 0.0
    for mode, ladder in (("fiber", s["fiber_ladder"]), ("neural", s["neural_ladder"])):
        spp = s["ref_spp"] + sum(ladder_spp(s["ref_spp"], ladder))
        seconds += spp * q[mode]["seconds_per_spp"] * scale
        renders = 2 + len(ladder_spp(s["ref_spp"], ladder))  # reference, ladder, equal time
        seconds += renders * q[mode]["build_seconds"]
    # The equal-time pair: neural at its spp to relMSE 0.01, fiber for the same time.
    c = max(l["c"] for l in q["neural"]["equal_quality"]["levels"])
    seconds += 2 * c / TARGET_REL_MSE * q["neural"]["seconds_per_spp"] * scale
    reference = s["ref_spp"] * q["fiber"]["seconds_per_spp"] * scale
    return seconds / 60, reference / 60


def estimate_text(timings, preset, kind, s):
    """'about N min on 2 cores ...' for --plan and a chunk's first line, and the minutes (or
    None). With --ref-parts N each part of the fiber reference is its own process: the 60
    minute budget holds per process."""
    est = estimate_minutes(timings, preset, kind, s)
    if est is None:
        return "no estimate (no quick table row, no chunk file)", None
    total, reference = est
    source = timings[(preset, kind)]["source"]
    if s["ref_parts"] <= 1:
        longest, text = total, "about %.0f min on 2 cores (from the %s)" % (total, source)
    else:
        part, rest = reference / s["ref_parts"], total - reference
        longest = max(part, rest)
        text = ("about %.0f min on 2 cores (from the %s): the fiber reference in %d parts of "
                "%.0f min (--ref-part K), then %.0f min" % (total, source, s["ref_parts"], part,
                                                            rest))
    if longest > BUDGET_MINUTES:
        text += " (over the %d minute budget)" % BUDGET_MINUTES
    return text, total


def chunk_command(preset, kind, extra=""):
    return "bench/table2.py --chunk %s,%s%s" % (preset, kind, extra)


def mb(n):
    return "%.3g" % (n / 1e6)


def ssim_scales_text(c):
    """'a / b' of SSIM at PLY_SCALES, marked when measured on a figure's 8-bit panels."""
    if "ssim_scales" not in c:
        return "-"
    return " / ".join("%.3f" % c["ssim_scales"][str(k)] for k in PLY_SCALES) + (
        " (png)" if c.get("ssim_scales_source") == "figure png" else "")


def mean_ratio_text(c):
    """Neural / fiber reference mean per channel, marked when measured on 8-bit panels."""
    if c.get("mean_ratio") is None:
        return "-"
    return " / ".join("-" if v is None else "%.3f" % v for v in c["mean_ratio"]) + (
        " (png)" if c.get("mean_ratio_source") == "figure png" else "")


def max_depth_text(c):
    ref = c.get("fiber_reference")
    if ref is None or ref.get("max_depth") is None:
        return "-"
    cut = ref.get("truncated_fraction")
    return "%d%s" % (ref["max_depth"], "" if cut is None else " (%.3g %%)" % (100 * cut))


def made_at_old_depth(c):
    return (c.get("fiber_reference") or {}).get("max_depth") == OLD_DEFAULT_MAX_DEPTH


def max_depth_measured():
    """bench/results/max-depth.json's rows by (preset, scene), or {} when it is missing."""
    path = os.path.join(ROOT, "bench", "results", "max-depth.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return {(r["preset"], r["scene"]): r for r in json.load(f)["rows"]}


def max_depth_lines(cells):
    """Rows whose fiber reference was made at the old max_depth of 100, with the light that
    limit cuts in fiber mode as bench/results/max-depth.json measured it."""
    old = [c for c in cells if made_at_old_depth(c)]
    if not old:
        return []
    measured = max_depth_measured()
    lines = ["", "Rows whose fiber reference was rendered at max_depth %d (weft's default "
             "before commit 74490ee), with what that limit costs the fiber render of the same "
             "scene at 128 px ([max-depth.md](max-depth.md)): the share of paths cut, and the "
             "light of a render at 1000 over one at 100 (R / G / B). Above 1.01 the reference is "
             "too dark and the row's quality columns hold that bias; its chunk needs a rerun." %
             OLD_DEFAULT_MAX_DEPTH, "",
             "| material | scene | cut at 100 | light at 1000 / at 100 | neural / fiber mean |",
             "|---|---|---|---|---|"]
    for c in old:
        m = measured.get((c["preset"], c["scene"]))
        lines.append("| %s | %s | %s | %s | %s |" % (
            c["preset"], c["scene"],
            "-" if m is None else "%.3f %%" % (100 * m["fiber_cut"]["100"]),
            "-" if m is None else " / ".join("%.3f" % v for v in m["fiber_light_ratio"]),
            mean_ratio_text(c)))
    return lines


def c_levels(eq):
    return ", ".join("%d: %.3g" % (l["spp"], l["c"]) for l in eq["levels"])


def model_fit(preset):
    """The shipped model's fit errors against its gather (models/<preset>.json "fit")."""
    try:
        with open(os.path.join(ROOT, "models", preset + ".json")) as f:
            fit = json.load(f).get("fit", {})
    except (OSError, ValueError):
        return None
    return fit if "m_rel_l2" in fit else None


def reason_lines(cells):
    """For the weave and knit rows below SSIM 0.97 at 4x4 px: what was measured of their cause,
    beside the same numbers for the rows that reach it (the shipped model's M and R fit errors,
    bench/results/exit-distance.json's distance from entry to exit in the ply)."""
    coarse = str(PLY_SCALES[-1])
    rows = [c for c in cells if c["scene"] != "closeup" and coarse in c.get("ssim_scales", {})]
    low = [c for c in rows if c["ssim_scales"][coarse] < 0.97]
    if not low:
        return []
    exits = {}
    path = os.path.join(ROOT, "bench", "results", "exit-distance.json")
    if os.path.exists(path):
        with open(path) as f:
            exits = {r["preset"]: r for r in json.load(f)["rows"]}
    lines = ["", "Rows below 0.97 at %sx%s px, with what was measured of their cause beside "
             "the rows that reach it: the shipped model's error against its own gather (M and R "
             "relative L2, models/README.md; M rel. L2 x the gather's M albedo weighs the M error "
             "by how much of the light M carries), the relMSE minus noise above, and how far light "
             "travels in the ply before it leaves (median and 90th percentile of the M exit "
             "distance in ply radii, [exit-distance.md](exit-distance.md); the model assumes "
             "0), and the light a fiber reference made at max_depth 100 lacks (light at 1000 / "
             "at 100, R / G / B, [max-depth.md](max-depth.md); - for a reference made deeper)."
             % (coarse, coarse), "",
             "| material | scene | SSIM at %sx%s px | M rel. L2 | M albedo | M rel. L2 x albedo "
             "| R rel. L2 | relMSE minus noise | exit distance median / 90th pct "
             "| fiber ref light lost to max_depth |" % (coarse, coarse),
             "|---|---|---|---|---|---|---|---|---|---|"]
    depth = max_depth_measured()
    for c in low + [c for c in rows if c not in low]:
        fit, e = model_fit(c["preset"]), exits.get(c["preset"])
        d = depth.get((c["preset"], c["scene"])) if made_at_old_depth(c) else None
        lines.append("| %s | %s | %.3f%s | %s | %s | %s | %s | %.4f | %s | %s |" % (
            c["preset"], c["scene"], c["ssim_scales"][coarse], "" if c in low else " (reaches)",
            "-" if fit is None else "%.3f" % fit["m_rel_l2"],
            "-" if e is None else "%.3f" % e["m_albedo"],
            "-" if fit is None or e is None else "%.3f" % (fit["m_rel_l2"] * e["m_albedo"]),
            "-" if fit is None else "%.3f" % fit["r_rel_l2"], c["rel_mse_minus_noise"],
            "-" if e is None else "%.2f / %.2f" % (e["median"], e["p90"]),
            "-" if d is None else " / ".join("%.3f" % v for v in d["fiber_light_ratio"])))
    return lines


def where_time_goes_lines(cells):
    """The speed-up as rays ratio x per-ray cost ratio x c ratio (ray_costs), for the chunks
    whose ladder renders recorded their rays."""
    rows, missing = [], []
    for c in cells:
        f = ladder_ray_costs(c["fiber"]["equal_quality"]["levels"])
        n = ladder_ray_costs(c["neural"]["equal_quality"]["levels"])
        if f and n:
            rows.append((c, f, n))
        else:
            missing.append("%s %s" % (c["preset"], c["scene"]))
    if not rows:
        return []
    lines = ["", "## Where the time goes: speed-up = rays ratio x per-ray cost ratio x c ratio",
             "", "Rays per sample (closest-hit and shadow queries) and thread-microseconds per "
             "ray of each mode's ladder renders; c ratio: fiber c / neural c at the top ladder "
             "level. Their product is the speed-up above (to rounding). A neural path is short "
             "(a ply is one bounce), but on weave and knit each of its rays costs about what a "
             "fiber-mode ray costs: the yarn BSDF and the lights take what Embree saves on the "
             "smaller scene (docs/render.md, section Where Table 2's time goes).", "",
             "| material | scene | fiber rays / sample | neural rays / sample | rays ratio "
             "| fiber us / ray | neural us / ray | per-ray ratio | c ratio | product |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for c, f, n in rows:
        rays = f["rays_per_sample"] / n["rays_per_sample"]
        per_ray = f["thread_us_per_ray"] / n["thread_us_per_ray"]
        c_ratio = (c["fiber"]["equal_quality"]["levels"][-1]["c"]
                   / c["neural"]["equal_quality"]["levels"][-1]["c"])
        lines.append("| %s | %s | %.2f | %.2f | %.2f | %.3f | %.3f | %.2f | %.2f | %.1fx |" % (
            c["preset"], c["scene"], f["rays_per_sample"], n["rays_per_sample"], rays,
            f["thread_us_per_ray"], n["thread_us_per_ray"], per_ray, c_ratio,
            rays * per_ray * c_ratio))
    if missing:
        lines += ["", "Without ray counts (chunks made before table2.py recorded them, their "
                  "ladder renders gone): %s." % ", ".join(missing)]
    return lines


def write_tables(title, caption, cells, out_md, missing=(), ablation_rows=(),
                 ablation_paths=0, figure_note=""):
    """table2*.md and .json from result cells (chunk files or one --quick run)."""
    lines = ["# " + title, "", caption, ""]
    chunks = [c for c in cells if "settings" in c]
    if chunks:
        notes = []
        for label, key in (("weft commits", lambda c: (c["provenance"]["weft_commit"] or "?")[:10]
                            + (" (src dirty)" if c["provenance"]["weft_source_dirty"] else "")),
                           ("weft binaries (sha256)",
                            lambda c: c["provenance"]["weft_binary_sha256"]),
                           ("machines", lambda c: c["provenance"]["machine"]),
                           ("thread counts", lambda c: str(c["threads_used"])),
                           ("yarn samplings", lambda c: str(c["yarn_sampling"]))):
            values = {}
            for c in chunks:
                values.setdefault(key(c), []).append("%s %s" % (c["preset"], c["scene"]))
            if len(values) > 1:
                notes.append("- The chunks come from %d %s: %s. Rows from different ones are "
                             "not strictly comparable (times above all)." % (
                                 len(values), label, "; ".join(
                                     "%s: %s" % (v, ", ".join(rows))
                                     for v, rows in sorted(values.items()))))
        days = sorted({c["run"]["finished"][:10] for c in chunks})
        notes.append("- Chunks made %s%s; settings, commit and date of each in the last table."
                     % (days[0], "" if len(days) == 1 else " to " + days[-1]))
        low = ["%s %s (%d)" % (c["preset"], c["scene"], c["ref_spp"]) for c in chunks
               if c["ref_spp"] < PAPER_REF_SPP[c["preset"]]]
        if low:
            notes.append("- References below the paper's sample count (1024; 4096 for silk and "
                         "cotton): %s." % ", ".join(low))
        if missing:
            notes.append("- Missing rows (%d of %d): %s." % (
                len(missing), len(missing) + len(cells),
                "; ".join("`%s`" % chunk_command(p, k) for p, k in missing)))
        lines += notes + [""]

    def targets(c):
        flags = []
        if c["scene"] != "closeup" and c["speedup"] < 15:
            flags.append("speed-up < 15x")
        if c["memory_ratio"] < 200:
            flags.append("memory < 200x")
        if c["ssim"] < 0.97:
            coarse = c.get("ssim_scales", {}).get(str(PLY_SCALES[-1]))
            flags.append("SSIM < 0.97" + ("" if coarse is None else
                                          " (%s 0.97 at %dx%d px)" % (
                                              ">=" if coarse >= 0.97 else "<", PLY_SCALES[-1],
                                              PLY_SCALES[-1])))
        if c["neural"]["equal_quality"]["c_spread"] > 1.25:
            flags.append("neural c spread > 1.25")
        return ", ".join(flags) or "met"

    order = {(p, k): i for i, (p, k) in enumerate((p, k) for p in PRESETS for k in SCENES)}
    rows = sorted([("cell", c) for c in cells] + [("missing", m) for m in missing],
                  key=lambda r: order.get((r[1]["preset"], r[1]["scene"]) if r[0] == "cell"
                                          else r[1], 0))
    lines += ["## Quality: neural vs the fiber reference, and each reference's own noise", "",
              "SSIM at 2x2 / 4x4 px: the same images averaged over 2 x 2 and 4 x 4 pixel "
              "blocks first (`weft compare --scale`, docs/compare.md): structure finer than a "
              "block (single fibers, which a ply-level model averages by design) no longer "
              "counts. (png): measured on the 8-bit panels of the committed figure, the renders "
              "being gone (`bench/table2.py --rescore`).", "",
              "| material | scene | pixels | ref spp | SSIM | SSIM at 2x2 / 4x4 px | relMSE "
              "| fiber ref noise c/N | neural ref noise c/N | relMSE minus noise "
              "| neural / fiber mean R / G / B | fiber ref max depth (cut) | issue 17 targets |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for kind, c in rows:
        if kind == "missing":
            lines.append("| %s | %s | *missing: `%s`* | | | | | | | | | | |" % (
                c[0], c[1], chunk_command(*c)))
            continue
        f, n = c["fiber"]["equal_quality"], c["neural"]["equal_quality"]
        lines.append("| %s | %s | %d | %d | %.3f | %s | %.4f | %.2g | %.2g | %.4f | %s | %s "
                     "| %s |" % (
                         c["preset"], c["scene"], c["size"], c["ref_spp"], c["ssim"],
                         ssim_scales_text(c), c["rel_mse"], f["reference_noise"],
                         n["reference_noise"], c["rel_mse_minus_noise"], mean_ratio_text(c),
                         max_depth_text(c), targets(c)))
    lines += max_depth_lines(cells)
    lines += reason_lines(cells)
    lines += ["", "## Time at equal quality (relative MSE %.2f) and memory" % TARGET_REL_MSE, "",
              "Memory of these 3 x 3 patches; the neural material (about 1 MB per yarn model) "
              "does not grow with the cloth, the geometry does: bench/memory_scale.py gives the "
              "same ratio at `weft scene --size` 6 and 12 ([memory-scale.md](memory-scale.md)).",
              "",
              "| material | scene | fiber s (EQ) | neural s (EQ) | speed-up | fiber s/spp "
              "| neural s/spp | fiber build s | fiber MB | neural MB | memory ratio | RSS ratio |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in cells:
        f, n = c["fiber"], c["neural"]
        lines.append(
            "| %s | %s | %.1f | %.2f | **%.1fx** | %.3f | %.3f | %.1f | %s | %s | **%.0fx** "
            "| %.1fx |" % (
                c["preset"], c["scene"], f["equal_quality"]["seconds_to_target"],
                n["equal_quality"]["seconds_to_target"], c["speedup"], f["seconds_per_spp"],
                n["seconds_per_spp"], f["build_seconds"], mb(f["embree_bytes"] + f.get("material_bytes", 0)),
                mb(n["embree_bytes"] + n.get("material_bytes", 0)), c["memory_ratio"], c["rss_ratio"]))
    lines += where_time_goes_lines(cells)
    lines += ["", "## Convergence: c = relMSE / (1/n + 1/N) at each ladder level n (spp: c)",
              "", "Equal at every level when variance falls as 1/spp; max/min > 1.25 for neural "
              "mode misses issue 17's target (a heavy tail).", "",
              "| material | scene | fiber c | fiber max/min | neural c | neural max/min "
              "| fiber spp to %.2f | neural spp to %.2f |" % (TARGET_REL_MSE, TARGET_REL_MSE),
              "|---|---|---|---|---|---|---|---|"]
    for c in cells:
        fl, nl = c["fiber"]["equal_quality"], c["neural"]["equal_quality"]
        lines.append("| %s | %s | %s | %.2f | %s | %s | %.0f | %.0f |" % (
            c["preset"], c["scene"], c_levels(fl), fl["c_spread"], c_levels(nl),
            ("%.2f" if nl["c_spread"] <= 1.25 else "**%.2f**") % nl["c_spread"],
            fl["spp_to_target"], nl["spp_to_target"]))
    lines += ["", "## Equal time: fiber mode given neural mode's time to relative MSE %.2f"
              % TARGET_REL_MSE, "",
              "| material | scene | seconds | fiber spp | fiber SSIM / relMSE | neural spp "
              "| neural SSIM / relMSE |", "|---|---|---|---|---|---|---|"]
    for c in cells:
        e = c["equal_time"]
        lines.append("| %s | %s | %.1f | %d | %.3f / %.4f | %d | %.3f / %.4f |" % (
            c["preset"], c["scene"], e["seconds"], e["fiber_spp"], e["fiber_ssim"],
            e["fiber_rel_mse"], e["neural_spp"], e["neural_ssim"], e["neural_rel_mse"]))
    duals = [c for c in cells if "dual" in c]
    if duals:
        lines += ["", "## Baseline: the dual-scattering model after ZMA23 (our reconstruction, "
                  "docs/dual-scattering.md), against the same fiber reference", "",
                  "Not ZMA23's own numbers: Zinke's dual scattering on KSZ15 fibers with an "
                  "analytic fiber count, re-implemented without the authors' text or code. "
                  "Equal-quality times as for neural mode (relative MSE %.2f against its own "
                  "converged render)." % TARGET_REL_MSE, "",
                  "| material | scene | baseline SSIM | neural SSIM | baseline / neural SSIM at "
                  "4x4 px | baseline relMSE minus noise "
                  "| neural relMSE minus noise | baseline s (EQ) | neural s (EQ) | fiber s (EQ) "
                  "| neural speed-up over baseline | baseline memory ratio | baseline c |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for c in duals:
            d = c["dual"]
            coarse = str(PLY_SCALES[-1])
            lines.append("| %s | %s | %.3f | %.3f | %s | %.4f | %.4f | %.1f | %.2f | %.1f "
                         "| **%.1fx** | %.0fx | %s |" % (
                             c["preset"], c["scene"], d["ssim"], c["ssim"],
                             "%.3f / %.3f" % (d["ssim_scales"][coarse], c["ssim_scales"][coarse])
                             if "ssim_scales" in d and "ssim_scales" in c else "-",
                             d["rel_mse_minus_noise"], c["rel_mse_minus_noise"],
                             d["equal_quality"]["seconds_to_target"],
                             c["neural"]["equal_quality"]["seconds_to_target"],
                             c["fiber"]["equal_quality"]["seconds_to_target"],
                             d["neural_speedup_over_dual"], d["memory_ratio"],
                             c_levels(d["equal_quality"])))
        without = ["%s %s" % (c["preset"], c["scene"]) for c in cells if "dual" not in c]
        if without:
            lines += ["", "Without the baseline yet (`bench/table2.py --chunk MATERIAL,SCENE "
                      "--baseline dual`): %s." % ", ".join(without)]
    if chunks:
        lines += ["", "## Chunks: settings and provenance", "",
                  "| material | scene | pixels | patch | ref spp | ladder fiber / neural (spp) "
                  "| threads | yarn sampling | sampler | weft commit | finished (UTC) | minutes "
                  "(estimate) |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for c in chunks:
            s, p, r = c["settings"], c["provenance"], c["run"]
            est = r.get("estimated_minutes")
            lines.append("| %s | %s | %d | %d | %d | %s / %s | %s | %s | %s | %s%s | %s | %.0f (%s) |"
                         % (c["preset"], c["scene"], s["size"], s["patch"], s["ref_spp"],
                            ",".join(str(l["spp"]) for l in c["fiber"]["equal_quality"]["levels"]),
                            ",".join(str(l["spp"]) for l in
                                     c["neural"]["equal_quality"]["levels"]),
                            c["threads_used"], c["yarn_sampling"],
                            s.get("sampler", "independent"), (p["weft_commit"] or "?")[:10],
                            " (src dirty)" if p["weft_source_dirty"] else "",
                            r["finished"].replace("T", " ")[:16], r["wall_seconds"] / 60,
                            "-" if est is None else "%.0f" % est))
    if ablation_rows:
        lines += ["", "## Ablations (paper Fig. 5), fleece, one gather (%d paths) and one fit "
                  "configuration for all variants" % ablation_paths, "",
                  "| scene | variant | SSIM vs fiber ref | relMSE vs fiber ref | s/spp "
                  "| s to relMSE 0.01 | time / full |", "|---|---|---|---|---|---|---|"]
        for r in ablation_rows:
            lines.append("| %s | %s | %.3f | %.4f | %.3f | %.2f | %.2fx |" % (
                r["scene"], r["variant"], r["ssim"], r["rel_mse"], r["seconds_per_spp"],
                r["equal_quality"]["seconds_to_target"], r["time_ratio_to_full"]))
    if figure_note:
        lines += ["", figure_note]
    text = "\n".join(lines) + "\n"
    benchlib.write_md_and_json(
        out_md, text, {"cells": cells, "missing": [{"preset": p, "scene": k} for p, k in missing],
                       "ablations": list(ablation_rows)})
    return text


def chunk_path(folder, preset, kind):
    return os.path.join(folder, "%s-%s.json" % (preset, kind))


def matching_settings(a, b):
    keys = ("size", "ref_spp", "patch", "fiber_ladder", "neural_ladder", "seeds")
    return all(a.get(k) == b.get(k) for k in keys) and a.get(
        "sampler", "independent") == b.get("sampler", "independent")


def run_chunk(bench, args, folder, preset, kind, s, timings):
    """Renders one (material, scene) chunk and writes its result file; returns its path."""
    path = chunk_path(folder, preset, kind)
    settings = dict(s, seeds={"reference": SEEDS["reference"],
                              "ladder": SEEDS["ladder"], "equal_time": SEEDS["equal_time"]},
                    threads=args.threads, sampler=args.sampler)
    if os.path.exists(path) and not args.redo:
        with open(path) as f:
            old = json.load(f)
        if matching_settings(old.get("settings", {}), settings):
            bench.say("%s %s: %s already holds these settings (--redo to run again)" % (
                preset, kind, shown_path(path)))
            # The baseline is scored against the chunk's own reference: its parts as recorded.
            s = dict(s, ref_parts=old["settings"].get("ref_parts", s["ref_parts"]))
            add_baselines(bench, args, folder, preset, kind, s, path)
            return path
    text, estimate = estimate_text(timings, preset, kind, s)
    bench.say("%s %s: %d x %d, %d spp references, ladders %s / %s, %s" % (
        preset, kind, s["size"], s["size"], s["ref_spp"],
        ladder_spp(s["ref_spp"], s["fiber_ladder"]), ladder_spp(s["ref_spp"], s["neural_ladder"]),
        text))
    started, t0 = now(), time.time()
    figure = os.path.join(folder, "%s-%s.png" % (preset, kind))
    cell = scene_cell(bench, s, preset, kind, os.path.join(bench.work, preset, kind), figure)
    cell["settings"] = settings
    cell["provenance"] = provenance(bench)
    cell["run"] = {"started": started, "finished": now(), "wall_seconds": time.time() - t0,
                   "estimated_minutes": estimate, "command": chunk_command(
                       preset, kind, shown_arguments(sys.argv[1:], drop=("--chunk", "--presets", "--scenes")))}
    cell["format"] = CHUNK_FORMAT
    os.makedirs(folder, exist_ok=True)
    write_json(path, cell)
    bench.say("%s %s: %.1f minutes, wrote %s" % (preset, kind, cell["run"]["wall_seconds"] / 60,
                                                 shown_path(path)))
    add_baselines(bench, args, folder, preset, kind, s, path)
    return path


def run_reference_part(bench, s, preset, kind, k):
    """--ref-part K: part K of the chunk's fiber reference (cached in the work folder)."""
    if not 0 <= k < s["ref_parts"]:
        sys.exit("table2: --ref-part %d: allowed 0..%d (--ref-parts %d)" % (
            k, s["ref_parts"] - 1, s["ref_parts"]))
    t0 = time.time()
    folder = os.path.join(bench.work, preset, kind)
    scene = chunk_scene(bench, s, preset, kind, folder)
    bench.reference(scene, folder, "fiber-ref", "fiber", SEEDS["reference"], s["ref_spp"],
                    s["ref_parts"], only_part=k)
    bench.say("%s %s: fiber reference part %d of %d in %.1f minutes (cached in %s)" % (
        preset, kind, k, s["ref_parts"], (time.time() - t0) / 60, folder))


def add_baselines(bench, args, folder, preset, kind, s, path):
    """--baseline dual: adds the baseline's results to the chunk file at `path` (renders only
    the baseline's images when the chunk's own renders are still in the work folder)."""
    if "dual" not in args.baseline:
        return
    with open(path) as f:
        cell = json.load(f)
    if "dual" in cell and not args.redo:
        bench.say("%s %s: the dual baseline is already in %s" % (preset, kind, shown_path(path)))
        return
    bench.say("%s %s: dual-scattering baseline" % (preset, kind))
    figure = os.path.join(folder, "%s-%s-fig10.png" % (preset, kind))
    cell["dual"] = dual_baseline(bench, s, preset, kind, os.path.join(bench.work, preset, kind),
                                 cell, figure)
    write_json(path, cell)
    bench.say("%s %s: baseline in %.1f minutes, wrote %s" % (
        preset, kind, cell["dual"]["run"]["wall_seconds"] / 60, shown_path(path)))


def figure_panels(figure, size, indices, out_dir):
    """Cuts panels `indices` (0 = leftmost) of a one-row `weft montage` figure of size x size
    renders into out_dir/panel-<i>.png (8-bit values kept); returns their paths."""
    try:
        from PIL import Image  # Debian: python3-pil; only for chunks whose renders are gone
    except ImportError:
        sys.exit("table2: --rescore from a figure needs Pillow (apt-get install python3-pil)")
    os.makedirs(out_dir, exist_ok=True)
    paths = []
    with Image.open(figure) as im:
        rgb = im.convert("RGB")
        for i in indices:
            x0 = MONTAGE_GAP + i * (size + MONTAGE_GAP)
            if x0 + size > rgb.width or MONTAGE_GAP + size > rgb.height:
                sys.exit("table2: %s is %d x %d: no panel %d of %d px" % (
                    figure, rgb.width, rgb.height, i, size))
            path = os.path.join(out_dir, "panel-%d.png" % i)
            rgb.crop((x0, MONTAGE_GAP, x0 + size, MONTAGE_GAP + size)).save(path)
            paths.append(path)
    return paths


def write_json(path, data):
    """data as indented JSON at path, through a temp file renamed over it."""
    with open(path + ".tmp", "w") as f:
        json.dump(data, f, indent=1)
    os.replace(path + ".tmp", path)


def add_ray_costs(cell, work):
    """Adds ray_costs to the ladder levels of a chunk file that lack them, from the cached
    ladder renders in work (only a render that is the level's own: same seed and spp, and
    the same seconds per spp to the bit). Returns whether it added any."""
    added = False
    for mode, eq in [(m, cell[m]["equal_quality"]) for m in ("fiber", "neural")] + (
            [("dual", cell["dual"]["equal_quality"])] if "dual" in cell else []):
        for level in eq["levels"]:
            if "rays_per_sample" in level:
                continue
            folder = os.path.join(work, "%s-%dspp" % (mode, level["spp"]))
            try:
                with open(os.path.join(folder, "image.json")) as f:
                    stats = json.load(f)
                with open(os.path.join(folder, "params.json")) as f:
                    cmd = json.load(f)["cmd"]
            except (OSError, ValueError, KeyError):
                continue
            seed = cmd[cmd.index("--seed") + 1] if "--seed" in cmd else None
            if (seed != str(level["seed"]) or stats.get("spp") != level["spp"]
                    or stats.get("seconds_per_spp") != level["seconds_per_spp"]):
                continue
            level.update(ray_costs(stats))
            added = True
    return added


def rescore(bench, args, results, name):
    """--rescore: adds SSIM at PLY_SCALES and the mean ratio (neural and baseline vs the fiber
    reference) to the chunk files that lack them: from the cached renders when the work folder
    still holds them, else from the 8-bit panels of the chunk's committed figures (marked
    "figure png"; its SSIM at full resolution is kept beside, to show how closely the PNG
    reproduces the EXR's); and the fiber reference's max_depth (OLD_DEFAULT_MAX_DEPTH for a
    chunk made before weft recorded it); and the ladder levels' ray costs (add_ray_costs)."""
    folder = os.path.join(results, name)
    for path in sorted(glob.glob(os.path.join(folder, "*-*.json"))):
        with open(path) as f:
            cell = json.load(f)
        if cell.get("format") != CHUNK_FORMAT:
            continue
        preset, kind, size = cell["preset"], cell["scene"], cell["size"]
        work = os.path.join(bench.work, preset, kind)
        added_rays = add_ray_costs(cell, work)
        if all(k in cell for k in ("ssim_scales", "mean_ratio", "fiber_reference")) and \
                not args.redo:
            if added_rays:
                write_json(path, cell)
                bench.say("%s %s: ray costs from the cached ladder renders" % (preset, kind))
            continue
        refs = {m: os.path.join(work, m + "-ref", "image.exr") for m in ("fiber", "neural", "dual")}
        pairs = [(cell, refs["neural"])] + ([(cell["dual"], refs["dual"])] if "dual" in cell else [])
        fiber_json = os.path.join(work, "fiber-ref", "image.json")
        if os.path.exists(fiber_json):
            with open(fiber_json) as f:
                cell["fiber_reference"] = fiber_reference(json.load(f))
        elif "fiber_reference" not in cell:
            cell["fiber_reference"] = {"max_depth": OLD_DEFAULT_MAX_DEPTH,
                                       "truncated_fraction": None}
        if all(os.path.exists(p) for p in [refs["fiber"]] + [r for _, r in pairs]):
            for target, image in pairs:
                if "ssim_scales" not in target or args.redo:
                    target["ssim_scales"] = bench.ssim_scales(image, refs["fiber"])
                    target["ssim_scales_source"] = "exr"
                target["mean_ratio"] = bench.compare(image, refs["fiber"])["mean_ratio"]
                target["mean_ratio_source"] = "exr"
        else:
            cut = os.path.join(bench.work, "rescore", "%s-%s" % (preset, kind))
            # Row figure: reference | neural | ...; Fig. 10 row: reference | baseline | neural.
            figures = [(cell, cell["figure"], (0, 1))]
            if "dual" in cell:
                figures.append((cell["dual"], cell["dual"]["figure"], (0, 1)))
            for target, figure, indices in figures:
                ref, image = figure_panels(os.path.join(results, figure), size, indices,
                                           os.path.join(cut, os.path.basename(figure)[:-4]))
                png = bench.compare(image, ref)
                if "ssim_scales" not in target or args.redo:
                    target["ssim_scales"] = bench.ssim_scales(image, ref)
                    target["ssim_scales_source"] = "figure png"
                    target["ssim_figure_png"] = png["ssim"]
                # Of the 8-bit display values: clipped highlights pull it towards 1.
                target["mean_ratio"] = png["mean_ratio"]
                target["mean_ratio_source"] = "figure png"
        write_json(path, cell)
        bench.say("%s %s: SSIM at %s px blocks %s (from %s)" % (
            preset, kind, " / ".join("%dx%d" % (k, k) for k in PLY_SCALES),
            " / ".join("%.3f" % cell["ssim_scales"][str(k)] for k in PLY_SCALES),
            cell["ssim_scales_source"]))


def assemble(results, name, weft):
    """table2.md, .json and the per-scene figures from the chunk files that exist."""
    folder = os.path.join(results, name)
    cells = []
    for path in sorted(glob.glob(os.path.join(folder, "*-*.json"))):
        with open(path) as f:
            cell = json.load(f)
        if cell.get("format") != CHUNK_FORMAT or (cell.get("preset"), cell.get("scene")) != tuple(
                os.path.basename(path)[:-5].split("-", 1)):
            print("table2: skipping %s (not a chunk file of format %d)" % (path, CHUNK_FORMAT),
                  file=sys.stderr)
            continue
        cells.append(cell)
    order = [(p, k) for p in PRESETS for k in SCENES]
    cells.sort(key=lambda c: order.index((c["preset"], c["scene"])))
    have = {(c["preset"], c["scene"]) for c in cells}
    missing = [pk for pk in order if pk not in have]
    can_montage = os.access(weft, os.X_OK)

    def stack(figures, out):
        """The existing row figures, one below the other, into `out`; whether it was made."""
        pngs = [os.path.join(results, f) for f in figures]
        pngs = [p for p in pngs if os.path.exists(p)]
        if not pngs or not can_montage:
            return False
        r = subprocess.run([weft, "montage"] + pngs + ["--columns", "1", "--out", out],
                           capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit("table2: weft montage failed: %s" % r.stderr)
        return True

    figures = []
    for kind in SCENES:
        if stack([c["figure"] for c in cells if c["scene"] == kind],
                 os.path.join(folder, "fig-%s.png" % kind)):
            figures.append("`%s/fig-%s.png` (%s)" % (name, kind, ", ".join(
                c["preset"] for c in cells if c["scene"] == kind and
                os.path.exists(os.path.join(results, c["figure"])))))
    fig10 = []
    for preset in PRESETS:
        if stack([c["dual"]["figure"] for c in cells if c["preset"] == preset and "dual" in c],
                 os.path.join(folder, "fig10-%s.png" % preset)):
            fig10.append("`%s/fig10-%s.png`" % (name, preset))
    note = ("Figures, one row per material: reference | neural | heatmap of 1 - SSIM | "
            "equal-time fiber. Per scene: %s. Per row: `%s/<material>-<scene>.png`." % (
                "; ".join(figures) or "none yet" + ("" if can_montage else
                                                    " (no weft binary for `weft montage`)"),
                name))
    if fig10:
        note += (" Fig. 10 (one row per scene: fiber reference | dual-scattering baseline | "
                 "neural | 1 - SSIM of the baseline | 1 - SSIM of neural): %s." % ", ".join(fig10))
    caption = (
        "Assembled by `bench/table2.py --assemble` from the chunk files in `%s/` (one per "
        "material and scene, made by `bench/table2.py --chunk MATERIAL,SCENE`). References "
        "at the paper's sample counts (1024 spp, 4096 for silk and cotton), fiber and neural "
        "mode each with its own converged render. c = relMSE x spp is measured at each "
        "ladder level (the render at n spp against the converged render at N spp: c = relMSE "
        "/ (1/n + 1/N)); a reference's own noise is c / N (c of the top level), and relMSE "
        "minus noise (neural vs fiber reference less both references' noise) estimates the "
        "model's error alone. Times are render seconds for each mode to reach relative MSE "
        "%.2f against its own converged image; memory is Embree geometry + BVH plus the "
        "materials' BSDFs (the yarn model's networks and tables), and peak RSS of the whole "
        "process. Issue 17's targets: speed-up >= 15x on weave and knit, "
        "memory ratio >= 200x, SSIM >= 0.97, neural c within 25 %% across the ladder." % (
            name, TARGET_REL_MSE))
    text = write_tables("Table 2 on this machine", caption, cells,
                        os.path.join(results, name + ".md"), missing=missing, figure_note=note)
    return text, len(cells), missing


def run_quick(bench, args, results, name, presets, scenes):
    """The one-run quick table (unchanged method), with the Fig. 5 ablations."""
    s = {"size": args.size or 128, "ref_spp": args.ref_spp or 256, "patch": 3,
         "fiber_ladder": list(QUICK_LADDER), "neural_ladder": list(QUICK_LADDER),
         "ref_parts": args.ref_parts or 1}
    cfg = {"figures": os.path.join(results, name), "ablation_paths": 2000000,
           "ablation_steps": {"t_net": 20000, "m_net": 40000}, "ablation_scenes": ["closeup"]}
    os.makedirs(cfg["figures"], exist_ok=True)
    caption = (
        "Written by `bench/table2.py%s` in one run (%s, %d threads). Renders of %d x %d pixels; "
        "references at %d spp, every material; ladder at 1/16 and 1/4 of it. c = relMSE / "
        "(1/n + 1/N) per ladder level; a reference's own noise is c / N; relMSE minus noise: "
        "the relative MSE of the two converged renders less both references' noise, an "
        "estimate of the model's error alone. Times are render seconds for each mode to reach "
        "relative MSE %.2f against its own converged image. Memory: Embree geometry + BVH "
        "(and peak RSS of the whole process)." % (
            shown_arguments(sys.argv[1:]), "%s, %d cores" % (os.uname().machine, os.cpu_count()),
            args.threads or os.cpu_count(), s["size"], s["size"], s["ref_spp"], TARGET_REL_MSE))
    note = ("Figures (reference | neural | heatmap of 1 - SSIM | equal-time fiber): `%s/`." % name)
    out_md = os.path.join(results, name + ".md")
    cells = []
    for preset in presets:
        for kind in scenes:
            bench.say("%s %s" % (preset, kind))
            cells.append(scene_cell(bench, s, preset, kind, os.path.join(bench.work, preset, kind),
                                    os.path.join(cfg["figures"], "%s-%s.png" % (preset, kind))))
            write_tables("Table 2 on this machine (--quick)", caption, cells, out_md,
                         figure_note=note)
    rows = []
    if not args.no_ablations and "fleece" in presets:
        rows = ablations(bench, cfg, cells)
        note += ("\nAblation figures: fiber reference | full | naive | no R lobe | cosine "
                 "sampling.")
    return write_tables("Table 2 on this machine (--quick)", caption, cells, out_md,
                        ablation_rows=rows, ablation_paths=cfg["ablation_paths"],
                        figure_note=note)


def shown_arguments(argv, drop=(), drop_flags=()):
    """The command's flags for captions, without machine-local paths (and without `drop`
    flags with a value and `drop_flags` flags without one)."""
    shown, skip = [], False
    local = ("--weft", "--work", "--results") + tuple(drop)
    for a in argv:
        if skip:
            skip = False
        elif a in local:
            skip = True
        elif a in drop_flags:
            pass
        elif not a.startswith(tuple(x + "=" for x in local)):
            shown.append(" " + a)
    return "".join(shown)


def parse_ladder(text, flag):
    try:
        divisors = [int(x) for x in text.split(",") if x]
    except ValueError:
        divisors = []
    if not divisors or any(d < 2 or d > 4096 for d in divisors):
        sys.exit("table2: %s %r: give divisors of the reference spp in [2, 4096], e.g. 64,16,4"
                 % (flag, text))
    return divisors


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    what = p.add_mutually_exclusive_group()
    what.add_argument("--chunk", default=None, metavar="MATERIAL,SCENE",
                      help="run one chunk, e.g. gabardine,knit, then assemble")
    what.add_argument("--assemble", action="store_true",
                      help="only assemble table2.md, .json and figures from the chunk files")
    what.add_argument("--plan", action="store_true",
                      help="print each chunk's command line, settings and estimated minutes")
    what.add_argument("--quick", action="store_true", help="the one-run quick table (42 min)")
    what.add_argument("--rescore", action="store_true",
                      help="add SSIM at 2x2 and 4x4 pixel blocks (weft compare --scale) to the "
                           "chunk files that lack it, from the cached renders or else from the "
                           "committed figures' 8-bit panels (needs python3-pil), and the ladder "
                           "levels' rays per sample and cost per ray from the cached renders, "
                           "then assemble")
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--work", default=None, help="cache folder (default bench/work/NAME)")
    p.add_argument("--results", default=os.path.join(ROOT, "bench", "results"),
                   help="folder of NAME.md, NAME.json and NAME/ (default bench/results)")
    p.add_argument("--name", default=None,
                   help="results name: RESULTS/NAME.md, .json and NAME/ (default table2 "
                        "or table2-quick)")
    p.add_argument("--presets", default=",".join(PRESETS), help="without --chunk: materials")
    p.add_argument("--scenes", default=",".join(SCENES), help="without --chunk: scenes")
    p.add_argument("--threads", type=int, default=0, help="render threads (0: all cores)")
    p.add_argument("--sampler", default="independent", choices=("independent", "sobol"),
                   help="weft render --sampler of every render of a chunk (docs/render.md); "
                        "recorded in the chunk's settings")
    p.add_argument("--baseline", default="", metavar="dual",
                   help="also render the dual-scattering baseline (after ZMA23) for each chunk "
                        "and add its columns (reuses the chunk's cached renders)")
    p.add_argument("--redo", action="store_true",
                   help="run a chunk even if its result file records the same settings")
    p.add_argument("--no-ablations", action="store_true", help="--quick without Fig. 5")
    p.add_argument("--size", type=int, default=None,
                   help="image side in pixels (default: per chunk, see --plan; 128 with --quick)")
    p.add_argument("--ref-spp", type=int, default=None,
                   help="spp of the converged renders (default 1024, 4096 for silk and cotton; "
                        "256 with --quick)")
    p.add_argument("--patch", type=int, default=None,
                   help="weave and knit: N x N yarns (default %d)" % DEFAULT_PATCH)
    p.add_argument("--fiber-ladder", default=None, metavar="D1,D2,...",
                   help="fiber ladder levels as divisors of the reference spp (default "
                        "64,16,4; 64,16 for cotton knit)")
    p.add_argument("--neural-ladder", default=None, metavar="D1,D2,...",
                   help="neural ladder levels as divisors of the reference spp (default 64,16,4)")
    p.add_argument("--ref-parts", type=int, default=None, metavar="N",
                   help="render the fiber reference as N parts of ref-spp / N samples, one "
                        "process each, merged (default 1; 2 for cotton weave, 3 for cotton knit)")
    p.add_argument("--ref-part", type=int, default=None, metavar="K",
                   help="with --chunk: render only part K (0..N-1) of the fiber reference and "
                        "stop; the chunk itself renders any part still missing")
    args = p.parse_args()
    name = args.name or ("table2-quick" if args.quick else "table2")
    if not name.replace("-", "").replace("_", "").isalnum():
        sys.exit("table2: --name %r: use letters, digits, '-' and '_'" % name)
    results = os.path.abspath(args.results)
    if args.work is None:
        args.work = os.path.join(ROOT, "bench", "work", name)
    for key, lo, hi in (("size", 16, 4096), ("ref_spp", 16, 1 << 20), ("patch", 1, 100),
                        ("ref_parts", 1, 64)):
        value = getattr(args, key)
        if value is not None and not lo <= value <= hi:
            sys.exit("table2: --%s %d is out of range [%d, %d]" % (key.replace("_", "-"), value,
                                                                   lo, hi))
    if args.baseline not in ("", "dual"):
        sys.exit("table2: --baseline %r: allowed dual" % args.baseline)
    if args.chunk:
        parts = args.chunk.split(",")
        if len(parts) != 2 or parts[0] not in PRESETS or parts[1] not in SCENES:
            sys.exit("table2: --chunk %r: give MATERIAL,SCENE with MATERIAL in %s and SCENE in %s"
                     % (args.chunk, ", ".join(PRESETS), ", ".join(SCENES)))
        chunks = [tuple(parts)]
    else:
        presets = [s for s in args.presets.split(",") if s]
        scenes = [s for s in args.scenes.split(",") if s]
        for s in presets:
            if s not in PRESETS:
                sys.exit("table2: --presets: unknown preset %r (allowed %s)" % (
                    s, ", ".join(PRESETS)))
        for s in scenes:
            if s not in SCENES:
                sys.exit("table2: --scenes: unknown scene %r (allowed %s)" % (
                    s, ", ".join(SCENES)))
        chunks = [(pr, k) for pr in presets for k in scenes]

    def settings(preset, kind):
        s = chunk_defaults(preset, kind)
        for key in ("size", "ref_spp", "patch", "ref_parts"):
            if getattr(args, key) is not None:
                s[key] = getattr(args, key)
        if args.fiber_ladder:
            s["fiber_ladder"] = parse_ladder(args.fiber_ladder, "--fiber-ladder")
        if args.neural_ladder:
            s["neural_ladder"] = parse_ladder(args.neural_ladder, "--neural-ladder")
        return s

    if args.plan:
        timings = load_timings(results, name)
        total = 0.0
        for preset, kind in chunks:
            s = settings(preset, kind)
            text, est = estimate_text(timings, preset, kind, s)
            total += est or 0.0
            print("%-45s # %d px, %d spp, ladders %s / %s: %s" % (
                chunk_command(preset, kind, shown_arguments(
                    sys.argv[1:], drop=("--presets", "--scenes"), drop_flags=("--plan",))),
                s["size"], s["ref_spp"], ",".join(map(str, s["fiber_ladder"])),
                ",".join(map(str, s["neural_ladder"])), text))
        print("# total about %.1f hours" % (total / 60))
        return
    if args.assemble:
        text, count, missing = assemble(results, name, os.path.abspath(args.weft))
        print(text)
        print("table2: %d chunk(s), %d missing; wrote %s" % (
            count, len(missing), os.path.join(results, name + ".md")), file=sys.stderr)
        return
    if not os.access(args.weft, os.X_OK):
        sys.exit("table2: %s is not an executable weft (build first, or pass --weft)" % args.weft)
    bench = Bench(args)
    if args.rescore:
        rescore(bench, args, results, name)
        text, count, missing = assemble(results, name, bench.weft)
        print(text)
        return
    if args.quick:
        print(run_quick(bench, args, results, name, sorted({c[0] for c in chunks},
                                                           key=PRESETS.index),
                        sorted({c[1] for c in chunks}, key=SCENES.index)))
        return
    if args.ref_part is not None:
        if not args.chunk:
            sys.exit("table2: --ref-part needs --chunk MATERIAL,SCENE")
        preset, kind = chunks[0]
        run_reference_part(bench, settings(preset, kind), preset, kind, args.ref_part)
        return
    timings = load_timings(results, name)
    for preset, kind in chunks:
        run_chunk(bench, args, os.path.join(results, name), preset, kind,
                  settings(preset, kind), timings)
        text, count, missing = assemble(results, name, bench.weft)
        bench.say("assembled %s: %d chunk(s), %d missing" % (name + ".md", count, len(missing)))
    print(text)


if __name__ == "__main__":
    main()
