#!/usr/bin/env python3
"""bench/smooth_tangents.py: what the smooth shading tangent (issue 47, item 0)
changes in the fiber renders and in the neural-vs-fiber agreement, one run.

The tubes' shading tangent was the segment's own direction, which jumps at
every joint of a fiber's polyline; it is now the sampled curve's tangent
(render/tube_accel.h). For each Table 2 scene given (`weft scene`, made by
the `after` binary as bench/table2.py makes it), renders at the same spp:
fiber mode with the `before` and the `after` binary at seeds 1 and 2, and
neural mode with each at seed 1. Writes, per scene:
- fiber before vs after (seed 1 both): SSIM and relMSE of the change, beside
  the noise floor (before seed 1 vs before seed 2: what two seeds of one
  binary differ by);
- per-channel means after / before (fiber);
- neural vs fiber SSIM (full resolution and at 4 x 4 px) with each binary.

    bench/smooth_tangents.py --before OLD/weft [--after build/release/weft]
        [--scenes fleece,weave silk,knit] [--spp 256] [--size 128] [--threads 0]
        [--out bench/results/smooth-tangents.md]
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


def weft_json(cmd):
    out = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def render(weft, scene, mode, spp, seed, threads, out):
    subprocess.run([weft, "render", scene, "--mode", mode, "--spp", str(spp), "--seed",
                    str(seed), "--threads", str(threads), "--quiet", "--out", out], check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.splitext(out)[0] + ".json") as f:
        return json.load(f)


def compare(weft, a, b, scale=1):
    return weft_json([weft, "compare", a, b, "--scale", str(scale)])


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--before", required=True, help="weft binary with segment tangents")
    p.add_argument("--after", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--scenes", nargs="+", default=["fleece,weave", "silk,knit"])
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--patch", type=int, default=3)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "smooth-tangents.md"))
    a = p.parse_args()
    results = {"date": now(), "spp": a.spp, "size": a.size, "patch": a.patch,
               "before": binary_digest(a.before), "after": binary_digest(a.after), "rows": []}
    lines = [
        "# Smooth shading tangents: fiber renders before and after, one run",
        "",
        f"`bench/smooth_tangents.py --spp {a.spp} --size {a.size}` ({results['date']}); "
        "each scene as bench/table2.py makes it (`weft scene KIND --size "
        f"{a.patch}`), fiber and neural mode at {a.spp} spp. *change*: fiber before vs after "
        "at the same seed; *noise*: fiber before at seeds 1 and 2. The neural-vs-fiber SSIM "
        "pairs each binary's own renders (seed 1), full resolution and at 4 x 4 px. Paths of "
        "the same seed part ways after the first bounce the tangent changes, so the change "
        "columns hold some noise too: they bound the change from above.",
        "",
        "| scene | SSIM change | SSIM noise | relMSE change | relMSE noise | fiber means after / before (r, g, b) | neural vs fiber SSIM before | after | at 4 x 4 px before | after |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    with tempfile.TemporaryDirectory(prefix="weft-tangents-") as work:
        for spec in a.scenes:
            preset, kind = spec.split(",")
            folder = os.path.join(work, f"{preset}-{kind}")
            scene = table2_scene(a.after, preset, kind, folder, a.size, a.patch)
            img = {}
            stats = {}
            for name, weft, mode, seed in (("fb1", a.before, "fiber", 1), ("fb2", a.before, "fiber", 2),
                                           ("fa1", a.after, "fiber", 1), ("nb1", a.before, "neural", 1),
                                           ("na1", a.after, "neural", 1)):
                img[name] = os.path.join(folder, name + ".exr")
                stats[name] = render(weft, scene, mode, a.spp, seed, a.threads, img[name])
                print(f"[smooth_tangents] {spec} {name}: {stats[name]['seconds']:.1f} s", flush=True)
            change = compare(a.after, img["fa1"], img["fb1"])
            noise = compare(a.after, img["fb2"], img["fb1"])
            nf = {k: compare(a.after, img["n" + k + "1"], img["f" + k + "1"]) for k in "ba"}
            nf4 = {k: compare(a.after, img["n" + k + "1"], img["f" + k + "1"], 4) for k in "ba"}
            means = change["mean_ratio"]  # per channel, after / before
            row = {"scene": spec, "ssim_change": change["ssim"], "ssim_noise": noise["ssim"],
                   "rel_mse_change": change["rel_mse"], "rel_mse_noise": noise["rel_mse"],
                   "fiber_mean_ratio": means,
                   "neural_vs_fiber_ssim": {"before": nf["b"]["ssim"], "after": nf["a"]["ssim"]},
                   "neural_vs_fiber_ssim_4px": {"before": nf4["b"]["ssim"],
                                                "after": nf4["a"]["ssim"]}}
            results["rows"].append(row)
            lines.append(
                f"| {preset} {kind} | {row['ssim_change']:.4f} | {row['ssim_noise']:.4f} | "
                f"{row['rel_mse_change']:.4f} | {row['rel_mse_noise']:.4f} | "
                + " / ".join("-" if m is None else f"{m:.3f}" for m in means)
                + f" | {nf['b']['ssim']:.3f} | {nf['a']['ssim']:.3f} | "
                f"{nf4['b']['ssim']:.3f} | {nf4['a']['ssim']:.3f} |")
    write_results(a.out, lines + [""], results)


if __name__ == "__main__":
    main()
