"""gather, fit and render from Python: the same arrays as the CLI, a tiny fit,
a tiny render."""
import json

import numpy as np
import pytest

import weft

GATHER_ARRAYS = ["count", "count_t", "p_t", "rdm_r", "rdm_m", "truncated", "depth"]
# Not in a recoloured gather.
WALK_ARRAYS = GATHER_ARRAYS + ["exit_distance"]
# A fit that trains for a few hundred steps (as src/cmd/fit_cli_test.cpp).
SHORT_FIT = {"t_net": {"steps": 200, "restarts": 2, "batch": 64},
             "m_net": {"hidden": [8, 8], "steps": 200, "batch": 64}, "appearance_nodes": 9}


def test_gather_matches_cli_and_fit_runs(cli, tmp_path):
    args = dict(preset="fleece", paths=4000, bins=[4, 8, 6, 12], seed=1)
    g = weft.gather(**args, out=tmp_path / "py-rdm")
    cli("gather", "--preset", "fleece", "--paths", 4000, "--bins", "4,8,6,12", "--seed", 1,
        "--quiet", "--out", tmp_path / "cli-rdm")
    for name in WALK_ARRAYS:
        from_cli = np.load(tmp_path / "cli-rdm" / f"{name}.npy")
        written = np.load(tmp_path / "py-rdm" / f"{name}.npy")
        assert g[name].dtype == from_cli.dtype and g[name].shape == from_cli.shape, name
        np.testing.assert_array_equal(g[name], from_cli, err_msg=name)
        np.testing.assert_array_equal(written, from_cli, err_msg=name)
    assert g["rdm_r"].shape == (4, 8, 6, 12, 3)
    assert g["stats"]["paths"] == 4000 and g["stats"]["out"] == str(tmp_path / "py-rdm")
    # Without out= nothing is written and the arrays are the same.
    again = weft.gather(**args, threads=1)
    np.testing.assert_array_equal(again["rdm_m"], g["rdm_m"])

    r = weft.fit(tmp_path / "py-rdm", config=SHORT_FIT, seed=3, out=tmp_path / "m.json")
    model, report = r["model"], r["report"]
    assert isinstance(model, weft.YarnModel)
    assert 0 <= report["t_rmse"] < 0.5 and np.isfinite(report["m_rel_l2"])
    assert len(report["m_loss"]["loss"]) > 0
    assert [layer["weight"].shape for layer in model.m_net["layers"]] == [(8, 6), (8, 8), (3, 8)]
    # The written model is the returned one, and the CLI fits the same model.
    loaded = weft.YarnModel.load(tmp_path / "m.json")
    (tmp_path / "short.json").write_text(json.dumps(SHORT_FIT))
    cli("fit", "--rdm", tmp_path / "py-rdm", "--out", tmp_path / "cli.json", "--config",
        tmp_path / "short.json", "--seed", 3, "--quiet", "--no-report")
    from_cli = weft.YarnModel.load(tmp_path / "cli.json")
    wi = np.array([0.0, 0.6, 0.8])
    wo = np.array([[0.3, 0.0, 0.954], [0.0, -0.6, -0.8]])
    np.testing.assert_array_equal(loaded.eval(wi, wo), model.eval(wi, wo))
    np.testing.assert_array_equal(from_cli.eval(wi, wo), model.eval(wi, wo))
    assert np.all(np.isfinite(model.eval(wi, wo)))


def test_fit_config_defaults():
    config = weft.fit_config()
    assert config["t_net"]["hidden"] == [7, 7]
    assert config["m_net"]["hidden"] == [21, 21, 21]
    assert weft.fit_config({"m_net": {"steps": 5}})["m_net"]["steps"] == 5


