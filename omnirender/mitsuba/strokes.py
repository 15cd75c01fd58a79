"""Lines and points for a renderer that only knows surfaces.

Segments become thin tubes (open hexagonal prisms) and points small spheres,
sized in pixels like the GL engine draws them (``DrawStyle.line_width`` and
``point_size``, ``PointSet.sizes``): the world size of a pixel is taken at the
depth of the shape's centre.  All tubes of a set form one mesh; points are
Mitsuba spheres (one mesh of octahedra when there are very many).
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry.pixels import pixel_size

__all__ = ["pixel_size", "tubes", "octahedra"]

_SIDES = 6


def tubes(a: np.ndarray, b: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of open hexagonal tubes from points ``a`` to ``b`` ((N, 3) each)."""
    keep = np.linalg.norm(b - a, axis=1) > 0.0
    a, b = a[keep], b[keep]
    n = len(a)
    if n == 0:
        return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32)
    d = b - a
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    helper = np.where(np.abs(d[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(d, u)
    angles = np.arange(_SIDES) * (2.0 * math.pi / _SIDES)
    ring = radius * (np.cos(angles)[None, :, None] * u[:, None, :] + np.sin(angles)[None, :, None] * v[:, None, :])
    vertices = np.concatenate([a[:, None, :] + ring, b[:, None, :] + ring], axis=1).reshape(-1, 3)
    k = np.arange(_SIDES)
    k1 = (k + 1) % _SIDES
    quad = np.stack([np.stack([k, k1, k1 + _SIDES], 1), np.stack([k, k1 + _SIDES, k + _SIDES], 1)], 1).reshape(-1, 3)
    faces = (quad[None, :, :] + (np.arange(n) * 2 * _SIDES)[:, None, None]).reshape(-1, 3)
    return vertices.astype(np.float32), faces.astype(np.uint32)


def octahedra(centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of one octahedron per point (for very many points)."""
    unit = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], np.float64)
    tri = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    vertices = centres[:, None, :] + radii[:, None, None] * unit[None, :, :]
    faces = tri[None, :, :] + (np.arange(len(centres)) * 6)[:, None, None]
    return vertices.reshape(-1, 3).astype(np.float32), faces.reshape(-1, 3).astype(np.uint32)
