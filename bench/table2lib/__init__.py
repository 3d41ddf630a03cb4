"""bench/table2lib: the code of bench/table2.py (the paper's Table 2 on this machine, in
chunks; docs/bench-table2.md).

config      materials, scenes, default sizes, ladders, seeds
schema      the chunk file as dataclasses (Chunk, Cell, Mode, Level, ...), read and written
stats       the noise constant c, equal-quality time, speed-up and its factors (pure functions)
measure     the renders and comparisons of a chunk, --quick, --ref-part, --baseline, --rescore
plan        --plan's estimates
report      table2.md and .json
assemble    --assemble: the table and the stacked figures from the chunk files
provenance  which weft made the numbers, and where
cli         the command line

The tests (test_*.py beside these) run with no weft binary:
    python3 -m unittest discover -s bench -t bench -p 'test_*.py'
"""
