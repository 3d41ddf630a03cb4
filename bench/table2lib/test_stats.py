"""table2lib.stats against hand-computed numbers and against the committed chunk files.

    python3 -m unittest discover -s bench -t bench -p 'test_*.py'
"""
import os
import unittest

from table2lib import schema, stats
from table2lib.config import ROOT

CHUNKS = os.path.join(ROOT, "bench", "results", "table2")


def level(spp, c, seconds_per_spp, rays=1.0, us=1.0):
    return {"spp": spp, "c": c, "seconds_per_spp": seconds_per_spp, "rays_per_sample": rays,
            "thread_us_per_ray": us}


class HandComputed(unittest.TestCase):
    def test_noise_constant(self):
        # relMSE 1/16 between two 16-spp renders: c (1/16 + 1/16) = 1/16, c = 0.5.
        self.assertEqual(stats.noise_constant(0.0625, 16, 16), 0.5)
        # 64 spp against 1024: 1/64 + 1/1024 = 17/1024; relMSE 0.034 -> c = 0.034 * 1024 / 17.
        self.assertAlmostEqual(stats.noise_constant(0.034, 64, 1024), 2.048, places=12)

    def test_ladder_with_one_c_is_flat(self):
        # A ladder whose relMSE falls as c (1/n + 1/N) with c = 2 gives c = 2 at every level.
        ref = 1024
        cs = [stats.noise_constant(2.0 * (1.0 / n + 1.0 / ref), n, ref) for n in (16, 64, 256)]
        for c in cs:
            self.assertAlmostEqual(c, 2.0, places=12)
        self.assertAlmostEqual(stats.c_spread(cs), 1.0, places=12)

    def test_heavy_tail_spreads(self):
        self.assertEqual(stats.c_spread([1.0, 1.5, 2.0]), 2.0)
        self.assertEqual(stats.c_spread([0.0, 1.0]), float("inf"))

    def test_equal_quality(self):
        # c = 2.5 at the top level: 250 spp to relMSE 0.01; the ladder's seconds per spp is the
        # spp-weighted mean (0.5 x 16 + 0.25 x 64) / 80 = 0.3, so 75 s; noise 2.5 / 256.
        eq = stats.equal_quality([level(16, 2.0, 0.5), level(64, 2.5, 0.25)], 256)
        self.assertAlmostEqual(eq["spp_to_target"], 250.0, places=9)
        self.assertAlmostEqual(eq["seconds_per_spp"], 0.3, places=12)
        self.assertAlmostEqual(eq["seconds_to_target"], 75.0, places=9)
        self.assertAlmostEqual(eq["c_spread"], 1.25, places=12)
        self.assertAlmostEqual(eq["reference_noise"], 2.5 / 256, places=15)

    def test_speedup_and_noise(self):
        self.assertEqual(stats.speedup(300.0, 12.0), 25.0)
        self.assertAlmostEqual(stats.rel_mse_minus_noise(0.01, 0.002, 0.003), 0.005, places=15)

    def test_ladder_spp(self):
        self.assertEqual(stats.ladder_spp(1024, (64, 16, 4)), [16, 64, 256])
        self.assertEqual(stats.ladder_spp(4096, (64, 16)), [64, 256])
        self.assertEqual(stats.ladder_spp(1024, (4, 4, 16)), [64, 256])
        self.assertEqual(stats.ladder_spp(16, (64,)), [1])

    def test_ray_costs(self):
        # 10 x 10 px, 4 spp: 400 samples, 4000 rays -> 10 rays per sample; 2 s on 2 threads
        # = 4 thread-seconds over 4000 rays = 1000 us per ray.
        costs = stats.ray_costs({"width": 10, "height": 10, "spp": 4, "rays": 4000,
                                 "seconds": 2.0, "threads": 2})
        self.assertEqual(costs["rays_per_sample"], 10.0)
        self.assertAlmostEqual(costs["thread_us_per_ray"], 1000.0, places=9)

    def test_factors_multiply_to_the_speedup(self):
        # Same pixels and threads: seconds per spp is proportional to rays x us per ray.
        # Fiber 60 rays x 2 us, neural 5 rays x 1.5 us: 12 x 4/3 = 16x the time per spp;
        # c 4 against 1: 4x the samples; the speed-up is 64.
        k = 1e-3
        fiber = [level(16, 4.0, 60 * 2.0 * k, 60, 2.0), level(64, 4.0, 60 * 2.0 * k, 60, 2.0)]
        neural = [level(16, 1.0, 5 * 1.5 * k, 5, 1.5), level(64, 1.0, 5 * 1.5 * k, 5, 1.5)]
        t = stats.time_factors(fiber, neural)
        self.assertAlmostEqual(t["rays"], 12.0, places=12)
        self.assertAlmostEqual(t["per_ray"], 4.0 / 3.0, places=12)
        self.assertAlmostEqual(t["c"], 4.0, places=12)
        self.assertAlmostEqual(stats.factor_product(t), 64.0, places=9)
        speedup = stats.speedup(stats.equal_quality(fiber, 1024)["seconds_to_target"],
                                stats.equal_quality(neural, 1024)["seconds_to_target"])
        self.assertAlmostEqual(speedup, 64.0, places=9)

    def test_ladder_ray_costs_weigh_by_samples(self):
        # 16 spp at 10 rays, 48 spp at 2 rays: (160 + 96) / 64 = 4 rays per sample; the cost
        # per ray is weighed by rays: (160 x 1 + 96 x 3) / 256 = 1.75 us.
        rays, us = stats.ladder_ray_costs([level(16, 1, 1, 10, 1.0), level(48, 1, 1, 2, 3.0)])
        self.assertEqual(rays, 4.0)
        self.assertEqual(us, 1.75)

    def test_scene_bytes(self):
        self.assertEqual(stats.scene_bytes({"geometry_bvh_bytes": 100, "material_bytes": 20}), 120)


