"""The renders and comparisons of a chunk (and of --quick, --ref-part, --baseline dual and
--rescore), each step cached in the work folder by benchlib.Runner (docs/bench-table2.md)."""
import json
import os
import sys
import time

import benchlib

from . import stats
from .config import (PLY_SCALES, QUICK_LADDER, ROOT, SEEDS, TARGET_REL_MSE, chunk_command,
                     chunk_path, shown_arguments)
from .plan import estimate_text
from .provenance import provenance
from .report import write_tables
from .schema import (AblationRow, Baseline, BaselineRun, Cell, Chunk, EqualQuality, EqualTime,
                     FiberReference, Level, Mode, Run, Seeds, Settings, chunk_files, load_chunk,
                     write_chunk)


class Bench(benchlib.Runner):
    """weft render, merge and compare for one run of bench/table2.py."""

    def __init__(self, args):
        super().__init__("table2", args.weft, args.work)
        self.args = args

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

    def montage(self, images, made, figure):
        """weft montage of images into `made` (in the work folder), published as `figure`
        (written only when its pixels change, benchlib.publish_png)."""
        self.run([self.weft, "montage"] + list(images) + ["--out", made])
        benchlib.publish_png(made, figure)

    def provenance(self):
        return provenance(self.weft, self.weft_sha256)


def convergence(bench, scene, folder, mode, ref_exr, ref_spp, divisors, extra=()):
    """Ladder renders at ref_spp / divisor: c per level, spp and seconds to relMSE 0.01."""
    levels = []
    for i, spp in enumerate(stats.ladder_spp(ref_spp, divisors)):
        st, exr = bench.render(scene, folder, "%s-%dspp" % (mode, spp), mode,
                               SEEDS["ladder"] + i, spp=spp, extra=extra)
        rel = bench.compare(exr, ref_exr)["rel_mse"]
        levels.append(Level(spp=spp, seed=SEEDS["ladder"] + i, rel_mse=rel,
                            c=stats.noise_constant(rel, spp, ref_spp),
                            seconds_per_spp=st["seconds_per_spp"], **stats.ray_costs(st)))
    return EqualQuality(levels=levels, **stats.equal_quality(levels, ref_spp))


def fiber_reference(st):
    """The fiber reference's path depth limit and the share of its paths cut there (weft
    render's image.json; docs/render.md#integrator)."""
    return FiberReference(
        max_depth=st.get("max_depth"), truncated_fraction=st.get("truncated_fraction"),
        # rendered in N parts (--ref-parts), each its own process; seconds: all of them
        parts=st.get("shards", {}).get("count", 1), seconds=st.get("seconds"))


def mode_result(st, eq):
    scene = st["scene"]
    return Mode(seconds_per_spp=st["seconds_per_spp"], seconds=st["seconds"],
                build_seconds=scene["build_seconds"], embree_bytes=scene["geometry_bvh_bytes"],
                material_bytes=scene.get("material_bytes", 0),
                peak_resident_bytes=st["peak_resident_bytes"], equal_quality=eq)


