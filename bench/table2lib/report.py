"""table2.md and table2.json (and the --quick table's) from result cells: the quality, time,
"Where the time goes", convergence, equal-time, baseline and provenance tables, and the
targets column."""
import json
import os

import benchlib

from .config import (PAPER_REF_SPP, PLY_SCALES, PRESETS, ROOT, SCENES, TARGET_REL_MSE,
                     chunk_command)
from .schema import Chunk, to_dict
from . import stats

COARSE = str(PLY_SCALES[-1])  # the coarsest block size, the one the targets name


def mb(n):
    return "%.3g" % (n / 1e6)


def ssim_scales_text(c):
    """'a / b': SSIM at each of PLY_SCALES."""
    return " / ".join("%.3f" % c.ssim_scales[str(k)] for k in PLY_SCALES)


def mean_ratio_text(c):
    """Neural / fiber reference mean per channel ('-' where the reference's is 0)."""
    return " / ".join("-" if v is None else "%.3f" % v for v in c.mean_ratio)


def max_depth_text(c):
    ref = c.fiber_reference
    if ref.max_depth is None:
        return "-"
    cut = ref.truncated_fraction
    return "%d%s" % (ref.max_depth, "" if cut is None else " (%.3g %%)" % (100 * cut))


def c_levels(eq):
    return ", ".join("%d: %.3g" % (l.spp, l.c) for l in eq.levels)


def targets(c):
    """Issue 17's targets a row misses, or 'met'."""
    flags = []
    if c.scene != "closeup" and c.speedup < 15:
        flags.append("speed-up < 15x")
    if c.memory_ratio < 200:
        flags.append("memory < 200x")
    if c.ssim < 0.97:
        coarse = c.ssim_scales.get(COARSE)
        flags.append("SSIM < 0.97" + ("" if coarse is None else " (%s 0.97 at %dx%d px)" % (
            ">=" if coarse >= 0.97 else "<", PLY_SCALES[-1], PLY_SCALES[-1])))
    if c.neural.equal_quality.c_spread > 1.25:
        flags.append("neural c spread > 1.25")
    return ", ".join(flags) or "met"


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
    rows = [c for c in cells if c.scene != "closeup" and COARSE in c.ssim_scales]
    low = [c for c in rows if c.ssim_scales[COARSE] < 0.97]
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
             "distance in ply radii, [exit-distance.md](exit-distance.md); the model assumes 0)."
             % (COARSE, COARSE), "",
             "| material | scene | SSIM at %sx%s px | M rel. L2 | M albedo | M rel. L2 x albedo "
             "| R rel. L2 | relMSE minus noise | exit distance median / 90th pct |"
             % (COARSE, COARSE),
             "|---|---|---|---|---|---|---|---|---|"]
    for c in low + [c for c in rows if c not in low]:
        fit, e = model_fit(c.preset), exits.get(c.preset)
        lines.append("| %s | %s | %.3f%s | %s | %s | %s | %s | %.4f | %s |" % (
            c.preset, c.scene, c.ssim_scales[COARSE], "" if c in low else " (reaches)",
            "-" if fit is None else "%.3f" % fit["m_rel_l2"],
            "-" if e is None else "%.3f" % e["m_albedo"],
            "-" if fit is None or e is None else "%.3f" % (fit["m_rel_l2"] * e["m_albedo"]),
            "-" if fit is None else "%.3f" % fit["r_rel_l2"], c.rel_mse_minus_noise,
            "-" if e is None else "%.2f / %.2f" % (e["median"], e["p90"])))
    return lines


def where_time_goes_lines(cells):
    """The speed-up as rays ratio x per-ray cost ratio x c ratio (stats.time_factors)."""
    if not cells:
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
    for c in cells:
        t = stats.time_factors(c.fiber.equal_quality.levels, c.neural.equal_quality.levels)
        lines.append("| %s | %s | %.2f | %.2f | %.2f | %.3f | %.3f | %.2f | %.2f | %.1fx |" % (
            c.preset, c.scene, t["fiber_rays_per_sample"], t["neural_rays_per_sample"],
            t["rays"], t["fiber_us_per_ray"], t["neural_us_per_ray"], t["per_ray"], t["c"],
            stats.factor_product(t)))
    return lines


