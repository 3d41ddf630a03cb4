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


if __name__ == "__main__":
    unittest.main()
