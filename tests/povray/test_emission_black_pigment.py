"""Emission and ambient survive a black diffuse colour (POV-Ray multiplies them by the pigment)."""

from __future__ import annotations

import re

import pytest

import omnirender as om
from omnirender.povray.api import scene_sdl


def _scene(material: om.Material) -> om.Node:
    return om.Node("s", [om.Camera.look_at(eye=(0, 0, 4)), material, om.Sphere()])


def test_black_channels_are_lifted_so_emission_is_not_multiplied_away():
    text, _ = scene_sdl(_scene(om.Material(diffuse=(0.5, 0, 0), emission=(0.5, 0.5, 0.5), ambient=(0, 0, 0))))
    pigment = [float(v) for v in re.search(r"pigment \{ rgb <([^>]*)>", text).group(1).split(",")]
    emission = [float(v) for v in re.search(r"emission rgb <([^>]*)>", text).group(1).split(",")]
    # pigment x emission is GL's emission (0.5 sRGB = 0.214 linear) in every channel
    assert [round(p * e, 4) for p, e in zip(pigment, emission, strict=True)] == [0.214] * 3
    assert max(pigment[1:]) < 1e-3  # the lifted channels stay invisible under diffuse light


@pytest.mark.povray
def test_an_emissive_black_material_glows_as_in_gl():
    # before: POV-Ray rendered it black (0, 0, 0); GL shows grey 128
    scene = _scene(om.Material(diffuse=(0, 0, 0), emission=(0.5, 0.5, 0.5), ambient=(0, 0, 0)))
    pov = om.render(scene, engine="povray", size=(17, 17)).pixel(8, 8)  # quality >= 2: 0-1 ignore emission
    assert all(abs(c - 128) <= 2 for c in pov[:3])
