#!/usr/bin/env python3
"""bench/trainer.py: training throughput of weft's networks against PyTorch
on the same networks, in one run (issue 42: at least 3 M samples/s on 2 cores).

Measured:
  - one Adam step on a mini-batch (forward, backward, update; log-MSE loss,
    exp output, random inputs and targets), samples per second, for the T
    network 3-7-7-1, the M networks 6-21-21-3 and 6-21-21-21-3, and a
    13-32-32-32-3 network (a family model's size): weft's trainer
    (bench_mlp BatchedTrainStep: what `weft fit` runs, MlpBatch passes on 8
    chunks) and Mlp::lossAndGradient (bench_mlp TrainStep: the Eigen form it
    replaced, one thread), against PyTorch (torch.nn Linear + PReLU per
    channel, torch.optim.Adam) with torch.set_num_threads(1) and (2);
  - a whole `weft fit` M training on a small fleece gather, drawing its
    samples from the RDM as a fit does: steps x batch / the fit's M seconds,
    with --threads 2 (and, with --before WEFT, the same fit by another
    weft binary, for a before/after ratio).
Writes bench/results/trainer.md and .json. PyTorch is Debian's python3-torch
(apt-get install python3-torch), for Debian's interpreter; without it the
PyTorch columns say n/a.

    /usr/bin/python3 bench/trainer.py [--build build/release] [--before OTHER_WEFT] [--seconds 2]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from benchlib import now, run, write_results  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NETWORKS = {0: [3, 7, 7, 1], 1: [6, 21, 21, 3], 2: [6, 21, 21, 21, 3], 3: [13, 32, 32, 32, 3]}
BATCH = 1024
FIT_CONFIG = {"t_net": {"steps": 200, "restarts": 1}, "m_net": {"steps": 20000}}


def weft_steps(bench_mlp, seconds):
    """items_per_second of bench_mlp's training steps at batch BATCH, keyed
    (name, architecture, threads)."""
    out = run([bench_mlp, "--benchmark_filter=TrainStep/.*/%d" % BATCH,
               "--benchmark_min_time=%g" % seconds, "--benchmark_format=json"], "trainer")
    rates = {}
    for b in json.loads(out)["benchmarks"]:
        parts = b["name"].split("/")
        threads = int(parts[3]) if parts[0] == "BatchedTrainStep" else 1
        rates[(parts[0], int(parts[1]), threads)] = b["items_per_second"]
    return rates


def torch_step_rate(torch, widths, threads, seconds):
    """Samples per second of PyTorch's Adam steps on the same network and loss."""
    torch.set_num_threads(threads)
    torch.manual_seed(1)
    layers = []
    for k in range(len(widths) - 1):
        layers.append(torch.nn.Linear(widths[k], widths[k + 1]))
        if k + 2 < len(widths):
            layers.append(torch.nn.PReLU(widths[k + 1]))
    net = torch.nn.Sequential(*layers)
    opt = torch.optim.Adam(net.parameters(), lr=1e-3)
    x = torch.rand(BATCH, widths[0]) * 2 - 1
    t = torch.rand(BATCH, widths[-1])

    def step():
        opt.zero_grad(set_to_none=True)
        y = torch.exp(net(x))
        loss = ((torch.log1p(y) - torch.log1p(t)) ** 2).sum(dim=1).mean()
        loss.backward()
        opt.step()

    for _ in range(20):
        step()
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        for _ in range(20):
            step()
        steps += 20
    return steps * BATCH / (time.perf_counter() - start)


