"""Radiance failing, missing or too slow: clear errors naming the program and the node, no files left behind."""

from __future__ import annotations

import tempfile
import time

import pytest

import omnirender as om
from omnirender.radiance import RadianceError, runner

pytestmark = pytest.mark.radiance


@pytest.fixture
def private_tmp(tmp_path, monkeypatch):
    """A private temporary folder: what is left in it after a render was left by that render."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    return tmp_path


def _scene(*items):
    return om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), *items])


def test_a_failing_program_is_named_with_radiances_message_and_the_node(private_tmp):
    s = _scene(om.Node("fine", [om.Sphere(radius=0.2)]))
    s.add(om.Node("broken", [om.radiance.Material("colorpict", strings=("red",)), om.Sphere()]))
    with pytest.raises(RadianceError) as info:
        om.render(s, engine="radiance", size=(8, 8))
    message = str(info.value)
    assert "rpict (rendering) failed" in message and "bad # arguments for colorpict" in message
    assert "was written for node /s/broken" in message and "keep=" in message
    assert list(private_tmp.iterdir()) == []


def test_errors_in_raw_text_name_the_node_that_holds_it(private_tmp):
    raw = om.radiance.Raw("void plastic mine 0 0 5 1 1 1 0 0\nmine sphere lump 0 0 3 1 2 3\n")
    with pytest.raises(RadianceError, match=r'(?s)oconv \(building the octree\) failed.*"lump".*node /s/handmade'):
        om.render(_scene(om.Node("handmade", [raw])), engine="radiance", size=(8, 8))
    assert list(private_tmp.iterdir()) == []


def test_a_timeout_stops_the_program_and_removes_the_files(private_tmp):
    slow = _scene(om.PointLight(position=(2, 2, 2)), om.radiance.Options(ab=3, ad=2048, aa=0), om.Sphere())
    started = time.perf_counter()
    with pytest.raises(RadianceError, match=r"rpict \(rendering\) took longer than the timeout of 0.3 s"):
        om.render(slow, engine="radiance", size=(200, 200), timeout=0.3)
    assert time.perf_counter() - started < 5
    assert list(private_tmp.iterdir()) == []


def test_progress_is_reported_and_a_failing_callback_stops_rendering(private_tmp):
    scene = _scene(
        om.PointLight(position=(2, 2, 2)),
        om.radiance.Options(ab=1, ad=256, as_=0, aa=0),
        om.Sphere(),
        om.Box(size=(10, 0.1, 10), center=(0, -1, 0)),
    )
    seen = []
    om.render(scene, engine="radiance", size=(120, 120), progress=lambda done, total: seen.append((done, total)))
    assert seen[-1] == (14400, 14400) and seen == sorted(seen) and len(seen) >= 3  # start, a report, the end

    def broken(done, total):
        raise ValueError("progress display broke")

    started = time.perf_counter()
    with pytest.raises(ValueError, match="progress display broke"):
        om.render(scene, engine="radiance", size=(400, 400), progress=broken)
    assert time.perf_counter() - started < 5  # rpict was stopped at its first report
    assert list(private_tmp.iterdir()) == []


def test_missing_radiance_says_how_to_install_it(monkeypatch, tmp_path):
    monkeypatch.setattr(runner, "radiance_paths", lambda: None)
    with pytest.raises(
        RadianceError, match=r"pyradiance package is not installed.*pip install 'omnirender\[radiance\]'"
    ):
        om.render(_scene(om.Sphere()), engine="radiance", size=(8, 8))
    with pytest.raises(RadianceError, match="pip install"):
        om.radiance.irradiance(_scene(om.Sphere()), [0, 0, 0], [0, 1, 0])
    ok, why = om.engines()["radiance"]
    assert not ok and "pip install 'omnirender[radiance]'" in why
    empty = tmp_path / "bin"
    empty.mkdir()
    monkeypatch.setattr(runner, "radiance_paths", lambda: (empty, tmp_path))
    with pytest.raises(RadianceError, match=r"program 'oconv' is missing from pyradiance"):
        om.render(_scene(om.Sphere()), engine="radiance", size=(8, 8))


def test_export_is_all_or_nothing(tmp_path, monkeypatch):
    target = tmp_path / "scene.rad"
    target.write_text("old")
    real = runner.run

    def failing(name, args, cwd, **kw):
        if name == "obj2mesh" and "om_" not in " ".join(args) and kw.get("what", "").endswith("/s/second"):
            raise RadianceError("Radiance: obj2mesh failed (simulated)")
        return real(name, args, cwd, **kw)

    monkeypatch.setattr("omnirender.radiance.build.run", failing)
    s = _scene(om.Node("first", [om.Torus()]), om.Node("second", [om.Translation(2, 0, 0), om.Torus()]))
    with pytest.raises(RadianceError, match="simulated"):
        om.export(s, target)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.rad"] and target.read_text() == "old"
    monkeypatch.setattr("omnirender.radiance.build.run", real)
    om.export(s, target)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.rad", "scene_mesh0.rtm", "scene_mesh1.rtm"]


def test_bad_options_are_refused_before_anything_runs():
    s = _scene(om.Sphere())
    for kw, message in [
        ({"oversample": 0}, "oversample must be a whole number 1..8"),
        ({"oversample": 2.5}, "oversample"),
        ({"timeout": -1}, "timeout must be a finite number of seconds > 0"),
        ({"timeout": float("nan")}, "timeout"),
        ({"options": "ab=2"}, "om.radiance.Options"),
        ({"exposure": 0}, "exposure must be a positive finite number"),
        ({"size": (4096, 4096), "oversample": 3}, "150,994,944 rays, more than"),
        ({"spp": 4}, r"unknown option\(s\) \['spp'\]"),
    ]:
        kw.setdefault("size", (8, 8))
        with pytest.raises((ValueError, TypeError), match=message):
            om.render(s, engine="radiance", **kw)


def test_keep_writes_the_description_and_its_files(tmp_path):
    import numpy as np

    s = _scene(om.Texture(np.zeros((2, 2, 3), np.uint8)), om.Rectangle())
    om.render(s, engine="radiance", size=(8, 8), keep=tmp_path / "kept")
    names = sorted(p.name for p in (tmp_path / "kept").iterdir())
    assert names == ["om_mesh0.rtm", "om_pic0.hdr", "scene.rad"]
