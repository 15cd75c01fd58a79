"""Attribute conversion (the VRS attribute simplifier): renderer-specific attributes mean something everywhere.

``om.povray.Finish``/``Pigment``, ``om.mitsuba.BSDF`` and ``om.radiance.Material``
are read natively by their own engine and converted to the closest generic
material by every other engine, through one simplifier
(``omnirender.attributes.conversion``).
"""

from __future__ import annotations

import numpy as np
import pytest
from engines import marks, require

import omnirender as om
from omnirender.attributes.conversion import GenericConversion

RED_LINEAR = (0.6, 0.03, 0.03)
ENGINES = ("gl", "povray", "mitsuba", "radiance")


def lit_sphere(*attributes) -> om.Node:
    s = om.Node(
        "s", [om.Camera.look_at((0, 0, 5)), om.Background((0, 0, 0)), om.DirectionalLight(direction=(0, 0, -1))]
    )
    s.add(om.Node("ball", [*attributes, om.Sphere()]))
    return s


def centre(image: om.Image) -> np.ndarray:
    return image.array[13:17, 18:22, :3].reshape(-1, 3).mean(axis=0)


def test_conversions_give_the_closest_generic_material():
    base = om.Material(diffuse=(1, 0.4, 0.6))
    (m,) = om.povray.Finish(phong=0.8, phong_size=60, reflection=0.3).generic(base)
    assert m.diffuse == base.diffuse and m.specular == (0.8, 0.8, 0.8) and m.shininess == 60
    assert om.povray.Finish(reflection=0.3).generic(base) is None  # nothing a Phong material can say
    (p,) = om.povray.Pigment(color=(1, 1, 1, 0.0, 0.5)).generic(None)
    assert p.diffuse == pytest.approx((1, 1, 1)) and p.opacity == pytest.approx(0.5)
    (d,) = om.mitsuba.BSDF({"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": 0.214}}).generic(None)
    assert d.diffuse == pytest.approx((0.5, 0.5, 0.5), abs=0.002)  # linear 0.214 is display 0.5
    (c,) = om.mitsuba.BSDF({"type": "roughconductor", "alpha": 0.09}).generic(None)
    assert isinstance(c, om.PBRMaterial) and c.metallic == 1 and c.roughness == pytest.approx(0.3)
    (r,) = om.radiance.Material("plastic", (0.214, 0.214, 0.214, 0.05, 0.1)).generic(None)
    assert r.diffuse == pytest.approx((0.5, 0.5, 0.5), abs=0.002) and r.shininess == pytest.approx(49.5)
    (g,) = om.radiance.Material("light", (5, 0.214, 0)).generic(None)
    assert g.emission[0] == pytest.approx(1.0) and g.diffuse == (0, 0, 0)
    assert om.radiance.Material("brightfunc", (), ("refl", "func.cal")).generic(None) is None


def test_the_owning_engine_keeps_reading_its_attribute_natively():
    finish = om.povray.Finish(phong=0.8)
    from omnirender.povray.api import scene_sdl

    sdl, _ = scene_sdl(lit_sphere(om.Material(diffuse=(1, 0.4, 0.6)), finish), size=(40, 30))
    assert "phong 0.8" in sdl
    from omnirender.povray.engine import POVRayEngine

    assert not isinstance(POVRayEngine(size=(4, 4)).attribute_handler(om.povray.Finish), GenericConversion)
    assert isinstance(om.Engine().attribute_handler(om.povray.Finish), GenericConversion)


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ENGINES])
def test_a_mitsuba_bsdf_looks_like_its_generic_material_in_every_engine(name):
    """Other engines converted it (before, they ignored it and drew the default grey)."""
    require(name)
    bsdf = om.mitsuba.BSDF({"type": "diffuse", "reflectance": {"type": "rgb", "value": list(RED_LINEAR)}})
    generic = om.Material(diffuse=om.attributes.conversion.display_rgb(RED_LINEAR), specular=(0, 0, 0))
    a = centre(om.render(lit_sphere(bsdf), engine=name, size=(40, 30)))
    b = centre(om.render(lit_sphere(generic), engine=name, size=(40, 30)))
    assert a[0] > 2.5 * a[1]  # red, not the default grey
    assert np.abs(a - b).max() < 12


@pytest.mark.gl
def test_a_povray_finish_adds_its_highlight_in_gl_over_the_current_material():
    require("gl")
    pink = om.Material(diffuse=(1, 0.4, 0.6))
    plain = om.render(lit_sphere(pink), engine="gl", size=(40, 30)).array[..., :3].astype(float)
    shiny = om.render(lit_sphere(pink, om.povray.Finish(phong=1.0, phong_size=40)), engine="gl", size=(40, 30))
    shiny = shiny.array[..., :3].astype(float)
    assert shiny[..., 1].max() > plain[..., 1].max() + 60  # a white highlight
    edge = (slice(5, 25), slice(8, 10))
    assert np.abs(shiny[edge] - plain[edge]).mean() < 8  # the diffuse pink elsewhere is unchanged
