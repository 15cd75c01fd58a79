"""Ellipsoids of Gaussian splats: world bounds and ray crossings at a confidence of ``sigma`` standard deviations.

A splat (centre ``p``, rotation matrix ``R`` of its unit quaternion, standard
deviations ``s``) is the Gaussian of covariance ``R S S^T R^T``; its
``sigma``-ellipsoid is ``{x : |S^-1 R^T (x - p)| <= sigma}``, the surface the
analysis engines use for the splat (3 by default: the support of the
rasteriser's kernel, which cuts the Gaussian off at 3 standard deviations).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["ellipsoid_bounds", "ray_ellipsoids"]


def ellipsoid_bounds(
    centres: Any, rotations: Any, scales: Any, matrix: np.ndarray | None = None, sigma: float = 3.0
) -> tuple[np.ndarray, np.ndarray] | None:
    """World AABB of the ``sigma``-ellipsoids after the affine ``matrix`` (exact; None for no splats).

    ``rotations`` are (N, 3, 3) matrices (``GaussianSplats.rotation_matrices()``).

    The half extent of an ellipsoid ``{A u : |u| <= 1}`` along axis ``i`` is
    the length of row ``i`` of ``A``; here ``A = M R S sigma``.
    """
    p = np.asarray(centres, np.float64).reshape(-1, 3)
    if not len(p):
        return None
    m = np.eye(4) if matrix is None else np.asarray(matrix, np.float64)
    a = m[:3, :3] @ (np.asarray(rotations, np.float64) * (sigma * np.asarray(scales, np.float64).reshape(-1, 1, 3)))
    half = np.linalg.norm(a, axis=2)
    world = p @ m[:3, :3].T + m[:3, 3]
    return (world - half).min(axis=0), (world + half).max(axis=0)


def ray_ellipsoids(
    origin: Any, direction: Any, centres: Any, rotations: Any, scales: Any, sigma: float = 3.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every crossing of the ray ``origin + t direction`` with the ``sigma``-ellipsoids (one coordinate frame).

    ``rotations`` are (N, 3, 3) matrices (``GaussianSplats.rotation_matrices()``).

    Returns ``(t, index, normals)``: the ray parameters of the entry and exit
    points (``direction`` is not normalised, so ``t`` is in its units), the
    splat each crossing belongs to, and the surface normals (the gradient of
    the ellipsoid's quadric, not normalised), all unsorted.
    """
    o = np.asarray(origin, np.float64).reshape(3)
    d = np.asarray(direction, np.float64).reshape(3)
    p = np.asarray(centres, np.float64).reshape(-1, 3)
    if not len(p):
        return np.zeros(0), np.zeros(0, np.int64), np.zeros((0, 3))
    r = np.asarray(rotations, np.float64).reshape(-1, 3, 3)
    s = sigma * np.asarray(scales, np.float64).reshape(-1, 3)
    # the ray in each ellipsoid's unit-sphere frame: u = S^-1 R^T (x - p)
    ou = np.einsum("nji,nj->ni", r, o - p) / s
    du = np.einsum("nji,j->ni", r, d) / s
    a = np.einsum("ni,ni->n", du, du)
    b = np.einsum("ni,ni->n", ou, du)
    c = np.einsum("ni,ni->n", ou, ou) - 1.0
    disc = b * b - a * c
    hit = (disc >= 0.0) & (a > 0.0)
    idx = np.nonzero(hit)[0]
    root = np.sqrt(disc[idx])
    t = np.concatenate([(-b[idx] - root) / a[idx], (-b[idx] + root) / a[idx]])
    which = np.concatenate([idx, idx])
    u = ou[which] + t[:, None] * du[which]
    normals = np.einsum("nij,nj->ni", r[which], u / s[which])  # R S^-1 u: the quadric's gradient direction
    return t, which, normals