def test_tiny_render(cli, tmp_path, root):
    cli("scene", "closeup", "--model", root / "models" / "fleece.json", "--width", 16,
        "--height", 16, "--out", tmp_path / "closeup")
    scene = tmp_path / "closeup" / "scene.json"
    image, stats = weft.render(scene, spp=2, seed=1)
    assert image.shape == (16, 16, 3) and image.dtype == np.float32
    assert np.all(np.isfinite(image)) and image.mean() > 0
    assert stats["spp"] == 2 and stats["mode"] == "neural" and stats["seed"] == 1
    assert stats["width"] == 16 and stats["scene_file"] == str(scene)

    # The CLI renders the same image.
    cli("render", scene, "--spp", 2, "--seed", 1, "--quiet", "--out", tmp_path / "cli.exr")
    assert json.loads((tmp_path / "cli.json").read_text())["scene_hash"] == stats["scene_hash"]

    # A dict scene, its relative paths resolved against base_dir.
    doc = json.loads(scene.read_text())
    image2, stats2 = weft.render(doc, spp=2, seed=1, base_dir=tmp_path / "closeup")
    np.testing.assert_array_equal(image2, image)
    assert stats2["scene_file"] is None

    fiber, fstats = weft.render(scene, mode="fiber", spp=1)
    assert fiber.shape == (16, 16, 3) and fstats["mode"] == "fiber"
    # Another arrangement of the fibers: by keyword or by the scene's render.fiber_seed.
    other, ostats = weft.render(scene, mode="fiber", spp=1, fiber_seed=3)
    assert not np.array_equal(other, fiber) and ostats["scene_hash"] != fstats["scene_hash"]
    seeded = dict(doc, render=dict(doc["render"], fiber_seed=3))
    np.testing.assert_array_equal(
        weft.render(seeded, mode="fiber", spp=1, base_dir=tmp_path / "closeup")[0], other)
    with pytest.raises(ValueError, match="fiber_seed"):
        weft.render(scene, spp=1, fiber_seed=-1)

    # The sobol sampler: by keyword or by the scene's render.sampler, the same image.
    sobol, sstats = weft.render(scene, spp=2, seed=1, sampler="sobol")
    assert sstats["sampler"] == "sobol" and stats["sampler"] == "independent"
    assert np.all(np.isfinite(sobol)) and not np.array_equal(sobol, image)
    doc["render"]["sampler"] = "sobol"
    np.testing.assert_array_equal(weft.render(doc, spp=2, seed=1, base_dir=tmp_path / "closeup")[0],
                                  sobol)
    with pytest.raises(ValueError, match='sampler "halton" is not a sampler: allowed independent'):
        weft.render(scene, spp=1, sampler="halton")

    # One path at a time or a tile's paths together: the same image bit for bit.
    np.testing.assert_array_equal(weft.render(scene, spp=2, seed=1, integrator="path")[0], image)
    np.testing.assert_array_equal(weft.render(scene, spp=2, seed=1, integrator="batch")[0], image)
    with pytest.raises(ValueError, match='integrator "wavefront" is not an integrator: allowed auto'):
        weft.render(scene, spp=1, integrator="wavefront")


def test_render_progress_shows_the_image_and_stops(cli, tmp_path, root):
    cli("scene", "closeup", "--model", root / "models" / "fleece.json", "--width", 24,
        "--height", 16, "--out", tmp_path / "closeup")
    scene = tmp_path / "closeup" / "scene.json"
    calls = []

    def stop_at_once(fraction, image):
        calls.append((fraction, image.shape, float(image.mean())))
        return False

    # A budget that would take minutes: the first call (after about a second) stops it.
    image, stats = weft.render(scene, spp=1 << 20, progress=stop_at_once)
    assert len(calls) == 1 and 0 < calls[0][0] < 1 and calls[0][1] == (16, 24, 3)
    assert calls[0][2] > 0 and stats["partial"] and 0 < stats["spp"] < 1 << 20
    assert image.shape == (16, 24, 3) and np.all(np.isfinite(image)) and image.mean() > 0

    # A callback that lets it run changes nothing: passes do not change the image.
    seen = []
    watched, wstats = weft.render(scene, spp=64, seed=3, progress=lambda f, im: seen.append(f))
    np.testing.assert_array_equal(watched, weft.render(scene, spp=64, seed=3)[0])
    assert not wstats["partial"] and all(0 < f <= 1 for f in seen)

    def fail(fraction, image):
        raise RuntimeError("the callback's own error")

    with pytest.raises(RuntimeError, match="the callback's own error"):
        weft.render(scene, spp=1 << 20, progress=fail)
    with pytest.raises(ValueError, match="progress: expected a callable"):
        weft.render(scene, spp=1, progress=3)
    with pytest.raises(ValueError, match=r"progress_seconds = 0.05 is out of range: allowed \[0.1"):
        weft.render(scene, spp=1, progress=lambda f, im: True, progress_seconds=0.05)
    # A shorter interval calls back more often (a viewport's cadence).
    ticks = []
    weft.render(scene, spp=1 << 20, progress=lambda f, im: ticks.append(f) or len(ticks) < 3,
                progress_seconds=0.1)
    assert len(ticks) == 3


