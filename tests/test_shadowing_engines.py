"""Shadowing, casts_shadows and Mirror in the offline engines: what they write, and what they warn about."""

from __future__ import annotations

import re
import warnings

import pytest

import omnirender as om


def scene(light_shadows: bool = True, shadowing=None, mirror: bool = False) -> om.Node:
    light = om.PointLight(position=(1, 4, 2), casts_shadows=light_shadows)
    root = om.Node("scene", [om.Camera.look_at((0, 2, 5), (0, 0, 0)), light])
    body = root.add(om.Node("body", [shadowing] if shadowing is not None else []))
    if mirror:
        body.add(om.Mirror(0.6))
    body.add(om.Sphere())
    return root


def test_povray_writes_shadowless_lights_no_shadow_objects_and_reflecting_finishes():
    text, _ = om.povray.scene_sdl(scene(light_shadows=False), (40, 30))
    assert re.search(r"light_source \{ [^}]* shadowless \}", text)
    text, _ = om.povray.scene_sdl(scene(shadowing=om.Shadowing(cast=False)), (40, 30))
    assert "no_shadow" in text and "light_group" not in text
    text, _ = om.povray.scene_sdl(scene(shadowing=om.Shadowing(receive=False)), (40, 30))
    group = text[text.index("light_group {") :]
    assert "shadowless" in group and "global_lights off" in group  # shadowless copies light it
    text, _ = om.povray.scene_sdl(scene(mirror=True), (40, 30))
    assert "finish { reflection { 0.6 } conserve_energy }" in text


@pytest.mark.povray
def test_an_object_that_receives_no_shadow_is_lit_in_povray():
    def dark_pixels(shadowing) -> int:  # seen from above, the light to the side: the ball's shadow on the floor
        root = om.Node("scene", [om.Camera.look_at((0, 6, 0.01), (0, 0, 0), fov=40), om.PointLight(position=(2, 3, 0))])
        root.add(om.Node("ball", [om.Sphere(center=(0, 1, 0), radius=0.5)]))
        floor = [om.Material(diffuse=(0.8, 0.8, 0.8), ambient=(0, 0, 0)), om.Box(size=(4, 0.1, 4))]
        root.add(om.Node("floor", [*([shadowing] if shadowing else []), *floor]))
        img = om.render(root, engine="povray", size=(40, 40))
        return int(((img.array[..., :3].mean(axis=2) < 40) & img.mask).sum())

    assert dark_pixels(None) > 30 and dark_pixels(om.Shadowing(receive=False)) == 0


@pytest.mark.mitsuba
def test_mitsuba_blends_mirrors_and_warns_about_what_it_cannot_do():
    from omnirender.mitsuba import MitsubaEngine

    engine = MitsubaEngine(size=(8, 8))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        engine.run(scene(light_shadows=False, shadowing=om.Shadowing(receive=False), mirror=True))
    messages = [str(w.message) for w in caught]
    assert any("casts_shadows=False" in m and "Mitsuba" in m for m in messages)
    assert any("Shadowing" in m and "/scene/body" in m for m in messages)
    bsdf = next(iter(engine.shapes.values()))["bsdf"]
    assert "blendbsdf" in str(bsdf).lower() and "conductor" in str(bsdf).lower()


@pytest.mark.radiance
def test_radiance_warns_about_shadowing_and_mirrors():
    from omnirender.radiance import RadianceEngine

    engine = RadianceEngine(size=(8, 8))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        engine.run(scene(shadowing=om.Shadowing(cast=False), mirror=True))
    messages = [str(w.message) for w in caught]
    assert any("Radiance" in m and "Shadowing" in m for m in messages)
    assert any("Radiance" in m and "Mirror" in m for m in messages)
