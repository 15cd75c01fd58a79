"""The world-space size of a pixel: how offline engines size lines and points given in pixels."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["pixel_size"]

#: The size of a pixel when there is no camera to measure it with (world units).
DEFAULT_PIXEL = 0.005


def pixel_size(camera: Any, view: np.ndarray | None, height: int, centre: np.ndarray) -> float:
    """World-space size of one pixel at ``centre`` (world coordinates) seen by ``camera`` through ``view``.

    Orthographic: the view height over the image height.  Perspective: the
    same at the depth of ``centre`` (never nearer than the near plane).
    """
    if camera is None or view is None:
        return DEFAULT_PIXEL
    if camera.is_orthographic:
        return camera.height / height
    depth = max(-(view[:3, :3] @ np.asarray(centre, np.float64) + view[:3, 3])[2], camera.near)
    return 2.0 * depth * math.tan(math.radians(camera.fov) / 2.0) / height
