"""bench/table2.py's command line (docs/bench-table2.md)."""
import argparse
import os
import sys

from .assemble import assemble
from .config import (DEFAULT_NAME, DEFAULT_PATCH, PRESETS, QUICK_NAME, ROOT, SCENES,
                     chunk_command, chunk_defaults, shown_arguments)
from .measure import Bench, rescore, run_chunk, run_quick, run_reference_part
from .plan import estimate_text, load_timings

DESCRIPTION = ("bench/table2.py: the paper's Table 2 and Fig. 8/9 on this machine, in chunks "
               "(docs/bench-table2.md).")


def parse_ladder(text, flag):
    try:
        divisors = [int(x) for x in text.split(",") if x]
    except ValueError:
        divisors = []
    if not divisors or any(d < 2 or d > 4096 for d in divisors):
        sys.exit("table2: %s %r: give divisors of the reference spp in [2, 4096], e.g. 64,16,4"
                 % (flag, text))
    return divisors


def parser():
    p = argparse.ArgumentParser(description=DESCRIPTION)
    what = p.add_mutually_exclusive_group()
    what.add_argument("--chunk", default=None, metavar="MATERIAL,SCENE",
                      help="run one chunk, e.g. gabardine,knit, then assemble")
    what.add_argument("--assemble", action="store_true",
                      help="only assemble table2.md, .json and figures from the chunk files "
                           "(no weft binary needed; the figures need python3-pil)")
    what.add_argument("--plan", action="store_true",
                      help="print each chunk's command line, settings and estimated minutes")
    what.add_argument("--quick", action="store_true", help="the one-run quick table (42 min)")
    what.add_argument("--rescore", action="store_true",
                      help="score every chunk again with this weft's `weft compare` (SSIM at "
                           "2x2 and 4x4 pixel blocks, mean ratio), from the chunk's own renders "
                           "still in the work folder, then assemble")
    p.add_argument("--weft", default=os.path.join(ROOT, "build", "release", "weft"))
    p.add_argument("--work", default=None, help="cache folder (default bench/work/NAME)")
    p.add_argument("--results", default=os.path.join(ROOT, "bench", "results"),
                   help="folder of NAME.md, NAME.json and NAME/ (default bench/results)")
    p.add_argument("--name", default=None,
                   help="results name: RESULTS/NAME.md, .json and NAME/ (default table2 "
                        "or table2-quick)")
    p.add_argument("--presets", default=",".join(PRESETS), help="without --chunk: materials")
    p.add_argument("--scenes", default=",".join(SCENES), help="without --chunk: scenes")
    p.add_argument("--threads", type=int, default=0, help="render threads (0: all cores)")
    p.add_argument("--sampler", default="independent", choices=("independent", "sobol"),
                   help="weft render --sampler of every render of a chunk (docs/render.md); "
                        "recorded in the chunk's settings")
    p.add_argument("--baseline", default="", metavar="dual",
                   help="also render the dual-scattering baseline (after ZMA23) for each chunk "
                        "and add its columns (reuses the chunk's cached renders)")
    p.add_argument("--redo", action="store_true",
                   help="run a chunk even if its result file records the same settings")
    p.add_argument("--no-ablations", action="store_true", help="--quick without Fig. 5")
    p.add_argument("--size", type=int, default=None,
                   help="image side in pixels (default: per chunk, see --plan; 128 with --quick)")
    p.add_argument("--ref-spp", type=int, default=None,
                   help="spp of the converged renders (default 1024, 4096 for silk and cotton; "
                        "256 with --quick)")
    p.add_argument("--patch", type=int, default=None,
                   help="weave and knit: N x N yarns (default %d)" % DEFAULT_PATCH)
    p.add_argument("--fiber-ladder", default=None, metavar="D1,D2,...",
                   help="fiber ladder levels as divisors of the reference spp (default "
                        "64,16,4; 64,16 for cotton knit)")
    p.add_argument("--neural-ladder", default=None, metavar="D1,D2,...",
                   help="neural ladder levels as divisors of the reference spp (default 64,16,4)")
    p.add_argument("--ref-parts", type=int, default=None, metavar="N",
                   help="render the fiber reference as N parts of ref-spp / N samples, one "
                        "process each, merged (default 1; 2 for cotton weave, 3 for cotton knit)")
    p.add_argument("--ref-part", type=int, default=None, metavar="K",
                   help="with --chunk: render only part K (0..N-1) of the fiber reference and "
                        "stop; the chunk itself renders any part still missing")
    return p


