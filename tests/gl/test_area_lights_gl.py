"""GL rectangle and disc lights: LTC shading against the exact form factor, sides, soft shadows (issue 26)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import omnirender as om
from omnirender.attributes.photometry import area_form_factor, srgb_to_linear

pytestmark = pytest.mark.gl

N = 48
HALF = 3.0  # the orthographic view shows x, z in [-3, 3]
KD = 0.8


def floor_scene(light, material=None, occluder=False, pipeline_size=None) -> om.Node:
    root = om.Node("scene", [om.Camera.orthographic((0, 10, 0), (0, 0, 0), up=(0, 0, -1), height=2 * HALF), light])
    mat = material or om.Material(diffuse=(KD, KD, KD), ambient=(0, 0, 0), specular=(0, 0, 0))
    root.add(om.Node("floor", [mat, om.Box(size=(8, 0.1, 8), center=(0, -0.05, 0))]))
    if occluder:
        root.add(om.Node("slab", [om.Box(size=(1.0, 0.05, 1.0), center=(0, 0.8, 0))]))
    return root


def linear(img) -> np.ndarray:
    return srgb_to_linear(img.array[..., 0].astype(np.float64) / 255.0)


def pixel_points() -> np.ndarray:
    c = (np.arange(N) + 0.5) / N * 2 * HALF - HALF
    x, z = np.meshgrid(c, c)  # image rows run along +z (up is -z)
    return np.stack([x, np.zeros_like(x), z], axis=-1)


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
@pytest.mark.parametrize(
    "light",
    [
        om.RectLight(position=(0.3, 1.5, -0.2), direction=(0.3, -1, 0.1), width=1.6, height=0.7, up=(0, 0, 1)),
        om.DiscLight(position=(-0.4, 1.2, 0.3), direction=(0, -1, 0), radius=0.6),
    ],
    ids=["rect", "disc"],
)
def test_diffuse_light_is_kd_l_times_the_exact_form_factor(light, pipeline):
    img = om.render(floor_scene(light), engine="gl", size=(N, N), samples=0, pipeline=pipeline)
    polygon = light.world_polygon(np.eye(4), 64)
    expected = srgb_to_linear(KD) * area_form_factor(pixel_points(), [0, 1, 0], polygon)
    got = linear(img)
    bright = expected > 0.02
    err = np.abs(got - expected)[bright] / expected[bright]
    name = type(light).__name__
    print(f"{name} {pipeline}: median relative error {np.median(err):.3f}, 95th {np.quantile(err, 0.95):.3f}")
    assert np.median(err) < 0.03  # sRGB quantisation is ~1 % at these levels; LTC's horizon clipping is approximate
    assert np.quantile(err, 0.95) < 0.10


def test_one_sided_and_two_sided():
    def value(two_sided: bool) -> float:
        light = om.RectLight(position=(0, 1.0, 0), direction=(0, 1, 0), width=1.0, height=1.0, two_sided=two_sided)
        return float(linear(om.render(floor_scene(light), engine="gl", size=(N, N), samples=0))[N // 2, N // 2])

    assert value(False) == 0.0  # the light faces away from the floor
    assert value(True) > 0.05


def test_soft_shadow_penumbra_follows_the_light_size():
    def penumbra(size: float) -> int:
        light = om.RectLight(position=(1.5, 2.0, 0), direction=(0, -1, 0), width=size, height=size, intensity=4.0)
        free = linear(om.render(floor_scene(light), engine="gl", size=(N, N), samples=0))
        shaded = linear(om.render(floor_scene(light, occluder=True), engine="gl", size=(N, N), samples=0))
        ratio = shaded / np.maximum(free, 1e-6)
        return int(((ratio > 0.1) & (ratio < 0.9) & (free > 0.01)).sum())

    small, large = penumbra(0.2), penumbra(1.2)
    print(f"penumbra pixels: {small} (0.2 wide light), {large} (1.2 wide light)")
    assert large > 2.5 * small


def test_casts_shadows_false_and_specular_and_pbr():
    # the shadow falls beside the slab (the camera looks down on it), its umbra around x = -1.2
    light = om.RectLight(position=(1.5, 2.0, 0), direction=(0, -1, 0), width=1.0, height=1.0, intensity=3.0)
    shaded = linear(om.render(floor_scene(light, occluder=True), engine="gl", size=(N, N), samples=0))
    light.casts_shadows = False
    free = linear(om.render(floor_scene(light, occluder=True), engine="gl", size=(N, N), samples=0))
    assert shaded[N // 2, 14] < 0.2 * free[N // 2, 14]
    shiny = om.Material(diffuse=(0.2, 0.2, 0.2), ambient=(0, 0, 0), specular=(1, 1, 1), shininess=60)
    plain = om.Material(diffuse=(0.2, 0.2, 0.2), ambient=(0, 0, 0), specular=(0, 0, 0))
    a = linear(om.render(floor_scene(light, shiny), engine="gl", size=(N, N), samples=0)).max()
    b = linear(om.render(floor_scene(light, plain), engine="gl", size=(N, N), samples=0)).max()
    assert a > b + 0.05  # a highlight
    pbr = om.PBRMaterial(base_color=(0.8, 0.8, 0.8), roughness=0.3, metallic=0.0)
    assert linear(om.render(floor_scene(light, pbr), engine="gl", size=(N, N), samples=0)).max() > 0.1


def test_more_area_lights_than_a_program_holds_warn():
    lights = [om.RectLight(position=(x, 2, 0), direction=(0, -1, 0), intensity=0.2) for x in np.linspace(-2, 2, 5)]
    root = floor_scene(lights[0])
    for light in lights[1:]:
        root.add(light)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        om.render(root, engine="gl", size=(16, 16), samples=0)
    assert any("rectangle/disc lights" in str(w.message) for w in caught)
