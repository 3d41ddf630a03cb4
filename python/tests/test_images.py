"""Issue 43, item 6: images and progress from Python: save_image / read_image
round trips (EXR bit for bit, PNG through weft's tone mapping, as the CLI
writes it), exposure "auto", and progress lines on sys.stderr."""
import io
import os
import sys

import numpy as np
import pytest

import weft

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FLEECE = os.path.join(ROOT, "tests", "data", "fleece-small.json")


def small_scene(tmp_path):
    (tmp_path / "yarn.txt").write_text("-0.2 0 0\n0 0.01 0\n0.2 0 0\n")
    return {"camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fov_deg": 8},
            "film": {"width": 16, "height": 12}, "render": {"spp": 2, "seed": 1},
            "yarns": [{"curves": "yarn.txt", "radius": 0.03, "plies": 3, "ply_twist": 0.3,
                       "model": FLEECE}]}


def test_save_image_round_trips_and_matches_the_cli(cli, tmp_path):
    rng = np.random.default_rng(3)
    image = rng.uniform(0, 4, size=(5, 7, 3)).astype(np.float32)
    assert weft.save_image(tmp_path / "a.exr", image) == 0.0
    np.testing.assert_array_equal(weft.read_image(tmp_path / "a.exr"), image)
    # PNG: the tone mapping of weft render's PNG (2^exposure, clamp, sRGB, 8 bits).
    weft.save_image(tmp_path / "a.png", image, exposure=-2)
    png = weft.read_image(tmp_path / "a.png")
    expected = np.clip(image * 0.25, 0, 1)
    assert np.max(np.abs(png - expected)) < 0.01
    # The same bytes as the CLI's PNG of the same render.
    scene = small_scene(tmp_path)
    img, stats = weft.render(scene, base_dir=tmp_path)
    import json
    (tmp_path / "s.json").write_text(json.dumps(scene).replace("yarn.txt", str(tmp_path / "yarn.txt")))
    cli("render", tmp_path / "s.json", "--exposure", "auto", "--quiet", "--out", tmp_path / "cli.exr")
    stops = weft.save_image(tmp_path / "py.png", img, exposure="auto")
    assert json.loads((tmp_path / "cli.json").read_text())["exposure"] == pytest.approx(stops)
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    np.testing.assert_array_equal(weft.read_image(tmp_path / "cli.exr"), img)


def test_save_image_refuses_bad_input(tmp_path):
    good = np.zeros((2, 2, 3), np.float32)
    with pytest.raises(ValueError, match="exr"):
        weft.save_image(tmp_path / "a.jpg", good)
    with pytest.raises(ValueError, match=r"\(H, W, 3\)"):
        weft.save_image(tmp_path / "a.exr", np.zeros((2, 2)))
    bad = good.copy()
    bad[1, 0, 2] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        weft.save_image(tmp_path / "a.exr", bad)
    with pytest.raises(ValueError, match="linear"):
        weft.save_image(tmp_path / "a.exr", good, exposure=1)
    with pytest.raises(ValueError, match="auto"):
        weft.save_image(tmp_path / "a.png", good, exposure="bright")
    with pytest.raises(ValueError, match="64"):
        weft.save_image(tmp_path / "a.png", good, exposure=100)
    assert not any(p.name.startswith("a.") for p in tmp_path.iterdir())


def test_progress_goes_to_python_stderr(tmp_path, monkeypatch):
    captured = io.StringIO()
    monkeypatch.setattr(sys, "stderr", captured)
    weft.render(small_scene(tmp_path), base_dir=tmp_path, quiet=False)
    text = captured.getvalue()
    assert "render neural" in text and "\r" not in text
    captured.truncate(0)
    weft.render(small_scene(tmp_path), base_dir=tmp_path)
    assert captured.getvalue() == ""


def test_scene_of_your_own_curves_with_a_floor(cli, tmp_path):
    knit = os.path.join(ROOT, "data", "curves", "knit-stockinette-tiny.bcc")
    summary = weft.scene("curves", curves=knit, model=FLEECE, out=tmp_path / "mine", width=24,
                         height=16, spp=1, floor=True, view="front")
    assert summary["kind"] == "curves" and summary["objects"] == 1
    assert summary["curve_file"]["radius_from"] == "largest_without_overlap"
    cli("scene", "curves", knit, "--model", FLEECE, "--out", tmp_path / "cli", "--width", 24,
        "--height", 16, "--spp", 1, "--floor", "--view", "front", "--quiet")
    assert (tmp_path / "mine" / "scene.json").read_text().replace(str(tmp_path / "mine"), "") == \
        (tmp_path / "cli" / "scene.json").read_text().replace(str(tmp_path / "cli"), "")
    points = weft.curves_points(knit)
    assert points.shape == (826, 4) and points[0, 0] == 0 and points[-1, 0] == 21
    cli("curves", "points", knit, "--out", tmp_path / "p.npy")
    np.testing.assert_array_equal(np.load(tmp_path / "p.npy"), points)
    with pytest.raises(ValueError, match="curve file"):
        weft.scene("curves", model=FLEECE, out=tmp_path / "x")
    with pytest.raises(ValueError, match="--view"):
        weft.scene("curves", curves=knit, model=FLEECE, out=tmp_path / "x", view="side")