def figure_name(figure):
    """A figure's path as a cell records it: relative to the results folder."""
    return os.path.basename(os.path.dirname(figure)) + "/" + os.path.basename(figure)


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
    eq_seconds = max(neural_eq.seconds_to_target, 0.01)
    eq_stats, eq_exr = bench.render(scene, folder, "fiber-equal-time", "fiber",
                                    SEEDS["equal_time"], seconds=eq_seconds)
    eq_quality = bench.compare(eq_exr, fiber_ref)
    neural_eq_stats, neural_eq_exr = bench.render(
        scene, folder, "neural-equal-time", "neural", SEEDS["equal_time"],
        spp=max(1, int(round(neural_eq.spp_to_target))))
    neural_eq_quality = bench.compare(neural_eq_exr, fiber_ref)

    bench.montage([fiber_ref, neural_ref, heatmap, eq_exr], os.path.join(folder, "figure.png"),
                  figure)
    return Cell(
        preset=preset, scene=kind, ref_spp=ref_spp, size=s["size"],
        yarn_sampling=neural_stats.get("yarn_sampling"),
        threads_used=fiber_stats.get("threads"),
        scene_stats={"fiber": fiber_stats["scene"], "neural": neural_stats["scene"]},
        ssim=quality["ssim"], rel_mse=quality["rel_mse"],
        ssim_scales=bench.ssim_scales(neural_ref, fiber_ref), ssim_scales_source="exr",
        # relMSE of two converged renders = their difference + each one's noise
        # (c / N): what is left after the noise is the neural model's error.
        rel_mse_minus_noise=stats.rel_mse_minus_noise(
            quality["rel_mse"], fiber_eq.reference_noise, neural_eq.reference_noise),
        # Per channel mean of the neural reference over the fiber one's: a bias
        # (one mode brighter) shows here, noise averages out.
        mean_ratio=quality["mean_ratio"], mean_ratio_source="exr",
        fiber_reference=fiber_reference(fiber_stats),
        fiber=mode_result(fiber_stats, fiber_eq),
        neural=mode_result(neural_stats, neural_eq),
        equal_time=EqualTime(seconds=eq_stats["seconds"], fiber_spp=eq_stats["spp"],
                             fiber_ssim=eq_quality["ssim"], fiber_rel_mse=eq_quality["rel_mse"],
                             neural_spp=neural_eq_stats["spp"],
                             neural_ssim=neural_eq_quality["ssim"],
                             neural_rel_mse=neural_eq_quality["rel_mse"]),
        speedup=stats.speedup(fiber_eq.seconds_to_target, neural_eq.seconds_to_target),
        # Geometry + BVH and the materials' BSDFs (the yarn's networks, energy
        # guard and sampling tables count in the neural memory).
        memory_ratio=stats.scene_bytes(fiber_stats["scene"]) / stats.scene_bytes(
            neural_stats["scene"]),
        rss_ratio=fiber_stats["peak_resident_bytes"] / neural_stats["peak_resident_bytes"],
        figure=figure_name(figure))


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
    bench.montage([fiber_ref, dual_ref, neural_ref, heatmap, neural_heatmap],
                  os.path.join(folder, "figure-fig10.png"), figure)
    fiber_eq, neural_eq = cell.fiber.equal_quality, cell.neural.equal_quality
    return Baseline(
        name="dual-scattering baseline (after ZMA23)",
        ssim=quality["ssim"], rel_mse=quality["rel_mse"],
        mean_ratio=quality["mean_ratio"], mean_ratio_source="exr",
        ssim_scales=bench.ssim_scales(dual_ref, fiber_ref), ssim_scales_source="exr",
        rel_mse_minus_noise=stats.rel_mse_minus_noise(
            quality["rel_mse"], fiber_eq.reference_noise, dual_eq.reference_noise),
        seconds_per_spp=dual_stats["seconds_per_spp"], seconds=dual_stats["seconds"],
        build_seconds=dual_stats["scene"]["build_seconds"],
        embree_bytes=dual_stats["scene"]["geometry_bvh_bytes"],
        material_bytes=dual_stats["scene"].get("material_bytes", 0),
        peak_resident_bytes=dual_stats["peak_resident_bytes"],
        equal_quality=dual_eq,
        speedup_over_fiber=stats.speedup(fiber_eq.seconds_to_target, dual_eq.seconds_to_target),
        neural_speedup_over_dual=stats.speedup(dual_eq.seconds_to_target,
                                               neural_eq.seconds_to_target),
        memory_ratio=stats.scene_bytes(fiber_stats["scene"]) / stats.scene_bytes(
            dual_stats["scene"]),
        figure=figure_name(figure),
        provenance=bench.provenance(),
        run=BaselineRun(finished=benchlib.now(), wall_seconds=time.time() - t0))


