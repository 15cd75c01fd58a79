"""Lights: OpenGL parameters, attenuation and spot factor."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om


def test_diffuse_and_specular_default_to_color_times_intensity():
    light = om.PointLight(color=(1, 0.5, 0.25), intensity=2)
    assert light.diffuse == (2.0, 1.0, 0.5)
    assert light.specular == (2.0, 1.0, 0.5)
    assert light.parameters()["diffuse"] is None  # follows colour changes after a rebuild
    light.color = (0, 0, 1)
    assert light.diffuse == (0.0, 0.0, 2.0)
    explicit = om.PointLight(diffuse=(0.1, 0.2, 0.3), specular=(0, 0, 0))
    assert explicit.diffuse == (0.1, 0.2, 0.3) and explicit.specular == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("c, lin, q", [(1, 0, 0), (1, 0.5, 0), (0.5, 0.2, 0.1), (0, 0, 1)])
@pytest.mark.parametrize("d", [0.0, 1.0, 2.5, 10.0])
def test_point_light_attenuation(c, lin, q, d):
    light = om.PointLight(constant=c, linear=lin, quadratic=q)
    if c == 0 and d == 0:
        return
    assert light.attenuation(d) == pytest.approx(1.0 / (c + lin * d + q * d * d), rel=1e-12)


def test_attenuation_vectorised_and_unattenuated_lights():
    light = om.SpotLight(constant=1, linear=1, quadratic=1)
    assert np.allclose(light.attenuation(np.array([0, 1, 2])), [1, 1 / 3, 1 / 7])
    assert om.DirectionalLight().attenuation(100.0) == 1.0
    assert om.AmbientLight().attenuation(7.0) == 1.0


def test_spot_factor_inside_and_outside_the_cone():
    spot = om.SpotLight(cutoff=30, exponent=2)
    inside = math.cos(math.radians(20))
    assert spot.spot_factor(inside) == pytest.approx(inside**2)
    assert spot.spot_factor(1.0) == 1.0
    assert spot.spot_factor(math.cos(math.radians(30))) == pytest.approx(math.cos(math.radians(30)) ** 2)
    assert spot.spot_factor(math.cos(math.radians(31))) == 0.0
    assert spot.spot_factor(-1.0) == 0.0
    flat = om.SpotLight(cutoff=90, exponent=0)
    assert flat.spot_factor(0.2) == 1.0
    assert np.allclose(spot.spot_factor(np.array([1.0, 0.0])), [1.0, 0.0])


def test_directions_are_normalised_and_world_transforms():
    d = om.DirectionalLight(direction=(0, -2, 0))
    assert d.direction == (0.0, -1.0, 0.0)
    m = om.Rotation(90, (0, 0, 1)).matrix
    assert np.allclose(d.world_direction(m), (1, 0, 0))
    p = om.PointLight(position=(1, 0, 0))
    t = om.Translation(0, 5, 0).matrix
    assert np.allclose(p.world_position(t), (1, 5, 0))


def test_ambient_light_and_radiance():
    a = om.AmbientLight(color=(1, 0.5, 0), intensity=0.4)
    assert a.ambient == pytest.approx((0.4, 0.2, 0.0))
    assert a.diffuse == (0.0, 0.0, 0.0) and a.specular == (0.0, 0.0, 0.0)
    assert om.PointLight(color=(1, 1, 1), intensity=3).radiance == (3.0, 3.0, 3.0)


def test_lights_are_preevaluated_by_the_engine():
    light = om.PointLight(position=(0, 0, 0))
    scene = om.Node("scene", [om.Node("lamp", [om.Translation(0, 4, 0), light])])
    seen = []

    class Probe(om.Shape):
        __slots__ = ()

    class ProbePainter(om.ShapePainter):
        __slots__ = ()
        service = "analysis"
        target = Probe

        def exec(self, shape, engine):
            seen.extend(engine.lights())

    scene.add(ProbePainter())
    scene.add(Probe())
    om.Engine().run(scene)
    assert len(seen) == 1 and seen[0][0] is light
    assert np.allclose(light.world_position(seen[0][1]), (0, 4, 0))