def provenance_notes(chunks, missing, cells):
    """The bullet list under the caption: what differs between the chunks, their days, low
    reference spp, missing rows."""
    notes = []
    for label, key in (("weft commits", lambda c: (c.provenance.weft_commit or "?")[:10]
                        + (" (src dirty)" if c.provenance.weft_source_dirty else "")),
                       ("weft binaries (sha256)", lambda c: c.provenance.weft_binary_sha256),
                       ("machines", lambda c: c.provenance.machine),
                       ("thread counts", lambda c: str(c.threads_used)),
                       ("yarn samplings", lambda c: str(c.yarn_sampling))):
        values = {}
        for c in chunks:
            values.setdefault(key(c), []).append("%s %s" % (c.preset, c.scene))
        if len(values) > 1:
            notes.append("- The chunks come from %d %s: %s. Rows from different ones are "
                         "not strictly comparable (times above all)." % (
                             len(values), label, "; ".join(
                                 "%s: %s" % (v, ", ".join(rows))
                                 for v, rows in sorted(values.items()))))
    days = sorted({c.run.finished[:10] for c in chunks})
    notes.append("- Chunks made %s%s; settings, commit and date of each in the last table."
                 % (days[0], "" if len(days) == 1 else " to " + days[-1]))
    low = ["%s %s (%d)" % (c.preset, c.scene, c.ref_spp) for c in chunks
           if c.ref_spp < PAPER_REF_SPP[c.preset]]
    if low:
        notes.append("- References below the paper's sample count (1024; 4096 for silk and "
                     "cotton): %s." % ", ".join(low))
    if missing:
        notes.append("- Missing rows (%d of %d): %s." % (
            len(missing), len(missing) + len(cells),
            "; ".join("`%s`" % chunk_command(p, k) for p, k in missing)))
    return notes