def matching_settings(a, b):
    """Whether two chunks' Settings ask for the same renders."""
    return all(getattr(a, k) == getattr(b, k) for k in (
        "size", "ref_spp", "patch", "fiber_ladder", "neural_ladder", "seeds", "sampler"))


def recorded_ref_parts(chunk):
    """The parts the chunk's fiber reference was rendered in, as recorded (a chunk file
    without them was made before --ref-parts: one render)."""
    return chunk.settings.ref_parts or chunk.fiber_reference.parts or 1


def run_chunk(bench, args, folder, preset, kind, s, timings):
    """Renders one (material, scene) chunk and writes its result file; returns its path."""
    path = chunk_path(folder, preset, kind)
    settings = Settings(size=s["size"], ref_spp=s["ref_spp"], patch=s["patch"],
                        fiber_ladder=list(s["fiber_ladder"]),
                        neural_ladder=list(s["neural_ladder"]), ref_parts=s["ref_parts"],
                        seeds=Seeds(**SEEDS), threads=args.threads, sampler=args.sampler)
    if os.path.exists(path) and not args.redo:
        old = load_chunk(path)
        if matching_settings(old.settings, settings):
            bench.say("%s %s: %s already holds these settings (--redo to run again)" % (
                preset, kind, shown_path(path)))
            # The baseline is scored against the chunk's own reference: its parts as recorded.
            add_baselines(bench, args, folder, preset, kind,
                          dict(s, ref_parts=recorded_ref_parts(old)), path)
            return path
    text, estimate = estimate_text(timings, preset, kind, s)
    bench.say("%s %s: %d x %d, %d spp references, ladders %s / %s, %s" % (
        preset, kind, s["size"], s["size"], s["ref_spp"],
        stats.ladder_spp(s["ref_spp"], s["fiber_ladder"]),
        stats.ladder_spp(s["ref_spp"], s["neural_ladder"]), text))
    started, t0 = benchlib.now(), time.time()
    figure = os.path.join(folder, "%s-%s.png" % (preset, kind))
    cell = scene_cell(bench, s, preset, kind, os.path.join(bench.work, preset, kind), figure)
    chunk = Chunk(**vars(cell), settings=settings, provenance=bench.provenance(),
                  run=Run(started=started, finished=benchlib.now(),
                          wall_seconds=time.time() - t0, estimated_minutes=estimate,
                          command=chunk_command(preset, kind, shown_arguments(
                              sys.argv[1:], drop=("--chunk", "--presets", "--scenes")))))
    os.makedirs(folder, exist_ok=True)
    write_chunk(path, chunk)
    bench.say("%s %s: %.1f minutes, wrote %s" % (preset, kind, chunk.run.wall_seconds / 60,
                                                 shown_path(path)))
    add_baselines(bench, args, folder, preset, kind, s, path)
    return path


def add_baselines(bench, args, folder, preset, kind, s, path):
    """--baseline dual: adds the baseline's results to the chunk file at `path` (renders only
    the baseline's images when the chunk's own renders are still in the work folder)."""
    if "dual" not in args.baseline:
        return
    chunk = load_chunk(path)
    if chunk.dual is not None and not args.redo:
        bench.say("%s %s: the dual baseline is already in %s" % (preset, kind, shown_path(path)))
        return
    bench.say("%s %s: dual-scattering baseline" % (preset, kind))
    figure = os.path.join(folder, "%s-%s-fig10.png" % (preset, kind))
    chunk.dual = dual_baseline(bench, s, preset, kind, os.path.join(bench.work, preset, kind),
                               chunk, figure)
    write_chunk(path, chunk)
    bench.say("%s %s: baseline in %.1f minutes, wrote %s" % (
        preset, kind, chunk.dual.run.wall_seconds / 60, shown_path(path)))


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
        preset, kind, k, s["ref_parts"], (time.time() - t0) / 60, shown_path(folder)))


