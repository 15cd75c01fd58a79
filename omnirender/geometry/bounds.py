"""Exact world-space axis-aligned bounds of transformed shapes.

A convex shape is described by its *support function* h(w) = max over points p
of the shape of w·p.  Under an affine map p' = A p + t the world AABB is, per
axis i, ``t_i + h(A[i])`` at the top and ``t_i - h(-A[i])`` at the bottom,
because a row of A is the local direction that world axis i pulls back to.
That gives exact boxes for transformed spheres (ellipsoids), disks, cylinders,
cones and tori (a circle plus a ball) without sampling.  Point-based shapes
(triangle, line and point sets; box corners) transform their points.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = [
    "Bounds",
    "support_bounds",
    "points_bounds",
    "sphere_bounds",
    "box_bounds",
    "cylinder_bounds",
    "cone_bounds",
    "disk_bounds",
    "rectangle_bounds",
    "torus_bounds",
    "union",
    "corners",
]

Bounds = tuple[np.ndarray, np.ndarray]


def support_bounds(support: Callable[[np.ndarray], np.ndarray], matrix: np.ndarray) -> Bounds:
    """World AABB of a convex local shape given by its support function ``support((k, 3)) -> (k,)``."""
    m = np.asarray(matrix, dtype=np.float64)
    a, t = m[:3, :3], m[:3, 3]
    return t - support(-a), t + support(a)


def _ring(w: np.ndarray) -> np.ndarray:
    """Support of the unit circle in the xz plane."""
    return np.sqrt(w[:, 0] ** 2 + w[:, 2] ** 2)


def sphere_bounds(center: Any, radius: float, matrix: np.ndarray) -> Bounds:
    c = np.asarray(center, dtype=np.float64)
    return support_bounds(lambda w: w @ c + radius * np.linalg.norm(w, axis=1), matrix)


def box_bounds(center: Any, size: Any, matrix: np.ndarray) -> Bounds:
    c = np.asarray(center, dtype=np.float64)
    h = 0.5 * np.asarray(size, dtype=np.float64)
    return support_bounds(lambda w: w @ c + np.abs(w) @ h, matrix)


def cylinder_bounds(radius: float, height: float, matrix: np.ndarray) -> Bounds:
    """Cylinder around +y centred at the origin (a disk swept along a segment)."""
    return support_bounds(lambda w: radius * _ring(w) + 0.5 * height * np.abs(w[:, 1]), matrix)


def cone_bounds(radius: float, height: float, matrix: np.ndarray) -> Bounds:
    """Cone with its base disk at y = -h/2 and apex at y = +h/2 (hull of disk and apex)."""
    h2 = 0.5 * height
    return support_bounds(lambda w: np.maximum(radius * _ring(w) - h2 * w[:, 1], h2 * w[:, 1]), matrix)


def disk_bounds(radius: float, matrix: np.ndarray) -> Bounds:
    """Disk in the xz plane centred at the origin."""
    return support_bounds(lambda w: radius * _ring(w), matrix)


def rectangle_bounds(size: Any, matrix: np.ndarray) -> Bounds:
    """Rectangle in the xz plane centred at the origin; ``size`` = (x extent, z extent)."""
    sx, sz = float(size[0]), float(size[1])
    return support_bounds(lambda w: 0.5 * (sx * np.abs(w[:, 0]) + sz * np.abs(w[:, 2])), matrix)


def torus_bounds(major_radius: float, minor_radius: float, matrix: np.ndarray) -> Bounds:
    """Torus around +y: a circle of ``major_radius`` in the xz plane plus a ball of ``minor_radius``."""
    return support_bounds(lambda w: major_radius * _ring(w) + minor_radius * np.linalg.norm(w, axis=1), matrix)


def points_bounds(points: Any, matrix: np.ndarray | None = None) -> Bounds | None:
    """AABB of points after the affine ``matrix`` (None when there are no points)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if not len(p):
        return None
    if matrix is not None:
        m = np.asarray(matrix, dtype=np.float64)
        # bounds of A p + t: transform the points (exact; no shortcut through the local box)
        p = p @ m[:3, :3].T + m[:3, 3]
    return p.min(axis=0), p.max(axis=0)


def corners(lo: Any, hi: Any) -> np.ndarray:
    """The 8 corners of an AABB, (8, 3)."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    idx = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    return np.where(idx == 0, lo, hi)


def union(a: Bounds | None, b: Bounds | None) -> Bounds | None:
    """The AABB enclosing both (either may be None)."""
    if a is None:
        return b
    if b is None:
        return a
    return np.minimum(a[0], b[0]), np.maximum(a[1], b[1])
