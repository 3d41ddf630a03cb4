#!/usr/bin/env python3
"""Fails on an absolute path of some machine in a committed text file.

A model, a test input or a benchmark record that names /tmp/g16/cotton or
/home/me/... says where a file lived on the machine that made it: nobody else
has that folder, and it leaks a user's layout. weft records its gather
folders relative instead (docs/model-format.md, "fit"). Run as

    python3 cmake/check_absolute_paths.py ROOT          # the files git tracks under ROOT
    python3 cmake/check_absolute_paths.py --walk ROOT   # every file under ROOT (no git)

Reads every tracked text file (binary files, with a NUL byte, are skipped)
and reports each absolute path under one of the folders below as
"FILE:LINE: PATH", then exits 1. A path counts where it starts a token: not
after a letter, digit, '.', '-', '_', '~', '/', '$', '}', ')' or '>', so
bench/work/x, the path part of a URL and paths under a placeholder
($tmp/work/x, <tmp>/work/x) do not. The documented examples in ALLOWED are not reported.
Exits 0 when nothing is found and 77 (the ctest's SKIP_RETURN_CODE) when ROOT
is not a git checkout.
"""

import fnmatch
import os
import re
import subprocess
import sys

# Top-level folders that hold a machine's or a user's files.
MACHINE_FOLDERS = ("tmp", "var/tmp", "work", "home", "root", "Users", "mnt", "scratch")

PATTERN = re.compile(r"(?<![\w.~/$})>-])/(?:%s)/[^\s\"'`<>)\],;|]*" %
                     "|".join(re.escape(f) for f in MACHINE_FOLDERS))

# Documented examples: (file glob relative to ROOT, path prefix, why it may stay).
ALLOWED = [
    ("bench/cluster/run", "/tmp/weft-slurm.XXXXXX",
     "the mktemp template of the cluster test's scratch folder"),
    ("docs/cluster.md", "/scratch/$USER/", "example --workdir of a cluster job"),
    ("scripts/cluster/*", "/scratch/", "example WORKDIR in the scripts' usage comments"),
    ("docs/curves.md", "/home/me/knit/knit.bcc", "a warning as weft prints it, quoted"),
    ("docs/model-format.md", "/home/me/weft", "how weft fit records an absolute gather folder"),
    ("docs/model-format.md", "/tmp/g16/cotton", "how weft fit records an absolute gather folder"),
    ("bench/test_benchlib.py", "/tmp/b", "a test that text around a path is left alone"),
    ("tests/paths/*", "/", "this checker's own fixture (tests/paths/absolute)"),
    ("cmake/check_absolute_paths.py", "/", "this checker's own examples and allowlist"),
]


def tracked_files(root):
    try:
        out = subprocess.run(["git", "ls-files", "-z"], cwd=root, capture_output=True,
                             check=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"check_absolute_paths: {root} is not a git checkout ({e}): skipped")
        sys.exit(77)
    return [f for f in out.decode("utf-8", "surrogateescape").split("\0") if f]


def all_files(root):
    found = []
    for folder, _, names in os.walk(root):
        for name in names:
            found.append(os.path.relpath(os.path.join(folder, name), root))
    return sorted(found)


def allowed(name, path):
    return any(fnmatch.fnmatch(name, glob) and path.startswith(prefix)
               for glob, prefix, _ in ALLOWED)


def main(argv):
    walk = "--walk" in argv
    args = [a for a in argv if a != "--walk"]
    if len(args) != 1:
        print(__doc__)
        return 2
    root = args[0]
    names = all_files(root) if walk else tracked_files(root)
    findings, checked = [], 0
    for name in names:
        full = os.path.join(root, name)
        if not os.path.isfile(full):  # deleted in the work tree, or a submodule
            continue
        with open(full, "rb") as f:
            data = f.read()
        if b"\0" in data:
            continue
        checked += 1
        text = data.decode("utf-8", "replace")
        for number, line in enumerate(text.splitlines(), 1):
            for match in PATTERN.finditer(line):
                if not allowed(name, match.group(0)):
                    findings.append(f"{name}:{number}: {match.group(0)}")
    if findings:
        print("absolute machine paths in committed files (record them relative, as "
              "docs/model-format.md says, or add a documented example to ALLOWED in "
              "cmake/check_absolute_paths.py):")
        for f in findings:
            print("  " + f)
        print(f"{len(findings)} absolute paths in {checked} text files")
        return 1
    print(f"absolute paths: {checked} text files, none outside the documented examples")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
