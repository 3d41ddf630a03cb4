"""The statistics of a chunk, as pure functions of recorded numbers (docs/bench-table2.md,
"Noise" and "Equal quality"); test_stats.py checks them against hand-computed values and
against every committed chunk file."""
from .config import TARGET_REL_MSE


def ladder_spp(ref_spp, divisors):
    """The ladder's spp levels, ascending, without repeats, each below ref_spp."""
    levels = sorted({max(1, ref_spp // d) for d in divisors})
    return [n for n in levels if n < ref_spp] or [1]


def noise_constant(rel_mse, n, ref_spp):
    """c of one ladder level: two independent renders at n and N spp differ by
    relMSE ~ c (1/n + 1/N), so c = relMSE / (1/n + 1/N)."""
    return rel_mse / (1.0 / n + 1.0 / ref_spp)


def spp_to_target(c, target=TARGET_REL_MSE):
    """Samples per pixel at which a mode of noise constant c reaches relative MSE `target`
    against the true image: n* = c / target."""
    return c / target


def ladder_seconds_per_spp(levels):
    """Seconds per spp over a ladder, each level weighted by its spp (levels: dicts or objects
    with spp and seconds_per_spp)."""
    return sum(_get(l, "seconds_per_spp") * _get(l, "spp") for l in levels) / sum(
        _get(l, "spp") for l in levels)


def c_spread(cs):
    """max / min of c over a ladder: 1 when variance falls as 1/spp; inf if a c is <= 0."""
    return max(cs) / min(cs) if min(cs) > 0 else float("inf")


def reference_noise(c, ref_spp):
    """The converged render's own noise: relative MSE of it against the true image, c / N."""
    return c / ref_spp


def rel_mse_minus_noise(rel_mse, *noises):
    """relMSE of two converged renders less both ones' noise (c / N each): what is left is the
    model's error, since relMSE(a, b) ~ error + c_a / N + c_b / N."""
    return rel_mse - sum(noises)


def speedup(seconds_slow, seconds_fast):
    """The ratio of two modes' times to the same quality."""
    return seconds_slow / seconds_fast


def equal_quality(levels, ref_spp):
    """A ladder's summary (levels: dicts with spp, c, seconds_per_spp, in ascending spp):
    spp and seconds to relative MSE 0.01 from the top level's c, the ladder's seconds per spp,
    max/min of c and the converged render's own noise."""
    c = _get(levels[-1], "c")
    n_star = spp_to_target(c)
    seconds_per_spp = ladder_seconds_per_spp(levels)
    return {"spp_to_target": n_star,
            "seconds_per_spp": seconds_per_spp,
            "seconds_to_target": n_star * seconds_per_spp,
            "c_spread": c_spread([_get(l, "c") for l in levels]),
            "reference_noise": reference_noise(c, ref_spp)}


def ray_costs(stats):
    """Rays (closest-hit and shadow queries) per sample and thread-microseconds per ray of one
    render (weft render's image.json): a mode's seconds per spp is their product over the
    threads, so the equal-quality speed-up splits into rays ratio x per-ray cost ratio x c
    ratio (time_factors)."""
    samples = stats["width"] * stats["height"] * stats["spp"]
    return {"rays_per_sample": stats["rays"] / samples,
            "thread_us_per_ray": stats["seconds"] * stats["threads"] / stats["rays"] * 1e6}


def ladder_ray_costs(levels):
    """ray_costs over a ladder, each level weighted by its samples: (rays per sample,
    thread-microseconds per ray)."""
    spp = sum(_get(l, "spp") for l in levels)
    rays = sum(_get(l, "rays_per_sample") * _get(l, "spp") for l in levels)
    busy = sum(_get(l, "rays_per_sample") * _get(l, "spp") * _get(l, "thread_us_per_ray")
               for l in levels)
    return rays / spp, busy / rays


def time_factors(fiber_levels, neural_levels):
    """The equal-quality speed-up as three factors (each fiber / neural): rays per sample,
    thread-microseconds per ray (both over the ladder) and c at the top ladder level. Their
    product is the speed-up, to rounding, when both ladders ran on the same threads."""
    f_rays, f_us = ladder_ray_costs(fiber_levels)
    n_rays, n_us = ladder_ray_costs(neural_levels)
    return {"fiber_rays_per_sample": f_rays, "neural_rays_per_sample": n_rays,
            "fiber_us_per_ray": f_us, "neural_us_per_ray": n_us,
            "rays": f_rays / n_rays, "per_ray": f_us / n_us,
            "c": _get(fiber_levels[-1], "c") / _get(neural_levels[-1], "c")}


def factor_product(factors):
    return factors["rays"] * factors["per_ray"] * factors["c"]


def scene_bytes(scene):
    """Memory of a render's scene (weft render's image.json "scene"): Embree geometry + BVH
    and the materials' BSDFs (the yarn's networks, energy guard and sampling tables)."""
    return scene["geometry_bvh_bytes"] + scene.get("material_bytes", 0)


def _get(obj, key):
    return obj[key] if isinstance(obj, dict) else getattr(obj, key)