def test_sharded_gather_and_render_merge(cli, tmp_path, root):
    args = dict(preset="fleece", paths=3000, bins=[4, 8, 6, 12], seed=2)
    whole = weft.gather(**args)
    parts = []
    for k in range(3):
        part = weft.gather(**args, shard=(k, 3), out=tmp_path / f"part{k}")
        assert part["stats"]["shard"]["index"] == k and part["sum_m"].dtype == np.int64
        parts.append(tmp_path / f"part{k}")
    # The shards' counts add up to the whole gather's.
    assert sum(weft.gather(**args, shard=(k, 3))["count"].sum() for k in range(3)) == 3000
    merged = weft.gather_merge(parts[::-1], out=tmp_path / "merged")
    for name in WALK_ARRAYS:
        np.testing.assert_array_equal(merged[name], whole[name], err_msg=name)
        np.testing.assert_array_equal(np.load(tmp_path / "merged" / f"{name}.npy"), whole[name])
    assert merged["stats"]["shards"] == 3
    with pytest.raises(ValueError, match="missing"):
        weft.gather_merge(parts[:2])
    with pytest.raises(ValueError, match="shard"):
        weft.gather(**args, shard=(3, 3))

    cli("scene", "closeup", "--model", root / "models" / "fleece.json", "--width", 12,
        "--height", 8, "--out", tmp_path / "closeup")
    scene = tmp_path / "closeup" / "scene.json"
    image, _ = weft.render(scene, spp=4, seed=1)
    for k in range(2):
        cli("render", scene, "--spp", 4, "--seed", 1, "--shard", f"{k}/2", "--quiet", "--out",
            tmp_path / f"r{k}.exr")
    _, part_stats = weft.render(scene, spp=4, seed=1, shard=(1, 2))
    assert part_stats["shard"]["first_sample"] == 2 and part_stats["spp"] == 2
    merged_image, stats = weft.render_merge([tmp_path / "r1.exr", tmp_path / "r0.exr"])
    np.testing.assert_allclose(merged_image, image, rtol=1e-6, atol=1e-12)
    assert stats["spp"] == 4 and stats["shards"]["count"] == 2


def test_any_colour_gather_and_recolour(cli, tmp_path):
    args = dict(preset="fleece", paths=3000, bins=[4, 8, 6, 12], seed=2)
    g = weft.gather(**args, any_colour=True, out=tmp_path / "ac")
    rows = g["stats"]["colour_paths"]
    assert g["paths_bins"].shape == (rows, 3) and g["paths_bins"].dtype == np.int32
    assert g["paths_kind"].shape == (rows,) and g["paths_kind"].dtype == np.uint8
    assert g["paths_weight"].shape == (rows, 3) and g["paths_weight"].dtype == np.float32
    # The gathered colour comes back exactly.
    same = weft.gather_recolour(tmp_path / "ac", c_tt=[0.452, 0.725, 0.948])
    for name in GATHER_ARRAYS:
        np.testing.assert_array_equal(same[name], g[name], err_msg=name)
    # Another colour, against the records summed here: sum of W0 C_TT^k per cell
    # over count and the outgoing bin's solid angle (rdm.h).
    c_tt = np.array([0.2, 0.4, 1.0])
    blue = weft.gather_recolour(tmp_path / "ac", c_tt=c_tt, out=tmp_path / "blue")
    assert blue["stats"]["recoloured_from"]["gather"] == str(tmp_path / "ac")
    ti, pi, to, po = args["bins"]
    bins, kind, w0 = g["paths_bins"], g["paths_kind"], g["paths_weight"].astype(np.float64)
    weight = w0 * c_tt[None, :] ** bins[:, 2:3]
    edges = np.linspace(0, np.pi, to + 1)
    solid = (np.cos(edges[:-1]) - np.cos(edges[1:]))[:, None] * (2 * np.pi / po) * np.ones(po)
    for label, name in ((0, "rdm_r"), (1, "rdm_m")):
        sums = np.zeros((ti * pi, to * po, 3))
        sel = kind == label
        np.add.at(sums, (bins[sel, 0], bins[sel, 1]), weight[sel])
        expected = sums / g["count"].reshape(-1, 1, 1) / solid.reshape(1, -1, 1)
        np.testing.assert_allclose(blue[name].reshape(ti * pi, to * po, 3), expected,
                                   rtol=1e-5, atol=1e-9, err_msg=name)
    # The CLI writes the same folder.
    cli("gather", "recolour", tmp_path / "ac", "--c-tt", "0.2,0.4,1", "--out", tmp_path / "cli")
    for name in GATHER_ARRAYS:
        np.testing.assert_array_equal(np.load(tmp_path / "cli" / f"{name}.npy"),
                                      np.load(tmp_path / "blue" / f"{name}.npy"), err_msg=name)
    with pytest.raises(ValueError, match="c_tt"):
        weft.gather_recolour(tmp_path / "ac", c_tt=[0.5, 0.5])
    with pytest.raises(ValueError, match="c_tt"):
        weft.gather_recolour(tmp_path / "ac", c_tt=[1.5, 0.5, 0.5])
    with pytest.raises(ValueError, match="not an any-colour gather"):
        weft.gather(**args, out=tmp_path / "plain")
        weft.gather_recolour(tmp_path / "plain", c_tt=[0.5, 0.5, 0.5])


