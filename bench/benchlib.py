"""bench/benchlib.py: what the Python benchmarks share.

run(): a command's stdout, or the program's exit with the command and its
stderr; cached() and cached_run(): work done once per folder, remembered by
its parameters or command line (a resumable benchmark's renders and gathers);
Runner: run() and cached() for one weft binary, its cached steps keyed by the
binary's SHA-256 as well, with a log; write_md_and_json() and write_results():
a result table and its data, written atomically; portable(): recorded data
without this machine's absolute paths; publish_png() and stack_pngs(): figures
written only when their pixels change (bench/README.md, "Figures").
"""
import datetime
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(cmd, program):
    """stdout of cmd; exits naming `program`, the command and its stderr when it fails."""
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("%s: %s failed (exit %d):\n%s" % (program, " ".join(map(str, cmd)),
                                                   r.returncode, r.stderr.strip()))
    return r.stdout


def write_md_and_json(out_md, text, data):
    """Writes out_md (the Markdown text) and the .json beside it (data, its absolute paths made
    portable), each to a temporary file renamed into place; returns the .json's path."""
    write_text(out_md, text)
    out_json = os.path.splitext(out_md)[0] + ".json"
    write_text(out_json, json.dumps(portable(data), indent=1))
    return out_json


def write_results(out, lines, results):
    """The Markdown table at `out` (lines joined) and the same results as JSON beside it (.json,
    its absolute paths made portable), each written to a temporary file and renamed; the table
    is printed."""
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    write_text(out, "\n".join(lines))
    write_text(os.path.splitext(out)[0] + ".json", json.dumps(portable(results), indent=2))
    print("\n".join(lines))


def write_text(path, text):
    """text at path, through a temporary file renamed over it."""
    with open(path + ".tmp", "w") as f:
        f.write(text)
    os.replace(path + ".tmp", path)


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


