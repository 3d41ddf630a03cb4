"""FiberBcsdf and YarnModel: parity with the CLI probes, sampler checks."""
import math

import numpy as np
import pytest

import weft
from conftest import unit_vectors


def direction_text(v):
    # repr() round-trips a float exactly, so the CLI parses the same doubles.
    return ",".join(repr(float(x)) for x in v)


# ---------------------------------------------------------------------------
# Parity with `weft fiber eval/sample` and `weft yarn eval/sample`.

def test_fiber_eval_matches_cli(cli, tmp_path, rng):
    wi, wo = unit_vectors(500, rng), unit_vectors(500, rng)
    np.save(tmp_path / "pairs.npy", np.hstack([wi, wo]))
    cli("fiber", "eval", "--preset", "silk", "--in", tmp_path / "pairs.npy",
        "--out", tmp_path / "values.npy")
    expected = np.load(tmp_path / "values.npy")
    got = weft.FiberBcsdf.preset("silk").eval(wi, wo)
    assert got.shape == (500, 3) and got.dtype == np.float64
    np.testing.assert_array_equal(got, expected)


def test_fiber_params_dict_matches_cli_params_file(cli, tmp_path, rng):
    params = {"c_r": [0.1, 0.2, 0.3], "c_tt": 0.5, "beta_r_deg": 12.0,
              "beta_tt_deg": 20.0, "gamma_tt_deg": 30.0}
    (tmp_path / "p.json").write_text(
        '{"c_r": [0.1, 0.2, 0.3], "c_tt": 0.5, "beta_r_deg": 12.0, '
        '"beta_tt_deg": 20.0, "gamma_tt_deg": 30.0}')
    wi, wo = unit_vectors(200, rng), unit_vectors(200, rng)
    np.save(tmp_path / "pairs.npy", np.hstack([wi, wo]))
    cli("fiber", "eval", "--params", tmp_path / "p.json", "--in", tmp_path / "pairs.npy",
        "--out", tmp_path / "values.npy")
    fiber = weft.FiberBcsdf(params)
    np.testing.assert_array_equal(fiber.eval(wi, wo), np.load(tmp_path / "values.npy"))
    assert fiber.params["c_tt"] == [0.5, 0.5, 0.5]


def test_fiber_sample_matches_cli(cli, tmp_path):
    wi = np.array([0.3, 0.8, -0.2])
    cli("fiber", "sample", "--preset", "fleece", "--wi", direction_text(wi), "--count", 2000,
        "--seed", 5, "--out", tmp_path / "s.npy")
    expected = np.load(tmp_path / "s.npy")
    s = weft.FiberBcsdf.preset("fleece").sample_seeded(wi, 2000, seed=5)
    np.testing.assert_array_equal(s["wo"], expected[:, 0:3])
    np.testing.assert_array_equal(s["weight"], expected[:, 3:6])
    np.testing.assert_array_equal(s["pdf"], expected[:, 6])
    assert set(np.unique(s["lobe"])) <= {0, 1}


def test_yarn_eval_matches_cli(cli, tmp_path, rng, root):
    model = root / "models" / "fleece.json"
    wi, wo = unit_vectors(300, rng), unit_vectors(300, rng)
    wi[:, 2] = np.abs(wi[:, 2])
    np.save(tmp_path / "pairs.npy", np.hstack([wi, wo]))
    cli("yarn", "eval", "--model", model, "--in", tmp_path / "pairs.npy",
        "--out", tmp_path / "values.npy")
    yarn = weft.YarnModel.load(model)
    np.testing.assert_array_equal(yarn.eval(wi, wo), np.load(tmp_path / "values.npy"))
    # --no-energy-guard is energy_guard=False.
    cli("yarn", "eval", "--model", model, "--in", tmp_path / "pairs.npy",
        "--out", tmp_path / "raw.npy", "--no-energy-guard")
    raw = weft.YarnModel.load(str(model), energy_guard=False)
    np.testing.assert_array_equal(raw.eval(wi, wo), np.load(tmp_path / "raw.npy"))


def test_yarn_sample_matches_cli(cli, tmp_path, root):
    model = root / "models" / "cotton.json"
    wi = np.array([0.2, -0.4, 0.7])
    cli("yarn", "sample", "--model", model, "--wi", direction_text(wi), "--count", 2000,
        "--seed", 3, "--out", tmp_path / "s.npy")
    expected = np.load(tmp_path / "s.npy")
    s = weft.YarnModel.load(model).sample_seeded(wi, 2000, seed=3)
    np.testing.assert_array_equal(s["wo"], expected[:, 0:3])
    np.testing.assert_array_equal(s["weight"], expected[:, 3:6])
    np.testing.assert_array_equal(s["pdf"], expected[:, 6])
    np.testing.assert_array_equal(s["lobe"], expected[:, 7].astype(np.int64))


# ---------------------------------------------------------------------------
# Samplers: chi-square against the pdf, the pdf's integral, weight = eval/pdf.

