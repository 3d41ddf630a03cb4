#!/usr/bin/env python3
"""bench/table2.py: the paper's Table 2 and Fig. 8/9 on this machine, in chunks.

One chunk is one material and one scene, rendered in fiber and neural mode
(references, an spp ladder, an equal-time pair) and written to
bench/results/table2/<material>-<scene>.json; --assemble makes table2.md,
.json and the figures from the chunk files. What a chunk measures, the noise
model, the defaults and every flag: docs/bench-table2.md. The code is the
package bench/table2lib/.

    bench/table2.py --chunk gabardine,knit [--size PX] [--ref-spp N] [--threads 0]
    bench/table2.py --assemble            # table2.md, .json and figures from the chunk files
    bench/table2.py --plan                # the chunks' command lines and estimated minutes
    bench/table2.py                       # every chunk of --presets x --scenes, then assemble
    bench/table2.py --quick               # the one-run quick table
    bench/table2.py --chunk fleece,weave --baseline dual   # adds the baseline's columns
    bench/table2.py --chunk cotton,knit --ref-part 0       # a part of a long fiber reference
    bench/table2.py --rescore             # scores again from the cached renders
  common: [--work DIR] [--results DIR] [--weft build/release/weft]
"""
from table2lib.cli import main

if __name__ == "__main__":
    main()
