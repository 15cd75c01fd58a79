"""Off-axis cameras (guacamole's screen + eye nodes): one window, every engine, zero disparity on the screen.

``om.Camera.from_screen(corners, eye)`` looks through a screen rectangle from a
tracked eye: the frustum is the screen, so a point on the screen lands on the
same pixel for every eye position.  Markers (small emissive spheres) sit on
the screen plane; every engine must draw them where the screen mapping says,
within half a pixel, and two eyes 6.5 cm apart must see them at the same pixel.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from engines import marks, require

import omnirender as om

SIZE = (160, 120)
SCREEN = ((-1.6, -1.2, 0.0), (1.6, -1.2, 0.0), (-1.6, 1.2, 0.0))  # 3.2 x 2.4: the image's aspect
MARKERS = ((0.8, 0.6, 0.0), (-1.0, -0.7, 0.0), (1.2, -0.9, 0.0))
ENGINES = ("gl", "povray", "mitsuba", "radiance")


def expected_pixel(p) -> tuple[float, float]:
    """Where a point on the screen belongs: the screen's own mapping onto the image (x right, y down)."""
    return (p[0] + 1.6) / 3.2 * SIZE[0], (1.2 - p[1]) / 2.4 * SIZE[1]


def marker_scene(camera: om.Camera) -> om.Node:
    s = om.Node("s", [camera, om.Background((0, 0, 0)), om.PointLight(position=(0, 0, 5))])
    for i, p in enumerate(MARKERS):
        s.add(om.Node(f"m{i}", [om.Translation(*p), om.Material(diffuse=(1, 1, 1), emission=(1, 1, 1)),
                                om.Sphere(radius=0.06)]))  # fmt: skip
    return s


def centroids(image: om.Image) -> list[tuple[float, float]]:
    a = image.array[..., :3].astype(np.float64).sum(axis=-1)
    out = []
    for p in MARKERS:
        px, py = expected_pixel(p)
        x0, y0 = int(px) - 8, int(py) - 8
        window = a[y0 : y0 + 16, x0 : x0 + 16]
        ys, xs = np.nonzero(window > 0.5 * window.max())
        weights = window[ys, xs]
        out.append(
            (x0 + 0.5 + float(np.average(xs, weights=weights)), y0 + 0.5 + float(np.average(ys, weights=weights)))
        )
    return out


def test_from_screen_frustum_is_the_screen_for_any_eye():
    for eye in [(0.0, 0.0, 3.0), (0.9, 0.5, 3.0), (-2.5, 1.7, 1.2), (0.3, -0.4, 10.0)]:
        cam = om.Camera.from_screen(SCREEN, eye, near=0.5, far=50.0)
        m = cam.projection_matrix(SIZE[0] / SIZE[1]) @ cam.view_matrix()
        corners = np.array([*SCREEN, (1.6, 1.2, 0.0)])
        ndc = (m @ np.c_[corners, np.ones(4)].T).T
        ndc = ndc[:, :2] / ndc[:, 3:4]
        assert np.allclose(ndc, [(-1, -1), (1, -1), (-1, 1), (1, 1)], atol=1e-9), eye
        assert cam.is_off_axis == (eye[:2] != (0.0, 0.0))
    # a symmetric look_at camera is a from_screen camera with the eye on the screen's axis
    centred = om.Camera.from_screen(SCREEN, (0.0, 0.0, 3.0))
    assert centred.shift == (0.0, 0.0) and centred.fov == pytest.approx(math.degrees(2 * math.atan(0.4)))


def test_from_screen_refuses_bad_screens_and_eyes_behind_them():
    with pytest.raises(ValueError, match="not in front of the screen"):
        om.Camera.from_screen(SCREEN, (0.0, 0.0, -2.0))
    with pytest.raises(ValueError, match="three finite world points"):
        om.Camera.from_screen(SCREEN[:2], (0.0, 0.0, 2.0))
    with pytest.raises(ValueError, match="no height"):
        om.Camera.from_screen(((0, 0, 0), (1, 0, 0), (2, 0, 0)), (0.0, 0.0, 2.0))
    with pytest.raises(ValueError, match="shift"):
        om.Camera(shift=(0.0, math.nan))


