"""bench/table2.py end to end with fake_weft.py in place of weft: a chunk, its baseline, a
reference in parts, --rescore, --assemble and --quick, each in a temp folder. The command line
runs in this process and fake_weft answers in it too (benchlib.run patched), so that the test
takes seconds; --assemble also runs as its own process."""
import contextlib
import io
import json
import os
import subprocess
import sys
import tempfile
import unittest
from unittest import mock

import benchlib
from table2lib import cli, fake_weft, schema, stats
from table2lib.config import ROOT

TABLE2 = os.path.join(ROOT, "bench", "table2.py")
FAKE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fake_weft.py")


class EndToEnd(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)
        self.weft = os.path.join(self.tmp.name, "weft")
        with open(self.weft, "w") as f:
            f.write('#!/bin/sh\nexec "%s" "%s" "$@"\n' % (sys.executable, FAKE))
        os.chmod(self.weft, 0o755)
        self.results = os.path.join(self.tmp.name, "results")
        self.work = os.path.join(self.tmp.name, "work")

    def fake_run(self, cmd, program):
        """benchlib.run, with the fake weft's commands answered in this process."""
        cmd = [str(c) for c in cmd]
        if cmd[0] != self.weft:
            return self.real_run(cmd, program)
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            fake_weft.main(cmd[1:])
        return out.getvalue()

    def table2(self, *args):
        """bench/table2.py ARGS in this process: its stdout."""
        argv = ["--weft", self.weft, "--work", self.work, "--results", self.results] + list(args)
        out = io.StringIO()
        self.real_run = benchlib.run
        with mock.patch.object(benchlib, "run", self.fake_run), \
                mock.patch.object(sys, "argv", [TABLE2] + argv), \
                contextlib.redirect_stdout(out):
            cli.main(argv)
        return out.getvalue()

    def chunk(self, name):
        return schema.load_chunk(os.path.join(self.results, "table2", name + ".json"))

    def test_chunk_baseline_parts_rescore_assemble(self):
        out = self.table2("--chunk", "fleece,closeup", "--size", "16", "--ref-spp", "64",
                          "--baseline", "dual")
        self.assertIn("| fleece | closeup | 16 | 64 |", out)
        c = self.chunk("fleece-closeup")
        self.assertEqual(c.run.command, "bench/table2.py --chunk fleece,closeup --size 16 "
                         "--ref-spp 64 --baseline dual")
        self.assertEqual([l.spp for l in c.fiber.equal_quality.levels], [1, 4, 16])
        # fake_weft's noise: relMSE = C / n + C / N, so c = C = 4 (fiber) and 1 (neural) at
        # every level, and the equal-quality times follow from its seconds per spp.
        for level in c.fiber.equal_quality.levels:
            self.assertAlmostEqual(level.c, 4.0, places=9)
        self.assertAlmostEqual(c.neural.equal_quality.spp_to_target, 100.0, places=6)
        t = stats.time_factors(c.fiber.equal_quality.levels, c.neural.equal_quality.levels)
        self.assertAlmostEqual(stats.factor_product(t) / c.speedup, 1.0, places=9)
        self.assertIsNotNone(c.dual)
        self.assertEqual(c.dual.figure, "table2/fleece-closeup-fig10.png")
        figures = ["fleece-closeup.png", "fleece-closeup-fig10.png"]
        if benchlib.pillow() is not None:  # the stacked figures need Pillow
            figures += ["fig-closeup.png", "fig10-fleece.png"]
        for f in figures:
            self.assertTrue(os.path.exists(os.path.join(self.results, "table2", f)), f)
        with open(os.path.join(self.results, "table2.json")) as f:
            self.assertEqual(json.load(f)["cells"][0], schema.to_dict(c))
        text = json.dumps(schema.to_dict(c))
        self.assertNotIn(self.tmp.name, text)

        # The same command again renders nothing and leaves every file as it was.
        before = self.snapshot()
        out = self.table2("--chunk", "fleece,closeup", "--size", "16", "--ref-spp", "64",
                          "--baseline", "dual")
        self.assertEqual(self.snapshot(), before)

        # --rescore scores again from the cached renders: the same numbers, the same files.
        self.table2("--rescore")
        self.assertEqual(self.snapshot(), before)

        # A reference in parts: --ref-part renders one part; the chunk the rest.
        self.table2("--chunk", "cotton,knit", "--size", "16", "--ref-spp", "64",
                    "--ref-parts", "2", "--ref-part", "1")
        self.assertTrue(os.path.exists(os.path.join(self.work, "cotton", "knit",
                                                    "fiber-ref-part1of2", "image.exr")))
        self.assertFalse(os.path.exists(os.path.join(self.results, "table2", "cotton-knit.json")))
        self.table2("--chunk", "cotton,knit", "--size", "16", "--ref-spp", "64",
                    "--ref-parts", "2")
        c = self.chunk("cotton-knit")
        self.assertEqual(c.fiber_reference.parts, 2)
        self.assertEqual(c.settings.ref_parts, 2)

        # --assemble alone needs no weft.
        os.remove(os.path.join(self.results, "table2.md"))
        r = subprocess.run([sys.executable, TABLE2, "--assemble", "--results", self.results,
                            "--weft", os.path.join(self.tmp.name, "no-weft")],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(self.results, "table2.md")) as f:
            md = f.read()
        self.assertIn("Missing rows (13 of 15)", md)
        self.assertIn("| cotton | knit | 16 | 64 |", md)

    def test_quick(self):
        out = self.table2("--quick", "--presets", "fleece", "--scenes", "closeup", "--size", "16",
                          "--ref-spp", "64")
        self.assertIn("## Ablations (paper Fig. 5)", out)
        with open(os.path.join(self.results, "table2-quick.json")) as f:
            data = json.load(f)
        self.assertEqual(len(data["cells"]), 1)
        self.assertEqual([r["variant"] for r in data["ablations"]],
                         ["full", "naive", "no_r_lobe", "cosine_sampling"])
        schema.from_dict(schema.Cell, data["cells"][0])
        self.assertTrue(os.path.exists(os.path.join(self.results, "table2-quick",
                                                    "ablation-fleece-closeup.png")))

    def snapshot(self):
        """Every result file's bytes, and the figures' modification times (with Pillow, a
        figure whose pixels did not change is not written at all)."""
        files = {}
        for folder, _, names in os.walk(self.results):
            for n in names:
                path = os.path.join(folder, n)
                with open(path, "rb") as f:
                    kept = n.endswith(".png") and benchlib.pillow() is not None
                    files[path] = (f.read(), os.stat(path).st_mtime_ns if kept else None)
        return files


if __name__ == "__main__":
    unittest.main()