class CommittedChunks(unittest.TestCase):
    """Every committed chunk file's derived numbers, recomputed from its raw ones."""

    def setUp(self):
        self.chunks = schema.chunk_files(CHUNKS)
        self.assertEqual(len(self.chunks), 15)

    def modes(self, c):
        return [c.fiber, c.neural] + ([c.dual] if c.dual is not None else [])

    def test_c_of_every_level(self):
        for path, c in self.chunks:
            for m in self.modes(c):
                for l in m.equal_quality.levels:
                    self.assertEqual(l.c, stats.noise_constant(l.rel_mse, l.spp, c.ref_spp), path)

    def test_equal_quality(self):
        for path, c in self.chunks:
            for m in self.modes(c):
                eq = m.equal_quality
                self.assertEqual(stats.equal_quality(eq.levels, c.ref_spp), {
                    k: getattr(eq, k) for k in ("spp_to_target", "seconds_per_spp",
                                                "seconds_to_target", "c_spread",
                                                "reference_noise")}, path)

    def test_speedups_and_ratios(self):
        for path, c in self.chunks:
            f, n = c.fiber.equal_quality, c.neural.equal_quality
            self.assertEqual(c.speedup, stats.speedup(f.seconds_to_target, n.seconds_to_target),
                             path)
            self.assertEqual(c.memory_ratio, stats.scene_bytes(c.scene_stats["fiber"])
                             / stats.scene_bytes(c.scene_stats["neural"]), path)
            self.assertEqual(c.rss_ratio,
                             c.fiber.peak_resident_bytes / c.neural.peak_resident_bytes, path)
            self.assertEqual(c.rel_mse_minus_noise, stats.rel_mse_minus_noise(
                c.rel_mse, f.reference_noise, n.reference_noise), path)
            if c.dual is not None:
                d = c.dual.equal_quality
                self.assertEqual(c.dual.speedup_over_fiber,
                                 stats.speedup(f.seconds_to_target, d.seconds_to_target), path)
                self.assertEqual(c.dual.neural_speedup_over_dual,
                                 stats.speedup(d.seconds_to_target, n.seconds_to_target), path)
                self.assertAlmostEqual(c.dual.rel_mse_minus_noise, stats.rel_mse_minus_noise(
                    c.dual.rel_mse, f.reference_noise, d.reference_noise), places=15, msg=path)

    def test_factors_multiply_to_the_recorded_speedup(self):
        for path, c in self.chunks:
            t = stats.time_factors(c.fiber.equal_quality.levels, c.neural.equal_quality.levels)
            self.assertAlmostEqual(stats.factor_product(t) / c.speedup, 1.0, places=12, msg=path)

    def test_ladders_match_the_settings(self):
        for path, c in self.chunks:
            s = c.settings
            self.assertEqual([l.spp for l in c.fiber.equal_quality.levels],
                             stats.ladder_spp(s.ref_spp, s.fiber_ladder), path)
            self.assertEqual([l.spp for l in c.neural.equal_quality.levels],
                             stats.ladder_spp(s.ref_spp, s.neural_ladder), path)


if __name__ == "__main__":
    unittest.main()