def chi2_p_value(stat, dof):
    """P(X >= stat), X ~ chi-square(dof), by the Wilson-Hilferty cube-root
    normal approximation (good to a few per cent of p for dof >= 30)."""
    k = float(dof)
    z = ((stat / k) ** (1.0 / 3.0) - (1.0 - 2.0 / (9.0 * k))) / math.sqrt(2.0 / (9.0 * k))
    return 0.5 * math.erfc(z / math.sqrt(2.0))


def expected_counts(pdf, theta_bins, phi_bins, n, order=8):
    """n times the pdf integrated over every (theta, phi) cell of the fiber
    grid w = (sin theta, cos theta cos phi, cos theta sin phi) (core/chi2.h),
    by Gauss-Legendre quadrature in each cell, in one vectorised pdf call."""
    x, w = np.polynomial.legendre.leggauss(order)
    dt, dp = math.pi / theta_bins, 2 * math.pi / phi_bins
    t0 = -math.pi / 2 + dt * np.arange(theta_bins)
    p0 = -math.pi + dp * np.arange(phi_bins)
    theta = (t0[:, None] + dt * (x[None, :] + 1) / 2).ravel()  # (TB * order)
    phi = (p0[:, None] + dp * (x[None, :] + 1) / 2).ravel()    # (PB * order)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    dirs = np.stack([np.sin(T), np.cos(T) * np.cos(P), np.cos(T) * np.sin(P)], axis=-1)
    density = pdf(dirs.reshape(-1, 3)).reshape(T.shape) * np.cos(T)
    weights = np.outer(np.tile(w, theta_bins), np.tile(w, phi_bins)) * (dt / 2) * (dp / 2)
    cells = (density * weights).reshape(theta_bins, order, phi_bins, order).sum(axis=(1, 3))
    return n * cells.ravel()


def observed_counts(wo, theta_bins, phi_bins):
    theta = np.arctan2(wo[:, 0], np.hypot(wo[:, 1], wo[:, 2]))
    phi = np.arctan2(wo[:, 2], wo[:, 1])
    i = np.clip(((theta + math.pi / 2) / math.pi * theta_bins).astype(int), 0, theta_bins - 1)
    j = np.clip(((phi + math.pi) / (2 * math.pi) * phi_bins).astype(int), 0, phi_bins - 1)
    return np.bincount(i * phi_bins + j, minlength=theta_bins * phi_bins).astype(float)


def chi2_test(observed, expected, min_expected=5.0):
    """Pearson's statistic with the cells expecting fewer than min_expected
    pooled into one (pbrt-v4 style); returns (statistic, dof, p)."""
    small = expected < min_expected
    obs, exp = observed[~small], expected[~small]
    if expected[small].sum() > 0:
        obs = np.append(obs, observed[small].sum())
        exp = np.append(exp, expected[small].sum())
    else:
        assert observed[small].sum() == 0, "samples where the pdf is zero"
    stat = float(np.sum((obs - exp) ** 2 / exp))
    dof = len(exp) - 1
    return stat, dof, chi2_p_value(stat, dof)


@pytest.mark.parametrize("preset", ["fleece", "silk"])
@pytest.mark.parametrize("wi", [(0.5, 0.866, 0.0), (-0.2, 0.1, 0.97), (0.9, 0.3, -0.3)])
def test_fiber_sampler_chi_square(preset, wi):
    fiber = weft.FiberBcsdf.preset(preset)
    wi = np.array(wi) / np.linalg.norm(wi)
    n, tb, pb = 200_000, 90, 45  # 2-degree rows: silk's R lobe is 1 degree wide
    s = fiber.sample_seeded(wi, n, seed=11)
    assert np.all(s["lobe"] >= 0)
    observed = observed_counts(s["wo"], tb, pb)
    expected = expected_counts(lambda wo: fiber.pdf(wi, wo), tb, pb, n)
    assert abs(expected.sum() / n - 1) < 1e-3  # the pdf integrates to 1
    stat, dof, p = chi2_test(observed, expected)
    # 6 tests at an overall level of 1% (Sidak).
    assert p > 1 - (1 - 0.01) ** (1 / 6), f"chi2 = {stat:.1f}, dof = {dof}, p = {p:.2e}"


def test_fiber_pdf_integrates_to_one_monte_carlo(rng):
    fiber = weft.FiberBcsdf.preset("cotton")
    n = 400_000
    wo = unit_vectors(n, rng)
    for wi in [(0.0, 1.0, 0.0), (0.6, 0.0, 0.8)]:
        integral = fiber.pdf(np.array(wi), wo).mean() * 4 * math.pi
        assert abs(integral - 1) < 0.03, integral


def test_yarn_pdf_integrates_to_one_minus_p_t(rng, root):
    yarn = weft.YarnModel.load(root / "models" / "fleece.json")
    n = 400_000
    wo = unit_vectors(n, rng)
    for wi in [(0.0, 0.0, 1.0), (0.5, 0.3, 0.81)]:
        wi = np.array(wi) / np.linalg.norm(wi)
        integral = yarn.pdf(wi, wo).mean() * 4 * math.pi
        assert abs(integral - (1 - yarn.p_t(wi))) < 0.03, integral


