"""Shader robustness: every material model under degenerate set-ups, read back as linear floats.

The matrix renders a sphere (and a plane facing the camera) with Phong
materials of shininess 0, 1, 40 and 10,000 and PBR materials of roughness 0,
0.5 and 1 with metallic 0 and 1, under a light at the eye, a grazing light, a
light behind the surface, a light exactly opposite the eye and an orthographic
camera.  A technique renders into a float target, so a NaN or infinity the
shader computes is seen as such (an 8-bit buffer would show it as black).
Where the answer is known in closed form (the point facing a light at the
eye) the value is checked against it.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import omnirender as om
from omnirender.attributes.photometry import srgb_to_linear
from omnirender.gl.engine.lighting import GLOBAL_AMBIENT

pytestmark = pytest.mark.gl

SIZE = (48, 48)
EYE = (0.0, 0.0, 5.0)


class LinearCapture(om.gl.GLTechnique):
    """Renders what it scopes into a float target "hdr" (linear light, unclamped)."""

    __slots__ = ()

    def prepare_pass(self, engine):
        engine.set_pass(om.gl.Pass("hdr", target=om.gl.Target("hdr", dtype="f4"), clear=om.gl.Clear((0, 0, 0, 0))))


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=SIZE, samples=0)
    yield e
    e.release()


MATERIALS = {
    **{f"phong-shininess-{n:g}": om.Material(diffuse=(0.7, 0.3, 0.2), specular=(1, 1, 1), shininess=n)
       for n in (0, 1, 40, 10000)},
    **{f"pbr-rough-{r:g}-metal-{m:g}": om.PBRMaterial(base_color=(0.7, 0.3, 0.2), roughness=r, metallic=m)
       for r in (0.0, 0.5, 1.0) for m in (0.0, 1.0)},
}  # fmt: skip

SETUPS = {
    "light-at-eye": lambda: [om.Camera.look_at(EYE, (0, 0, 0), fov=30), om.PointLight(position=EYE)],
    "grazing": lambda: [om.Camera.look_at(EYE, (0, 0, 0), fov=30), om.DirectionalLight(direction=(-1, 0, -0.002))],
    "behind": lambda: [om.Camera.look_at(EYE, (0, 0, 0), fov=30), om.DirectionalLight(direction=(0, 0, 1))],
    "opposite-eye": lambda: [om.Camera.look_at(EYE, (0, 0, 0), fov=30), om.PointLight(position=(0, 0, -5))],
    "orthographic": lambda: [om.Camera.orthographic(eye=EYE, height=2.5), om.PointLight(position=EYE)],
}


def render_linear(engine, setup: str, material, shape) -> tuple[np.ndarray, np.ndarray]:
    """(linear RGBA float image of the shape, 8-bit sRGB image of the same frame)."""
    scene = om.Node("scene", SETUPS[setup]())
    scene.add(om.Node("capture", [LinearCapture(), material, shape]))
    scene.add(om.Node("visible", [material, shape]))
    picture = engine.render(scene, background=(0, 0, 0))
    return engine.target("hdr").color_array(), picture.array


@pytest.mark.parametrize("setup,name", list(itertools.product(SETUPS, MATERIALS)))
def test_no_nan_and_no_black_speckle_inside_coverage(engine, setup, name):
    material = MATERIALS[name]
    for shape in (om.Sphere(radius=1.0), om.Rectangle(size=(2, 2))):
        if isinstance(shape, om.Rectangle):
            shape_node = [om.Rotation(90, (1, 0, 0)), shape]  # facing the camera
        else:
            shape_node = [shape]
        hdr, srgb = render_linear(engine, setup, material, om.Node("shape", shape_node))
        covered = hdr[..., 3] > 0.99
        assert covered.sum() > 100, f"{setup}/{name}: the shape is not where the test expects it"
        rgb = hdr[..., :3][covered]
        assert np.isfinite(rgb).all(), f"{setup}/{name}: NaN or infinity in {np.count_nonzero(~np.isfinite(rgb))} px"
        assert (rgb >= 0).all(), f"{setup}/{name}: negative radiance"
        # every covered pixel receives at least the ambient term: none may be black
        black = (srgb[..., :3][covered] == 0).all(axis=1)
        assert not black.any(), f"{setup}/{name}: {int(black.sum())} black pixels inside the lit coverage"


PIXEL = (24, 24)


def facing(setup: str = "light-at-eye") -> float:
    """N.V at PIXEL on the unit sphere, from the analytic ray cast (with the light at the eye, L = V = H)."""
    (hit, *_) = om.pick(om.Node("s", [*SETUPS[setup](), om.Sphere(radius=1.0)]), pixel=PIXEL, size=SIZE)
    to_eye = np.asarray(EYE) - np.asarray(hit.point)
    return float(np.dot(hit.normal, to_eye / np.linalg.norm(to_eye)))


def at(hdr: np.ndarray) -> np.ndarray:
    return hdr[PIXEL[1], PIXEL[0], :3]


@pytest.mark.parametrize("shininess", [0, 1, 40])
def test_phong_facing_a_light_at_the_eye_is_analytic(engine, shininess):
    """L = V: ambient + diffuse (N.V) + specular (R.V)^shininess with R.V = 2 (N.V)^2 - 1 (shininess 0 as 1)."""
    diffuse, specular = (0.7, 0.3, 0.2), (0.5, 0.5, 0.5)
    mat = om.Material(diffuse=diffuse, specular=specular, shininess=shininess, ambient=(0.1, 0.1, 0.1))
    hdr, _ = render_linear(engine, "light-at-eye", mat, om.Sphere(radius=1.0))
    c = facing()
    expected = (
        srgb_to_linear(diffuse) * c
        + srgb_to_linear(specular) * (2 * c * c - 1) ** max(shininess, 1)
        + srgb_to_linear((0.1, 0.1, 0.1)) * GLOBAL_AMBIENT
    )
    assert at(hdr) == pytest.approx(expected, rel=0.01)


@pytest.mark.parametrize("roughness,metallic", [(0.0, 0.0), (0.5, 0.0), (0.5, 1.0), (1.0, 1.0)])
def test_pbr_facing_a_light_at_the_eye_is_analytic(engine, roughness, metallic):
    """L = V = H (so F = F0): Cook-Torrance with GGX D, Schlick-GGX G, evaluated at the pixel's N.V."""
    base = np.asarray(srgb_to_linear((0.7, 0.3, 0.2)))
    mat = om.PBRMaterial(base_color=(0.7, 0.3, 0.2), roughness=roughness, metallic=metallic)
    hdr, _ = render_linear(engine, "light-at-eye", mat, om.Sphere(radius=1.0))
    c = facing()
    rough = max(roughness, 0.04)
    a2 = rough**4
    k = (rough + 1) ** 2 / 8
    d = a2 / (math.pi * (c * c * (a2 - 1) + 1) ** 2)
    g = (c / (c * (1 - k) + k)) ** 2
    f0 = 0.04 * (1 - metallic) + base * metallic
    kd = (1 - f0) * (1 - metallic)
    spec = d * g * f0 / (4 * c * c)
    ambient = GLOBAL_AMBIENT * (base * (1 - metallic) + f0 * metallic)
    expected = ambient + (kd * base + math.pi * spec) * c
    assert at(hdr) == pytest.approx(expected, rel=0.02)


