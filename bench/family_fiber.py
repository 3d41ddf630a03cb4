#!/usr/bin/env python3
"""bench/family_fiber.py: the family model against the fibers (issue 42, docs/family.md).

Table 2's knit (`weft scene knit`, a 3 x 3 patch, 128 x 128) at a few yarns,
each rendered three times in one run:
  - fiber: the explicit fibers of the yarn's dedicated model (its fiber and
    ply), the reference, at --ref-spp;
  - dedicated: neural mode with that dedicated model;
  - family: neural mode with the family model at the same yarn (the dedicated
    model's fiber and ply parameters in "yarn", its C_TT as the colour).
The yarns: fleece and cotton (models/NAME.json) and held-out yarn K of
bench/family.py (its dedicated fit, WORK/held-K-dedicated.json, a yarn of the
box no family training yarn lies on). Reported per yarn: SSIM at 4 x 4 pixel
blocks against the fiber reference (`weft compare --scale 4`: the ply-scale
structure) for both neural images and their difference (target: the family
within 0.01 of the dedicated model), and each neural image's per-channel
means over the fiber reference's, with family / dedicated per channel
(target: within 2 %). Writes bench/results/family-fiber.md and .json.

    bench/family_fiber.py [--family models/family.json] [--weft build/release/weft]
                          [--held-work bench/work/family] [--held 0] [--size 128]
                          [--ref-spp 256] [--spp 256] [--threads 0] [--work DIR]

About 6 minutes per yarn on 2 cores at the defaults (the fiber reference is
most of it); renders are cached in --work by their command line.
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from benchlib import cached, cached_run, now, portable_path, run, write_results  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROGRAM = "bench/family_fiber.py"
SSIM_TARGET = 0.01
MEAN_TARGET = 0.02


def compare(weft, image, reference, scale):
    line = run([weft, "compare", image, reference, "--scale", scale], PROGRAM).strip().splitlines()
    return json.loads(line[-1])


def yarn_of(model):
    """The family "yarn" object and colour of a dedicated model: its fiber and ply."""
    with open(model) as f:
        m = json.load(f)
    fiber, ply = m["fiber"], m["ply"]
    yarn = {"fibers": ply["fibers"], "density": ply["density"], "twist": ply["twist"],
            "beta_r_deg": fiber["beta_r_deg"], "beta_tt_deg": fiber["beta_tt_deg"],
            "gamma_tt_deg": fiber["gamma_tt_deg"], "c_r": fiber["c_r"]}
    return yarn, fiber["c_tt"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--family", default=os.path.join(ROOT, "models", "family.json"))
    ap.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    ap.add_argument("--presets", default="fleece,cotton")
    ap.add_argument("--held-work", default=os.path.join(ROOT, "bench", "work", "family"),
                    help="bench/family.py's --work folder (its held-out dedicated fits)")
    ap.add_argument("--held", default="0", help="held-out yarns of --held-work, e.g. 0,3 ('' for none)")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--patch", type=int, default=3)
    ap.add_argument("--ref-spp", type=int, default=256)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--work", default=os.path.join(ROOT, "bench", "work", "family-fiber"))
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "family-fiber.md"))
    a = ap.parse_args()
    weft, family = a.weft, os.path.abspath(a.family)
    points = [(p, os.path.join(ROOT, "models", p + ".json")) for p in a.presets.split(",") if p]
    for k in (int(k) for k in a.held.split(",") if k):
        model = os.path.join(a.held_work, f"held-{k}-dedicated.json")
        if not os.path.exists(model):
            sys.exit(f"{PROGRAM}: {model} is missing: run bench/family.py --work {a.held_work} first")
        points.append((f"held-out {k}", model))
    render_flags = ["--threads", str(a.threads), "--seed", "1", "--quiet"]
    rows = []
    for name, dedicated in points:
        folder = os.path.join(a.work, name.replace(" ", "-"))
        yarn, colour = yarn_of(dedicated)
        scenes, scene_cmds = {}, {}
        for variant, model, extra in (
                ("dedicated", dedicated, []),
                ("family", family, ["--yarn", json.dumps(yarn), "--colours", ",".join(map(str, colour))])):
            scene_dir = os.path.join(folder, f"scene-{variant}")
            scene_cmds[variant] = [weft, "scene", "knit", "--model", os.path.abspath(model),
                                   "--size", str(a.patch), "--width", str(a.size), "--height",
                                   str(a.size), "--spp", "1", "--quiet", "--out",
                                   os.path.join(scene_dir, "s")] + extra
            cached_run(scene_dir, scene_cmds[variant], PROGRAM)
            scenes[variant] = os.path.join(scene_dir, "s", "scene.json")
        images, stats = {}, {}
        for variant, scene, mode, spp in (("fiber", scenes["dedicated"], "fiber", a.ref_spp),
                                          ("dedicated", scenes["dedicated"], "neural", a.spp),
                                          ("family", scenes["family"], "neural", a.spp)):
            out = os.path.join(folder, f"render-{variant}")
            images[variant] = os.path.join(out, "image.exr")
            cmd = [weft, "render", scene, "--mode", mode, "--spp", str(spp)] + render_flags + [
                "--out", images[variant]]
            # Keyed by the scene's command too: a new scene renders again.
            cached(out, {"render": cmd, "scene": scene_cmds["family" if variant == "family" else "dedicated"]},
                   lambda _: run(cmd, PROGRAM))
            with open(os.path.join(out, "image.json")) as f:
                stats[variant] = json.load(f)
        score = {v: compare(weft, images[v], images["fiber"], 4) for v in ("dedicated", "family")}
        mean = {v: score[v]["mean_ratio"] for v in score}
        family_over_dedicated = [f / d for f, d in zip(mean["family"], mean["dedicated"])]
        rows.append({"point": name, "dedicated_model": portable_path(dedicated), "yarn": yarn,
                     "c_tt": colour, "ssim4": {v: score[v]["ssim"] for v in score},
                     "ssim4_difference": score["dedicated"]["ssim"] - score["family"]["ssim"],
                     "mean_over_fiber": mean, "mean_ratio": family_over_dedicated,
                     "seconds_per_spp": {v: stats[v]["seconds_per_spp"] for v in stats}})
        print(f"{name}: done", flush=True)

    def triple(v):
        return " ".join(f"{x:.3f}" for x in v)

    lines = [
        "# The family model against the fibers: Table 2's knit",
        "",
        f"`bench/family_fiber.py --held {a.held} --size {a.size} --ref-spp {a.ref_spp} --spp {a.spp}`, "
        f"{now()}. Table 2's knit ({a.patch} x {a.patch} loops, {a.size} x {a.size}) at each yarn: "
        "the fiber reference (the dedicated model's fibers and ply), neural mode with the dedicated "
        f"model, and neural mode with `{os.path.basename(family)}` at the same yarn and C_TT. "
        "SSIM after averaging over 4 x 4 pixel blocks against the fiber reference (`weft compare "
        "--scale 4`); means: each image's per-channel mean over the reference's. Targets: SSIM "
        f"difference (dedicated - family) <= {SSIM_TARGET}, family / dedicated means within "
        f"{MEAN_TARGET:.0%}.",
        "",
        "| point | SSIM 4x4: dedicated | SSIM 4x4: family | SSIM difference | means / fiber: dedicated "
        "| means / fiber: family | means ratio (family / dedicated) |",
        "| --- | ---: | ---: | ---: | --- | --- | --- |",
    ]
    for r in rows:
        lines.append(f"| {r['point']} | {r['ssim4']['dedicated']:.4f} | {r['ssim4']['family']:.4f} | "
                     f"{r['ssim4_difference']:.4f} | {triple(r['mean_over_fiber']['dedicated'])} | "
                     f"{triple(r['mean_over_fiber']['family'])} | {triple(r['mean_ratio'])} |")
    lines.append("")
    write_results(a.out, lines, {"date": now(), "size": a.size, "patch": a.patch,
                                 "ref_spp": a.ref_spp, "spp": a.spp, "family": portable_path(family),
                                 "rows": rows})


if __name__ == "__main__":
    main()
