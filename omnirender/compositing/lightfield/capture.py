"""Making light fields from scenes: cameras on a sphere cap, and rendered views with depth.

:func:`capture_light_field` renders any scene from a list of cameras with the
GL engine (or Mitsuba, or any engine whose images carry depth) and keeps image,
depth and calibration of each view, so light-field tests and examples need no
external data.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...core.camera import Camera
from .data import LightField, LightFieldView

__all__ = ["sphere_cap_cameras", "capture_light_field"]


def sphere_cap_cameras(
    center: Sequence[float],
    radius: float,
    count: int,
    cap: float = 25.0,
    axis: Sequence[float] = (0.0, 0.0, 1.0),
    up: Sequence[float] = (0.0, 1.0, 0.0),
    fov: float = 35.0,
    near: float = 0.1,
    far: float = 1000.0,
) -> list[Camera]:
    """``count`` cameras on the cap of the sphere (``center``, ``radius``) within ``cap`` degrees of ``axis``,
    all looking at ``center`` (a Fibonacci spiral: evenly spread, the first on the axis)."""
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise ValueError(f"sphere_cap_cameras: count must be a whole number >= 1, got {count!r}")
    if not 0.0 <= cap < 90.0:
        raise ValueError(f"sphere_cap_cameras: cap must be in [0, 90) degrees, got {cap!r}")
    if not radius > 0:
        raise ValueError(f"sphere_cap_cameras: radius must be > 0, got {radius!r}")
    c = np.asarray(center, dtype=np.float64)
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    u = np.asarray(up, dtype=np.float64)
    e1 = u - a * (u @ a)
    if np.linalg.norm(e1) < 1e-9:
        raise ValueError("sphere_cap_cameras: up must not be parallel to axis")
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    cos_cap = math.cos(math.radians(cap))
    golden = math.pi * (3.0 - math.sqrt(5.0))
    cameras = []
    for i in range(count):
        # area-uniform in cos(theta) on the cap, azimuth by the golden angle
        cos_t = 1.0 - (1.0 - cos_cap) * (i / max(count - 1, 1)) if count > 1 else 1.0
        sin_t = math.sqrt(max(0.0, 1.0 - cos_t * cos_t))
        phi = i * golden
        direction = a * cos_t + (e1 * math.cos(phi) + e2 * math.sin(phi)) * sin_t
        eye = c + radius * direction
        cameras.append(Camera.look_at(tuple(eye), tuple(c), tuple(u), fov=fov, near=near, far=far))
    return cameras


def capture_light_field(
    scene: Any, cameras: Sequence[Camera], size: tuple[int, int] = (640, 480), engine: str = "gl", **options: Any
) -> LightField:
    """Render ``scene`` from every camera in ``cameras`` and return the light field of those views.

    The scene's own camera is replaced by each of ``cameras`` (perspective
    ``om.Camera`` s in world coordinates); ``engine`` must give images with
    depth (``"gl"``, ``"mitsuba"``); other ``options`` go to ``om.render``.  GL
    views are rendered over transparent black (colour premultiplied by
    coverage); images of other engines, rendered with a transparent
    ``om.Background`` (straight alpha), are premultiplied.
    """
    from ...render import render
    from ...scene.node import Node

    cameras = list(cameras)
    if len(cameras) < 2:
        raise ValueError(f"capture_light_field: needs at least 2 cameras, got {len(cameras)}")
    for i, camera in enumerate(cameras):
        if not isinstance(camera, Camera) or camera.is_orthographic or camera.is_off_axis:
            raise TypeError(
                f"capture_light_field: camera {i} must be a perspective om.Camera on its axis (no shift; light-field "
                f"views are pinhole cameras), got {camera!r:.60}"
            )
    if engine == "gl":
        images = _gl_images(scene, cameras, size, options)
    else:
        from ...attributes.environment import Background

        clear = Background((0.0, 0.0, 0.0, 0.0))  # declared first: it wins over the scene's own
        images = (
            render(Node.transient([camera, clear, scene]), engine=engine, size=size, **options) for camera in cameras
        )
    views = []
    for camera, image in zip(cameras, images, strict=False):
        if image.depth is None:
            raise ValueError(f"capture_light_field: engine {engine!r} returned no depth; light fields need depth maps")
        rgba = image.array
        if engine != "gl":
            alpha = rgba[..., 3:4].astype(np.float64) / 255.0
            rgba = np.concatenate([np.round(rgba[..., :3] * alpha), rgba[..., 3:4]], axis=2).astype(np.uint8)
        views.append(LightFieldView.from_camera(camera, rgba, image.depth))
    return LightField(views)


def _gl_images(scene: Any, cameras: list[Camera], size: tuple[int, int], options: dict[str, Any]) -> Any:
    """The views rendered by one GL engine (``om.render`` would make a context per view), over transparent black."""
    from ...gl.glengine import GLEngine
    from ...render import _check_size
    from ...scene.node import Node

    size = _check_size(size)
    engine_options = {k: options.pop(k) for k in ("samples", "on_missing", "technique") if k in options}
    options.setdefault("background", (0.0, 0.0, 0.0, 0.0))
    unknown = sorted(set(options) - {"background", "mask"})
    if unknown:
        raise TypeError(
            f"capture_light_field: unknown GL options {unknown}; it takes samples, background, mask, on_missing and "
            "technique"
        )
    with GLEngine(size=size, **engine_options) as engine:
        for camera in cameras:
            yield engine.render(Node.transient([camera, scene]), **options)
