"""Stereo pairs: off-axis eyes, disparity against the analytic answer, packings, viewer, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om
from omnirender.gl.techniques.stereo import disparity_pixels

W, H = 240, 180
SEPARATION, CONVERGENCE, FOV = 0.2, 4.0, 40.0


def ball_scene(distance: float, x: float = 0.0) -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at((0, 0, 0), (0, 0, -1), fov=FOV, near=0.1, far=100))
    scene.add(om.Background((0, 0, 0)))
    ball = scene.add(om.Node("ball"))
    ball.add(om.Translation(x, 0, -distance))
    ball.add(om.Color((1, 1, 1)))
    ball.add(om.Sphere(radius=0.05 * distance))
    return scene


def centroid_x(rgb: np.ndarray) -> float:
    weight = rgb[..., :3].astype(float).sum(-1)
    weight[weight < 30] = 0
    xs = np.arange(rgb.shape[1])[None, :]
    return float((weight * xs).sum() / weight.sum())


def eye_image(scene: om.Node, mode: str) -> np.ndarray:
    stereo = om.gl.Stereo(mode, eye_separation=SEPARATION, convergence=CONVERGENCE)
    return om.render(scene, engine="gl", size=(W, H), stereo=stereo).array


def test_disparity_is_zero_at_convergence_and_grows_as_computed():
    fov_x = 2 * math.degrees(math.atan(math.tan(math.radians(FOV / 2)) * W / H))
    measured = {}
    for d in (2.0, CONVERGENCE, 8.0, 16.0):
        scene = ball_scene(d)
        measured[d] = centroid_x(eye_image(scene, "left")) - centroid_x(eye_image(scene, "right"))
        expected = disparity_pixels(d, W, fov_x, SEPARATION, CONVERGENCE)
        assert measured[d] == pytest.approx(expected, abs=0.6), (d, measured[d], expected)
    assert abs(measured[CONVERGENCE]) < 0.3
    assert measured[2.0] > 10  # nearer than the convergence plane: crossed (the left image lies to the right)
    assert measured[16.0] < measured[8.0] < -5  # farther: uncrossed, growing with distance


def test_eyes_see_no_vertical_parallax_and_the_centre_camera_lies_between():
    scene = ball_scene(8.0, x=0.5)
    left, right = eye_image(scene, "left"), eye_image(scene, "right")
    mono = om.render(scene, engine="gl", size=(W, H)).array
    rows = [np.nonzero(img[..., :3].sum(-1).sum(1) > 200)[0] for img in (left, right)]
    assert abs(rows[0].mean() - rows[1].mean()) < 0.05
    xl, xr, xm = centroid_x(left), centroid_x(right), centroid_x(mono)
    assert xl < xm < xr and xm == pytest.approx((xl + xr) / 2, abs=0.3)


def test_side_by_side_and_top_bottom_pack_the_two_eyes():
    scene = ball_scene(8.0)
    half = om.gl.Stereo("left", eye_separation=SEPARATION, convergence=CONVERGENCE)
    left_half = om.render(scene, engine="gl", size=(W // 2, H), stereo=half).array
    sbs = eye_image(scene, "side-by-side")
    assert np.abs(sbs[:, : W // 2].astype(int) - left_half.astype(int)).max() <= 2
    right_eye = om.gl.Stereo("right", eye_separation=SEPARATION, convergence=CONVERGENCE)
    right_half = om.render(scene, engine="gl", size=(W - W // 2, H), stereo=right_eye).array
    assert np.abs(sbs[:, W // 2 :].astype(int) - right_half.astype(int)).max() <= 2
    tb = eye_image(scene, "top-bottom")
    top = om.render(scene, engine="gl", size=(W, H // 2), stereo=half).array
    assert np.abs(tb[: H // 2].astype(int) - top.astype(int)).max() <= 2


def test_anaglyph_puts_the_left_eye_in_red_and_the_right_eye_in_cyan():
    scene = ball_scene(8.0)
    ana = eye_image(scene, "anaglyph")
    left, right = eye_image(scene, "left"), eye_image(scene, "right")
    assert np.abs(ana[..., 0].astype(int) - left[..., 0]).max() <= 2
    assert np.abs(ana[..., 1:3].astype(int) - right[..., 1:3]).max() <= 2
    assert centroid_x(ana[..., [0, 0, 0]]) < centroid_x(ana[..., [1, 1, 1]])  # far ball: red left of cyan


def test_viewer_draws_stereo_frames():
    scene = ball_scene(8.0)
    viewer = om.Viewer(size=(W, H), stereo=om.gl.Stereo("side-by-side", SEPARATION, CONVERGENCE))
    try:
        viewer.add_renderable(scene)
        viewer.set_eye_to_world((0, 0, 0), (0, 0, -1), (0, 1, 0))
        img = viewer.rerender().array
        lit = img[..., :3].astype(int).sum(-1) > 200
        cols = np.nonzero(lit.any(0))[0]
        assert cols.min() < W // 2 and cols.max() >= W // 2  # a ball in each half
        assert not lit[:, W // 2 - 2 : W // 2 + 2].any()
        viewer.stereo = None
        mono = viewer.rerender().array[..., :3].astype(int).sum(-1) > 200
        assert np.nonzero(mono.any(0))[0].mean() == pytest.approx(W / 2, abs=2)
    finally:
        viewer.close()


def test_stereo_errors_say_what_to_give():
    with pytest.raises(ValueError, match="mode must be one of"):
        om.gl.Stereo("interlaced")
    with pytest.raises(ValueError, match="eye_separation must be a finite number > 0"):
        om.gl.Stereo(eye_separation=-1)
    scene = ball_scene(4.0)
    scene.remove(scene.items[0])
    scene.insert(0, om.Camera.orthographic((0, 0, 0), (0, 0, -1), height=2))
    with pytest.raises(ValueError, match="orthographic; stereo needs a perspective camera"):
        om.render(scene, engine="gl", size=(64, 48), stereo=om.gl.Stereo())
    with pytest.raises(ValueError, match="pipeline='forward'"):
        om.gl.GLEngine(size=(64, 48), pipeline="deferred", stereo=om.gl.Stereo()).release()
    with pytest.raises(TypeError, match="om.gl.Stereo"):
        om.Viewer(stereo="side-by-side")
