"""Lighting against OpenGL's formulas, volumes, text placement, out-of-memory reporting."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(64, 48), samples=0)
    yield e
    e.release()


def linear(value: int) -> float:
    c = value / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def plane_with(light: om.Light) -> om.Node:
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 10), fov=30))
    s.add(light)
    s.add(om.Color(1, 1, 1))
    s.add(om.Rectangle(size=(20, 20)))
    s.insert(2, om.Rotation(90, (1, 0, 0)))  # the rectangle faces +z, towards the camera
    return s


@pytest.mark.parametrize("linear_att, quadratic", [(0.0, 0.0), (0.5, 0.0), (0.0, 0.25)])
def test_point_light_attenuation_follows_opengl(engine, linear_att, quadratic):
    d = 2.0
    light = om.PointLight(position=(0, 0, d), intensity=0.6, linear=linear_att, quadratic=quadratic)
    img = engine.render(plane_with(light))
    expected = 0.2 + 0.6 / (1.0 + linear_att * d + quadratic * d * d)  # global ambient 0.2 x colour + diffuse
    assert linear(img.pixel(32, 24)[0]) == pytest.approx(expected, abs=0.01)


def test_spot_light_cutoff_and_exponent(engine):
    light = om.SpotLight(position=(0, 0, 2), direction=(0, 0, -1), cutoff=30, exponent=2, intensity=0.6)
    img = engine.render(plane_with(light))
    centre = linear(img.pixel(32, 24)[0])
    assert centre == pytest.approx(0.2 + 0.6, abs=0.01)
    # a point on the plane at 40 degrees off the axis is outside the cone: ambient only
    x = 2.0 * np.tan(np.radians(40))
    px = int(round(32 + x / (10 * np.tan(np.radians(15))) * 24))
    assert linear(img.pixel(px, 24)[0]) == pytest.approx(0.2, abs=0.01)
    # inside the cone at 20 degrees: cos^2 spot factor times the oblique incidence and 1/(d^2) = 1
    x = 2.0 * np.tan(np.radians(20))
    px = x / (10 * np.tan(np.radians(15))) * 24 + 31.5
    c = np.cos(np.radians(20))
    expected = 0.2 + 0.6 * c**2 * c
    value = np.interp(
        px, [int(px), int(px) + 1], [linear(img.pixel(int(px), 24)[0]), linear(img.pixel(int(px) + 1, 24)[0])]
    )
    assert value == pytest.approx(expected, abs=0.02)


def test_directional_light_lambert(engine):
    light = om.DirectionalLight(direction=(0, -1, -1), intensity=0.7)
    img = engine.render(plane_with(light))
    assert linear(img.pixel(32, 24)[0]) == pytest.approx(0.2 + 0.7 * np.cos(np.radians(45)), abs=0.01)


def test_volume_depth_matches_first_significant_sample(engine):
    z, y, x = np.mgrid[-1:1:24j, -1:1:24j, -1:1:24j]
    data = (np.sqrt(x**2 + y**2 + z**2) < 0.5).astype(np.float32)  # an opaque ball of radius 0.5
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 5), fov=30))
    s.add(om.Volume(data, spacing=2 / 23, transfer_function=[(0.0, (1, 1, 1, 0)), (1.0, (1, 0.5, 0.2, 1))]))
    img = engine.render(s)
    assert img.depth[24, 32] == pytest.approx(4.5, abs=0.1)
    # colour-depth consistency: coloured where (and only where) the depth is finite
    coloured = np.abs(img.array[:, :, :3].astype(int) - img.array[0, 0, :3].astype(int)).max(axis=2) > 3
    assert np.array_equal(coloured, np.isfinite(img.depth))


def test_text_is_drawn_at_the_projected_position(engine):
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 5)))
    s.add(om.Color(1, 1, 1))
    s.add(om.Text("Hi", position=(0, 0, 0), size=12))
    img = engine.render(s, background=(0, 0, 0))
    ys, xs = np.nonzero(img.array[:, :, 0] > 128)
    assert len(xs) > 10
    # lower-left corner at the projection of the origin (the image centre)
    assert 31 <= xs.min() <= 35 and 12 <= ys.min() and ys.max() <= 26


def test_out_of_memory_becomes_a_clear_error():
    from omnirender.gl.engine.context import GLError
    from omnirender.gl.engine.resources import gpu_call

    def fail(*args, **kwargs):
        raise RuntimeError("GL_OUT_OF_MEMORY")

    with pytest.raises(GLError, match="out of memory while uploading vertices of X"):
        gpu_call(fail, what="vertices of X")
