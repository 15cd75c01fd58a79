"""Shading agreement, not just silhouettes (issue 14): the material chart in every engine, compared in CIELAB.

The chart (``omnirender.chart``) has Phong diffuse / specular / shininess,
a PBR metallic x roughness grid, textured, emissive, vertex-coloured,
alpha-masked surfaces and the appearance model's combination rules, under
the same lights.  Per-patch mean colours are compared with CIEDE2000: the
median between any two engines must be at most 10, and the combination
rules (a Color after a Material, a Material after a PBRMaterial, a Color
alone) must give the same colour everywhere (below 8: a bug there is a
different colour, e.g. red instead of blue; Radiance reflects ambient light
with the diffuse colour, a documented departure worth a few units).
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
import pytest
from engines import marks, require

import omnirender as om
from omnirender.chart import CHART_PATCHES, material_chart, patch_means
from omnirender.colorimetry import cielab, delta_e2000

ENGINES = ("gl", "povray", "mitsuba", "radiance")
SIZE = (240, 120)
MEDIAN_LIMIT = 10.0
RULE_LIMIT = (
    8.0  # a wrong rule is another colour (red for blue: dE > 50); Radiance reflects ambient with the diffuse colour
)
RULES = ("color after material", "material after pbr", "color only", "phong red")


@functools.cache
def chart_lab(name: str) -> np.ndarray:
    options = {"mitsuba": {"spp": 16}}.get(name, {})
    return cielab(patch_means(om.render(material_chart(), engine=name, size=SIZE, **options)))


@pytest.mark.parametrize(
    "a,b", [pytest.param(a, b, marks=marks(a, b), id=f"{a}-{b}") for a, b in itertools.combinations(ENGINES, 2)]
)
def test_material_chart_agrees_in_cielab(a, b):
    require(a)
    require(b)
    delta = delta_e2000(chart_lab(a), chart_lab(b))
    worst = int(np.argmax(delta))
    report = f"{a} vs {b}: median dE2000 {np.median(delta):.2f}, worst {CHART_PATCHES[worst]!r} {delta[worst]:.1f}"
    print(report)
    assert np.median(delta) <= MEDIAN_LIMIT, report
    for rule in RULES:
        i = CHART_PATCHES.index(rule)
        assert delta[i] < RULE_LIMIT, f"{report}; the combination rule {rule!r} differs by {delta[i]:.1f}"


def test_colour_difference_is_ciede2000():
    # Sharma, Wu and Dalal's test pairs
    pairs = [((50, 2.6772, -79.7751), (50, 0, -82.7485), 2.0425), ((50, 2.5, 0), (73, 25, -18), 27.1492)]
    for lab1, lab2, expected in pairs:
        assert float(delta_e2000(lab1, lab2)) == pytest.approx(expected, abs=1e-4)
    assert np.allclose(cielab([255, 255, 255]), [100, 0, 0], atol=0.05)


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ENGINES])
def test_a_scene_without_camera_gets_the_same_fitted_camera_everywhere(name):
    require(name)
    scene = om.Node("s", [om.PointLight(position=(3, 3, 3)), om.Sphere(radius=2, center=(5, 0, 0))])
    img = om.render(scene, engine=name, size=(64, 48), **({"spp": 4} if name == "mitsuba" else {}))
    expected = om.Camera.fitted(om.bounds(scene), (64, 48))
    # the sphere fills the fitted view: its silhouette is a centred disc of the fitted size
    ys, xs = np.nonzero(img.mask)
    assert abs(xs.mean() - 31.5) < 1 and abs(ys.mean() - 23.5) < 1
    assert np.isclose(expected.center, (5, 0, 0)).all() and 0.15 < img.mask.mean() < 0.2


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ("gl", "povray", "mitsuba")])
def test_a_nearly_opaque_surface_is_in_the_depth_and_mask(name):
    """A 0.94-opaque cylinder in front of the camera: depth and mask show it in GL as in the offline engines."""
    require(name)
    scene = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5), fov=30), om.PointLight(position=(2, 3, 5))])
    scene.add(om.Node("glass", [om.Material(diffuse=(0.3, 0.6, 0.9), opacity=0.94), om.Cylinder(radius=0.5)]))
    options = {"mitsuba": {"spp": 8}, "povray": {"depth": True}}.get(name, {})
    img = om.render(scene, engine=name, size=(48, 48), **options)
    assert img.mask[24, 24] and not img.mask[24, 2]
    assert img.depth is not None and 4.3 < img.depth[24, 24] < 4.7  # the front of the cylinder (radius 0.5)
