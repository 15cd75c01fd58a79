"""Tiled rendering (omnirender.tiling): off-axis tiles stitched without seams, streamed PNG files, refusals."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import omnirender as om
from omnirender import tiling
from omnirender.demo import demo_scene


def test_tiles_cover_the_image_once_and_keep_their_margins_inside():
    rows = tiling.plan_tiles((1000, 700), 256, margin=64)
    cover = np.zeros((700, 1000), np.int32)
    for row in rows:
        for t in row:
            cover[t.y : t.y + t.h, t.x : t.x + t.w] += 1
            rx, ry, rw, rh = t.render
            assert 0 <= rx <= t.x and 0 <= ry <= t.y and rx + rw <= 1000 and ry + rh <= 700
            assert (700 - (ry + rh)) % 16 == 0 and rx % 16 == 0  # pattern phase kept (rows from the bottom)
    assert (cover == 1).all()
    assert rows[-1][0].y + rows[-1][0].h == 700 and rows[-1][0].h == 256  # full rows at the bottom


@pytest.mark.parametrize("camera", [om.Camera.look_at((3, 2, 5), fov=40), om.Camera.orthographic((3, 2, 5), height=3)])
def test_a_tile_camera_sees_its_window_of_the_full_view(camera):
    size, window = (800, 600), (200, 100, 300, 250)
    tile = tiling.TileCamera(camera, size, window)
    point = np.array([0.3, -0.2, 0.1, 1.0])

    def pixel(proj, w, h):
        clip = proj @ camera.view_matrix() @ point
        ndc = clip[:2] / clip[3]
        return np.array([(ndc[0] + 1) * w / 2, (1 - ndc[1]) * h / 2])

    full = pixel(camera.projection_matrix(800 / 600), 800, 600)
    part = pixel(tile.projection_matrix(123.0), 300, 250)  # the aspect an engine passes is ignored
    assert np.allclose(part, full - np.array(window[:2]), atol=1e-9)


@pytest.fixture(scope="module")
def demo():
    return demo_scene()


def test_a_tiled_gl_render_equals_the_untiled_one_without_seams(demo):
    whole = om.render(demo, size=(320, 240))
    tiled = om.render(demo, size=(320, 240), tile=96)
    assert tiled.info["tiles"] == 12
    diff = np.abs(whole.array.astype(np.int16) - tiled.array.astype(np.int16)).max(axis=2)
    assert (diff > 2).mean() < 0.002  # isolated edge pixels (a sample's coverage flips with the matrix rounding)
    for x in range(96, 320, 96):  # the seams themselves
        assert (diff[:, x - 1 : x + 1] > 2).mean() < 0.02
    finite = np.isfinite(whole.depth)
    assert np.array_equal(finite, np.isfinite(tiled.depth)) or (finite != np.isfinite(tiled.depth)).mean() < 0.002
    assert np.allclose(whole.depth[finite & np.isfinite(tiled.depth)], tiled.depth[finite & np.isfinite(tiled.depth)],
                       rtol=1e-3)  # fmt: skip


def test_tiles_stream_into_a_png_file(demo, tmp_path):
    from PIL import Image

    path = om.render_to_file(demo, tmp_path / "poster.png", size=(200, 150), tile=64)
    stitched = om.render(demo, size=(200, 150), tile=64)
    with Image.open(path) as img:
        assert img.size == (200, 150)
        assert np.array_equal(np.asarray(img.convert("RGBA")), stitched.array)
    with pytest.raises(ValueError, match=r"\.png"):
        om.render_to_file(demo, tmp_path / "poster.jpg", size=(64, 64))


def test_the_gl_engine_tiles_by_itself_beyond_its_framebuffer_limit(demo, monkeypatch):
    monkeypatch.setattr(tiling, "_gl_max_size", lambda: 1024)
    monkeypatch.setattr(tiling, "DEFAULT_MARGIN", 32)
    image = om.render(demo, size=(4100, 64), samples=0, read_depth=False)
    assert image.array.shape == (64, 4100, 4) and image.info["tiles"] > 1
    with pytest.raises(ValueError, match="om.render_to_file"):
        om.render(demo, size=(40000, 40000))


def test_other_engines_refuse_tiles_clearly(demo):
    with pytest.raises(ValueError, match="tile= is supported by the gl engine only; povray renders the whole size"):
        om.render(demo, engine="povray", size=(64, 48), tile=32)
    with pytest.raises(ValueError, match="tile must be a whole number"):
        om.render(demo, size=(64, 48), tile=3)


def test_effects_that_look_at_the_whole_image_warn_in_a_tiled_render(demo):
    chain = om.gl.PostProcess([om.gl.FXAA(), om.gl.Vignette()])
    with pytest.warns(UserWarning, match="Vignette look"):
        om.render(om.Node("r", [chain, demo]), size=(64, 48), tile=32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        om.render(om.Node("r", [om.gl.PostProcess([om.gl.FXAA()]), demo]), size=(64, 48), tile=32)
