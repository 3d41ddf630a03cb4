"""The chunks' fixed choices: materials, scenes, default sizes and sample counts, ladders,
seeds (docs/bench-table2.md, "Defaults and sizes")."""
import os

import benchlib

ROOT = benchlib.ROOT
PRESETS = ["fleece", "silk", "polyester", "cotton", "gabardine"]
SCENES = ["closeup", "weave", "knit"]
TARGET_REL_MSE = 0.01
# The paper's reference sample counts (Table 2).
PAPER_REF_SPP = {"fleece": 1024, "silk": 4096, "polyester": 1024, "cotton": 4096,
                 "gabardine": 1024}
# Default image side per chunk (docs/bench-table2.md for the estimates behind it).
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
QUICK_LADDER = (16, 4)
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
BUDGET_MINUTES = 60
# The Table 2 files: RESULTS/NAME.md, .json and RESULTS/NAME/ (chunk files and figures).
DEFAULT_NAME = "table2"
QUICK_NAME = "table2-quick"


def chunk_defaults(preset, kind):
    """A chunk's default settings (each one a flag of bench/table2.py)."""
    return {"size": DEFAULT_SIZE[(preset, kind)], "ref_spp": PAPER_REF_SPP[preset],
            "patch": DEFAULT_PATCH,
            "fiber_ladder": list(DEFAULT_FIBER_LADDER.get((preset, kind), DEFAULT_LADDER)),
            "neural_ladder": list(DEFAULT_LADDER),
            "ref_parts": DEFAULT_REF_PARTS.get((preset, kind), 1)}


def chunk_order():
    """Every (material, scene), in the table's order."""
    return [(p, k) for p in PRESETS for k in SCENES]


def chunk_path(folder, preset, kind):
    return os.path.join(folder, "%s-%s.json" % (preset, kind))


def chunk_command(preset, kind, extra=""):
    return "bench/table2.py --chunk %s,%s%s" % (preset, kind, extra)


def shown_arguments(argv, drop=(), drop_flags=()):
    """The command's flags for captions and chunk files, without machine-local paths (and
    without `drop` flags with a value and `drop_flags` flags without one)."""
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