def test_sample_weight_is_eval_over_pdf(rng, root):
    u = rng.random((1000, 3))
    wi = np.array([0.1, 0.2, 0.97]) / np.linalg.norm([0.1, 0.2, 0.97])
    for bsdf in [weft.FiberBcsdf.preset("gabardine"),
                 weft.YarnModel.load(root / "models" / "silk.json")]:
        s = bsdf.sample(wi, u)
        cont = s["pdf"] > 0
        assert cont.sum() > 500
        f = bsdf.eval(wi, s["wo"][cont])
        np.testing.assert_allclose(s["weight"][cont], f / s["pdf"][cont, None], rtol=1e-9)
        np.testing.assert_allclose(bsdf.pdf(wi, s["wo"][cont]), s["pdf"][cont], rtol=1e-9)
        # The same u gives the same samples (the rejection steps are seeded by u).
        again = bsdf.sample(np.tile(wi, (1000, 1)), u)
        np.testing.assert_array_equal(again["wo"], s["wo"])


def test_yarn_delta_lobe_and_p_t(root):
    yarn = weft.YarnModel.load(root / "models" / "fleece.json")
    wi = np.array([0.0, math.sin(math.radians(75)), math.cos(math.radians(75))])
    pt = yarn.p_t(wi)
    assert isinstance(pt, float) and 0.05 < pt < 0.5  # fleece: about 0.16
    # The fitted sampler picks the delta lobe with probability P(T), weight 1.
    fitted = weft.YarnModel.load(root / "models" / "fleece.json", sampling="fitted")
    lobes = fitted.sample_seeded(wi, 20000, seed=2)["lobe"]
    assert abs(np.mean(lobes == 0) - pt) < 0.02
    # The tabulated one (default) picks it with its own P_T and weight P(T) / P_T.
    samples = yarn.sample_seeded(wi, 20000, seed=2)
    delta = samples["lobe"] == 0
    assert 0.02 < np.mean(delta) < 0.98
    assert np.all(samples["weight"][delta] == samples["weight"][delta][0, 0])
    pick = pt / samples["weight"][delta][0, 0]
    assert abs(np.mean(delta) - pick) < 0.02
    s = yarn.sample(wi, np.array([0.0, 0.5, 0.5]))  # u[0] = 0 picks the delta T lobe
    assert s["lobe"] == 0 and s["pdf"] == 0.0
    np.testing.assert_allclose(s["wo"], -wi, rtol=0, atol=1e-15)
    assert yarn.p_t(np.array([wi, wi])).shape == (2,)


def test_single_vectors_and_broadcasting():
    fiber = weft.FiberBcsdf.preset("fleece")
    wi, wo = np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0])
    one = fiber.eval(wi, wo)
    assert one.shape == (3,)
    assert isinstance(fiber.pdf(wi, wo), float)
    many = fiber.eval(wi, np.array([wo, wo, wo]))
    assert many.shape == (3, 3)
    np.testing.assert_array_equal(many[1], one)
    # Lists are accepted as well as arrays.
    np.testing.assert_array_equal(fiber.eval([0, 1, 0], [[0, -1, 0]])[0], one)


def test_network_weights_match_model_file(root):
    import json
    doc = json.loads((root / "models" / "fleece.json").read_text())
    yarn = weft.YarnModel.load(root / "models" / "fleece.json")
    for name in ["t_net", "m_net"]:
        net = getattr(yarn, name)
        assert net["output"] == doc[name]["output"]
        assert len(net["layers"]) == len(doc[name]["layers"])
        for layer, ref in zip(net["layers"], doc[name]["layers"]):
            assert layer["weight"].dtype == np.float32
            np.testing.assert_array_equal(layer["weight"], np.array(ref["weight"], np.float32))
            np.testing.assert_array_equal(layer["bias"], np.array(ref["bias"], np.float32))
            if ref["prelu"] is None:
                assert layer["prelu"] is None
            else:
                np.testing.assert_array_equal(layer["prelu"], np.array(ref["prelu"], np.float32))
    assert yarn.t_net["layers"][0]["weight"].shape[1] == 3
    assert yarn.m_net["layers"][0]["weight"].shape[1] == 6
    # The model round-trips through its dict.
    again = weft.YarnModel(yarn.to_dict())
    wi, wo = np.array([0.0, 0.0, 1.0]), np.array([0.3, 0.0, 0.954])
    np.testing.assert_array_equal(again.eval(wi, wo), yarn.eval(wi, wo))
    assert yarn.fiber.params == weft.FiberBcsdf.preset("fleece").params


def test_calls_release_the_gil():
    # While a long call runs in a thread, the main thread keeps executing
    # Python: were the GIL held, its loop would stop for the whole call.
    import threading
    import time
    fiber = weft.FiberBcsdf.preset("fleece")
    call = {}

    def work():
        start = time.perf_counter()
        fiber.sample_seeded([0.0, 1.0, 0.0], 1_000_000)
        call["seconds"] = time.perf_counter() - start

    worker = threading.Thread(target=work)
    ticks = [time.perf_counter()]
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    longest_stop = np.diff(ticks).max()
    assert longest_stop < 0.5 * call["seconds"], (longest_stop, call["seconds"])
