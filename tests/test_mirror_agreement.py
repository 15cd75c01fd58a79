"""A sphere's mirrored image in a floor mirror covers the same pixels in GL and POV-Ray (issue 10).

The reflection region of an engine is the set of floor pixels that change when
the red sphere is added above the mirror (the light casts no shadows, so only
the reflection changes the floor); the floor's pixels come from the GL depth of
the floor alone.  The two engines' regions must overlap with an intersection
over union of at least 0.95.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import omnirender as om

SIZE = (240, 180)
AGREEMENT = 0.95


def scene(sphere: bool = True, floor_only: bool = False, mirror: bool = True) -> om.Node:
    root = om.Node("scene", [om.Camera.look_at((0, 2.6, 6.5), (0, 0.4, 0), fov=40),
                             om.PointLight(position=(2, 6, 5), casts_shadows=False),
                             om.Background((0.55, 0.6, 0.7))])  # fmt: skip
    floor = [om.Material(diffuse=(0.35, 0.35, 0.35))] + ([om.Mirror(0.75)] if mirror else [])
    root.add(om.Node("floor", [*floor, om.Rectangle(size=(5, 5))]))
    if sphere and not floor_only:
        root.add(
            om.Node("ball", [om.Material(diffuse=(0.95, 0.1, 0.1)), om.Sphere(center=(0.3, 0.9, 0.4), radius=0.6)])
        )
    return root


@functools.cache
def floor_pixels() -> np.ndarray:
    full = om.render(scene(), engine="gl", size=SIZE, samples=0)
    alone = om.render(scene(floor_only=True), engine="gl", size=SIZE, samples=0)
    with np.errstate(invalid="ignore"):
        return np.isfinite(full.depth) & (np.abs(full.depth - alone.depth) < 1e-3)


def reflection_region(engine: str, **options) -> np.ndarray:
    with_ball = om.render(scene(), engine=engine, size=SIZE, **options).array[..., :3].astype(int)
    without = om.render(scene(sphere=False), engine=engine, size=SIZE, **options).array[..., :3].astype(int)
    return floor_pixels() & (np.abs(with_ball - without).max(axis=2) > 30)


@pytest.mark.gl
@pytest.mark.povray
def test_mirror_reflection_region_agrees_with_povray():
    gl = reflection_region("gl", samples=0)
    pov = reflection_region("povray")
    assert pov.sum() > 800, "the sphere must be seen in the mirror"
    score = float((gl & pov).sum() / (gl | pov).sum())
    print(f"mirror reflection region: IoU {score:.3f} ({gl.sum()} GL / {pov.sum()} POV-Ray pixels)")
    assert score >= AGREEMENT


@pytest.mark.gl
def test_without_the_mirror_attribute_the_floor_shows_no_reflection():
    plain = om.render(scene(mirror=False), engine="gl", size=SIZE, samples=0).array[..., :3].astype(int)
    empty = om.render(scene(sphere=False, mirror=False), engine="gl", size=SIZE, samples=0).array[..., :3].astype(int)
    assert not (floor_pixels() & (np.abs(plain - empty).max(axis=2) > 30)).any()