def test_colour_range_fit(tmp_path):
    weft.gather(preset="fleece", paths=6000, bins=[4, 8, 6, 12], seed=1, any_colour=True,
                out=tmp_path / "ac")
    fitted = weft.fit(tmp_path / "ac", config=SHORT_FIT, colour_range=(0.3, 0.999),
                      colour_functions=3, out=tmp_path / "any.json")
    colour = fitted["report"]["colour"]
    assert colour["functions"] == 3 and len(colour["m_rel_l2_by_colour"]) == 8
    # Version 3: its energy calibration is by colour, one per node colour.
    model = json.load(open(tmp_path / "any.json"))
    assert model["version"] == 4  # with its appearance table (docs/colour.md)
    assert len(model["appearance"]["c_tt"]) == 9  # SHORT_FIT's appearance_nodes
    assert len(model["energy_calibration"]["c_tt"]) == len(colour["energy_calibration"]["nodes"]) == 7
    with pytest.raises(ValueError, match="colour_range"):
        weft.fit(tmp_path / "ac", config=SHORT_FIT, colour_range=(0.5, 0.4))
    with pytest.raises(ValueError, match="colour_functions"):
        weft.fit(tmp_path / "ac", config=SHORT_FIT, colour_range=(0.3, 0.9), colour_functions=1)


def test_gather_family_matches_cli(cli, tmp_path):
    args = dict(points=3, paths=300, seed=4, bins=(3, 8, 6, 12))
    summary = weft.gather_family(out=tmp_path / "py", **args)
    assert summary["points_gathered"] == 3 and summary["shard"] == "0/1"
    cli("gather", "family", "--points", 3, "--paths", 300, "--seed", 4, "--bins", "3,8,6,12",
        "--quiet", "--out", tmp_path / "cli")
    assert (tmp_path / "py" / "family.json").read_bytes() == \
        (tmp_path / "cli" / "family.json").read_bytes()
    for k in range(3):
        name = "points/%05d/paths_weight.npy" % k
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    # Shard 1 of 2 into the CLI's folder keeps what is there.
    again = weft.gather_family(out=tmp_path / "cli", shard=(1, 2), **args)
    assert again["points_kept"] == again["end_point"] - again["first_point"] == 2
    box = {"fibers": [300, 300], "density": [0.3, 0.3], "twist": [0.24, 0.24],
           "beta_r_deg": [7.238, 7.238], "beta_tt_deg": [10, 10], "gamma_tt_deg": [25.989, 25.989],
           "c_r": [0.05, 0.05]}
    one = weft.gather_family(out=tmp_path / "fixed", box=box, points=1, paths=300)
    assert one["points_gathered"] == 1
    family = json.loads((tmp_path / "fixed" / "family.json").read_text())
    assert family["yarns"][0]["fibers"] == 300 and family["yarns"][0]["c_r"] == [0.05] * 3
    with pytest.raises(ValueError, match="points"):
        weft.gather_family(out=tmp_path / "bad", points=0, paths=300)
    with pytest.raises(ValueError, match="density"):
        weft.gather_family(out=tmp_path / "bad", points=1, paths=300,
                           box=dict(box, density=[0.5, 0.4]))
    with pytest.raises(ValueError, match="another family"):
        weft.gather_family(out=tmp_path / "py", points=3, paths=300, seed=5, bins=(3, 8, 6, 12))
    edges = weft.gather_family(out=tmp_path / "edges", design="edges", **args)
    assert edges["points_gathered"] == 3
    assert json.loads((tmp_path / "edges" / "family.json").read_text())["design"] == "edges"
    with pytest.raises(ValueError, match="halton, edges"):
        weft.gather_family(out=tmp_path / "bad", design="grid", **args)


