"""Bad input raises ValueError carrying weft's message, never a crash."""
import math

import numpy as np
import pytest

import weft

FLEECE = {"c_r": [0.04, 0.087, 0.087], "c_tt": [0.452, 0.725, 0.948],
          "beta_r_deg": 7.238, "beta_tt_deg": 10.0, "gamma_tt_deg": 25.989}


def test_unknown_preset():
    with pytest.raises(ValueError, match=r'unknown preset "wool" \(allowed: fleece, silk'):
        weft.FiberBcsdf.preset("wool")


@pytest.mark.parametrize("key,value,message", [
    ("beta_r_deg", math.nan, "beta_r_deg"),
    ("beta_tt_deg", 0.0, "beta_tt_deg"),
    ("c_r", [0.1, math.nan, 0.1], "c_r"),
    ("c_tt", [1.5, 0.5, 0.5], "c_tt"),
    ("gamma_tt_deg", "wide", "gamma_tt_deg"),
])
def test_bad_fiber_parameters(key, value, message):
    params = dict(FLEECE, **{key: value})
    with pytest.raises(ValueError, match=message):
        weft.FiberBcsdf(params)


def test_missing_and_unknown_fiber_keys():
    with pytest.raises(ValueError, match="gamma_tt_deg"):
        weft.FiberBcsdf({k: v for k, v in FLEECE.items() if k != "gamma_tt_deg"})
    with pytest.raises(ValueError, match='unknown key "colour"'):
        weft.FiberBcsdf(dict(FLEECE, colour=1))


def test_missing_and_malformed_model(tmp_path):
    with pytest.raises(ValueError, match="nowhere.json"):
        weft.YarnModel.load(tmp_path / "nowhere.json")
    (tmp_path / "bad.json").write_text('{"format": "weft-yarn-model", ')
    with pytest.raises(ValueError, match="bad.json"):
        weft.YarnModel.load(tmp_path / "bad.json")
    with pytest.raises(ValueError, match="format"):
        weft.YarnModel({"format": "something else"})


def test_wrong_array_shapes():
    fiber = weft.FiberBcsdf.preset("fleece")
    wo = np.tile([0.0, 1.0, 0.0], (4, 1))
    with pytest.raises(ValueError, match=r"wi: expected shape \(n, 3\) or \(3,\), got \(4, 2\)"):
        fiber.eval(np.zeros((4, 2)), wo)
    with pytest.raises(ValueError, match=r"got \(2,\)"):
        fiber.pdf(np.zeros(2), wo)
    with pytest.raises(ValueError, match="wi has 3 rows but wo has 4"):
        fiber.eval(np.tile([0.0, 1.0, 0.0], (3, 1)), wo)
    with pytest.raises(ValueError, match="u: expected shape"):
        fiber.sample([0.0, 1.0, 0.0], np.zeros((5, 2)))
    with pytest.raises(ValueError, match="wi: expected a float array"):
        fiber.eval("up", wo)


def test_bad_directions_and_random_numbers():
    fiber = weft.FiberBcsdf.preset("fleece")
    with pytest.raises(ValueError, match="wo row 1: .* is not a unit vector"):
        fiber.eval([0.0, 1.0, 0.0], [[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]])
    with pytest.raises(ValueError, match="wi row 0"):
        fiber.pdf([math.nan, 1.0, 0.0], [0.0, 1.0, 0.0])
    with pytest.raises(ValueError, match=r"wi row 0: \(0, 0, 0\)"):  # wi is named first
        fiber.eval(np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"u row 2: .* must lie in \[0, 1\)"):
        fiber.sample([0.0, 1.0, 0.0], [[0.1, 0.1, 0.1], [0.2, 0.2, 0.2], [0.5, 1.0, 0.5]])
    with pytest.raises(ValueError, match="non-zero"):
        fiber.sample_seeded([0.0, 0.0, 0.0], 10)
    with pytest.raises(ValueError, match="count"):
        fiber.sample_seeded([0.0, 1.0, 0.0], 0)


def test_bad_pipeline_arguments(tmp_path, root):
    with pytest.raises(ValueError, match="paths"):
        weft.gather(preset="fleece", paths=0)
    with pytest.raises(ValueError, match="preset gives fiber and ply parameters"):
        weft.gather(preset="fleece", fibers=10, paths=10)
    with pytest.raises(ValueError, match="meta.json"):
        weft.fit(tmp_path)
    with pytest.raises(ValueError, match="stepz"):
        weft.fit_config({"t_net": {"stepz": 1}})
    with pytest.raises(ValueError, match="nowhere.json"):
        weft.render(tmp_path / "nowhere.json")
    with pytest.raises(ValueError, match="mode"):
        weft.render(tmp_path / "nowhere.json", mode="photon")
    with pytest.raises(ValueError, match="camera"):
        weft.render({"film": {"width": 4, "height": 4}})
    with pytest.raises(ValueError, match="sampling"):
        weft.YarnModel.load(root / "models" / "fleece.json", sampling="importance")


def test_nested_and_cyclic_structures_raise():
    # Python's own structures have no nesting limit: weft applies the JSON one (64).
    deep = []
    for _ in range(30000):
        deep = [deep]
    with pytest.raises(ValueError, match="nested deeper than 64 levels"):
        weft.render({"camera": deep})
    cyclic = {"camera": {}}
    cyclic["camera"]["self"] = cyclic
    with pytest.raises(ValueError, match="contains itself"):
        weft.render(cyclic)
    with pytest.raises(ValueError, match="nested deeper than 64 levels"):
        weft.YarnModel({"format": deep})


def test_subnormal_incident_direction_is_normalised():
    fiber = weft.FiberBcsdf.preset("fleece")
    tiny = fiber.sample_seeded([1e-320, 0.0, 0.0], 8, seed=3)
    unit = fiber.sample_seeded([1.0, 0.0, 0.0], 8, seed=3)
    for key in unit:
        np.testing.assert_array_equal(tiny[key], unit[key])
