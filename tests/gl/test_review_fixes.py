"""Regression tests for review findings on the GL engine: blend order, segment order, resources, clipping, errors."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(96, 72), samples=0)
    yield e
    e.release()


def two_transparent_spheres(separate: bool) -> om.Node:
    """Red sphere behind, blue sphere in front, both 50% opaque and unlit (emission only), same mesh."""
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6), center=(0, 0, 0), fov=40))
    s.add(om.AmbientLight(intensity=0.0))
    for i, (color, z) in enumerate((((1, 0, 0), -0.6), ((0, 0, 1), 0.6))):
        n = s.add(om.Node(f"t{i}"))
        if separate and i:
            # a different (no-op) draw state: the two spheres cannot share one draw call
            n.add(om.gl.PolygonOffset(0.0, 0.0))
        n.add(om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), specular=(0, 0, 0), emission=color, opacity=0.5))
        n.add(om.Sphere(center=(0.35 * (1 if i else -1), 0, z), radius=0.9))
    return s


def test_transparent_instances_of_one_mesh_blend_back_to_front(engine):
    merged = engine.render(two_transparent_spheres(False), background=(1, 1, 1)).array.astype(int)
    split = engine.render(two_transparent_spheres(True), background=(1, 1, 1)).array.astype(int)
    assert np.abs(merged - split).max() <= 2
    # analytic overlap colour at the centre, where both spheres cover the pixel twice (back and front faces):
    # white, then red back and front face, then blue back and front face, each blended "over" with alpha 0.5
    c = np.array([1.0, 1.0, 1.0])
    for color in ((1, 0, 0), (1, 0, 0), (0, 0, 1), (0, 0, 1)):
        c = 0.5 * np.asarray(color, float) + 0.5 * c
    expected = np.round(c * 255)
    assert np.abs(merged[36, 48, :3] - expected).max() <= 6, (merged[36, 48], expected)


def test_plain_shapes_after_a_special_state_shape_are_drawn_after_it(engine):
    """A green box (plain), a red sphere without depth test, then a blue box in front: blue must win."""
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6)))
    x = s.add(om.Node("x"))
    x.add(om.Color(0, 1, 0))
    x.add(om.Box(size=(0.5, 0.5, 0.5), center=(-2, 0, 0)))  # same mesh as the blue box: would share its batch
    sp = s.add(om.Node("s"))
    sp.add(om.gl.DepthTest(False))
    sp.add(om.Color(1, 0, 0))
    sp.add(om.Sphere(radius=1, center=(0, 0, -1)))
    y = s.add(om.Node("y"))
    y.add(om.Color(0, 0, 1))
    y.add(om.Box(size=(1, 1, 1), center=(0, 0, 1)))
    r, g, b, _ = engine.render(s).pixel(48, 36)
    assert b > 200 and r < 50, (r, g, b)
