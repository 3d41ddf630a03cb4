#!/usr/bin/env python3
"""bench/batched_shading.py: neural s/spp with the batched integrator against the per-path one (issue 45).

For each material and scene (`weft scene weave|knit`, Table 2's sky and two
sphere lights), renders the same scene in neural mode with `--integrator path`
and `--integrator batch`, alternating, `--rounds` times each, and takes each
integrator's fastest s/spp (on a shared machine noise only adds time). The two
images must be the same bit for bit (the EXR files are compared); a
difference is reported in the table and makes the exit status 1. Writes
bench/results/batched-shading.md and .json (--out).

    bench/batched_shading.py [--materials polyester,silk,fleece,cotton,gabardine]
                             [--scenes weave,knit] [--size 128] [--spp 32] [--rounds 3] [--threads 2]
"""
import argparse
import filecmp
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from benchlib import write_results  # noqa: E402


def render(weft, folder, integrator, spp, threads, name):
    image = os.path.join(folder, name + ".exr")
    subprocess.run([weft, "render", os.path.join(folder, "scene.json"), "--mode", "neural", "--spp",
                    str(spp), "--threads", str(threads), "--seed", "1", "--quiet", "--integrator",
                    integrator, "--out", image], check=True, capture_output=True)
    with open(os.path.join(folder, name + ".json")) as f:
        return image, json.load(f)["seconds_per_spp"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    ap.add_argument("--materials", default="polyester,silk,fleece,cotton,gabardine")
    ap.add_argument("--scenes", default="weave,knit")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "batched-shading.md"))
    a = ap.parse_args()
    rows, same_everywhere = [], True
    with tempfile.TemporaryDirectory() as tmp:
        for material in a.materials.split(","):
            for kind in a.scenes.split(","):
                folder = os.path.join(tmp, material + "-" + kind)
                subprocess.run([a.weft, "scene", kind, "--model",
                                os.path.join(ROOT, "models", material + ".json"), "--width",
                                str(a.size), "--height", str(a.size), "--out", folder],
                               check=True, capture_output=True)
                times = {"path": [], "batch": []}
                images = {}
                for r in range(a.rounds):
                    for integrator in ("path", "batch"):
                        image, s = render(a.weft, folder, integrator, a.spp, a.threads,
                                          f"{integrator}-{r}")
                        times[integrator].append(s)
                        images.setdefault(integrator, image)
                same = filecmp.cmp(images["path"], images["batch"], shallow=False)
                same_everywhere &= same
                path_s, batch_s = min(times["path"]), min(times["batch"])
                rows.append({"material": material, "scene": kind, "path_s_per_spp": path_s,
                             "batch_s_per_spp": batch_s, "ratio": batch_s / path_s,
                             "same_image": same, "path_runs": times["path"],
                             "batch_runs": times["batch"]})
                print(f"{material} {kind}: path {path_s:.4f}, batch {batch_s:.4f} s/spp, "
                      f"ratio {batch_s / path_s:.3f}, same image {same}", file=sys.stderr)
    lines = ["# Batched shading against one path at a time (bench/batched_shading.py)", "",
             f"Neural mode, `weft scene` weave and knit (sky and two sphere lights), {a.size} x "
             f"{a.size}, {a.spp} spp, {a.threads} threads, seed 1; `--integrator path` and "
             f"`--integrator batch` alternating, {a.rounds} runs each, the fastest s/spp of each. "
             "Same image: the two EXR files are equal byte for byte.", "",
             "| material | scene | path s/spp | batch s/spp | batch / path | same image |",
             "| --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['material']} | {r['scene']} | {r['path_s_per_spp']:.4f} | "
                     f"{r['batch_s_per_spp']:.4f} | {r['ratio']:.3f} | "
                     f"{'yes' if r['same_image'] else 'NO'} |")
    lines += ["", "Command: `bench/batched_shading.py --materials " + a.materials + " --scenes " +
              a.scenes + f" --size {a.size} --spp {a.spp} --rounds {a.rounds} --threads {a.threads}`",
              ""]
    write_results(a.out, lines, {"size": a.size, "spp": a.spp, "threads": a.threads,
                                 "rounds": a.rounds, "rows": rows})
    return 0 if same_everywhere else 1


if __name__ == "__main__":
    sys.exit(main())
