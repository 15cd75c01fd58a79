"""Lighting simulation with rtrace against analytic answers: numbers in physical units, not pictures."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om
from omnirender.attributes.photometry import srgb_to_linear

pytestmark = pytest.mark.radiance


def _ground(*lights, rho=0.5):
    s = om.Node("s", list(lights))
    s.add(om.Node("ground", [om.Color(rho, rho, rho), om.Rectangle(size=(100, 100))]))
    return s


def _points_and_expected(light_at, intensity, cases):
    points, normals, expected = [], [], []
    for x, tilt in cases:
        p = np.array([x, 1e-3, 0.4])
        normal = np.array([math.sin(math.radians(tilt)), math.cos(math.radians(tilt)), 0.0])
        to_light = np.asarray(light_at) - p
        d = np.linalg.norm(to_light)
        points.append(p)
        normals.append(normal)
        expected.append(intensity * max(to_light @ normal / d, 0.0) / (d * d))
    return points, normals, np.array(expected)


CASES = [(0, 0), (1, 0), (2, 30), (-3, -45), (4, 60), (6, 10), (2, -80)]


def test_an_isotropic_point_light_gives_i_cos_theta_over_d_squared():
    """A PointLight with attenuation (0, 0, 1) has intensity pi * color * intensity (W/sr) at every distance."""
    k = 2.5
    light = om.PointLight(position=(0.5, 3, 0), color=(1, 0.5, 0.25), intensity=k, constant=0, quadratic=1)
    points, normals, expected = _points_and_expected((0.5, 3, 0), math.pi * k, CASES)
    measured = om.radiance.irradiance(_ground(light), points, normals)
    assert measured.shape == (len(CASES), 3)
    lit = expected > 0
    assert np.abs(measured[lit, 0] / expected[lit] - 1).max() < 0.02  # within 2 % (measured: < 0.05 %)
    assert measured[:, 1] == pytest.approx(0.5 * measured[:, 0], rel=1e-3)  # the light's colour per channel
    assert np.all(measured[~lit] == 0)  # facing away (the last point, tilted past the horizon of the light)
    lux = om.radiance.illuminance(_ground(light), points, normals)
    assert lux == pytest.approx(179 * measured @ [0.265, 0.670, 0.065], rel=1e-6)


def test_gl_style_point_lights_are_matched_at_the_centre_of_interest():
    """Constant attenuation (GL's default): the intensity is pi * c * d_ref^2 with d_ref to the camera's centre."""
    light = om.PointLight(position=(0, 4, 0))
    scene = _ground(om.Camera.look_at(eye=(5, 5, 5), center=(0, 1, 0)), light)
    d_ref = 3.0
    points, normals, expected = _points_and_expected((0, 4, 0), math.pi * d_ref**2, CASES[:4])
    measured = om.radiance.irradiance(scene, points, normals)[:, 0]
    assert np.abs(measured / expected - 1).max() < 0.02


def test_a_diffuse_plane_under_a_uniform_sky():
    """Sky radiance L: horizontal irradiance pi L, illuminance 179 pi L lux; the plane's luminance 179 rho L."""
    radiance = 40.0
    scene = _ground(om.radiance.Sky(intensity=radiance), om.radiance.Options(ab=1, aa=0, ad=256, as_=0))
    points = [[0, 1e-3, 0], [10, 1e-3, -20], [-30, 1e-3, 5]]
    lux = om.radiance.illuminance(scene, points, [[0, 1, 0]] * 3)
    assert np.abs(lux / (179 * math.pi * radiance) - 1).max() < 0.05
    rays = [[0, 2, 0, 0.2, -1, 0.1], [3, 10, -4, -0.5, -1, 0.3]]
    rho = float(srgb_to_linear(0.5))  # colours are display values: 0.5 reflects 21.4 %
    luminance = om.radiance.luminance(scene, rays)
    assert np.abs(luminance / (179 * rho * radiance) - 1).max() < 0.05
    # without interreflection the sky does not light the plane: it is a glow, as the Sky docstring says
    dark = om.radiance.illuminance(scene, points[:1], [[0, 1, 0]], options=om.radiance.Options(ab=0))
    assert dark[0] == 0.0


def test_several_processes_give_the_same_numbers_and_inputs_are_checked():
    light = om.PointLight(position=(0, 3, 0), constant=0, quadratic=1)
    points, normals, _ = _points_and_expected((0, 3, 0), math.pi, CASES * 20)
    one = om.radiance.irradiance(_ground(light), points, normals)
    two = om.radiance.irradiance(_ground(light), points, normals, processes=2)
    assert np.allclose(one, two)
    scene = _ground(light)
    for args, message in [
        (([[0, 0]], [[0, 1, 0]]), r"points must be \(N, 3\)"),
        (([[0, 0, float("nan")]], [[0, 1, 0]]), r"points\[0\] is not finite"),
        (([[0, 0, 0]], [[0, 0, 0]]), r"normals\[0\] is the zero vector"),
        (([[0, 0, 0], [1, 0, 0]], [[0, 1, 0]]), "2 points but 1 normals"),
    ]:
        with pytest.raises(ValueError, match=message):
            om.radiance.irradiance(scene, *args)
    with pytest.raises(ValueError, match="processes must be"):
        om.radiance.irradiance(scene, [0, 0, 0], [0, 1, 0], processes=0)
    with pytest.raises(ValueError, match=r"rays must be \(N, 6\)"):
        om.radiance.luminance(scene, [[0, 1, 0]])
    with pytest.raises(ValueError, match="zero vector"):
        om.radiance.luminance(scene, ([[0, 1, 0]], [[0, 0, 0]]))
    with pytest.raises(TypeError, match="om.radiance.Options"):
        om.radiance.irradiance(scene, [0, 0, 0], [0, 1, 0], options={"ab": 1})
