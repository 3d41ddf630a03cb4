"""bench/exit_table2.py's noise estimate on synthetic renders of known noise:
two halves of a render, each with twice the variance of the whole, must give
the whole's relative MSE against the truth.

    python3 -m unittest discover -s bench -t bench -p 'test_*.py'
"""
import unittest

try:
    import numpy as np
except ImportError:  # scripts install python3-numpy; without it there is nothing to test
    np = None

import exit_table2


@unittest.skipIf(np is None, "needs numpy")
class Noise(unittest.TestCase):
    def test_the_mean_of_two_halves_has_the_noise_of_the_whole(self):
        rng = np.random.default_rng(5)
        size = 400
        truth = np.full((size, size, 3), 0.4) + 0.2 * np.sin(np.arange(size) / 9.0)[:, None, None]
        sigma = 0.1 * truth  # the whole render's per-pixel standard deviation
        halves = [truth + np.sqrt(2) * sigma * rng.standard_normal(truth.shape) for _ in range(2)]
        want = float(np.mean(sigma * sigma / (truth * truth + exit_table2.REL_MSE_EPSILON)))
        got = exit_table2.mean_noise(halves[0], halves[1], truth, np)
        self.assertAlmostEqual(got, want, delta=0.02 * want)
        # And it is the mean's own error against the truth.
        mean = (halves[0] + halves[1]) / 2
        seen = float(np.mean((mean - truth) ** 2 / (truth * truth + exit_table2.REL_MSE_EPSILON)))
        self.assertAlmostEqual(got, seen, delta=0.02 * seen)


if __name__ == "__main__":
    unittest.main()