def test_yarn_appearance_matches_cli_and_inverts(cli, root):
    model = root / "tests" / "data" / "fleece-colour-small.json"
    reach = weft.yarn_appearance(model)
    assert reach == json.loads(cli("yarn", "appearance", "--model", model))
    wanted = "#c08a6e"
    found = weft.yarn_appearance(model, appearance=wanted)
    assert found == json.loads(cli("yarn", "appearance", "--model", model, "--appearance", wanted))
    assert found == weft.yarn_appearance(model, appearance=(0xc0 / 255, 0x8a / 255, 0x6e / 255))
    # The C_TT found gives that appearance, evaluated directly (not by the table).
    linear = found["appearance"]["linear"]
    for c in range(3):
        assert found["appearance_direct"][c] == pytest.approx(linear[c], rel=0.01)
    back = weft.yarn_appearance(model, c_tt=found["c_tt"])
    assert back["appearance"]["srgb"] == pytest.approx(found["appearance"]["srgb"], abs=2e-3)
    with pytest.raises(ValueError, match="not both"):
        weft.yarn_appearance(model, appearance=wanted, c_tt=(0.5, 0.5, 0.5))
    with pytest.raises(ValueError, match="appearance"):
        weft.yarn_appearance(model, appearance="#12345")
    with pytest.raises(ValueError, match="appearance"):
        weft.yarn_appearance(model, appearance=(0.5, 1.5, 0.5))
    with pytest.raises(ValueError, match="c_tt"):
        weft.yarn_appearance(model, c_tt=(0.5, 0.5))
    with pytest.raises(ValueError, match="c_tt"):
        weft.yarn_appearance(model, c_tt=(0.01, 0.5, 0.5))  # below the colour range
    with pytest.raises(ValueError, match="one colour"):
        weft.yarn_appearance(root / "tests" / "data" / "fleece-small.json", appearance=wanted)


def test_scene_with_appearances_matches_cli(cli, tmp_path, root):
    model = root / "tests" / "data" / "fleece-colour-small.json"
    summary = weft.scene("knit", model=model, out=tmp_path / "py", size=2, width=12, height=8,
                         appearances=["#c08a6e", (0.35, 0.4, 0.6)], stripe=1)
    cli("scene", "knit", "--model", model, "--out", tmp_path / "cli", "--size", 2, "--width", 12,
        "--height", 8, "--appearance", "#c08a6e", "0.35,0.4,0.6", "--stripe", 1)
    py_scene = json.loads((tmp_path / "py" / "scene.json").read_text())
    assert py_scene == json.loads((tmp_path / "cli" / "scene.json").read_text())
    assert py_scene["yarns"][1]["appearance"] == [0.35, 0.4, 0.6]
    assert summary["kind"] == "knit"
    with pytest.raises(ValueError, match=r"appearances\[0\]"):
        weft.scene("knit", model=model, out=tmp_path / "bad", appearances=["#zz0000"])
    with pytest.raises(ValueError, match="appearances"):
        weft.scene("knit", model=model, out=tmp_path / "bad", appearances="#c08a6e")
    with pytest.raises(ValueError, match="not both"):
        weft.scene("knit", model=model, out=tmp_path / "bad", appearances=["#c08a6e"],
                   colours=[(0.5, 0.5, 0.5)])


