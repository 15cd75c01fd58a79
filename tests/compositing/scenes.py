"""Small scenes and light fields shared by the compositing tests."""

from __future__ import annotations

import numpy as np

import omnirender as om

C = om.compositing

CAMERA = om.Camera.look_at((0, 1.0, 6.0), (0, 0, 0), fov=40)
LIGHT = om.PointLight(position=(3, 5, 4))


def ball(center=(-0.5, 0, 0), radius=1.0, color=(1.0, 0.3, 0.2), light=True, opacity=1.0) -> om.Node:
    items = [LIGHT] if light else []
    material = om.Material(diffuse=color, opacity=opacity)
    return om.Node("ball", [*items, material, om.Sphere(center=center, radius=radius)])


def cube(center=(0.6, 0, 0.3), size=1.5, color=(0.2, 0.4, 1.0), light=True) -> om.Node:
    items = [LIGHT] if light else []
    return om.Node("cube", [*items, om.Material(diffuse=color), om.Box(size=(size, size, size), center=center)])


def fog_volume(n: int = 20, alpha: float = 0.12, spacing: float = 1.2) -> om.Volume:
    z, y, x = np.mgrid[-1 : 1 : n * 1j, -1 : 1 : n * 1j, -1 : 1 : n * 1j]
    inside = np.clip((1.0 - np.sqrt(x**2 + y**2 + z**2)) * 6.0, 0.0, 1.0)
    tf = [(0.0, (0.9, 0.5, 0.3, 0.0)), (1.0, (0.9, 0.5, 0.3, alpha))]
    return om.Volume(inside, spacing=spacing * 2.0 / (n - 1), transfer_function=tf)


def checker(seed: int, cells: int = 6, size: int = 192) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = np.kron(rng.uniform(0.25, 1.0, (cells, cells, 3)), np.ones((size // cells, size // cells, 1)))
    y, x = np.mgrid[0:size, 0:size] / size
    img = 0.7 * img + 0.3 * np.stack([x, y, 1 - x], 2)
    return (np.clip(img, 0, 1) * 255).astype(np.uint8)


def textured_scene() -> om.Node:
    """A diffuse textured scene (view-independent colours) for light-field accuracy tests."""
    matte = dict(diffuse=(1, 1, 1), specular=(0, 0, 0))
    s = om.Node("textured", [om.PointLight(position=(4, 6, 8))])
    s.add(
        om.Node("ground", [om.Texture(checker(1)), om.Material(**matte), om.Box(size=(4, 0.2, 3), center=(0, -0.8, 0))])
    )
    s.add(
        om.Node("ball", [om.Texture(checker(2, 8)), om.Material(**matte), om.Sphere(center=(-0.6, 0, 0.2), radius=0.7)])
    )
    s.add(om.Node("box", [om.Texture(checker(3, 4)), om.Material(**matte), om.Rotation(30, (0, 1, 0)),
                          om.Box(size=(0.9, 1.2, 0.9), center=(0.8, -0.1, -0.2))]))  # fmt: skip
    return s


#: Where the textured scene's light field is captured from, and novel views inside that region.
CAPTURE = dict(center=(0, -0.2, 0), radius=7.0, cap=22.0, axis=(0, 0.35, 1), fov=35)
NOVEL = dict(center=(0, -0.2, 0), radius=7.0, count=5, cap=15.0, axis=(0.1, 0.3, 1), fov=35)


def capture_cameras(count: int) -> list[om.Camera]:
    c = CAPTURE
    return C.sphere_cap_cameras(c["center"], c["radius"], count, cap=c["cap"], axis=c["axis"], fov=c["fov"])


def novel_cameras() -> list[om.Camera]:
    c = NOVEL
    return C.sphere_cap_cameras(c["center"], c["radius"], c["count"], cap=c["cap"], axis=c["axis"], fov=c["fov"])[1:4]