def test_shininess_zero_is_a_broad_highlight_not_a_flood(engine):
    """Shininess 0 behaves as 1 (POV-Ray's phong_size floor): unlit points get no specular at all."""
    mat = lambda n: om.Material(diffuse=(0.2, 0.2, 0.2), specular=(1, 1, 1), shininess=n)  # noqa: E731
    zero, _ = render_linear(engine, "grazing", mat(0), om.Sphere(radius=1.0))
    one, _ = render_linear(engine, "grazing", mat(1), om.Sphere(radius=1.0))
    assert np.abs(zero - one).max() < 1e-5
    ambient_only = srgb_to_linear((0.2, 0.2, 0.2)) * GLOBAL_AMBIENT
    # the half of the sphere turned away from the grazing light shows the ambient term only
    left = zero[SIZE[1] // 2, 8:14, :3]
    assert left == pytest.approx(np.broadcast_to(ambient_only, left.shape), rel=0.02)


@pytest.mark.povray
@pytest.mark.parametrize("shininess", [0, 5, 40, 200])
def test_phong_highlights_agree_with_povray_in_cielab(shininess):
    """Shininess is a Phong exponent in both engines: the highlights agree pixel by pixel, 0 included."""
    from test_engines_agree import cielab

    scene = om.Node("scene", [om.Camera.look_at((0, 0, 5), (0, 0, 0), fov=30)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.3, -1)))
    scene.add(om.Material(diffuse=(0.6, 0.25, 0.2), specular=(0.6, 0.6, 0.6), shininess=shininess))
    scene.add(om.Sphere(radius=1.0))
    gl = om.render(scene, engine="gl", size=(64, 64), samples=0)
    pov = om.render(scene, engine="povray", size=(64, 64))
    inside = gl.mask & pov.mask
    inside[:, :8] = inside[:, -8:] = False  # leave the silhouette's anti-aliased rim out
    delta = np.linalg.norm(cielab(gl.rgb[inside]) - cielab(pov.rgb[inside]), axis=-1)
    assert np.median(delta) < 1.5 and np.percentile(delta, 95) < 3, f"CIELAB distances {np.percentile(delta, [50, 95])}"
