"""GL and POV-Ray agree on where shadows fall (issue 10).

A sphere and a box above a plane, lit by one point, one spot or one
directional light, hard shadows, no ambient on the plane.  Each engine renders
the scene twice, with the sphere and the box casting shadows and without
(``om.Shadowing(cast=False)``, POV-Ray's ``no_shadow``); a plane pixel is in shadow when it is darker than
half its unshadowed value.  The plane's pixels come from the GL depth of the
plane alone.  The intersection over union of the two engines' shadow regions
must be at least 0.85 with shadow maps and 0.95 with stencil shadow volumes.
(Agreement over all plane pixels would say little: without any shadow it is
already above 95 %.)
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import omnirender as om

SIZE = (240, 180)
LIGHTS = {
    "point": lambda: om.PointLight(position=(1.5, 4.0, 2.0)),
    "spot": lambda: om.SpotLight(position=(1.0, 4.5, 2.5), direction=(-0.25, -1.0, -0.5), cutoff=40),
    "directional": lambda: om.DirectionalLight(direction=(-0.9, -1.0, -0.5)),
}
SHADOW_MAP_IOU = 0.85
SHADOW_VOLUME_IOU = 0.95


def scene(light: str, shadows: bool = True, technique=None, objects: bool = True) -> om.Node:
    root = om.Node("scene", [om.Camera.look_at((0.5, 4.5, 6.5), (0, 0.3, 0), fov=45), LIGHTS[light]()])
    body = root.add(om.Node("body", [technique] if technique is not None else []))
    if not shadows:
        body.add(om.Shadowing(cast=False))
    body.add(om.Node("plane", [om.Material(diffuse=(0.8, 0.8, 0.8), ambient=(0, 0, 0)),
                               om.Box(size=(9, 0.1, 9), center=(0, -0.05, 0))]))  # fmt: skip
    if objects:
        body.add(
            om.Node("ball", [om.Material(diffuse=(0.9, 0.3, 0.2)), om.Sphere(center=(-0.9, 0.9, 0.2), radius=0.6)])
        )
        body.add(om.Node("box", [om.Material(diffuse=(0.2, 0.4, 0.9)), om.Box(size=0.8, center=(1.0, 0.7, -0.3))]))
    return root


def luminance(img) -> np.ndarray:
    return img.array[..., :3].astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])


@functools.cache
def plane_pixels(light: str) -> np.ndarray:
    full = om.render(scene(light, shadows=False), engine="gl", size=SIZE, samples=0)
    alone = om.render(scene(light, shadows=False, objects=False), engine="gl", size=SIZE, samples=0)
    with np.errstate(invalid="ignore"):  # inf - inf where both see the background
        return np.isfinite(full.depth) & (np.abs(full.depth - alone.depth) < 1e-3)


def shadow_mask(engine: str, light: str, technique=None, **options) -> np.ndarray:
    lit = luminance(om.render(scene(light, False, technique), engine=engine, size=SIZE, **options))
    shaded = luminance(om.render(scene(light, True, technique), engine=engine, size=SIZE, **options))
    return plane_pixels(light) & (lit > 25) & (shaded < 0.5 * lit)


@functools.cache
def povray_mask(light: str) -> np.ndarray:
    return shadow_mask("povray", light)


def iou(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / max((a | b).sum(), 1))


@pytest.mark.gl
@pytest.mark.povray
@pytest.mark.parametrize("light", sorted(LIGHTS))
def test_shadow_maps_agree_with_povray(light):
    pov = povray_mask(light)
    gl = shadow_mask("gl", light, om.gl.ShadowMaps(softness=0), samples=0)
    assert pov.sum() > 400, "the scene must have a real shadow region"
    score = iou(gl, pov)
    print(f"shadow maps, {light} light: IoU {score:.3f} ({gl.sum()} GL / {pov.sum()} POV-Ray shadow pixels)")
    assert score >= SHADOW_MAP_IOU


@pytest.mark.gl
@pytest.mark.povray
@pytest.mark.parametrize("light", sorted(LIGHTS))
def test_shadow_volumes_agree_with_povray(light):
    pov = povray_mask(light)
    gl = shadow_mask("gl", light, om.gl.ShadowVolumes(), samples=0)
    score = iou(gl, pov)
    print(f"shadow volumes, {light} light: IoU {score:.3f} ({gl.sum()} GL / {pov.sum()} POV-Ray shadow pixels)")
    assert score >= SHADOW_VOLUME_IOU
