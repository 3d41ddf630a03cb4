"""table2.md and table2.json: --assemble of the committed chunk files gives the committed
table, byte for byte; the targets column and the missing rows."""
import copy
import glob
import os
import shutil
import tempfile
import unittest
from unittest import mock

import benchlib
from table2lib import report, schema
from table2lib.assemble import assemble
from table2lib.config import ROOT

RESULTS = os.path.join(ROOT, "bench", "results")


class Assemble(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)
        self.folder = os.path.join(self.tmp.name, "table2")
        os.makedirs(self.folder)
        for path in glob.glob(os.path.join(RESULTS, "table2", "*-*.json")):
            shutil.copy(path, self.folder)
        for path in glob.glob(os.path.join(RESULTS, "table2", "*-*.png")):
            os.symlink(path, os.path.join(self.folder, os.path.basename(path)))
        # Stacking the figures is test_benchlib's; here only their names count.
        self.stacked = []
        patch = mock.patch.object(benchlib, "stack_pngs",
                                  lambda pngs, out: self.stacked.append(out) or False)
        patch.start()
        self.addCleanup(patch.stop)

    def read(self, folder, name):
        with open(os.path.join(folder, name), "rb") as f:
            return f.read()

    def test_committed_table(self):
        text, count, missing = assemble(self.tmp.name, "table2")
        self.assertEqual((count, missing), (15, []))
        for name in ("table2.md", "table2.json"):
            self.assertEqual(self.read(self.tmp.name, name), self.read(RESULTS, name), name)
        self.assertEqual(len(self.stacked), 8)  # 3 scenes, 5 materials (Fig. 10)

    def test_missing_rows(self):
        os.remove(os.path.join(self.folder, "silk-knit.json"))
        text, count, missing = assemble(self.tmp.name, "table2")
        self.assertEqual(missing, [("silk", "knit")])
        self.assertIn("- Missing rows (1 of 15): `bench/table2.py --chunk silk,knit`.", text)
        self.assertIn("| silk | knit | *missing: `bench/table2.py --chunk silk,knit`* |", text)

    def test_product_column_is_the_speedup(self):
        text, _, _ = assemble(self.tmp.name, "table2")
        speedups, products = {}, {}
        for line in text.splitlines():
            cols = [c.strip() for c in line.strip("|").split("|")]
            if len(cols) == 12 and cols[4].startswith("**"):  # the time table
                speedups[cols[0], cols[1]] = cols[4].strip("*")
            if len(cols) == 10 and cols[9].endswith("x"):  # where the time goes
                products[cols[0], cols[1]] = cols[9]
        self.assertEqual(len(speedups), 15)
        self.assertEqual(products, speedups)


class Targets(unittest.TestCase):
    def setUp(self):
        self.cell = schema.load_chunk(os.path.join(RESULTS, "table2", "fleece-weave.json"))

    def test_met(self):
        c = copy.deepcopy(self.cell)
        c.ssim, c.speedup, c.memory_ratio = 0.98, 20.0, 250.0
        c.neural.equal_quality.c_spread = 1.1
        self.assertEqual(report.targets(c), "met")

    def test_missed(self):
        c = copy.deepcopy(self.cell)
        c.ssim, c.speedup, c.memory_ratio = 0.9, 10.0, 150.0
        c.ssim_scales = {"2": 0.95, "4": 0.98}
        c.neural.equal_quality.c_spread = 1.3
        self.assertEqual(report.targets(c), "speed-up < 15x, memory < 200x, SSIM < 0.97 "
                         "(>= 0.97 at 4x4 px), neural c spread > 1.25")
        c.ssim_scales = {"2": 0.9, "4": 0.96}
        self.assertIn("SSIM < 0.97 (< 0.97 at 4x4 px)", report.targets(c))

    def test_closeup_has_no_speedup_target(self):
        c = copy.deepcopy(self.cell)
        c.scene, c.ssim, c.speedup, c.memory_ratio = "closeup", 0.98, 5.0, 250.0
        c.neural.equal_quality.c_spread = 1.0
        self.assertEqual(report.targets(c), "met")


if __name__ == "__main__":
    unittest.main()
