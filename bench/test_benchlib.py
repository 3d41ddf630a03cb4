"""bench/benchlib.py: the cache keys, portable paths in recorded results, and figures written
only when their pixels change.

    python3 -m unittest discover -s bench -t bench -p 'test_*.py'
"""
import json
import os
import tempfile
import unittest
from unittest import mock

import benchlib

Image = benchlib.pillow()


class Cache(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)
        self.made = []

    def make(self, folder):
        self.made.append(folder)
        with open(os.path.join(folder, "out.txt"), "w") as f:
            f.write("made")

    def test_cached_by_params(self):
        folder = os.path.join(self.tmp.name, "step")
        benchlib.cached(folder, {"cmd": ["a"]}, self.make)
        benchlib.cached(folder, {"cmd": ["a"]}, self.make)
        self.assertEqual(len(self.made), 1)
        benchlib.cached(folder, {"cmd": ["b"]}, self.make)
        self.assertEqual(len(self.made), 2)

    def test_binary_digest(self):
        path = os.path.join(self.tmp.name, "weft")
        with open(path, "wb") as f:
            f.write(b"abc")
        self.assertEqual(benchlib.binary_digest(path), "ba7816bf8f01cfea")  # SHA-256 of abc

    def test_runner_keys_by_binary(self):
        # The same command line with the same binary resumes; a rebuilt binary makes it again.
        weft = os.path.join(self.tmp.name, "weft")
        with open(weft, "wb") as f:
            f.write(b"one")
        work = os.path.join(self.tmp.name, "work")
        folder = os.path.join(work, "render")
        benchlib.Runner("test", weft, work).cached(folder, {"cmd": ["render"]}, self.make)
        benchlib.Runner("test", weft, work).cached(folder, {"cmd": ["render"]}, self.make)
        self.assertEqual(len(self.made), 1)
        with open(os.path.join(folder, "params.json")) as f:
            self.assertEqual(json.load(f), {"cmd": ["render"],
                                            "weft_sha256": benchlib.binary_digest(weft)})
        with open(weft, "wb") as f:
            f.write(b"two")
        benchlib.Runner("test", weft, work).cached(folder, {"cmd": ["render"]}, self.make)
        self.assertEqual(len(self.made), 2)


class PortablePaths(unittest.TestCase):
    def test_paths(self):
        tmp = tempfile.gettempdir()
        self.assertEqual(benchlib.portable_path(os.path.join(benchlib.ROOT, "build", "weft")),
                         "build/weft")
        self.assertEqual(benchlib.portable_path(os.path.join(tmp, "weft-bench-x1y2", "a.exr")),
                         "<tmp>/a.exr")
        self.assertEqual(benchlib.portable_path(os.path.join(tmp, "weft-nee")), "<tmp>/weft-nee")
        self.assertEqual(benchlib.portable_path("/no/such/folder/weft"), "<elsewhere>/weft")
        for s in ("build/weft", "fleece", "", "a /tmp/b"):
            self.assertEqual(benchlib.portable_path(s), s)

    def test_other_checkout(self):
        with tempfile.TemporaryDirectory() as other, \
                mock.patch.object(benchlib, "_temp_roots", lambda: []):
            os.makedirs(os.path.join(other, ".git"))
            self.assertEqual(benchlib.portable_path(os.path.join(other, "build", "weft")),
                             "<%s>/build/weft" % os.path.basename(other))

    def test_data(self):
        data = {"settings": {"weft": os.path.join(benchlib.ROOT, "build", "release", "weft"),
                             "size": 256, "ratio": 0.1 + 0.2, "flags": [True, None]},
                "outputs": [os.path.join(tempfile.gettempdir(), "weft-x", "scene.json")]}
        self.assertEqual(benchlib.portable(data), {
            "settings": {"weft": "build/release/weft", "size": 256, "ratio": 0.1 + 0.2,
                         "flags": [True, None]},
            "outputs": ["<tmp>/scene.json"]})

    def test_writers(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "r.md")
            benchlib.write_md_and_json(out, "# r\n", {"out": out, "n": 1})
            with open(os.path.join(tmp, "r.json")) as f:
                self.assertEqual(json.load(f), {"out": "<tmp>/r.md", "n": 1})


@unittest.skipIf(Image is None, "needs Pillow (python3-pil)")
class Figures(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def png(self, name, size, colour, save=None):
        path = os.path.join(self.tmp.name, name)
        (save or (lambda im, p: im.save(p)))(Image.new("RGB", size, colour), path)
        return path

    def state(self, path):
        with open(path, "rb") as f:
            return os.stat(path).st_mtime_ns, f.read()

    def test_publish_only_new_pixels(self):
        dest = self.png("dest.png", (8, 4), (10, 20, 30), lambda im, p: im.save(p, compress_level=0))
        before = self.state(dest)
        # The same pixels, encoded otherwise: dest keeps its bytes.
        made = self.png("made.png", (8, 4), (10, 20, 30))
        self.assertFalse(benchlib.publish_png(made, dest))
        self.assertEqual(self.state(dest), before)
        # Other pixels: written, optimised (smaller than the uncompressed original).
        made = self.png("made2.png", (8, 4), (10, 20, 31))
        self.assertTrue(benchlib.publish_png(made, dest))
        with Image.open(dest) as im:
            self.assertEqual(im.getpixel((0, 0)), (10, 20, 31))
        self.assertLess(os.path.getsize(dest), len(before[1]))
        self.assertTrue(os.path.exists(made))
        # A new destination is written.
        self.assertTrue(benchlib.publish_png(made, os.path.join(self.tmp.name, "new", "a.png")))

    def test_stack_centres_without_scaling(self):
        a = self.png("a.png", (10, 6), (255, 0, 0))
        b = self.png("b.png", (4, 2), (0, 0, 255))
        dest = os.path.join(self.tmp.name, "fig.png")
        self.assertTrue(benchlib.stack_pngs([a, b], dest))
        with Image.open(dest) as im:
            # cells 10 x 6, gap 4: 4 + 10 + 4 wide, 4 + 6 + 4 + 6 + 4 high
            self.assertEqual(im.size, (18, 24))
            self.assertEqual(im.getpixel((4, 4)), (255, 0, 0))
            self.assertEqual(im.getpixel((3, 4)), (255, 255, 255))
            # b centred in the second cell: x 4 + 3, y 14 + 2
            self.assertEqual(im.getpixel((7, 16)), (0, 0, 255))
            self.assertEqual(im.getpixel((6, 16)), (255, 255, 255))
            self.assertEqual(im.getpixel((10, 17)), (0, 0, 255))
            self.assertEqual(im.getpixel((11, 17)), (255, 255, 255))
        self.assertFalse(benchlib.stack_pngs([a, b], dest))

    def test_stack_is_weft_montage(self):
        # The committed Fig. 8/9 close-up figure was made by `weft montage --columns 1` of the
        # row figures: stack() gives the same pixels.
        folder = os.path.join(benchlib.ROOT, "bench", "results", "table2")
        rows = []
        for material in ("fleece", "silk", "polyester", "cotton", "gabardine"):
            with Image.open(os.path.join(folder, material + "-closeup.png")) as im:
                rows.append(im.convert("RGB"))
        with Image.open(os.path.join(folder, "fig-closeup.png")) as im:
            self.assertTrue(benchlib.same_pixels(benchlib.stack(rows), im.convert("RGB")))


if __name__ == "__main__":
    unittest.main()
