"""4x4 matrix helpers (column vectors, pre-multiplication, float64), as in the core transforms."""

from __future__ import annotations

import math

import numpy as np

from ..core.transform import axis_angle_matrix

__all__ = [
    "translation_matrix",
    "scaling_matrix",
    "rotation_matrix",
    "rotation_between",
    "align_y_matrix",
    "transform_points",
    "transform_directions",
    "transform_normals",
    "normal_matrix",
]


def translation_matrix(offset) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = offset
    return m


def scaling_matrix(factors) -> np.ndarray:
    f = np.broadcast_to(np.asarray(factors, dtype=np.float64), (3,))
    return np.diag([f[0], f[1], f[2], 1.0])


def rotation_matrix(angle_degrees: float, axis) -> np.ndarray:
    """Right-handed rotation by ``angle_degrees`` about ``axis`` (normalised here)."""
    a = np.asarray(axis, dtype=np.float64)
    return axis_angle_matrix(a / np.linalg.norm(a), math.radians(angle_degrees))


def rotation_between(a, b) -> np.ndarray:
    """The 4x4 rotation turning direction ``a`` onto direction ``b`` (shortest arc; any axis when opposite)."""
    u = np.asarray(a, dtype=np.float64)
    v = np.asarray(b, dtype=np.float64)
    u = u / np.linalg.norm(u)
    v = v / np.linalg.norm(v)
    axis = np.cross(u, v)
    s = float(np.linalg.norm(axis))
    c = float(np.clip(np.dot(u, v), -1.0, 1.0))
    if s < 1e-12:
        if c > 0:
            return np.eye(4)
        # Opposite: turn 180 degrees about any axis perpendicular to u.
        helper = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
        return rotation_matrix(180.0, np.cross(u, helper))
    return rotation_matrix(math.degrees(math.atan2(s, c)), axis)


def align_y_matrix(origin, direction) -> np.ndarray:
    """The rigid transform that moves the origin to ``origin`` and turns +y onto ``direction``."""
    m = rotation_between((0.0, 1.0, 0.0), direction)
    m[:3, 3] = origin
    return m


def transform_points(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(N, 3) points mapped by a 4x4 matrix (with perspective divide when the last row is not (0, 0, 0, 1))."""
    m = np.asarray(matrix, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64)
    out = p @ m[:3, :3].T + m[:3, 3]
    last = m[3]
    if not np.array_equal(last, (0.0, 0.0, 0.0, 1.0)):
        w = p @ last[:3] + last[3]
        out = out / w[:, None]
    return out


def transform_directions(matrix: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(N, 3) directions mapped by the linear part of a 4x4 matrix (not normalised)."""
    m = np.asarray(matrix, dtype=np.float64)
    return np.asarray(directions, dtype=np.float64) @ m[:3, :3].T


def normal_matrix(matrix: np.ndarray) -> np.ndarray:
    """The 3x3 inverse transpose of the linear part: maps normals so they stay perpendicular to surfaces."""
    return np.linalg.inv(np.asarray(matrix, dtype=np.float64)[:3, :3]).T


def transform_normals(matrix: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(N, 3) unit normals mapped by a 4x4 model matrix (inverse transpose, renormalised)."""
    n = np.asarray(normals, dtype=np.float64) @ normal_matrix(matrix).T
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)
