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
    with pytest.raises(TypeError, match="om.gl.Stereo"):
        om.Viewer(stereo="side-by-side")


def _centroid(rgb: np.ndarray) -> tuple[float, float]:
    weight = rgb[..., :3].astype(float).sum(-1)
    weight[weight < 0.5 * weight.max()] = 0
    ys, xs = np.indices(weight.shape)
    return float((weight * xs).sum() / weight.sum()) + 0.5, float((weight * ys).sum() / weight.sum()) + 0.5


def test_screen_stereo_with_a_tracked_head_node_has_zero_disparity_on_the_screen():
    """guacamole's screen + eye nodes: each eye looks through the screen rectangle (off-axis); a marker on the
    screen lands on the same pixel of both eye images within half a pixel, wherever the tracked head is."""
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 3), (0, 0, 0), near=0.5, far=50), om.Background((0, 0, 0))])
    tracker = om.Translation(0.4, -0.3, 2.5)
    head = scene.add(om.Node("head", [tracker]))
    scene.add(om.Node("marker", [om.Translation(0.8, 0.6, 0.0), om.Rotation(90, (1, 0, 0)), om.Color((1, 1, 1)),
                                 om.Rectangle(size=(0.1, 0.1))]))  # fmt: skip  # flat, in the screen's plane
    # the screen node (not drawn): a 3.2 x 2.4 rectangle turned to face +z, its -z edge up
    screen = om.Node("screen", [om.Rotation(90, (1, 0, 0)), om.Rectangle(size=(3.2, 2.4))])
    stereo = om.gl.Stereo("side-by-side", eye_separation=0.065, screen=screen, head=head)
    expected = ((0.8 + 1.6) / 3.2 * 160, (1.2 - 0.6) / 2.4 * 120)
    seen = []
    for position in [(0.4, -0.3, 2.5), (-1.0, 0.5, 1.5)]:
        tracker.offset = position
        img = om.render(scene, engine="gl", size=(2 * 160, 120), stereo=stereo).array
        left, right = _centroid(img[:, :160]), _centroid(img[:, 160:])
        assert abs(left[0] - right[0]) <= 0.5 and abs(left[1] - right[1]) <= 0.5, position
        assert abs(left[0] - expected[0]) <= 0.5 and abs(left[1] - expected[1]) <= 0.5, position
        seen.append(img)
    with pytest.raises(ValueError, match="either convergence= or screen="):
        om.gl.Stereo(screen=screen, convergence=3)
    with pytest.raises(ValueError, match="head= needs screen="):
        om.gl.Stereo(head=head)


@pytest.mark.parametrize("mode", ["side-by-side", "top-bottom", "anaglyph", "right"])
def test_stereo_with_the_deferred_pipeline_equals_forward_per_eye(mode):
    """guacamole's stereo on its deferred pipeline: each eye through the whole pipeline (one G-buffer layout, an
    eye-sized target copied into its place); per eye within 3/255 of forward stereo."""
    scene = om.Node("s", [om.Camera.look_at((0, 1, 5), (0, 0, 0)), om.PointLight(position=(3, 4, 5)),
                          om.Background((0.1, 0.1, 0.2))])  # fmt: skip
    scene.add(
        om.Node("a", [om.Material(diffuse=(1, 0.3, 0.2), specular=(1, 1, 1), shininess=30), om.Sphere(radius=0.8)])
    )
    scene.add(om.Node("b", [om.Translation(1.2, 0, -1), om.Material(diffuse=(0.2, 0.8, 0.3)), om.Box(size=(1, 1, 1))]))
    scene.add(
        om.Node("f", [om.Translation(0, -0.9, 0), om.Material(diffuse=(0.7, 0.7, 0.7)), om.Box(size=(6, 0.1, 6))])
    )
    stereo = om.gl.Stereo(mode, eye_separation=0.3)
    images = {}
    for pipeline in ("forward", "deferred"):
        with om.gl.GLEngine(size=(160, 80), samples=0, stereo=stereo, pipeline=pipeline) as engine:
            images[pipeline] = engine.render(scene).array[..., :3].astype(int)
            names = [p["name"] for p in engine.stats["passes"] if "eye" in p["name"]]
        assert any("left" in n for n in names) == (mode != "right")
    forward, deferred = images["forward"], images["deferred"]
    halves = {
        "side-by-side": [(slice(None), slice(0, 80)), (slice(None), slice(80, None))],
        "top-bottom": [(slice(0, 40), slice(None)), (slice(40, None), slice(None))],
    }.get(mode, [(slice(None),) * 2])
    for half in halves:  # fmt: skip
        assert np.abs(forward[half] - deferred[half]).mean() <= 3.0
    assert forward.std() > 20  # something was drawn


def _shaded_scene(post: om.gl.PostProcess | None = None) -> om.Node:
    scene = om.Node("s", [om.Camera.look_at((0, 1, 5), (0, 0, 0)), om.PointLight(position=(3, 4, 5)),
                          om.Background((0.7, 0.7, 0.75))])  # fmt: skip
    if post is not None:
        scene.insert(0, post)
    scene.add(
        om.Node("a", [om.Material(diffuse=(1, 0.3, 0.2), specular=(1, 1, 1), shininess=30), om.Sphere(radius=0.8)])
    )
    box = [om.Translation(1.2, 0, -1), om.Rotation(25, (0, 1, 0)), om.Material(diffuse=(0.2, 0.8, 0.3))]
    scene.add(om.Node("b", [*box, om.Box(size=(1, 1, 1))]))
    return scene


