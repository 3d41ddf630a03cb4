#!/usr/bin/env python3
"""bench/exit_distance.py: how far light travels inside each material's ply.

The yarn model assumes that light leaves a ply where it entered (paper 8,
"Limitations"; very high albedo, such as cotton's C_TT = 0.999, breaks it).
`weft gather` measures, for every M path (multiple scattering), the distance
between its entry and exit points along the ply's bounding cylinder
(docs/gather.md#exit-distance). This program gathers each preset's ply (the
shipped models' fiber and ply parameters, models/README.md) and reports per
material, in one run:

  - the M albedo (M weight per path, averaged over incident directions) and
    the weighted mean, median and 90th percentile of the exit distance, in
    ply radii, in the channel with the most M light;
  - the same distances in pixels of Table 2's weave and knit renders (ply
    radius in pixels from the chunk's scene: `weft scene`'s yarn radius,
    plies, camera and film), beside the chunk's SSIM at 4 x 4 px blocks and
    its "relMSE minus noise" (the model's error) from
    bench/results/table2.json, where those exist;
  - the signed offsets' spread along and around the axis, and their
    correlation, per band of incident angle (docs/gather.md#exit-offset).

Writes bench/results/exit-distance.md and .json (or --out).

    bench/exit_distance.py [--weft build/release/weft] [--paths 200000]
                           [--presets fleece,silk,polyester,cotton,gabardine]

About 5 minutes on 2 cores at the default (cotton's long walks are most of it).
"""
import argparse
import datetime
import json
import math
import os
import sys
import tempfile

import benchlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRESETS = ("fleece", "silk", "polyester", "cotton", "gabardine")
SCENES = ("weave", "knit")


def run(cmd):
    return benchlib.run(cmd, "exit_distance")


