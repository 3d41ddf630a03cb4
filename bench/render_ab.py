#!/usr/bin/env python3
"""bench/render_ab.py: render time of two weft binaries on the same scene, one run.

For a change that must not make rendering slower (e.g. issue 16's Bsdf
interface): renders the close-up of bench/render.py (one 3-ply yarn filling
the frame; sky and two sphere lights) in neural and fiber mode with a
`before` and an `after` binary at the same seed and spp. The runs alternate
(before, after, then after, before, ...) so that both binaries share the noise
of a busy machine. Writes, per mode, the medians of each binary's render
seconds (the render's own wall-clock "seconds": process start and scene build
excluded) and CPU seconds (user + system of the whole process, scene build
included: less sensitive to other work on the machine than wall-clock time),
the ratios after / before, and whether the two wrote byte-identical EXR
images, to bench/results/render-ab.md and .json.

    bench/render_ab.py --before ../baseline/build/weft --after build/weft
                       [--runs 3] [--size 128] [--spp-neural 64] [--spp-fiber 8]
                       [--threads 1] [--seed 1] [--model tests/data/fleece-small.json]
                       [--scene closeup|weave|knit] [--patch 3]
                       [--out bench/results/render-ab.md]

--scene weave or knit renders, instead of the close-up, the cloth that `weft scene`
makes (the Table 2 scenes of bench/table2.py: a patch x patch swatch, sky and two
sphere lights), made once by the `after` binary.
"""
import argparse
import filecmp
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from benchlib import portable_path, write_results  # noqa: E402
from render import closeup_scene  # noqa: E402


def render(weft, scene, mode, spp, threads, seed, out):
    cmd = [weft, "render", scene, "--mode", mode, "--spp", str(spp), "--threads", str(threads),
           "--seed", str(seed), "--quiet", "--out", out]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise subprocess.CalledProcessError(proc.returncode, cmd)
    with open(os.path.splitext(out)[0] + ".json") as f:
        return json.load(f)["seconds"], usage.ru_utime + usage.ru_stime


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--before", required=True, help="weft binary before the change")
    p.add_argument("--after", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--model", default=os.path.join(ROOT, "tests", "data", "fleece-small.json"))
    p.add_argument("--runs", type=int, default=3, help="runs per binary and mode")
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--spp-neural", type=int, default=64)
    p.add_argument("--spp-fiber", type=int, default=8)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--scene", choices=("closeup", "weave", "knit"), default="closeup")
    p.add_argument("--patch", type=int, default=3, help="weave / knit: swatch size (weft scene --size)")
    p.add_argument("--title", default="before / after")
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "render-ab.md"))
    a = p.parse_args()
    binaries = {"before": os.path.abspath(a.before), "after": os.path.abspath(a.after)}
    spp = {"neural": a.spp_neural, "fiber": a.spp_fiber}

    results = {"settings": vars(a), "load_average_start": os.getloadavg(), "modes": {}}
    with tempfile.TemporaryDirectory(prefix="weft-bench-ab-") as tmp:
        if a.scene == "closeup":
            scene = closeup_scene(tmp, a.model, a.size)
        else:
            subprocess.run([binaries["after"], "scene", a.scene, "--model", os.path.abspath(a.model),
                            "--width", str(a.size), "--height", str(a.size), "--spp", "1",
                            "--size", str(a.patch), "--out", os.path.join(tmp, "s")],
                           check=True, stdout=subprocess.DEVNULL)
            scene = os.path.join(tmp, "s", "scene.json")
        for mode in ("neural", "fiber"):
            seconds = {"before": [], "after": []}
            cpu = {"before": [], "after": []}
            for r in range(a.runs):
                for which in (("before", "after") if r % 2 == 0 else ("after", "before")):
                    out = os.path.join(tmp, "%s-%s.exr" % (mode, which))
                    s, c = render(binaries[which], scene, mode, spp[mode], a.threads, a.seed, out)
                    seconds[which].append(s)
                    cpu[which].append(c)
                    print("bench/render_ab: %s %s run %d: %.3f s, %.3f s CPU"
                          % (mode, which, r + 1, s, c), file=sys.stderr)
            identical = filecmp.cmp(os.path.join(tmp, "%s-before.exr" % mode),
                                    os.path.join(tmp, "%s-after.exr" % mode), shallow=False)
            b, f = statistics.median(seconds["before"]), statistics.median(seconds["after"])
            cb, cf = statistics.median(cpu["before"]), statistics.median(cpu["after"])
            results["modes"][mode] = {"spp": spp[mode], "seconds": seconds, "cpu_seconds": cpu,
                                      "median_before": b, "median_after": f, "ratio": f / b,
                                      "median_cpu_before": cb, "median_cpu_after": cf,
                                      "cpu_ratio": cf / cb, "identical_exr": identical}
    results["load_average_end"] = os.getloadavg()

    lines = [
        "# Render time, %s (bench/render_ab.py)" % a.title,
        "",
        "%s, %dx%d, model `%s`, seed %d, %d thread(s); %d runs per "
        "binary and mode, alternating; medians of the render's wall-clock seconds (scene build "
        "excluded) and of the process's CPU seconds (scene build included). Load average %.1f "
        "at the start, %.1f at the end (%d cores)."
        % ("The close-up of bench/render.py" if a.scene == "closeup"
           else "The %s of `weft scene %s --size %d`" % (a.scene, a.scene, a.patch),
           a.size, a.size, portable_path(os.path.abspath(a.model)), a.seed, a.threads,
           a.runs, results["load_average_start"][0], results["load_average_end"][0],
           os.cpu_count()),
        "",
        "| mode | spp | before s | after s | after / before | before CPU s | after CPU s "
        "| after / before (CPU) | EXR identical |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for mode, m in results["modes"].items():
        lines.append("| %s | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %s |" % (
            mode, m["spp"], m["median_before"], m["median_after"], m["ratio"],
            m["median_cpu_before"], m["median_cpu_after"], m["cpu_ratio"],
            "yes" if m["identical_exr"] else "no"))
    lines += ["", "Every run (seconds, then CPU seconds), in order:", ""]
    for mode, m in results["modes"].items():
        for which in ("before", "after"):
            lines.append("- %s, %s: %s; CPU %s" % (
                mode, which, " ".join("%.3f" % s for s in m["seconds"][which]),
                " ".join("%.3f" % s for s in m["cpu_seconds"][which])))
    lines.append("")

    write_results(a.out, lines, results)


if __name__ == "__main__":
    main()