def test_scene_with_colours_matches_cli(cli, tmp_path, root):
    model = root / "tests" / "data" / "fleece-small.json"
    # As weft scene prints: a model of one colour will not render these colours in neural mode.
    with pytest.warns(UserWarning, match="fitted for one colour"):
        summary = weft.scene("knit", model=model, out=tmp_path / "py", size=2, width=12,
                             height=8, colours=[(0.9, 0.2, 0.1), (0.1, 0.3, 0.8)], stripe=1)
    assert summary["kind"] == "knit" and len(summary["curves"]) == 2
    assert summary["colours"] == [[0.9, 0.2, 0.1], [0.1, 0.3, 0.8]]
    cli("scene", "knit", "--model", model, "--out", tmp_path / "cli", "--size", 2, "--width", 12,
        "--height", 8, "--colours", "0.9,0.2,0.1", "0.1,0.3,0.8", "--stripe", 1)
    for name in ("yarns-1.txt", "yarns-2.txt"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    py_scene = json.loads((tmp_path / "py" / "scene.json").read_text())
    cli_scene = json.loads((tmp_path / "cli" / "scene.json").read_text())
    assert py_scene == cli_scene
    assert [y["colour"] for y in py_scene["yarns"]] == [[0.9, 0.2, 0.1], [0.1, 0.3, 0.8]]
    with pytest.raises(ValueError, match="colours"):
        weft.scene("knit", model=model, out=tmp_path / "bad", colours=[(0.5, 0.5)])
    with pytest.raises(ValueError, match="one colour"):
        weft.scene("closeup", model=model, out=tmp_path / "bad", colours=[(0, 0, 0), (1, 1, 1)])
    # The CLI's flag rules hold here too (SceneOptions::validate).
    with pytest.raises(ValueError, match="--stripe and --dye-length"):
        weft.scene("knit", model=model, out=tmp_path / "bad", colours=[(0, 0, 0), (1, 1, 1)],
                   stripe=2, dye_length=3)
    with pytest.raises(ValueError, match="two --colours"):
        weft.scene("knit", model=model, out=tmp_path / "bad", stripe=2)
    with pytest.raises(ValueError, match="closeup, weave, knit"):
        weft.scene("twill", model=model, out=tmp_path / "bad")


def test_family_yarn_matches_weft_yarn_at(cli, root, tmp_path, rng):
    family = root / "models" / "family.json"
    yarn = {"fibers": 420, "density": 0.27, "twist": 0.1, "beta_r_deg": 5, "beta_tt_deg": 20,
            "gamma_tt_deg": 30, "c_r": [0.3, 0.6, 0.9]}
    cli("yarn", "at", "--family", family, "--yarn", json.dumps(yarn), "--out", tmp_path / "y.json")
    wi = np.array([[0.3, 0.2, np.sqrt(1 - 0.13)]] * 64)
    wo = rng.normal(size=(64, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    ours = weft.YarnModel.from_family(family, yarn).eval(wi, wo)
    assert np.array_equal(ours, weft.YarnModel.load(tmp_path / "y.json").eval(wi, wo))
    assert np.all(ours >= 0) and np.any(ours > 0)
    with pytest.raises(ValueError, match=r"twist = 0\.5.*\[0, 0\.3\]"):
        weft.YarnModel.from_family(family, dict(yarn, twist=0.5))


def test_scene_with_a_family_yarn(root, tmp_path):
    family = root / "models" / "family.json"
    yarn = {"fibers": 420, "density": 0.27, "twist": 0.1, "beta_r_deg": 5, "beta_tt_deg": 20,
            "gamma_tt_deg": 30, "c_r": [0.3, 0.6, 0.9]}
    weft.scene("closeup", model=family, out=tmp_path / "s", yarn=yarn, width=16, height=16, spp=1,
               colours=[(0.8, 0.5, 0.35)])
    scene = json.loads((tmp_path / "s" / "scene.json").read_text())
    assert scene["yarns"][0]["yarn"]["fibers"] == 420
    with pytest.raises(ValueError, match="--yarn"):
        weft.scene("closeup", model=family, out=tmp_path / "t")
