"""bench/benchlib.py: what the Python benchmarks share.

run(): a command's stdout, or the program's exit with the command and its
stderr; cached() and cached_run(): work done once per folder, remembered by
its parameters or command line (a resumable benchmark's renders and gathers);
write_md_and_json(): a result table and its data, written atomically.
"""
import json
import os
import shutil
import subprocess
import sys


def run(cmd, program):
    """stdout of cmd; exits naming `program`, the command and its stderr when it fails."""
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("%s: %s failed (exit %d):\n%s" % (program, " ".join(map(str, cmd)),
                                                   r.returncode, r.stderr.strip()))
    return r.stdout


def write_md_and_json(out_md, text, data):
    """Writes out_md (the Markdown text) and the .json beside it (data), each to a temporary
    file renamed into place; returns the .json's path."""
    with open(out_md + ".tmp", "w") as f:
        f.write(text)
    os.replace(out_md + ".tmp", out_md)
    out_json = os.path.splitext(out_md)[0] + ".json"
    with open(out_json + ".tmp", "w") as f:
        json.dump(data, f, indent=1)
    os.replace(out_json + ".tmp", out_json)
    return out_json


def cached(folder, params, make, stamp="params.json"):
    """Runs make(folder) in a fresh folder unless folder/stamp already records `params`."""
    stamp = os.path.join(folder, stamp)
    if os.path.exists(stamp):
        with open(stamp) as f:
            if json.load(f) == params:
                return
    if os.path.isdir(folder):
        shutil.rmtree(folder)
    os.makedirs(folder)
    make(folder)
    with open(stamp + ".tmp", "w") as f:
        json.dump(params, f, indent=1)
    os.replace(stamp + ".tmp", stamp)


def cached_run(folder, cmd, program):
    """Runs cmd (which writes into `folder`) unless folder/cmd.json records the same command."""
    cached(folder, cmd, lambda _: run(cmd, program), stamp="cmd.json")
