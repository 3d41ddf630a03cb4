"""bench/fidelity_budget.py's split, on synthetic renders whose parts are known:
a smooth truth, one structure field per fiber arrangement, a ply-level bias of
the neural images and independent noise per render. The estimates must find
each part's relative MSE within a few per cent of the value the fields were
drawn with.

    python3 -m unittest discover -s bench -t bench -p 'test_*.py'
"""
import unittest

try:
    import numpy as np
except ImportError:  # scripts install python3-numpy; without it there is nothing to test
    np = None

import fidelity_budget


@unittest.skipIf(np is None, "needs numpy")
class Split(unittest.TestCase):
    def test_parts_are_recovered(self):
        rng = np.random.default_rng(7)
        size = 512
        truth = np.full((size, size, 3), 0.5) + 0.1 * np.sin(np.arange(size) / 9.0)[None, :, None]
        structure, bias, noise_fiber, noise_neural = 0.04, 0.03, 0.06, 0.05
        arrangement = [structure * truth * rng.standard_normal(truth.shape) for _ in range(2)]
        ply_level = bias * truth * rng.standard_normal(truth.shape)

        def render(base, sigma):
            return base + sigma * truth * rng.standard_normal(truth.shape)

        img = {"F0a": render(truth + arrangement[0], noise_fiber),
               "F0b": render(truth + arrangement[0], noise_fiber),
               "F1a": render(truth + arrangement[1], noise_fiber),
               "F1b": render(truth + arrangement[1], noise_fiber),
               "Na": render(truth + ply_level, noise_neural),
               "Nb": render(truth + ply_level, noise_neural)}
        rows, neural_over_fiber, _ = fidelity_budget.budget(img, np)
        # What each part's relative MSE is at one pixel (K = 1): sigma^2 t^2 / (t^2 + 0.01),
        # averaged over the truth's values.
        t2 = truth ** 2
        weight = np.mean(t2 / (t2 + fidelity_budget.REL_MSE_EPSILON))
        at1 = rows[1]
        self.assertAlmostEqual(at1["noise_fiber"], noise_fiber ** 2 * weight, delta=0.03 * noise_fiber ** 2)
        self.assertAlmostEqual(at1["noise_neural"], noise_neural ** 2 * weight, delta=0.03 * noise_neural ** 2)
        self.assertAlmostEqual(at1["structure"], structure ** 2 * weight, delta=0.1 * structure ** 2)
        self.assertAlmostEqual(at1["ply_level"], bias ** 2 * weight, delta=0.1 * bias ** 2)
        self.assertAlmostEqual(at1["model_error"], (structure ** 2 + bias ** 2) * weight,
                               delta=0.1 * (structure ** 2 + bias ** 2))
        # Independent pixels: every part falls as 1 / K^2 with K x K blocks.
        self.assertAlmostEqual(rows[4]["structure"] * 16, at1["structure"], delta=0.2 * at1["structure"])
        for ratio in neural_over_fiber:
            self.assertAlmostEqual(ratio, 1.0, delta=0.01)


if __name__ == "__main__":
    unittest.main()