def made_by(render_folder, sha256):
    """Whether the cached render in render_folder exists and was made by the binary `sha256`."""
    try:
        with open(os.path.join(render_folder, "params.json")) as f:
            params = json.load(f)
    except (OSError, ValueError):
        return False
    return (sha256 is not None and params.get("weft_sha256") == sha256
            and os.path.exists(os.path.join(render_folder, "image.exr")))


def rescore(bench, results, name):
    """--rescore: scores every chunk again with this weft's `weft compare`, from the chunk's own
    renders in the work folder (made by the binary its provenance names): SSIM at PLY_SCALES
    and the per-channel mean ratio of neural, and of the baseline, against the fiber
    reference. A chunk whose renders are gone is left as it is."""
    for path, chunk in chunk_files(os.path.join(results, name)):
        work = os.path.join(bench.work, chunk.preset, chunk.scene)
        made = chunk.provenance.weft_binary_sha256
        targets = [(chunk, "neural-ref", made)]
        if chunk.dual is not None:
            targets.append((chunk.dual, "dual-ref", chunk.dual.provenance.weft_binary_sha256))
        fiber = os.path.join(work, "fiber-ref")
        if not all(made_by(os.path.join(work, f), sha) for f, sha in
                   [("fiber-ref", made)] + [(r, sha) for _, r, sha in targets]):
            bench.say("%s %s: its renders are not in %s: left as it is" % (
                chunk.preset, chunk.scene, shown_path(work)))
            continue
        for target, render, _ in targets:
            image = os.path.join(work, render, "image.exr")
            target.ssim_scales = bench.ssim_scales(image, os.path.join(fiber, "image.exr"))
            target.ssim_scales_source = "exr"
            target.mean_ratio = bench.compare(image, os.path.join(fiber, "image.exr"))[
                "mean_ratio"]
            target.mean_ratio_source = "exr"
        write_chunk(path, chunk)
        bench.say("%s %s: SSIM at %s px blocks %s" % (
            chunk.preset, chunk.scene, " / ".join("%dx%d" % (k, k) for k in PLY_SCALES),
            " / ".join("%.3f" % chunk.ssim_scales[str(k)] for k in PLY_SCALES)))


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
        if cell.preset != "fleece" or cell.scene not in cfg["ablation_scenes"]:
            continue
        kind = cell.scene
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
            st, ref = bench.render(scene, vdir, "ref", "neural", 1, spp=cell.ref_spp,
                                   extra=extra)
            eq = convergence(bench, scene, vdir, "neural", ref, cell.ref_spp, QUICK_LADDER,
                             extra=extra)
            quality = bench.compare(ref, fiber_ref, os.path.join(vdir, "heatmap.png"))
            results[name] = {"ssim": quality["ssim"], "rel_mse": quality["rel_mse"],
                             "seconds_per_spp": st["seconds_per_spp"], "equal_quality": eq,
                             "image": ref}
        full_time = results["full"]["equal_quality"].seconds_to_target
        for name, r in results.items():
            rows.append(AblationRow(
                scene=kind, variant=name, ssim=r["ssim"], rel_mse=r["rel_mse"],
                seconds_per_spp=r["seconds_per_spp"], equal_quality=r["equal_quality"],
                time_ratio_to_full=r["equal_quality"].seconds_to_target / full_time))
        figure = os.path.join(cfg["figures"], "ablation-fleece-%s.png" % kind)
        bench.montage([fiber_ref] + [results[n]["image"] for n in
                                     ("full", "naive", "no_r_lobe", "cosine_sampling")],
                      os.path.join(folder, kind, "figure.png"), figure)
    return rows


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


def shown_path(path):
    """A path for progress lines: relative to the current folder when inside it."""
    rel = os.path.relpath(path)
    return path if rel.startswith("..") else rel