def fit_rate(weft, rdm, work, name):
    """M-network samples per second of a whole weft fit (2 threads) on `rdm`."""
    config = os.path.join(work, "fit.json")
    with open(config, "w") as f:
        json.dump(FIT_CONFIG, f)
    summary = json.loads(run([weft, "fit", "--rdm", rdm, "--config", config, "--threads", "2",
                              "--seed", "1", "--quiet", "--out",
                              os.path.join(work, name + ".json")], "trainer").splitlines()[-1])
    rate = summary["m_samples_per_second"]
    return rate, FIT_CONFIG["m_net"]["steps"] * 1024 / rate


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--before", help="another weft binary whose fit is timed too")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "trainer.md"))
    args = ap.parse_args()
    weft = os.path.join(args.build, "weft")
    rates = weft_steps(os.path.join(args.build, "bench_mlp"), args.seconds)
    try:
        import torch
        torch_version = torch.__version__
    except ImportError:
        torch, torch_version = None, None
        print("trainer: no PyTorch for %s (apt-get install python3-torch, and run with "
              "/usr/bin/python3)" % sys.executable, file=sys.stderr)

    rows, results = [], {"date": now(), "batch": BATCH, "torch": torch_version, "networks": []}
    for arch, widths in NETWORKS.items():
        r = {"network": "-".join(map(str, widths)),
             "weft_1": rates[("BatchedTrainStep", arch, 1)],
             "weft_2": rates[("BatchedTrainStep", arch, 2)],
             "eigen_1": rates[("TrainStep", arch, 1)]}
        if torch:
            r["torch_1"] = torch_step_rate(torch, widths, 1, args.seconds)
            r["torch_2"] = torch_step_rate(torch, widths, 2, args.seconds)
        results["networks"].append(r)

    with tempfile.TemporaryDirectory() as work:
        rdm = os.path.join(work, "rdm")
        run([weft, "gather", "--preset", "fleece", "--paths", "400000", "--seed", "1", "--quiet",
             "--out", rdm], "trainer")
        fits = [("this build", weft)] + ([("before", args.before)] if args.before else [])
        results["fit"] = []
        for name, binary in fits:
            rate, seconds = fit_rate(binary, rdm, work, name.replace(" ", "-"))
            results["fit"].append({"binary": name, "m_steps": FIT_CONFIG["m_net"]["steps"],
                                   "m_seconds": seconds, "samples_per_second": rate})

    def m(v):
        return "%.2f" % (v / 1e6)

    lines = ["# Training throughput: weft against PyTorch (bench/trainer.py)", "",
             "Samples per second (millions) of one Adam step on a batch of %d (forward, backward, "
             "update; log-MSE loss, exp output), measured in one run on this machine. weft: "
             "`weft fit`'s trainer (MlpBatch passes on 8 chunks, bench_mlp BatchedTrainStep); "
             "Eigen: Mlp::lossAndGradient, the form it replaced (one thread); PyTorch %s with "
             "1 and 2 threads. Ratios are weft / PyTorch on the same thread count." % (
                 BATCH, torch_version or "(not installed)"), "",
             "| network | weft 1 thread | weft 2 threads | Eigen 1 thread | PyTorch 1 thread "
             "| PyTorch 2 threads | ratio weft/PyTorch, 1 thread | ratio weft/PyTorch, 2 threads "
             "| ratio weft/Eigen, 1 thread |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in results["networks"]:
        t1, t2 = r.get("torch_1"), r.get("torch_2")
        lines.append("| %s | %s | %s | %s | %s | %s | %s | %s | %.1f |" % (
            r["network"], m(r["weft_1"]), m(r["weft_2"]), m(r["eigen_1"]),
            m(t1) if t1 else "n/a", m(t2) if t2 else "n/a",
            "%.1f" % (r["weft_1"] / t1) if t1 else "n/a",
            "%.1f" % (r["weft_2"] / t2) if t2 else "n/a", r["weft_1"] / r["eigen_1"]))
    lines += ["", "A whole `weft fit` M training (6-21-21-21-3, batch 1024, %d steps, `--threads 2`) "
              "on a fleece gather of 400k paths, its samples drawn from the RDM as a fit does:" %
              FIT_CONFIG["m_net"]["steps"], "",
              "| weft binary | M seconds | M samples/s (millions) |", "| --- | ---: | ---: |"]
    for f in results["fit"]:
        lines.append("| %s | %.1f | %s |" % (f["binary"], f["m_seconds"], m(f["samples_per_second"])))
    if len(results["fit"]) == 2:
        lines += ["", "ratio this build / before: %.1f" % (
            results["fit"][0]["samples_per_second"] / results["fit"][1]["samples_per_second"])]
    lines += ["", "Made by: `bench/trainer.py%s` on %s." % (
        " --before <older weft>" if args.before else "", results["date"])]
    write_results(args.out, lines, results)


if __name__ == "__main__":
    main()