def quality_lines(cells, missing):
    order = {(p, k): i for i, (p, k) in enumerate((p, k) for p in PRESETS for k in SCENES)}
    rows = sorted([("cell", c) for c in cells] + [("missing", m) for m in missing],
                  key=lambda r: order.get((r[1].preset, r[1].scene) if r[0] == "cell"
                                          else r[1], 0))
    lines = ["## Quality: neural vs the fiber reference, and each reference's own noise", "",
             "SSIM at 2x2 / 4x4 px: the same images averaged over 2 x 2 and 4 x 4 pixel "
             "blocks first (`weft compare --scale`, docs/compare.md): structure finer than a "
             "block (single fibers, which a ply-level model averages by design) no longer "
             "counts.", "",
             "| material | scene | pixels | ref spp | SSIM | SSIM at 2x2 / 4x4 px | relMSE "
             "| fiber ref noise c/N | neural ref noise c/N | relMSE minus noise "
             "| neural / fiber mean R / G / B | fiber ref max depth (cut) | issue 17 targets |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for kind, c in rows:
        if kind == "missing":
            lines.append("| %s | %s | *missing: `%s`* | | | | | | | | | | |" % (
                c[0], c[1], chunk_command(*c)))
            continue
        f, n = c.fiber.equal_quality, c.neural.equal_quality
        lines.append("| %s | %s | %d | %d | %.3f | %s | %.4f | %.2g | %.2g | %.4f | %s | %s "
                     "| %s |" % (
                         c.preset, c.scene, c.size, c.ref_spp, c.ssim, ssim_scales_text(c),
                         c.rel_mse, f.reference_noise, n.reference_noise, c.rel_mse_minus_noise,
                         mean_ratio_text(c), max_depth_text(c), targets(c)))
    return lines


def time_lines(cells):
    lines = ["", "## Time at equal quality (relative MSE %.2f) and memory" % TARGET_REL_MSE, "",
             "Memory of these 3 x 3 patches; the neural material (about 1 MB per yarn model) "
             "does not grow with the cloth, the geometry does: bench/memory_scale.py gives the "
             "same ratio at `weft scene --size` 6 and 12 ([memory-scale.md](memory-scale.md)). "
             "s/spp: the ladder's renders' (spp-weighted), which run alone; the references' "
             "wall clock can carry other work.",
             "",
             "| material | scene | fiber s (EQ) | neural s (EQ) | speed-up | fiber s/spp "
             "| neural s/spp | fiber build s | fiber MB | neural MB | memory ratio | RSS ratio |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in cells:
        f, n = c.fiber, c.neural
        lines.append(
            "| %s | %s | %.1f | %.2f | **%.1fx** | %.3f | %.3f | %.1f | %s | %s | **%.0fx** "
            "| %.1fx |" % (
                c.preset, c.scene, f.equal_quality.seconds_to_target,
                n.equal_quality.seconds_to_target, c.speedup, f.equal_quality.seconds_per_spp,
                n.equal_quality.seconds_per_spp, f.build_seconds, mb(f.embree_bytes + f.material_bytes),
                mb(n.embree_bytes + n.material_bytes), c.memory_ratio, c.rss_ratio))
    return lines


def convergence_lines(cells):
    lines = ["", "## Convergence: c = relMSE / (1/n + 1/N) at each ladder level n (spp: c)",
             "", "Equal at every level when variance falls as 1/spp; max/min > 1.25 for neural "
             "mode misses issue 17's target (a heavy tail).", "",
             "| material | scene | fiber c | fiber max/min | neural c | neural max/min "
             "| fiber spp to %.2f | neural spp to %.2f |" % (TARGET_REL_MSE, TARGET_REL_MSE),
             "|---|---|---|---|---|---|---|---|"]
    for c in cells:
        fl, nl = c.fiber.equal_quality, c.neural.equal_quality
        lines.append("| %s | %s | %s | %.2f | %s | %s | %.0f | %.0f |" % (
            c.preset, c.scene, c_levels(fl), fl.c_spread, c_levels(nl),
            ("%.2f" if nl.c_spread <= 1.25 else "**%.2f**") % nl.c_spread,
            fl.spp_to_target, nl.spp_to_target))
    return lines


def equal_time_lines(cells):
    lines = ["", "## Equal time: fiber mode given neural mode's time to relative MSE %.2f"
             % TARGET_REL_MSE, "",
             "| material | scene | seconds | fiber spp | fiber SSIM / relMSE | neural spp "
             "| neural SSIM / relMSE |", "|---|---|---|---|---|---|---|"]
    for c in cells:
        e = c.equal_time
        lines.append("| %s | %s | %.1f | %d | %.3f / %.4f | %d | %.3f / %.4f |" % (
            c.preset, c.scene, e.seconds, e.fiber_spp, e.fiber_ssim, e.fiber_rel_mse,
            e.neural_spp, e.neural_ssim, e.neural_rel_mse))
    return lines


def baseline_lines(cells):
    duals = [c for c in cells if getattr(c, "dual", None) is not None]
    if not duals:
        return []
    lines = ["", "## Baseline: the dual-scattering model after ZMA23 (our reconstruction, "
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
        d = c.dual
        lines.append("| %s | %s | %.3f | %.3f | %s | %.4f | %.4f | %.1f | %.2f | %.1f "
                     "| **%.1fx** | %.0fx | %s |" % (
                         c.preset, c.scene, d.ssim, c.ssim,
                         "%.3f / %.3f" % (d.ssim_scales[COARSE], c.ssim_scales[COARSE]),
                         d.rel_mse_minus_noise, c.rel_mse_minus_noise,
                         d.equal_quality.seconds_to_target,
                         c.neural.equal_quality.seconds_to_target,
                         c.fiber.equal_quality.seconds_to_target,
                         d.neural_speedup_over_dual, d.memory_ratio, c_levels(d.equal_quality)))
    without = ["%s %s" % (c.preset, c.scene) for c in cells
               if getattr(c, "dual", None) is None]
    if without:
        lines += ["", "Without the baseline yet (`bench/table2.py --chunk MATERIAL,SCENE "
                  "--baseline dual`): %s." % ", ".join(without)]
    return lines


def chunk_lines(chunks):
    lines = ["", "## Chunks: settings and provenance", "",
             "| material | scene | pixels | patch | ref spp | ladder fiber / neural (spp) "
             "| threads | yarn sampling | sampler | weft commit | finished (UTC) | minutes "
             "(estimate) |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in chunks:
        s, p, r = c.settings, c.provenance, c.run
        est = r.estimated_minutes
        lines.append("| %s | %s | %d | %d | %d | %s / %s | %s | %s | %s | %s%s | %s | %.0f (%s) |"
                     % (c.preset, c.scene, s.size, s.patch, s.ref_spp,
                        ",".join(str(l.spp) for l in c.fiber.equal_quality.levels),
                        ",".join(str(l.spp) for l in c.neural.equal_quality.levels),
                        c.threads_used, c.yarn_sampling, s.sampler,
                        (p.weft_commit or "?")[:10], " (src dirty)" if p.weft_source_dirty else "",
                        r.finished.replace("T", " ")[:16], r.wall_seconds / 60,
                        "-" if est is None else "%.0f" % est))
    return lines


def ablation_lines(ablation_rows, ablation_paths):
    if not ablation_rows:
        return []
    lines = ["", "## Ablations (paper Fig. 5), fleece, one gather (%d paths) and one fit "
             "configuration for all variants" % ablation_paths, "",
             "| scene | variant | SSIM vs fiber ref | relMSE vs fiber ref | s/spp "
             "| s to relMSE 0.01 | time / full |", "|---|---|---|---|---|---|---|"]
    for r in ablation_rows:
        lines.append("| %s | %s | %.3f | %.4f | %.3f | %.2f | %.2fx |" % (
            r.scene, r.variant, r.ssim, r.rel_mse, r.seconds_per_spp,
            r.equal_quality.seconds_to_target, r.time_ratio_to_full))
    return lines


def tables_text(title, caption, cells, missing=(), ablation_rows=(), ablation_paths=0,
                figure_note=""):
    """The Markdown of table2*.md from result cells (chunks, or one --quick run's cells)."""
    lines = ["# " + title, "", caption, ""]
    chunks = [c for c in cells if isinstance(c, Chunk)]
    if chunks:
        lines += provenance_notes(chunks, missing, cells) + [""]
    lines += quality_lines(cells, missing)
    lines += reason_lines(cells)
    lines += time_lines(cells)
    lines += where_time_goes_lines(cells)
    lines += convergence_lines(cells)
    lines += equal_time_lines(cells)
    lines += baseline_lines(cells)
    if chunks:
        lines += chunk_lines(chunks)
    lines += ablation_lines(ablation_rows, ablation_paths)
    if figure_note:
        lines += ["", figure_note]
    return "\n".join(lines) + "\n"


def write_tables(title, caption, cells, out_md, missing=(), ablation_rows=(),
                 ablation_paths=0, figure_note=""):
    """table2*.md and .json from result cells; returns the Markdown."""
    text = tables_text(title, caption, cells, missing, ablation_rows, ablation_paths,
                       figure_note)
    benchlib.write_md_and_json(
        out_md, text, {"cells": [to_dict(c) for c in cells],
                       "missing": [{"preset": p, "scene": k} for p, k in missing],
                       "ablations": [to_dict(r) for r in ablation_rows]})
    return text
