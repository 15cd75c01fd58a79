"""om.RectLight / om.DiscLight: validation, placement under transforms, the photometric rule (issue 26)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om
from omnirender.attributes.photometry import area_form_factor, area_power


def test_parameters_rebuild_the_light():
    for light in (om.RectLight(width=2, height=0.5, two_sided=True), om.DiscLight(radius=0.3, casts_shadows=False)):
        again = type(light)(**light.parameters())
        assert again.parameters() == light.parameters()


@pytest.mark.parametrize(
    "make,words",
    [
        (lambda: om.RectLight(width=0), ["RectLight", "width", "> 0"]),
        (lambda: om.RectLight(height=-1), ["RectLight", "height"]),
        (lambda: om.DiscLight(radius=0), ["DiscLight", "radius"]),
        (lambda: om.RectLight(direction=(0, 0, 0)), ["RectLight", "direction"]),
        (lambda: om.RectLight(direction=(0, 0, 1), up=(0, 0, -3)), ["RectLight", "parallel", "give an up"]),
        (lambda: om.RectLight(color=(2, 0, 0)), ["RectLight", "color"]),
    ],
)
def test_invalid_parameters_name_the_component_and_the_fix(make, words):
    with pytest.raises(ValueError) as info:
        make()
    for word in words:
        assert word in str(info.value)


def test_a_flattening_matrix_is_refused():
    with pytest.raises(ValueError, match="RectLight: the transforms in effect flatten the light to zero area"):
        om.RectLight().world_frame(np.diag([0.0, 1.0, 1.0, 1.0]))


def test_transforms_place_turn_and_scale_the_light():
    light = om.RectLight(position=(1, 0, 0), direction=(0, 0, -1), width=2.0, height=1.0)
    m = om.Translation((0, 3, 0)).matrix @ om.Rotation(axis=(1, 0, 0), angle=90).matrix
    m = m @ np.diag([2.0, 2.0, 2.0, 1.0])
    centre, hu, hv, normal = light.world_frame(m)
    np.testing.assert_allclose(centre, (2, 3, 0), atol=1e-12)
    np.testing.assert_allclose(normal, (0, 1, 0), atol=1e-12)  # -z turned about x by 90 degrees
    assert np.linalg.norm(hu) == pytest.approx(2.0) and np.linalg.norm(hv) == pytest.approx(1.0)
    assert light.world_area(m) == pytest.approx(8.0)
    # a mirror keeps the lit side on the transformed direction
    assert light.world_frame(np.diag([1.0, 1.0, -1.0, 1.0]))[3] == pytest.approx((0, 0, 1))


def test_polygon_is_counter_clockwise_from_the_lit_side():
    for light in (om.RectLight(direction=(0, -1, 0)), om.DiscLight(direction=(0.3, -1, 0.2))):
        pts = light.world_polygon(np.eye(4))
        n = np.cross(pts[1] - pts[0], pts[2] - pts[0])
        assert np.dot(n, light.world_direction(np.eye(4))) > 0


def test_form_factor_is_exact():
    # a disc of radius r at height h over a point: F = r^2 / (h^2 + r^2)
    disc = om.DiscLight(position=(0, 2, 0), direction=(0, -1, 0), radius=1.0)
    f = area_form_factor([[0, 0, 0]], [0, 1, 0], disc.world_polygon(np.eye(4), 256))
    assert f[0] == pytest.approx(1 / 5, rel=1e-4)
    # a huge light over a point: F -> 1 (a head-on directional light of the same colour)
    big = om.RectLight(position=(0, 1e-3, 0), direction=(0, -1, 0), width=1e3, height=1e3)
    assert area_form_factor([[0, 0, 0]], [0, 1, 0], big.world_polygon(np.eye(4)))[0] == pytest.approx(1, abs=1e-5)
    # behind the light nothing, unless two-sided
    rect = om.RectLight(position=(0, 2, 0), direction=(0, -1, 0))
    assert area_form_factor([[0, 3, 0]], [0, -1, 0], rect.world_polygon(np.eye(4)))[0] == 0.0
    assert area_form_factor([[0, 3, 0]], [0, -1, 0], rect.world_polygon(np.eye(4)), two_sided=True)[0] > 0.1
    # a light half below the horizon counts only above it
    wall = om.RectLight(position=(0, 0, -1), direction=(0, 0, 1), width=2, height=2)
    full = area_form_factor([[0, 0, 0]], [0, 0, -1], wall.world_polygon(np.eye(4)))[0]
    half = area_form_factor([[0, 0, 0]], [0, 1, 0], wall.world_polygon(np.eye(4)))[0]
    assert 0 < half < full


def test_power_is_pi_radiance_area_per_side():
    light = om.RectLight(width=2, height=3, color=(1, 0.5, 0), intensity=2.0)
    np.testing.assert_allclose(area_power(light, np.eye(4)), np.array([2.0, 1.0, 0.0]) * math.pi * 6)
    two = om.DiscLight(radius=1, two_sided=True)
    np.testing.assert_allclose(area_power(two, np.eye(4)), 2 * math.pi * math.pi)
