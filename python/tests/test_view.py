"""weft.view: the live page served from Python (docs/view.md)."""
import json
import urllib.error
import urllib.request

import pytest

import weft


def _get(url):
    with urllib.request.urlopen(url, timeout=30) as r:
        return r.status, r.headers, r.read()


def test_view_serves_the_page_and_frames(cli, tmp_path, root):
    cli("scene", "closeup", "--model", root / "models" / "fleece.json", "--width", 24,
        "--height", 24, "--spp", 2, "--out", tmp_path / "scene")
    v = weft.view(str(tmp_path / "scene" / "scene.json"), out=str(tmp_path / "saved"),
                  models_dir=str(root / "models"), threads=1)
    try:
        assert v.url.startswith("http://127.0.0.1:")
        assert "<iframe" in v._repr_html_()
        status, _, body = _get(v.url)
        assert status == 200 and b"/view.js" in body
        state = json.loads(_get(v.url + "api/state")[2])
        ids = [m["id"] for m in state["models"]]
        assert "fleece" in ids and "family" in ids and "cotton-colour" in ids
        # A frame of the neural layer: a JPEG, its samples in the headers.
        status, headers, body = _get(v.url + "api/frame?layer=neural&after=0")
        assert status == 200 and body[:2] == b"\xff\xd8"
        assert int(headers["X-Weft-Spp"]) >= 0
        # A refused edit: 400 with the field named, and the state unchanged.
        bad = urllib.request.Request(v.url + "api/edit", data=b'{"film": {"width": 3}}',
                                     method="POST")
        with pytest.raises(urllib.error.HTTPError) as e:
            urllib.request.urlopen(bad, timeout=30)
        assert e.value.code == 400
        assert "edit: film.width = 3" in json.loads(e.value.read())["error"]
        assert v.state()["film"] == state["film"]
        # Save once an image of both samples exists.
        for _ in range(300):
            _get(v.url + "api/frame?layer=neural&after=0")
            if (v.stats()["neural"] or {}).get("spp") == 2:
                break
        saved = v.save()
        assert saved["spp"] == 2 and (tmp_path / "saved" / saved["scene"]).exists()
    finally:
        v.stop()
    with pytest.raises(ValueError, match="stopped"):
        v.state()


def test_view_refuses_bad_arguments(tmp_path):
    with pytest.raises(ValueError, match="port"):
        weft.view(str(tmp_path / "scene.json"), port=70000)
    with pytest.raises(ValueError, match="missing.json"):
        weft.view(str(tmp_path / "missing.json"))