def test_screen_node_and_tracked_head_node_give_corners_and_eye():
    """A screen node's om.Rectangle (facing +y, -z edge up) turned to face +z; a head node moved by a tracker."""
    root = om.Node("root", [om.Translation(0.0, 1.0, 0.0)])
    screen = root.add(om.Node("screen", [om.Rotation(axis=(1, 0, 0), angle=90), om.Rectangle(size=(3.2, 2.4))]))
    head = root.add(om.Node("head", [om.Translation(0.2, 0.1, 2.0)]))
    corners = om.screen_corners(screen)
    assert np.allclose(corners, np.array(SCREEN) + (0, 1, 0), atol=1e-12)
    assert np.allclose(om.node_origin(head), (0.2, 1.1, 2.0))
    with pytest.raises(ValueError, match="holds no om.Rectangle"):
        om.screen_corners(head)


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ENGINES])
def test_every_engine_draws_the_screen_where_the_off_axis_frustum_puts_it(name):
    require(name)
    cam = om.Camera.from_screen(SCREEN, (0.9, 0.5, 3.0), near=0.5, far=50.0)
    assert cam.is_off_axis
    found = centroids(om.render(marker_scene(cam), engine=name, size=SIZE))
    for p, (x, y) in zip(MARKERS, found, strict=True):
        ex, ey = expected_pixel(p)
        assert abs(x - ex) <= 0.5 and abs(y - ey) <= 0.5, (name, p, (x, y), (ex, ey))


@pytest.mark.gl
def test_two_eyes_see_screen_points_at_the_same_pixel():
    """Zero disparity on the screen plane: left and right eye images agree there within half a pixel."""
    require("gl")
    head = np.array([0.4, -0.3, 2.5])
    eyes = [head + (-0.0325, 0, 0), head + (0.0325, 0, 0)]
    images = [om.render(marker_scene(om.Camera.from_screen(SCREEN, e, near=0.5, far=50)), engine="gl", size=SIZE)
              for e in eyes]  # fmt: skip
    left, right = (centroids(img) for img in images)
    for (xl, yl), (xr, yr) in zip(left, right, strict=True):
        assert abs(xl - xr) <= 0.5 and abs(yl - yr) <= 0.5
    # a point behind the screen does diverge (uncrossed disparity): the eyes really differ
    behind = [om.Node("s", [om.Camera.from_screen(SCREEN, e, near=0.5, far=50), om.Background((0, 0, 0)),
              om.Node("b", [om.Translation(0, 0, -3), om.Material(emission=(1, 1, 1)), om.Sphere(radius=0.1)])])
              for e in eyes]  # fmt: skip
    xs = []
    for s in behind:
        a = om.render(s, engine="gl", size=SIZE).array[..., 0].astype(float)
        xs.append(float(np.average(np.nonzero(a > 128)[1])))
    # the right eye sees it farther right by e d / (D + d) on the screen (D eye-screen, d screen-point distances)
    expected = 0.065 * 3.0 / (2.5 + 3.0) / 3.2 * SIZE[0]
    assert xs[1] - xs[0] == pytest.approx(expected, abs=0.5)


def test_rib_and_gltf_exports_keep_or_report_the_shift(tmp_path):
    cam = om.Camera.from_screen(SCREEN, (0.9, 0.5, 3.0), near=0.5, far=50.0)
    scene = om.Node("s", [cam, om.Sphere()])
    from omnirender.formats import rib

    text = rib.to_text(scene, size=SIZE)
    # RenderMan: fov spans the (vertical) smaller side; the window is the screen's, in units of tan(fov / 2)
    left, right, bottom, top = (float(v) for v in text.split("ScreenWindow ")[1].split()[:4])
    assert (right - left) / (top - bottom) == pytest.approx(SIZE[0] / SIZE[1])
    assert (left + right) / 2 == pytest.approx(2 * cam.shift[0]) and (bottom + top) / 2 == pytest.approx(
        2 * cam.shift[1]
    )
    assert "ScreenWindow" not in rib.to_text(om.Node("s", [om.Camera.look_at((0, 0, 5)), om.Sphere()]))
    with pytest.warns(UserWarning, match="off-axis shift"):
        om.export(scene, tmp_path / "s.glb", size=SIZE)
