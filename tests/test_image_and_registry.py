"""om.Image, atomic files, the engine/exporter registries and notebook display."""

from __future__ import annotations

import io
import os

import numpy as np
import pytest

import omnirender as om
from omnirender.fileio import atomic_write


def test_image_validates_and_fills_alpha():
    img = om.Image(np.zeros((4, 6, 3), np.uint8))
    assert img.array.shape == (4, 6, 4) and img.size == (6, 4) and img.pixel(0, 0) == (0, 0, 0, 255)
    with pytest.raises(ValueError, match="uint8"):
        om.Image(np.zeros((4, 6, 3), np.float32))
    with pytest.raises(ValueError, match="depth"):
        om.Image(np.zeros((4, 6, 4), np.uint8), depth=np.zeros((3, 3)))


def test_image_mask_prefers_depth():
    array = np.zeros((2, 2, 4), np.uint8)
    array[0, 0, 3] = 255
    depth = np.full((2, 2), np.inf, np.float32)
    depth[1, 1] = 2.0
    assert om.Image(array).mask.tolist() == [[True, False], [False, False]]
    assert om.Image(array, depth=depth).mask.tolist() == [[False, False], [False, True]]


def test_image_save_round_trip_and_png_repr(tmp_path):
    from PIL import Image as PILImage

    rng = np.random.default_rng(1)
    array = rng.integers(0, 256, (5, 7, 4), dtype=np.uint8)
    path = om.Image(array).save(tmp_path / "x.png")
    np.testing.assert_array_equal(np.asarray(PILImage.open(path)), array)
    np.testing.assert_array_equal(np.asarray(PILImage.open(io.BytesIO(om.Image(array)._repr_png_()))), array)
    assert os.listdir(tmp_path) == ["x.png"]  # no temporary file left behind
    with pytest.raises(ValueError, match="unsupported extension"):
        om.Image(array).save(tmp_path / "x.gif")
    with pytest.raises(FileNotFoundError, match="does not exist"):
        om.Image(array).save(tmp_path / "missing" / "x.png")


def test_atomic_write_leaves_the_old_file_on_failure(tmp_path):
    target = tmp_path / "f.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_write(target) as fh:
            fh.write("half")
            raise RuntimeError("boom")
    assert target.read_text() == "old" and os.listdir(tmp_path) == ["f.txt"]
    with atomic_write(target) as fh:
        fh.write("new")
    assert target.read_text() == "new"
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask  # not the private mode of mkstemp


def test_render_rejects_unknown_engines_and_bad_sizes():
    scene = om.Node("s")
    with pytest.raises(ValueError, match=r"unknown engine 'nope'.*gl.*mitsuba.*povray"):
        om.render(scene, engine="nope")
    for size in [(0, 10), (10, -1), ("a", 3), 5, (10.5, 10), (1, 2, 3)]:
        with pytest.raises(ValueError, match="size"):
            om.render(scene, engine="gl", size=size)


def test_render_and_export_reject_what_is_not_a_scene(tmp_path):
    # before: om.render(None) returned an empty image, om.render(5) failed inside the GL compiler
    for bad in [None, 5, "scene.yaml", [om.Sphere(), "sphere"]]:
        with pytest.raises(TypeError, match=r"om\.render\(engine='gl'\): scene.*om\.Node"):
            om.render(bad, engine="gl", size=(8, 8))
        with pytest.raises(TypeError, match=r"om\.export\('s\.glb'\): scene.*om\.Node"):
            om.export(bad, tmp_path / "s.glb")
    assert not (tmp_path / "s.glb").exists()


def test_image_pixel_outside_names_the_valid_range():
    image = om.Image(np.zeros((4, 6, 4), np.uint8))
    assert image.pixel(5, 3) == (0, 0, 0, 0)
    for x, y in [(6, 0), (0, 4), (-1, 0), (0, -1)]:  # negative indices used to wrap around silently
        with pytest.raises(IndexError, match=r"outside the 6x4 image.*\[0, 6\).*\[0, 4\)"):
            image.pixel(x, y)


def test_export_rejects_unknown_extensions(tmp_path):
    with pytest.raises(ValueError, match=r"unknown extension '\.xyz'.*\.glb.*\.pov.*\.rib"):
        om.export(om.Node("s"), tmp_path / "scene.xyz")
    assert set(om.exporters()) >= {".glb", ".pov", ".rib", ".rad"}


def test_engines_report_availability_with_a_reason():
    listing = om.engines()
    assert {"gl", "povray", "mitsuba", "radiance"} <= set(listing)
    for ok, why in listing.values():
        assert isinstance(ok, bool) and isinstance(why, str) and why


def test_third_party_engine_registration():
    calls = []

    def fake_render(scene, size, **options):
        calls.append((size, options))
        return om.Image(np.zeros((size[1], size[0], 4), np.uint8), engine="fake")

    om.register_engine("fake-test", fake_render, description="a test engine")
    try:
        img = om.render(om.Node("s"), engine="fake-test", size=(8, 4), quality=3)
        assert img.size == (8, 4) and calls == [((8, 4), {"quality": 3})]
        with pytest.raises(ValueError, match="already registered"):
            om.register_engine("fake-test", fake_render)
    finally:
        from omnirender.render import unregister_engine

        unregister_engine("fake-test")
    assert "fake-test" not in om.engines()


@pytest.mark.gl
def test_node_displays_itself_in_a_notebook():
    from PIL import Image as PILImage

    scene = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 4)), om.Sphere(radius=1)])
    png = scene._repr_png_()
    image = PILImage.open(io.BytesIO(png))
    assert image.size == om.Node.repr_size


def test_render_docstring_lists_options_the_engines_really_take():
    import inspect
    import re

    import omnirender.mitsuba.rendering
    import omnirender.povray
    import omnirender.radiance

    doc = inspect.getdoc(om.render)
    renders = [
        ("povray", omnirender.povray.render),
        ("mitsuba", omnirender.mitsuba.rendering.render),
        ("radiance", omnirender.radiance.render),
    ]
    for engine, fn in renders:
        line = re.search(rf"- {engine}: (.*?);\n\s*- ", doc, re.S).group(1)
        named = set(re.findall(r"``(\w+)``", line))
        assert named and named <= set(inspect.signature(fn).parameters), (engine, named)


def test_image_checks_hdr_and_empty_arrays_and_hints_at_float_conversion():
    rgba = np.zeros((4, 6, 4), np.uint8)
    assert om.Image(rgba, hdr=np.zeros((4, 6, 3), np.float32)).hdr.shape == (4, 6, 3)
    for hdr in [np.zeros((4, 6)), np.zeros((4, 5, 3)), np.zeros((4, 6, 3), np.uint8)]:
        with pytest.raises(ValueError, match=r"Image: hdr must be \(4, 6, 3\|4\) floats"):
            om.Image(rgba, hdr=hdr)
    with pytest.raises(ValueError, match="at least 1x1 pixels"):
        om.Image(np.zeros((0, 0, 4), np.uint8))
    with pytest.raises(ValueError, match=r"float32; convert floats in \[0, 1\] with"):
        om.Image(np.zeros((4, 6, 4), np.float32))