def _stereo_image(scene: om.Node, mode: str, pipeline: str, samples: int, size=(240, 100), passes=None) -> np.ndarray:
    stereo = om.gl.Stereo(mode, eye_separation=0.3)
    with om.gl.GLEngine(size=size, samples=samples, stereo=stereo, pipeline=pipeline) as engine:
        image = engine.render(scene).array[..., :3].astype(int)
        if passes is not None:
            passes.extend(p["name"] for p in engine.stats["passes"])
        return image


def _eyes(mode: str, image: np.ndarray) -> list[np.ndarray]:
    h, w = image.shape[:2]
    if mode == "side-by-side":
        return [image[:, : w // 2], image[:, w // 2 :]]
    if mode == "top-bottom":
        return [image[: h // 2], image[h // 2 :]]
    return [image]


def _edges(image: np.ndarray) -> np.ndarray:
    """Pixels next to a colour step of more than 60/255 (silhouettes)."""
    g = image.sum(-1)
    step = np.zeros(g.shape, bool)
    step[:, 1:] |= np.abs(np.diff(g, axis=1)) > 180
    step[1:] |= np.abs(np.diff(g, axis=0)) > 180
    return step


@pytest.mark.gl_needs(samples=4)
@pytest.mark.parametrize("mode", ["side-by-side", "top-bottom", "anaglyph"])
def test_deferred_stereo_eyes_are_multisampled_as_the_engine_is(mode):
    """Each deferred eye is drawn into a multisampled eye target (the engine's samples) and resolved by its copy:
    per eye within 3/255 of forward stereo with the same MSAA, and its edges are as smooth as forward's (a
    single-sampled deferred eye is not)."""
    scene = _shaded_scene()
    forward = _stereo_image(scene, mode, "forward", 4)
    deferred = _stereo_image(scene, mode, "deferred", 4)
    aliased = _stereo_image(scene, mode, "deferred", 0)
    for f, d, a in zip(_eyes(mode, forward), _eyes(mode, deferred), _eyes(mode, aliased), strict=True):
        assert np.abs(f - d).mean() <= 3.0, np.abs(f - d).mean()
        edge = _edges(f)
        assert edge.sum() > 50
        # on the silhouettes the multisampled deferred eye is much nearer forward's MSAA than one sample is
        assert np.abs(f - d)[edge].mean() < 0.5 * np.abs(f - a)[edge].mean(), (
            np.abs(f - d)[edge].mean(),
            np.abs(f - a)[edge].mean(),
        )
    assert forward.std() > 20


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
@pytest.mark.parametrize("samples", [0, 4])
def test_post_processing_runs_on_each_eye(pipeline, samples):
    """The post-processing chain at the top of the scene runs on each eye's image (an eye is a frame of its
    own): side by side, each half equals that eye rendered alone at the half's size with the same chain, and the
    vignette darkens the corners of each eye, not of the whole frame."""
    post = om.gl.PostProcess([om.gl.Vignette(amount=0.6, start=0.2), om.gl.FXAA()])
    scene = _shaded_scene(post)
    w, h = 240, 100
    sbs = _stereo_image(scene, "side-by-side", pipeline, samples, (w, h))
    for sign, half in ((-1, sbs[:, : w // 2]), (1, sbs[:, w // 2 :])):
        alone = _stereo_image(scene, "left" if sign < 0 else "right", pipeline, samples, (w // 2, h))
        assert np.abs(half - alone).max() <= 2, (sign, np.abs(half - alone).max())
    # the background row at the top: bright at each eye's centre column, dark at each eye's edges
    top = sbs[2, :, :].sum(-1).astype(float)
    centre, edge = top[[w // 4, 3 * w // 4]], top[[1, w // 2 - 2, w // 2 + 1, w - 2]]
    assert centre.min() > edge.max() + 60, (centre, edge)
    plain = _stereo_image(_shaded_scene(), "side-by-side", pipeline, samples, (w, h))
    assert abs(plain[2, w // 2].sum() - plain[2, w // 4].sum()) < 10  # without the chain the background is flat


@pytest.mark.parametrize("mode", ["side-by-side", "top-bottom", "anaglyph"])
def test_deferred_stereo_with_msaa_and_a_post_chain_equals_forward_per_eye(mode):
    """Issue 26's target with MSAA and a post chain: stereo deferred equals stereo forward per eye (mean
    <= 3/255)."""
    post = om.gl.PostProcess([om.gl.ToneMap("aces"), om.gl.Vignette(), om.gl.FXAA()])
    scene = _shaded_scene(post)
    forward = _stereo_image(scene, mode, "forward", 4)
    passes: list[str] = []
    deferred = _stereo_image(scene, mode, "deferred", 4, passes=passes)
    for f, d in zip(_eyes(mode, forward), _eyes(mode, deferred), strict=True):
        assert np.abs(f - d).mean() <= 3.0, np.abs(f - d).mean()
    assert forward.std() > 20
    # each eye: the chain around the deferred pipeline (its G-buffer passes), its effects, then the eye's copy
    for eye in ("left eye", "right eye"):
        assert {
            f"{eye}/scene/geometry",
            f"{eye}/scene/shading",
            f"{eye}/Vignette",
            f"{eye}/FXAA",
            f"{eye} copy",
        } <= set(passes), passes
