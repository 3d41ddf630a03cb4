"""--assemble: table2.md, .json and the stacked figures from whatever chunk files exist. Needs
no weft binary and renders nothing; the figures need Pillow (python3-pil) and are written only
when their pixels change."""
import os
import sys

import benchlib

from .config import PRESETS, SCENES, TARGET_REL_MSE, chunk_order
from .report import write_tables
from .schema import chunk_files


def stack_figures(results, rows, out):
    """The row figures `rows` (paths relative to results) that exist, one below the other, into
    `out`; returns the rows used ([] when none exists)."""
    rows = [f for f in rows if os.path.exists(os.path.join(results, f))]
    if rows and benchlib.stack_pngs([os.path.join(results, f) for f in rows], out) is None:
        print("table2: %s not stacked: needs Pillow (apt-get install python3-pil)"
              % os.path.basename(out), file=sys.stderr)
    return rows


def figure_note(results, name, cells):
    """Stacks the per-scene (Fig. 8/9) and per-material (Fig. 10) figures; the sentence that
    names them."""
    folder = os.path.join(results, name)
    figures = []
    for kind in SCENES:
        rows = [c for c in cells if c.scene == kind]
        used = stack_figures(results, [c.figure for c in rows],
                             os.path.join(folder, "fig-%s.png" % kind))
        if used:
            figures.append("`%s/fig-%s.png` (%s)" % (name, kind, ", ".join(
                c.preset for c in rows if c.figure in used)))
    fig10 = []
    for preset in PRESETS:
        if stack_figures(results, [c.dual.figure for c in cells
                                   if c.preset == preset and c.dual is not None],
                         os.path.join(folder, "fig10-%s.png" % preset)):
            fig10.append("`%s/fig10-%s.png`" % (name, preset))
    note = ("Figures, one row per material: reference | neural | heatmap of 1 - SSIM | "
            "equal-time fiber. Per scene: %s. Per row: `%s/<material>-<scene>.png`." % (
                "; ".join(figures) or "none yet", name))
    if fig10:
        note += (" Fig. 10 (one row per scene: fiber reference | dual-scattering baseline | "
                 "neural | 1 - SSIM of the baseline | 1 - SSIM of neural): %s." % ", ".join(fig10))
    return note


def caption(name):
    return (
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


def assemble(results, name):
    """RESULTS/NAME.md, .json and the stacked figures from the chunk files in RESULTS/NAME/:
    (the Markdown, the number of chunks, the missing (material, scene) pairs)."""
    cells = [chunk for _, chunk in chunk_files(os.path.join(results, name))]
    order = chunk_order()
    cells.sort(key=lambda c: order.index((c.preset, c.scene)))
    have = {(c.preset, c.scene) for c in cells}
    missing = [pk for pk in order if pk not in have]
    note = figure_note(results, name, cells)
    text = write_tables("Table 2 on this machine", caption(name), cells,
                        os.path.join(results, name + ".md"), missing=missing, figure_note=note)
    return text, len(cells), missing