def ply_radius_px(weft, preset, kind, size, work):
    """Ply radius in pixels at the centre of Table 2's scene (`weft scene KIND --size 3`)."""
    out = os.path.join(work, "scene-%s-%s-%d" % (preset, kind, size))
    run([weft, "scene", kind, "--model", os.path.join(ROOT, "models", preset + ".json"),
         "--width", str(size), "--height", str(size), "--spp", "1", "--size", "3", "--out", out])
    with open(os.path.join(out, "scene.json")) as f:
        s = json.load(f)
    cam, yarn = s["camera"], s["yarns"][0]
    distance = math.dist(cam["from"], cam["to"])
    pixel = 2 * distance * math.tan(math.radians(cam["fov_deg"]) / 2) / s["film"]["width"]
    plies = yarn.get("plies", 1)
    radius = yarn["radius"] * yarn.get("scale", 1.0)
    if plies > 1:  # render/yarn_geometry.cpp plyRadius: plies touching around the centre
        sine = math.sin(math.pi / plies)
        radius *= sine / (1 + sine)
    return radius / pixel


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--paths", type=int, default=200000)
    p.add_argument("--presets", default=",".join(PRESETS))
    p.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "weft-exit-distance"))
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "exit-distance.md"))
    args = p.parse_args()
    if not os.path.exists(args.weft):
        sys.exit("exit_distance: no weft binary at %s (build first, or give --weft)" % args.weft)
    presets = args.presets.split(",")
    for preset in presets:
        if preset not in PRESETS:
            sys.exit("exit_distance: --presets: unknown %r (allowed %s)" % (preset,
                                                                            ", ".join(PRESETS)))
    os.makedirs(args.work, exist_ok=True)
    table2 = {}
    t2 = os.path.join(ROOT, "bench", "results", "table2.json")
    if os.path.exists(t2):
        with open(t2) as f:
            table2 = {(c["preset"], c["scene"]): c for c in json.load(f)["cells"]}
    rows = []
    for preset in presets:
        out = os.path.join(args.work, preset)
        print("exit_distance: gather %s, %d paths" % (preset, args.paths), flush=True)
        summary = json.loads(run([args.weft, "gather", "--preset", preset, "--paths",
                                  str(args.paths), "--seed", "1", "--quiet", "--out", out]))
        with open(os.path.join(out, "meta.json")) as f:
            meta = json.load(f)
        e = meta["exit_distance"]
        # The channel with the most M light: the one that shows a transport error most.
        c = max(range(3), key=lambda k: e["m_weight"][k])
        row = {"preset": preset, "paths": args.paths, "mean_depth": meta["mean_depth"],
               "c_tt": meta["fiber"]["c_tt"], "exit_distance": e, "channel": c,
               "m_albedo": e["m_weight"][c], "mean": e["mean"][c], "median": e["median"][c],
               "p90": e["p90"][c], "beyond_fraction": e["beyond_fraction"][c],
               "gather_seconds": summary["seconds"], "scenes": {},
               "exit_offset": meta.get("exit_offset")}
        for kind in SCENES:
            cell = table2.get((preset, kind))
            size = cell["size"] if cell else 256
            px = ply_radius_px(args.weft, preset, kind, size, args.work)
            scene = {"size": size, "ply_radius_px": px, "median_px": row["median"] * px,
                     "p90_px": row["p90"] * px}
            if cell:
                scene["ssim"] = cell["ssim"]
                scene["ssim_4x4"] = cell.get("ssim_scales", {}).get("4")
                scene["rel_mse_minus_noise"] = cell["rel_mse_minus_noise"]
            row["scenes"][kind] = scene
        rows.append(row)

    lines = [
        "# How far light travels in the ply (M paths)",
        "",
        "Made by `bench/exit_distance.py` on %s: `weft gather --preset P --paths %d --seed 1` "
        "per material, in one run. Distance from entry to exit along the ply's bounding "
        "cylinder, in ply radii (docs/gather.md#exit-distance), weighted by the M path weight, "
        "in the channel with the most M light (R, G, B = 0, 1, 2); the model assumes 0. Pixels: the ply radius in Table 2's weave "
        "and knit renders (at the chunk's resolution), beside the chunk's SSIM of neural vs "
        "the fiber reference at full resolution and at 4 x 4 px blocks and its relMSE minus "
        "the references' noise (the model's own error), from bench/results/table2.json."
        % (datetime.date.today().isoformat(), args.paths),
        "",
        "| material | C_TT | mean depth | channel | M albedo | mean | median | 90th pct "
        "| beyond 16 R | gather s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append("| %s | %s | %.1f | %d | %.3f | %.2f | %.2f | %.2f | %.3f | %.0f |" % (
            r["preset"], ", ".join("%.3g" % c for c in r["c_tt"]), r["mean_depth"],
            r["channel"], r["m_albedo"], r["mean"], r["median"], r["p90"], r["beyond_fraction"],
            r["gather_seconds"]))
    lines += ["", "| material | scene | px | ply radius px | median px | 90th pct px | SSIM "
              "| SSIM at 4x4 px | relMSE minus noise |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        for kind in SCENES:
            s = r["scenes"][kind]
            fmt = lambda v, f: "-" if v is None else f % v
            lines.append("| %s | %s | %d | %.1f | %.1f | %.1f | %s | %s | %s |" % (
                r["preset"], kind, s["size"], s["ply_radius_px"], s["median_px"], s["p90_px"],
                fmt(s.get("ssim"), "%.3f"), fmt(s.get("ssim_4x4"), "%.3f"),
                fmt(s.get("rel_mse_minus_noise"), "%.4f")))
    lines += ["", "Signed exit offsets (docs/gather.md#exit-offset), same channel, per band of "
              "theta_i from the normal (0-22.5, 22.5-45, 45-67.5, 67.5-90 degrees): the standard "
              "deviation of the offset along the axis (dz, ply radii) and around it (dpsi, "
              "radians: ply radii of arc), and their correlation; every mean is within 0.06 "
              "of 0 (exit-distance.json has them).", "",
              "| material | sd dz by band | sd dpsi by band | correlation by band |",
              "|---|---|---|---|"]
    for r in rows:
        bands = r["exit_offset"]["theta_bands_summary"]
        c = r["channel"]
        lines.append("| %s | %s | %s | %s |" % (
            r["preset"], " / ".join("%.2f" % b["sd_dz"][c] for b in bands),
            " / ".join("%.2f" % b["sd_dpsi"][c] for b in bands),
            " / ".join("%.2f" % b["correlation"][c] for b in bands)))
    out_json = benchlib.write_md_and_json(args.out, "\n".join(lines) + "\n",
                                          {"paths": args.paths, "rows": rows})
    print("exit_distance: wrote %s and %s" % (args.out, out_json))


if __name__ == "__main__":
    main()
