"""Every integer argument of the module is checked where it enters (issue 41).

pybind11's own conversion raised "RuntimeError: Unable to cast Python
instance to C++ type" for `weft.render(scene, spp=2**40)` and TypeError for a
float, and took True as 1. Now every integer argument goes through one
conversion that accepts a Python int (or a NumPy integer) within the
argument's range and raises ValueError naming the argument and that range
for anything else: a value too large, a negative one, a float, a bool. The
arguments are checked before any file is read or any work is done.
"""
import functools
import pathlib
import re

import numpy as np
import pytest

import weft

ROOT = pathlib.Path(__file__).resolve().parents[2]
FLEECE_MODEL = ROOT / "models" / "fleece.json"
FLEECE = {"c_r": [0.04, 0.087, 0.087], "c_tt": [0.452, 0.725, 0.948],
          "beta_r_deg": 7.238, "beta_tt_deg": 10.0, "gamma_tt_deg": 25.989}
U64 = "[0, 18446744073709551615]"
NOWHERE = ROOT / "python" / "tests" / "no-such-input"


def _fiber():
    return weft.FiberBcsdf.preset("fleece")


@functools.cache
def _yarn():
    # Without the energy guard and the tabulated sampler, which take about
    # 3 s to prepare and play no part in reading the arguments.
    return weft.YarnModel.load(FLEECE_MODEL, energy_guard=False, sampling="cosine")


def _gather(**args):
    return weft.gather(**dict({"preset": "fleece", "paths": 10, "bins": [2, 2, 2, 2]}, **args))


def _scene(tmp, **args):
    return weft.scene("closeup", model=FLEECE_MODEL, out=tmp / "scene", **args)


# (argument as named in the message, its range, a call that passes value v to it)
CASES = [
    ("count", "[1, 100000000]", lambda v, tmp: _fiber().sample_seeded([0, 1, 0], v)),
    ("seed", U64, lambda v, tmp: _fiber().sample_seeded([0, 1, 0], 4, seed=v)),
    ("count", "[1, 100000000]", lambda v, tmp: _yarn().sample_seeded([0, 0, 1], v)),
    ("seed", U64, lambda v, tmp: _yarn().sample_seeded([0, 0, 1], 4, seed=v)),
    ("paths", "[1, 2147483648]", lambda v, tmp: _gather(paths=v)),
    ("seed", U64, lambda v, tmp: _gather(seed=v)),
    ("ply_seed", U64, lambda v, tmp: _gather(ply_seed=v)),
    ("bins[2]", "[1, 4096]", lambda v, tmp: _gather(bins=[2, 2, v, 2])),
    ("max_depth", "[1, 1000000]", lambda v, tmp: _gather(max_depth=v)),
    ("threads", "[0, 1024]", lambda v, tmp: _gather(threads=v)),
    ("segments_per_twist", "[16, 65536]", lambda v, tmp: _gather(segments_per_twist=v)),
    ("fibers", "[1, 1000000]",
     lambda v, tmp: weft.gather(params=FLEECE, fibers=v, density=0.3, twist=0.2, paths=10)),
    ("shard n", "[1, 65536]", lambda v, tmp: _gather(shard=(0, v))),
    ("shard k", "[0, 1]", lambda v, tmp: _gather(shard=(v, 2))),
    ("seed", U64, lambda v, tmp: weft.fit(NOWHERE, seed=v)),
    ("threads", "[0, 1024]", lambda v, tmp: weft.fit(NOWHERE, threads=v)),
    ("colour_functions", "[2, 12]",
     lambda v, tmp: weft.fit(NOWHERE, colour_range=(0.2, 0.9), colour_functions=v)),
    ("size", "[1, 100]", lambda v, tmp: _scene(tmp, size=v)),
    ("plies", "[1, 16]", lambda v, tmp: _scene(tmp, plies=v)),
    ("width", "[1, 16384]", lambda v, tmp: _scene(tmp, width=v)),
    ("height", "[1, 16384]", lambda v, tmp: _scene(tmp, height=v)),
    ("spp", "[1, 1048576]", lambda v, tmp: _scene(tmp, spp=v)),
    ("stripe", "[1, 100]", lambda v, tmp: _scene(tmp, stripe=v)),
    ("spp", "[1, 1048576]", lambda v, tmp: weft.render(NOWHERE, spp=v)),
    ("threads", "[0, 1024]", lambda v, tmp: weft.render(NOWHERE, threads=v)),
    ("seed", U64, lambda v, tmp: weft.render(NOWHERE, seed=v)),
    ("fiber_seed", U64, lambda v, tmp: weft.render(NOWHERE, fiber_seed=v)),
    ("shard n", "[1, 65536]", lambda v, tmp: weft.render(NOWHERE, spp=4, shard=(0, v))),
    ("shard k", "[0, 2]", lambda v, tmp: weft.render(NOWHERE, spp=4, shard=(v, 3))),
]

# Values no integer argument takes: beyond every range (2^64 for the seeds,
# which take any uint64), negative, a float (even an integral one), a bool.
BAD_VALUES = [("too large", None), ("negative", -1), ("float", 2.5), ("integral float", 4.0),
              ("bool", True), ("string", "4")]


@pytest.mark.parametrize("name,allowed,call", CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
@pytest.mark.parametrize("kind,value", BAD_VALUES, ids=[b[0] for b in BAD_VALUES])
def test_bad_integer_argument_raises_value_error_naming_it(tmp_path, name, allowed, call, kind,
                                                           value):
    if value is None:
        value = 2**64 if allowed == U64 else 2**40
    pattern = re.escape(f"{name}: expected an integer in {allowed}, got ")
    with pytest.raises(ValueError, match=pattern):
        call(value, tmp_path)
    assert not (tmp_path / "scene").exists()


def test_render_spp_2_to_the_40_names_spp_and_its_range():
    # The reproducer of issue 41.
    with pytest.raises(ValueError, match=re.escape("spp: expected an integer in [1, 1048576], "
                                                   "got 1099511627776")):
        weft.render(NOWHERE, spp=2**40)


def test_numpy_integers_and_the_range_ends_are_accepted():
    fiber = _fiber()
    a = fiber.sample_seeded([0, 1, 0], np.int64(3), seed=np.uint64(2**64 - 1))
    b = fiber.sample_seeded([0, 1, 0], 3, seed=2**64 - 1)
    np.testing.assert_array_equal(a["wo"], b["wo"])
    part = _gather(shard=(np.int32(1), np.int16(2)), threads=np.uint8(1), seed=0)
    assert part["stats"]["shard"]["index"] == 1