def binary_digest(path):
    """The first 16 hex digits of the file's SHA-256."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()[:16]


class Runner:
    """One weft binary's commands for a resumable benchmark: run() logs each command to
    WORK/log.txt, say() prints and logs a progress line, and cached() keys a step by its
    parameters (the command line) and the binary's SHA-256, so that a rebuilt weft does every
    step again (its images and timings are its own) while an interrupted run with the same
    binary resumes."""

    def __init__(self, program, weft, work):
        self.program = program
        self.weft = os.path.abspath(weft)
        self.weft_sha256 = binary_digest(self.weft) if os.path.exists(self.weft) else None
        self.work = os.path.abspath(work)
        os.makedirs(self.work, exist_ok=True)
        self.started = time.time()

    def log(self, line):
        with open(os.path.join(self.work, "log.txt"), "a") as f:
            f.write(line + "\n")

    def say(self, text):
        line = "[%s %6.0fs] %s" % (self.program, time.time() - self.started, text)
        print(line, flush=True)
        self.log(line)

    def run(self, cmd):
        """stdout of cmd (logged); exits with its stderr when it fails."""
        self.log("$ " + " ".join(map(str, cmd)))
        return run(cmd, self.program)

    def cached(self, folder, params, make):
        """Runs make(folder) unless folder/params.json already records `params` made by this
        weft binary."""
        cached(folder, dict(params, weft_sha256=self.weft_sha256), make)


def table2_scene(weft, preset, kind, folder, size, patch=3, extra=()):
    """`weft scene KIND` of models/PRESET.json as bench/table2.py makes it (a
    PATCH x PATCH weave or knit; a close-up), SIZE pixels square, in FOLDER;
    returns FOLDER/scene.json."""
    cmd = [weft, "scene", kind, "--model", os.path.join(ROOT, "models", preset + ".json"),
           "--width", str(size), "--height", str(size), "--spp", "1", "--out", folder]
    if kind != "closeup":
        cmd += ["--size", str(patch)]
    subprocess.run(cmd + list(extra), check=True, stdout=subprocess.DEVNULL)
    return os.path.join(folder, "scene.json")


def now():
    """The time in UTC, to the second, as ISO 8601."""
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


# ---- Paths in recorded results -------------------------------------------------------------

TMP_MARKER = "<tmp>"


def _within(path, folder):
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def _temp_roots():
    roots = {os.path.abspath(tempfile.gettempdir()), "/tmp", "/var/tmp"}
    return sorted(roots | {os.path.realpath(r) for r in roots}, key=len, reverse=True)


def portable_path(path):
    """An absolute path as committed results may record it: relative to the repository root
    when inside it; "<tmp>/REST" inside the temp folder (REST without the first folder below
    it, usually a mkdtemp folder; a file right in it keeps its name); "<NAME>/REST" inside
    another git checkout NAME; else "<elsewhere>/" and the file name. Other strings are
    returned as they are."""
    if not isinstance(path, str) or not path.startswith("/"):
        return path
    p = os.path.normpath(path)
    for root in {ROOT, os.path.realpath(ROOT)}:
        if _within(p, root):
            return os.path.relpath(p, root)
    for tmp in _temp_roots():
        if _within(p, tmp) and p != tmp:
            parts = os.path.relpath(p, tmp).split(os.sep)
            return "/".join([TMP_MARKER] + (parts[1:] if len(parts) > 1 else parts))
    folder = os.path.dirname(p)
    while folder not in ("/", ""):
        if os.path.exists(os.path.join(folder, ".git")):
            return "<%s>/%s" % (os.path.basename(folder), os.path.relpath(p, folder))
        folder = os.path.dirname(folder)
    return "<elsewhere>/" + os.path.basename(p)


def portable(data):
    """data (JSON: dicts, lists, strings, numbers) with every string that is an absolute path
    replaced by portable_path(string); numbers and everything else unchanged."""
    if isinstance(data, dict):
        return {k: portable(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [portable(v) for v in data]
    return portable_path(data)


# ---- Figures -------------------------------------------------------------------------------
#
# A figure is written only when its pixels change: a writer makes the PNG anywhere (weft
# montage into a work or temp folder, or an image in memory) and publishes it; when the file
# at the destination already holds the same pixels it is left untouched (same bytes, no git
# change), else the new PNG is written there, re-encoded smaller (Pillow's optimize=True,
# lossless). Pillow is Debian's python3-pil; without it a made PNG is moved into place as it
# is, and stack_pngs() makes nothing.

MONTAGE_GAP = 4  # weft montage's default gap: pixels between and around the cells
WHITE = (255, 255, 255)  # weft montage's default background


def pillow():
    """The PIL.Image module, or None when Pillow is missing."""
    try:
        from PIL import Image
    except ImportError:
        return None
    return Image


def same_pixels(a, b):
    """Whether two PIL images have the same size and RGB(A) pixels."""
    return a.size == b.size and a.mode == b.mode and a.tobytes() == b.tobytes()


def save_png(image, dest):
    """Writes the PIL image to dest (losslessly optimised) unless dest already holds the same
    pixels; returns whether dest was written."""
    Image = pillow()
    if os.path.exists(dest):
        try:
            with Image.open(dest) as old:
                old.load()
                if same_pixels(old.convert(image.mode), image):
                    return False
        except (OSError, ValueError):
            pass  # unreadable: written anew
    os.makedirs(os.path.dirname(os.path.abspath(dest)), exist_ok=True)
    tmp = dest + ".tmp.png"
    image.save(tmp, format="PNG", optimize=True)
    os.replace(tmp, dest)
    return True


def publish_png(made, dest):
    """The PNG file `made` (e.g. weft montage's output in a work folder) becomes dest, unless
    dest already holds the same pixels; `made` is left where it is. Returns whether dest was
    written."""
    Image = pillow()
    if Image is None:
        os.makedirs(os.path.dirname(os.path.abspath(dest)), exist_ok=True)
        shutil.copyfile(made, dest + ".tmp")
        os.replace(dest + ".tmp", dest)
        return True
    with Image.open(made) as im:
        im.load()
        image = im.convert("RGBA" if "A" in im.getbands() else "RGB")
    return save_png(image, dest)


def stack(images, gap=MONTAGE_GAP, background=WHITE):
    """PIL images one below the other, each centred in a cell as large as the largest, `gap`
    pixels between and around the cells: weft montage --columns 1 of PNG inputs, pixel for
    pixel (8-bit values kept, nothing scaled)."""
    Image = pillow()
    cell_w = max(im.width for im in images)
    cell_h = max(im.height for im in images)
    out = Image.new("RGB", (cell_w + 2 * gap, len(images) * (cell_h + gap) + gap), background)
    for i, im in enumerate(images):
        out.paste(im.convert("RGB"), (gap + (cell_w - im.width) // 2,
                                      gap + i * (cell_h + gap) + (cell_h - im.height) // 2))
    return out


def stack_pngs(pngs, dest):
    """The PNG files one below the other (stack) into dest, written only when its pixels
    change. Returns None without Pillow (nothing made), else whether dest was written."""
    Image = pillow()
    if Image is None:
        return None
    images = []
    for path in pngs:
        with Image.open(path) as im:
            im.load()
            images.append(im.convert("RGB"))
    return save_png(stack(images), dest)
