"""Which weft made a chunk's numbers, and where: recorded in every chunk file."""
import datetime
import os
import subprocess

from .config import ROOT
from .schema import Provenance

# The files whose uncommitted changes make a chunk's script "dirty".
SCRIPT_PATHS = ["bench/table2.py", "bench/table2lib", "bench/benchlib.py"]


def git_out(args, cwd):
    try:
        r = subprocess.run(["git"] + args, cwd=cwd, capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return r.stdout.strip() if r.returncode == 0 else None


def machine():
    """'x86_64, N cores, CPU model' of this machine."""
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return "%s, %d cores, %s" % (os.uname().machine, os.cpu_count(), cpu)


def provenance(weft, weft_sha256):
    """The Provenance of numbers made now by the weft binary at `weft` (its digest given)."""
    top = git_out(["rev-parse", "--show-toplevel"], os.path.dirname(os.path.realpath(weft)))
    commit = dirty = None
    if top:
        commit = git_out(["rev-parse", "HEAD"], top)
        dirty = bool(git_out(["status", "--porcelain", "--", "src", "CMakeLists.txt"], top))
    version = subprocess.run([weft, "--version"], capture_output=True, text=True).stdout.strip()
    return Provenance(
        # HEAD of the git checkout the binary sits in (the binary may be older: its mtime and
        # hash are beside it); source_dirty: uncommitted changes under src/.
        weft_commit=commit, weft_source_dirty=dirty, weft_version=version,
        weft_binary_sha256=weft_sha256,
        weft_binary_mtime=datetime.datetime.fromtimestamp(
            os.path.getmtime(weft), datetime.timezone.utc).isoformat(timespec="seconds"),
        script_commit=git_out(["rev-parse", "HEAD"], ROOT),
        script_dirty=bool(git_out(["status", "--porcelain", "--"] + SCRIPT_PATHS, ROOT)),
        machine=machine())
