"""The VRS transforms: reflection, direction of flight and polar coordinates, in every engine."""

from __future__ import annotations

import math

import numpy as np
import pytest
from engines import marks, require

import omnirender as om


def test_reflection_mirrors_in_its_plane():
    r = om.Reflection(normal=(0, 2, 0), point=(0, 1, 0))
    m = r.matrix
    assert np.linalg.det(m[:3, :3]) == pytest.approx(-1.0)
    assert np.allclose(m @ [3, 0, 2, 1], [3, 2, 2, 1])  # y = 0 goes to y = 2 across the plane y = 1
    assert np.allclose(m @ m, np.eye(4))
    assert r.parameters() == {"normal": [0.0, 1.0, 0.0], "point": [0.0, 1.0, 0.0]}
    r.point = (0, 0, 0)
    assert np.allclose(r.matrix @ [0, 1, 0, 1], [0, -1, 0, 1])
    with pytest.raises(ValueError, match="normal must not be the zero vector"):
        om.Reflection(normal=(0, 0, 0))


def test_direction_of_flight_turns_z_along_the_velocity():
    d = om.DirectionOfFlight(velocity=(3, 0, 4), up=(0, 1, 0), position=(1, 2, 3))
    m = d.matrix
    assert np.allclose(m[:3, 2], (0.6, 0, 0.8)) and np.allclose(m[:3, 1], (0, 1, 0))
    assert np.allclose(m[:3, 3], (1, 2, 3)) and np.linalg.det(m[:3, :3]) == pytest.approx(1.0)
    d.velocity = (0, -5, 0.0001)
    assert np.allclose(d.matrix[:3, 2], (0, -1, 0), atol=1e-4)
    with pytest.raises(ValueError, match="parallel"):
        om.DirectionOfFlight(velocity=(0, 2, 0))


def test_polar_places_and_orients_on_a_sphere():
    p = om.Polar(radius=2, azimuth=90, elevation=30)
    assert np.allclose(p.matrix[:3, 3], (2 * math.cos(math.radians(30)), 1.0, 0.0))
    assert np.allclose(p.matrix[:3, :3], np.eye(3))
    o = om.Polar(radius=2, azimuth=0, elevation=90, orient=True)
    assert np.allclose(o.matrix[:3, 3], (0, 2, 0)) and np.allclose(o.matrix[:3, 2], (0, 1, 0))
    assert np.linalg.det(o.matrix[:3, :3]) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="radius"):
        om.Polar(radius=-1)


def test_the_transforms_move_what_follows_for_analysis_engines():
    s = om.Node("s", [om.Reflection(normal=(1, 0, 0)), om.Sphere(center=(2, 0, 0), radius=0.5)])
    lo, hi = om.bounds(s)
    assert np.allclose(lo, (-2.5, -0.5, -0.5)) and np.allclose(hi, (-1.5, 0.5, 0.5))
    s = om.Node("s", [om.Polar(radius=3, azimuth=90, elevation=0), om.Sphere(radius=0.5)])
    assert np.allclose(om.bounds(s)[0], (2.5, -0.5, -0.5))
    hit = om.pick(om.Node("s", [om.DirectionOfFlight((1, 0, 0), position=(0, 0, -5)), om.Box(size=(1, 1, 4))]),
                  ray=((0, 0, 0), (0, 0, -1)), nearest=True)[0]  # fmt: skip
    assert hit.distance == pytest.approx(4.5)  # the 4-long box lies along x now: 1 wide along z


ENGINES = ("gl", "povray", "mitsuba", "radiance")


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ENGINES])
def test_every_engine_mirrors_an_asymmetric_shape_the_same_way(name):
    """A cone lying along +x, mirrored to -x by a Reflection: the silhouette lies left, as the matrix says."""
    require(name)
    s = om.Node("s", [om.Camera.look_at((0, 0, 8), (0, 0, 0)), om.Background((0, 0, 0)),
                      om.DirectionalLight(direction=(0, 0, -1))])  # fmt: skip
    s.add(om.Node("c", [om.Reflection(normal=(1, 0, 0)), om.Translation(1, 0, 0), om.Rotation(-90, (0, 0, 1)),
                        om.Material(diffuse=(1, 1, 1)), om.Cone(radius=0.6, height=2)]))  # fmt: skip
    a = om.render(s, engine=name, size=(80, 60)).array[..., :3].astype(float).sum(axis=-1)
    cols = np.nonzero((a > 30).any(axis=0))[0]
    # everything left of the centre: the cone spans x in [-2, 0], so column 40 (x = 0) is the apex's edge pixel,
    # which a reconstruction filter or a denoiser may touch; a cone mirrored the wrong way spans columns 40-60
    assert cols.size and cols.max() <= 40 and cols.min() < 25
    lit = a[:, cols]
    assert lit[lit > 30].mean() > 150  # and lit from the front (the mirrored faces face the light)
