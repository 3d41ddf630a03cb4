#!/usr/bin/env python3
"""bench/family_render.py: the render cost of a family model (issue 42, docs/family.md).

One knit (`weft scene knit`), its 8 yarn curves split over 5 yarn entries, one
per preset (fleece, silk, polyester, cotton, gabardine), rendered twice in
neural mode, each in its own process, in one run:
  - dedicated: each entry with the preset's shipped model (models/NAME.json)
    at its own colour;
  - family: each entry with the family model and the preset's parameters in
    "yarn", at the preset's C_TT clamped into the family's colour range: 5
    different yarns of one family.
Reported: the scene's build seconds (loading the models and building each
yarn's tables: the issue's target is under 1 s), the seconds per spp
(target: family / dedicated <= 1.2) and, for information, the SSIM of the
family image against the dedicated one (`weft compare`). Writes
bench/results/family-render.md and .json.

    bench/family_render.py [--family models/family.json] [--weft build/release/weft]
                           [--size 256] [--spp 32] [--threads 2]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from any_colour import PRESETS  # noqa: E402  (Table 3)
from benchlib import now, write_results  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MATERIALS = ("fleece", "silk", "polyester", "cotton", "gabardine")


def run_json(cmd):
    r = subprocess.run([str(c) for c in cmd], check=True, stdout=subprocess.PIPE, text=True)
    lines = [l for l in r.stdout.splitlines() if l.strip()]
    return json.loads(lines[-1]) if lines else {}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--family", default=os.path.join(ROOT, "models", "family.json"))
    ap.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--work", default=os.path.join(ROOT, "bench", "work", "family-render"))
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "family-render.md"))
    a = ap.parse_args()
    weft, work = a.weft, a.work
    family_path = os.path.abspath(a.family)
    with open(family_path) as f:
        lo, hi = json.load(f)["colour"]["c_tt_range"]
    if os.path.isdir(work):
        shutil.rmtree(work)
    os.makedirs(work)
    run_json([weft, "scene", "knit", "--model", os.path.join(ROOT, "models", "fleece.json"),
              "--out", os.path.join(work, "knit")])
    with open(os.path.join(work, "knit", "scene.json")) as f:
        base = json.load(f)
    entry = base["yarns"][0]
    with open(os.path.join(work, "knit", entry["curves"])) as f:
        text = f.read()
    curves = [c.strip() for c in text.split("\n\n")]
    curves = ["\n".join(l for l in c.splitlines() if not l.startswith("#")) for c in curves]
    curves = [c for c in curves if c]
    groups = [curves[k::len(MATERIALS)] for k in range(len(MATERIALS))]
    for k, g in enumerate(groups):
        with open(os.path.join(work, "knit", f"yarn-{k}.txt"), "w") as f:
            f.write("\n\n".join(g) + "\n")
    results = {}
    for variant in ("dedicated", "family"):
        scene = dict(base)
        scene["film"] = {"width": a.size, "height": a.size}
        yarns = []
        for k, m in enumerate(MATERIALS):
            y = {key: entry[key] for key in ("plies", "ply_twist", "radius", "scale")}
            y["curves"] = f"yarn-{k}.txt"
            if variant == "dedicated":
                y["model"] = os.path.join(ROOT, "models", f"{m}.json")
            else:
                fiber_cr, c_tt, beta_r, beta_tt, gamma_tt, (n, rho, alpha) = PRESETS[m]
                y["model"] = family_path
                y["yarn"] = {"fibers": n, "density": rho, "twist": alpha, "beta_r_deg": beta_r,
                             "beta_tt_deg": beta_tt, "gamma_tt_deg": gamma_tt, "c_r": fiber_cr}
                y["colour"] = [min(max(c, lo), hi) for c in c_tt]
            yarns.append(y)
        scene["yarns"] = yarns
        path = os.path.join(work, "knit", f"{variant}.json")
        with open(path, "w") as f:
            json.dump(scene, f, indent=1)
        exr = os.path.join(work, f"{variant}.exr")
        run_json([weft, "render", path, "--mode", "neural", "--spp", a.spp, "--threads", a.threads,
                  "--quiet", "--out", exr])
        with open(os.path.join(work, f"{variant}.json")) as f:
            stats = json.load(f)
        results[variant] = {"build_seconds": stats["scene"]["build_seconds"],
                            "seconds_per_spp": stats["seconds_per_spp"],
                            "material_bytes": stats["scene"]["material_bytes"]}
    compare = run_json([weft, "compare", os.path.join(work, "family.exr"),
                        os.path.join(work, "dedicated.exr"), "--heatmap",
                        os.path.join(work, "ssim.png")])
    d, f = results["dedicated"], results["family"]
    ratio = f["seconds_per_spp"] / d["seconds_per_spp"]
    lines = [
        "# The render cost of a family model: 5 yarns, 5 parameter points",
        "",
        f"`bench/family_render.py --size {a.size} --spp {a.spp} --threads {a.threads}`, {now()}. "
        "A knit (`weft scene knit`) whose 8 yarn curves are split over 5 entries, one per "
        "preset; neural mode, each render in its own process. Build: the scene's "
        "`build_seconds` (models read, each yarn's tables built).",
        "",
        "| scene | build s | s/spp | s/spp ratio (family / dedicated; target <= 1.2) | material bytes | SSIM vs dedicated |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
        f"| dedicated (models/NAME.json) | {d['build_seconds']:.2f} | {d['seconds_per_spp']:.3f} | 1.00 "
        f"| {d['material_bytes']} | 1 |",
        f"| family (5 yarns of {os.path.basename(family_path)}) | {f['build_seconds']:.2f} | "
        f"{f['seconds_per_spp']:.3f} | {ratio:.2f} | {f['material_bytes']} | "
        f"{compare.get('ssim', float('nan')):.4f} |",
    ]
    write_results(a.out, lines, {"results": results, "ratio": ratio, "compare": compare,
                                 "size": a.size, "spp": a.spp, "threads": a.threads})


if __name__ == "__main__":
    main()
