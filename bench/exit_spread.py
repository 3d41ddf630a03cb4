#!/usr/bin/env python3
"""bench/exit_spread.py: what moving the exit point changes (issue 47, item 3),
one run.

For each preset given a model with an exit-offset table (`weft fit` with
"exit_offset": true, docs/exit-point.md) and each scene kind, the Table 2
scene (`weft scene KIND` of models/PRESET.json, as bench/table2.py makes it)
is rendered at the same spp (swatch-knit and swatch-woven: the real
swatches of data/curves as bench/shared_data.py lights and draws them, under
a sky and one sphere light):
  Fa, Fb  fiber mode, seeds 1 and 2 (the reference)
  Na, Nb  neural mode with models/PRESET.json (today's model), seeds 1 and 2
  Ea, Eb  neural mode with the exit model, seeds 1 and 2
in the order Fa, Fb, Na, Ea, Nb, Eb (the two neural models alternate, so
that a machine's drift falls on both). Per neural model X, against the
fibers (weights 1 / (F^2 + 0.01) as bench/fidelity_budget.py weighs, F the
mean of the fiber renders smoothed over 3 x 3 pixels, so that the weights do
not follow the noise they weigh):
  means       per channel, mean(X) / mean(F) over both seeds: the bias
  error       D(Xa, Fa) - vX - vF, the model's own error (Table 2's "relMSE
              minus both references' noise"), at K = 1 and 4 (both images
              averaged over K x K pixel blocks first), with D the weighted
              mean square difference and vX = D(Xa, Xb) / 2 the noise of one
              render
  SSIM        of the seed mean of X against that of F (`weft compare`, at
              --scale 1 and 4); both seed means' noise lowers it a little
  s/spp       render seconds per sample, and exit / today's ratio.

    bench/exit_spread.py --models fleece=FLEECE-EXIT.json [polyester=...]
        [--scenes weave knit weave-1ply closeup closeup-1ply swatch-knit swatch-woven]
        [--spp 256] [--size 128]
        [--weft build/release/weft]
        [--out bench/results/exit-spread.md]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from benchlib import binary_digest, now, table2_scene, write_results  # noqa: E402
from fidelity_budget import REL_MSE_EPSILON, blocks  # noqa: E402
import shared_data  # noqa: E402

SCALES = (1, 4)


def render(weft, scene, mode, spp, seed, threads, out, made_by=None):
    """Renders (unless `out` and its image.json are there from an earlier run
    with --work) and returns the render's statistics (weft render's JSON:
    seconds, rays, ...). With `made_by` (the
    binary's digest, benchlib.binary_digest) a cached render counts only if
    the same binary made it: OUT.made-by holds the digest of the one that did."""
    stats = os.path.splitext(out)[0] + ".json"
    stamp = out + ".made-by"
    done = os.path.exists(out) and os.path.exists(stats)
    if done:
        with open(stats) as f:
            done = not json.load(f).get("partial", False)  # stopped early (SIGTERM)
    if done and made_by is not None:
        done = made_by_of(out) == made_by
    if not done:
        if os.path.exists(stamp):
            os.remove(stamp)  # the render it named is replaced now
        subprocess.run([weft, "render", scene, "--mode", mode, "--spp", str(spp), "--seed",
                        str(seed), "--threads", str(threads), "--quiet", "--out", out],
                       check=True, stdout=subprocess.DEVNULL)
        if made_by is not None:
            with open(stamp, "w") as f:
                f.write(made_by + "\n")
    with open(stats) as f:
        return json.load(f)


def made_by_of(out):
    """The digest of the binary that made the render `out` (render()'s OUT.made-by), or None
    where it was not recorded."""
    try:
        with open(out + ".made-by") as f:
            return f.read().strip()
    except OSError:
        return None


def make_scene(weft, preset, kind, folder, size, patch):
    """The scene of `kind` with models/PRESET.json: a Table 2 scene (KIND or
    KIND-Nply, `weft scene KIND --plies N`, as bench/fidelity_budget.py's
    scenes with fewer contacts), or
    swatch-SWATCH of bench/shared_data.py; returns its scene.json."""
    if not kind.startswith("swatch-"):
        base, _, plies = kind.partition("-")
        if plies and not (plies.endswith("ply") and plies[:-3].isdigit()):
            sys.exit(f"bench/exit_spread: unknown scene {kind} (KIND or KIND-Nply)")
        return table2_scene(weft, preset, base, folder, size, patch,
                            ["--plies", plies[:-3]] if plies else [])
    files = dict(shared_data.SWATCHES)
    swatch = kind[len("swatch-"):]
    if swatch not in files:
        sys.exit(f"bench/exit_spread: unknown scene {kind} (swatch-" +
                 ", swatch-".join(files) + ")")
    os.makedirs(folder, exist_ok=True)
    bcc = os.path.join(shared_data.SHARED, files[swatch])
    radius = shared_data.swatch_radius(weft, bcc, folder)
    scene = shared_data.swatch_scene(folder, "scene", bcc,
                                     os.path.join(ROOT, "models", preset + ".json"), size, 1, radius)
    return scene


def with_model(scene, model, out):
    """scene.json with every yarn's model replaced by `model`, written as `out`."""
    with open(scene) as f:
        desc = json.load(f)
    for yarn in desc["yarns"]:
        yarn["model"] = os.path.abspath(model)
    with open(out, "w") as f:
        json.dump(desc, f)
    return out


def smooth(image, np):
    """The image's 3 x 3 box average (edges repeated)."""
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = image.shape[:2]
    return sum(padded[i:i + h, j:j + w] for i in range(3) for j in range(3)) / 9.0


def model_metrics(img, name, np):
    """Means ratio and the model's own error per block size for renders
    img[name + 'a'], img[name + 'b'] against img['Fa'], img['Fb']; also the
    error with each channel of the neural renders scaled to the fibers' mean
    ("matched": what no per-channel brightness can remove)."""
    fiber_mean = (img["Fa"].reshape(-1, 3).mean(axis=0) + img["Fb"].reshape(-1, 3).mean(axis=0))
    mine = img[name + "a"].reshape(-1, 3).mean(axis=0) + img[name + "b"].reshape(-1, 3).mean(axis=0)
    errors = {}
    for k in SCALES:
        b = {key: blocks(x, k) for key, x in img.items()}
        # The weights from the fiber mean smoothed over 3 x 3 blocks, so that
        # they do not follow the noise of the renders they weigh.
        reference = smooth((b["Fa"] + b["Fb"]) / 2, np)
        w = 1.0 / (reference * reference + REL_MSE_EPSILON)

        def d(x, y):
            return float(np.mean(w * (x - y) ** 2))

        noise_fiber = d(b["Fa"], b["Fb"]) / 2
        noise = d(b[name + "a"], b[name + "b"]) / 2
        scale = fiber_mean / mine
        errors[k] = {"error": d(b[name + "a"], b["Fa"]) - noise - noise_fiber,
                     "noise": noise, "noise_fiber": noise_fiber,
                     "error_matched": d(b[name + "a"] * scale, b["Fa"]) -
                     noise * float(np.mean(scale * scale)) - noise_fiber}
    return {"means": [float(x) for x in mine / fiber_mean], "by_scale": errors}


def compare(weft, a, b, scale):
    """`weft compare A B --scale K`'s JSON line (SSIM, relative MSE, mean ratio), B the reference."""
    line = subprocess.run([weft, "compare", a, b, "--scale", str(scale)], check=True,
                          stdout=subprocess.PIPE, text=True).stdout
    return json.loads(line)


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--python", default=os.path.join(ROOT, "build", "release", "python"),
                   help="folder of the weft Python module (images are read and written with it)")
    p.add_argument("--models", nargs="+", required=True, help="PRESET=MODEL.json with exit offsets")
    p.add_argument("--scenes", nargs="+", default=["weave", "knit"])
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--patch", type=int, default=3)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "exit-spread.md"))
    p.add_argument("--work", help="keep the renders in this folder and reuse those already "
                   "there (same settings: the folder is not checked)")
    p.add_argument("--fiber-only", action="store_true",
                   help="render the fiber references only (into --work) and stop: they may run "
                   "beside other work, the neural renders, which are timed, not")
    a = p.parse_args()
    if a.fiber_only and not a.work:
        sys.exit("bench/exit_spread: --fiber-only needs --work")
    sys.path.insert(0, a.python)
    import numpy as np
    import weft

    models = dict(m.split("=", 1) for m in a.models)
    results = {"date": now(), "spp": a.spp, "size": a.size, "patch": a.patch, "models": a.models,
               "weft": binary_digest(a.weft), "rows": []}
    lines = [
        "# The exit spread against the fibers",
        "",
        f"`bench/exit_spread.py --models {' '.join(a.models)} --scenes {' '.join(a.scenes)} "
        f"--spp {a.spp} --size {a.size}` "
        f"({results['date']}): each "
        f"scene as bench/table2.py makes it (`weft scene KIND --size {a.patch}`, KIND-Nply "
        f"with `--plies N`, {a.size} x {a.size} px; swatch-*: a swatch of data/curves as bench/shared_data.py draws it, "
        f"under a sky and one sphere light), {a.spp} spp per render, two seeds per mode; "
        "*today*: neural mode with "
        "models/PRESET.json, *exit*: with the model fitted with exit offsets "
        "(docs/exit-point.md). *error*: one neural render against one fiber render less both "
        "renders' noise (Table 2's relMSE minus noise), at full resolution and over 4 x 4 px "
        "blocks; SSIM of the seed means; s/spp of the neural renders, made alternately.",
        "",
        "| scene | model | neural / fiber means r / g / b | error | error 4x4 px | noise | SSIM | "
        "SSIM 4x4 px | s/spp |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    with tempfile.TemporaryDirectory(prefix="weft-exit-spread-") as tmp:
        work = a.work or tmp
        os.makedirs(work, exist_ok=True)
        for preset, exit_model in models.items():
            for kind in a.scenes:
                folder = os.path.join(work, f"{preset}-{kind}")
                scene = os.path.join(folder, "scene.json")
                if not os.path.exists(scene):
                    scene = make_scene(a.weft, preset, kind, folder, a.size, a.patch)
                exit_scene = with_model(scene, exit_model, os.path.join(folder, "exit.json"))
                img, seconds, rays = {}, {"N": [], "E": []}, {"N": [], "E": []}
                for key, mode, path, seed in (("Fa", "fiber", scene, 1), ("Fb", "fiber", scene, 2),
                                              ("Na", "neural", scene, 1),
                                              ("Ea", "neural", exit_scene, 1),
                                              ("Nb", "neural", scene, 2),
                                              ("Eb", "neural", exit_scene, 2)):
                    if a.fiber_only and mode != "fiber":
                        break
                    out = os.path.join(folder, key + ".exr")
                    s = render(a.weft, path, mode, a.spp, seed, a.threads, out)
                    if mode == "neural":
                        seconds[key[0]].append(s["seconds"] / a.spp)
                        rays[key[0]].append(s["rays"] / a.spp)
                    img[key] = np.asarray(weft.read_image(out), dtype=np.float64)
                    print(f"[exit_spread] {preset} {kind} {key}", flush=True)
                if a.fiber_only:
                    continue
                # Seed means, for SSIM.
                for key in ("F", "N", "E"):
                    weft.save_image(os.path.join(folder, key + ".exr"),
                                    ((img[key + "a"] + img[key + "b"]) / 2).astype(np.float32))
                row = {"preset": preset, "scene": kind}
                for key, label in (("N", "today"), ("E", "exit")):
                    m = model_metrics(img, key, np)
                    m["ssim"] = {str(k): compare(a.weft, os.path.join(folder, key + ".exr"),
                                                 os.path.join(folder, "F.exr"), k)["ssim"]
                                 for k in SCALES}
                    m["seconds_per_spp"] = sum(seconds[key]) / len(seconds[key])
                    m["rays_per_spp"] = sum(rays[key]) / len(rays[key])
                    row[label] = m
                    lines.append(
                        f"| {preset} {kind} | {label} | " +
                        " / ".join(f"{x:.3f}" for x in m["means"]) +
                        f" | {m['by_scale'][1]['error']:.4f} | {m['by_scale'][4]['error']:.4f} | "
                        f"{m['by_scale'][1]['noise']:.5f} | "
                        f"{m['ssim']['1']:.3f} | {m['ssim']['4']:.3f} | "
                        f"{m['seconds_per_spp']:.4f} |")
                row["seconds_ratio"] = row["exit"]["seconds_per_spp"] / row["today"]["seconds_per_spp"]
                row["rays_ratio"] = row["exit"]["rays_per_spp"] / row["today"]["rays_per_spp"]
                row["noise_ratio"] = (row["exit"]["by_scale"][1]["noise"] /
                                      row["today"]["by_scale"][1]["noise"])
                results["rows"].append(row)
    if a.fiber_only:
        return
    lines += ["", "*noise*: of one render at full resolution (the weighted mean square "
              "difference of its two seeds, over 2). Exit / today's s/spp: " + ", ".join(
                  f"{r['preset']} {r['scene']} {r['seconds_ratio']:.2f}" for r in results["rows"]),
              "", "The model's own error at full resolution with each channel's mean matched "
              "to the fibers' (today -> exit; what no per-channel brightness removes): " +
              ", ".join(f"{r['preset']} {r['scene']} "
                        f"{r['today']['by_scale'][1]['error_matched']:.4f} -> "
                        f"{r['exit']['by_scale'][1]['error_matched']:.4f}"
                        for r in results["rows"]),
              "", "Exit / today's rays per spp (closest-hit and shadow queries): " + ", ".join(
                  f"{r['preset']} {r['scene']} {r['rays_ratio']:.2f}" for r in results["rows"]),
              "", "Exit / today's noise: " + ", ".join(
                  f"{r['preset']} {r['scene']} {r['noise_ratio']:.2f}" for r in results["rows"]),
              "", "Exit / today's noise x s/spp (time to equal noise): " + ", ".join(
                  f"{r['preset']} {r['scene']} {r['noise_ratio'] * r['seconds_ratio']:.2f}"
                  for r in results["rows"]), ""]
    write_results(a.out, lines, results)


if __name__ == "__main__":
    main()
