"""bench/exit_spread.py's metrics on synthetic renders whose parts are known:
a truth, a per-channel bias and a per-pixel error of the neural images, and
independent noise per render. The means must find the bias and the error
estimate the error's relative MSE, not the noise.

    python3 -m unittest discover -s bench -t bench -p 'test_*.py'
"""
import unittest

try:
    import numpy as np
except ImportError:  # scripts install python3-numpy; without it there is nothing to test
    np = None

import exit_spread


@unittest.skipIf(np is None, "needs numpy")
class Metrics(unittest.TestCase):
    def test_bias_and_error_are_recovered_apart_from_the_noise(self):
        rng = np.random.default_rng(3)
        size = 400
        truth = np.full((size, size, 3), 0.5) + 0.1 * np.cos(np.arange(size) / 7.0)[:, None, None]
        bias = np.array([1.0, 1.02, 1.06])
        error = 0.05 * truth * rng.standard_normal(truth.shape)

        def render(base, sigma):
            return base + sigma * truth * rng.standard_normal(truth.shape)

        img = {"Fa": render(truth, 0.08), "Fb": render(truth, 0.08),
               "Na": render(truth * bias + error, 0.06), "Nb": render(truth * bias + error, 0.06)}
        m = exit_spread.model_metrics(img, "N", np)
        for c in range(3):
            self.assertAlmostEqual(m["means"][c], bias[c], delta=0.002)
        # The error's relative MSE at one pixel: (bias - 1)^2 t^2 + 0.05^2 t^2, over t^2 + 0.01.
        t2 = truth * truth
        want = float(np.mean(((bias - 1) ** 2 * t2 + 0.05 ** 2 * t2) / (t2 + 0.01)))
        got = m["by_scale"][1]["error"]
        self.assertAlmostEqual(got, want, delta=0.05 * want)
        # The noise is found as the noise, not as error.
        noise = float(np.mean(0.06 ** 2 * t2 / (t2 + 0.01)))
        self.assertAlmostEqual(m["by_scale"][1]["noise"], noise, delta=0.05 * noise)

    def test_matched_error_removes_the_channel_bias_and_keeps_the_rest(self):
        rng = np.random.default_rng(4)
        size = 400
        truth = np.full((size, size, 3), 0.5) + 0.1 * np.sin(np.arange(size) / 5.0)[None, :, None]
        bias = np.array([0.97, 1.0, 1.08])
        error = 0.04 * truth * rng.standard_normal(truth.shape)
        img = {k: truth + 0.05 * truth * rng.standard_normal(truth.shape) for k in ("Fa", "Fb")}
        for k in ("Na", "Nb"):
            img[k] = (truth + error) * bias + 0.05 * truth * rng.standard_normal(truth.shape)
        m = exit_spread.model_metrics(img, "N", np)["by_scale"][1]
        # Scaled back by 1 / bias the neural images are truth + error (and their noise).
        t2 = truth * truth
        want = float(np.mean(0.04 ** 2 * t2 / (t2 + 0.01)))
        self.assertAlmostEqual(m["error_matched"], want, delta=0.05 * want)
        self.assertGreater(m["error"], 2 * want)  # the bias is in the error, not in the matched


class CachedRenders(unittest.TestCase):
    """render() reuses a render made by the binary it is given and makes it again otherwise."""

    def test_a_cached_render_counts_only_for_the_binary_that_made_it(self):
        import os
        import stat
        import tempfile
        with tempfile.TemporaryDirectory() as tmp:
            calls = os.path.join(tmp, "calls")
            weft = os.path.join(tmp, "weft")
            with open(weft, "w") as f:  # writes OUT and OUT's statistics, counts its runs
                f.write("#!/bin/sh\nout=\"\"\nwhile [ $# -gt 0 ]; do [ \"$1\" = --out ] && "
                        "out=\"$2\"; shift; done\necho x >> " + calls + "\necho image > \"$out\"\n"
                        "echo '{\"seconds\": 1.5, \"rays\": 10}' > \"${out%.exr}.json\"\n")
            os.chmod(weft, os.stat(weft).st_mode | stat.S_IXUSR)
            out = os.path.join(tmp, "e.exr")

            def runs():
                with open(calls) as f:
                    return len(f.readlines())

            self.assertIsNone(exit_spread.made_by_of(out))
            stats = exit_spread.render(weft, "s.json", "neural", 4, 1, 0, out, "binary-a")
            self.assertEqual((runs(), stats["seconds"], stats["rays"]), (1, 1.5, 10))
            self.assertEqual(exit_spread.made_by_of(out), "binary-a")
            exit_spread.render(weft, "s.json", "neural", 4, 1, 0, out, "binary-a")
            self.assertEqual(runs(), 1)  # the same binary: reused
            exit_spread.render(weft, "s.json", "neural", 4, 1, 0, out, "binary-b")
            self.assertEqual((runs(), exit_spread.made_by_of(out)), (2, "binary-b"))
            exit_spread.render(weft, "s.json", "neural", 4, 1, 0, out)
            self.assertEqual(runs(), 2)  # no binary asked for: any cached render
            os.remove(out + ".made-by")
            exit_spread.render(weft, "s.json", "neural", 4, 1, 0, out, "binary-b")
            self.assertEqual(runs(), 3)  # unstamped: made again
            os.remove(out)
            exit_spread.render(weft, "s.json", "neural", 4, 1, 0, out)
            self.assertEqual(runs(), 4)  # made again without a binary named: no stamp left
            self.assertIsNone(exit_spread.made_by_of(out))


if __name__ == "__main__":
    unittest.main()
