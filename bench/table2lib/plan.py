"""--plan: each chunk's expected minutes on 2 cores, from the row's last chunk file or else the
quick table (docs/bench-table2.md, "Defaults and sizes")."""
import json
import os

from .config import BUDGET_MINUTES, PRESETS, ROOT, SCENES, TARGET_REL_MSE, chunk_path
from .schema import load_chunk, to_dict
from .stats import ladder_spp


def max_depth_measured():
    """bench/results/max-depth.json's rows by (preset, scene), or {} when it is missing."""
    path = os.path.join(ROOT, "bench", "results", "max-depth.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return {(r["preset"], r["scene"]): r for r in json.load(f)["rows"]}


def load_timings(results, name="table2"):
    """Per (preset, scene), the timings the estimates start from: the chunk file
    RESULTS/NAME/<preset>-<scene>.json, else the quick table's cell (RESULTS/table2-quick.json,
    or bench/results/'s: 128 px, made at max_depth 100), its fiber seconds per spp times
    bench/results/max-depth.json's time at 1000 over at 100 (up to 2x for cotton); {} if
    neither exists."""
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
            if os.path.exists(path):
                timings[(preset, kind)] = dict(to_dict(load_chunk(path)), source="last chunk")
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