def chosen_chunks(args):
    """The (material, scene) pairs the command names: --chunk, else --presets x --scenes."""
    if args.chunk:
        parts = args.chunk.split(",")
        if len(parts) != 2 or parts[0] not in PRESETS or parts[1] not in SCENES:
            sys.exit("table2: --chunk %r: give MATERIAL,SCENE with MATERIAL in %s and SCENE in %s"
                     % (args.chunk, ", ".join(PRESETS), ", ".join(SCENES)))
        return [tuple(parts)]
    presets = [s for s in args.presets.split(",") if s]
    scenes = [s for s in args.scenes.split(",") if s]
    for s in presets:
        if s not in PRESETS:
            sys.exit("table2: --presets: unknown preset %r (allowed %s)" % (s, ", ".join(PRESETS)))
    for s in scenes:
        if s not in SCENES:
            sys.exit("table2: --scenes: unknown scene %r (allowed %s)" % (s, ", ".join(SCENES)))
    return [(pr, k) for pr in presets for k in scenes]


def chunk_settings(args, preset, kind):
    """A chunk's defaults with the command's flags over them."""
    s = chunk_defaults(preset, kind)
    for key in ("size", "ref_spp", "patch", "ref_parts"):
        if getattr(args, key) is not None:
            s[key] = getattr(args, key)
    if args.fiber_ladder:
        s["fiber_ladder"] = parse_ladder(args.fiber_ladder, "--fiber-ladder")
    if args.neural_ladder:
        s["neural_ladder"] = parse_ladder(args.neural_ladder, "--neural-ladder")
    return s


def plan(args, results, name, chunks):
    timings = load_timings(results, name)
    total = 0.0
    for preset, kind in chunks:
        s = chunk_settings(args, preset, kind)
        text, est = estimate_text(timings, preset, kind, s)
        total += est or 0.0
        print("%-45s # %d px, %d spp, ladders %s / %s: %s" % (
            chunk_command(preset, kind, shown_arguments(
                sys.argv[1:], drop=("--presets", "--scenes"), drop_flags=("--plan",))),
            s["size"], s["ref_spp"], ",".join(map(str, s["fiber_ladder"])),
            ",".join(map(str, s["neural_ladder"])), text))
    print("# total about %.1f hours" % (total / 60))


def main(argv=None):
    args = parser().parse_args(argv)
    name = args.name or (QUICK_NAME if args.quick else DEFAULT_NAME)
    if not name.replace("-", "").replace("_", "").isalnum():
        sys.exit("table2: --name %r: use letters, digits, '-' and '_'" % name)
    results = os.path.abspath(args.results)
    if args.work is None:
        args.work = os.path.join(ROOT, "bench", "work", name)
    for key, lo, hi in (("size", 16, 4096), ("ref_spp", 16, 1 << 20), ("patch", 1, 100),
                        ("ref_parts", 1, 64)):
        value = getattr(args, key)
        if value is not None and not lo <= value <= hi:
            sys.exit("table2: --%s %d is out of range [%d, %d]" % (key.replace("_", "-"), value,
                                                                   lo, hi))
    if args.baseline not in ("", "dual"):
        sys.exit("table2: --baseline %r: allowed dual" % args.baseline)
    chunks = chosen_chunks(args)

    if args.plan:
        plan(args, results, name, chunks)
        return
    if args.assemble:
        text, count, missing = assemble(results, name)
        print(text)
        print("table2: %d chunk(s), %d missing; wrote %s" % (
            count, len(missing), os.path.join(results, name + ".md")), file=sys.stderr)
        return
    if not os.access(args.weft, os.X_OK):
        sys.exit("table2: %s is not an executable weft (build first, or pass --weft)" % args.weft)
    bench = Bench(args)
    if args.rescore:
        rescore(bench, results, name)
        text, count, missing = assemble(results, name)
        print(text)
        return
    if args.quick:
        print(run_quick(bench, args, results, name,
                        sorted({c[0] for c in chunks}, key=PRESETS.index),
                        sorted({c[1] for c in chunks}, key=SCENES.index)))
        return
    if args.ref_part is not None:
        if not args.chunk:
            sys.exit("table2: --ref-part needs --chunk MATERIAL,SCENE")
        preset, kind = chunks[0]
        run_reference_part(bench, chunk_settings(args, preset, kind), preset, kind,
                           args.ref_part)
        return
    timings = load_timings(results, name)
    for preset, kind in chunks:
        run_chunk(bench, args, os.path.join(results, name), preset, kind,
                  chunk_settings(args, preset, kind), timings)
        text, count, missing = assemble(results, name)
        bench.say("assembled %s: %d chunk(s), %d missing" % (name + ".md", count, len(missing)))
    print(text)
