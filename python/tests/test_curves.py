"""weft.curves_info: the report of `weft curves info`, and the yarn overlap
warning of weft.render."""
import json
import math
import pathlib

import pytest

import weft

SHARED_KNIT = pathlib.Path(__file__).resolve().parents[3] / "shared" / "data" / "knit-stockinette-tiny.bcc"


def write_pair(folder):
    """Two parallel yarns 0.3 apart."""
    path = folder / "pair.txt"
    path.write_text("0 0 0\n10 0 0\n\n0 0.3 0\n10 0.3 0\n")
    return path


def test_curves_info_matches_cli(cli, tmp_path):
    pair = write_pair(tmp_path)
    report = weft.curves_info(pair, radius=0.25)
    assert report["curves"] == 2 and report["points"] == 4 and report["segments"] == 2
    assert math.isclose(report["min_distance"], 0.3, rel_tol=1e-7)
    assert math.isclose(report["largest_radius_without_overlap"], 0.15, rel_tol=1e-7)
    assert report["overlap"]["fraction"] == 1.0 and report["overlap"]["curves_overlapping"] == 2
    assert report["file"] == str(pair)
    # The CLI's --json holds the same report.
    cli("curves", "info", pair, "--radius", 0.25, "--json", tmp_path / "r.json")
    assert json.loads((tmp_path / "r.json").read_text()) == report
    plain = weft.curves_info(str(pair))
    assert plain["overlap"] is None and plain["min_distance"] == report["min_distance"]


def test_curves_info_errors(tmp_path):
    pair = write_pair(tmp_path)
    for bad in (0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="radius .* allowed finite and > 0"):
            weft.curves_info(pair, radius=bad)
    with pytest.raises(ValueError, match="missing.bcc"):
        weft.curves_info(tmp_path / "missing.bcc")


def test_curves_info_shared_knit():
    if not SHARED_KNIT.exists():
        pytest.skip(f"{SHARED_KNIT} is missing")
    report = weft.curves_info(SHARED_KNIT, radius=1.0)
    assert report["curves"] == 22 and report["points"] == 826
    assert 0 < report["largest_radius_without_overlap"] < 1


def test_render_warns_about_overlapping_yarns(tmp_path, root):
    write_pair(tmp_path)
    scene = {
        "camera": {"from": [5, 0.15, 20], "to": [5, 0.15, 0]},
        "film": {"width": 8, "height": 8},
        "yarns": [{"curves": "pair.txt", "radius": 0.25,
                   "model": str(root / "models" / "fleece.json")}],
    }
    with pytest.warns(UserWarning, match=r"yarns\[0\] .*100.0% of the yarn length"):
        _, stats = weft.render(scene, spp=1, base_dir=tmp_path)
    overlap = stats["yarn_overlap"][0]
    assert overlap["overlap_fraction"] == 1.0 and overlap["radius"] == 0.25
    assert math.isclose(overlap["largest_radius_without_overlap"], 0.15, rel_tol=1e-7)


def test_render_warns_about_paths_cut_at_max_depth(tmp_path, root):
    write_pair(tmp_path)
    scene = {
        "camera": {"from": [5, 0.15, 20], "to": [5, 0.15, 0]},
        "film": {"width": 8, "height": 8},
        "render": {"max_depth": 1},
        "yarns": [{"curves": "pair.txt", "radius": 0.1,
                   "model": str(root / "models" / "fleece.json")}],
    }
    with pytest.warns(UserWarning, match=r"reached render.max_depth = 1 scattering events"):
        _, stats = weft.render(scene, mode="fiber", spp=2, base_dir=tmp_path)
    assert stats["truncated_paths"] > 0
    assert math.isclose(stats["truncated_fraction"], stats["truncated_paths"] / (8 * 8 * 2))
