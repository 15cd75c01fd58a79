"""Model matrices as translation, rotation (unit quaternions) and scale, and back, for arrays of instances.

glTF places things by T * R * S (translation, rotation, scale applied first):
nodes and ``EXT_mesh_gpu_instancing``'s per-instance attributes alike.  Not
every 4x4 matrix is such a product: a shear (axes that are not perpendicular
after the transform), a projective last row, a degenerate (zero) axis or a
mirroring (negative determinant, which glTF could hold as a negative scale
but instanced viewers draw with the wrong faces culled) are not.
:func:`decompose_trs` says which instances are representable and why the
first one that is not is not.  Quaternions are (x, y, z, w), glTF's order.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["TRS", "decompose_trs", "compose_trs", "decomposable", "ORTHOGONALITY_TOLERANCE"]

#: The largest |R^T R - I| entry accepted for the rotation left after the column scales are divided out:
#: float32 data has about 6e-8 relative precision, so a real shear shows far above this.
ORTHOGONALITY_TOLERANCE = 1e-5


class TRS(NamedTuple):
    """Per-instance translations (N, 3), unit quaternions (N, 4: x, y, z, w), scales (N, 3) and validity."""

    translation: np.ndarray
    rotation: np.ndarray
    scale: np.ndarray
    #: (N,) booleans: the matrix equals T * R * S with positive scales (within the tolerance)
    valid: np.ndarray
    #: (N,) reasons for the invalid ones ("" where valid): "projective", "degenerate", "mirrored", "sheared"
    reason: np.ndarray


def decompose_trs(matrices: np.ndarray, tolerance: float = ORTHOGONALITY_TOLERANCE) -> TRS:
    """(N, 4, 4) model matrices (column vectors) as T * R * S; see the module docs for what cannot be."""
    m = np.asarray(matrices, np.float64).reshape(-1, 4, 4)
    n = len(m)
    linear = m[:, :3, :3]
    scale = np.linalg.norm(linear, axis=1)  # the length of each column: the scale of that axis
    reason = np.full(n, "", dtype=object)
    projective = np.any(m[:, 3] != (0.0, 0.0, 0.0, 1.0), axis=1)
    degenerate = ~(scale > 1e-12 * np.maximum(scale.max(axis=1, keepdims=True), 1e-300)).all(axis=1)
    safe = np.where(scale > 0.0, scale, 1.0)
    rot = linear / safe[:, None, :]
    error = np.abs(np.einsum("nji,njk->nik", rot, rot) - np.eye(3)).max(axis=(1, 2))
    sheared = error > tolerance
    mirrored = np.linalg.det(rot) < 0.0
    for name, bad in (("sheared", sheared), ("mirrored", mirrored), ("degenerate", degenerate)):
        reason[bad] = name
    reason[projective] = "projective"
    valid = reason == ""
    return TRS(m[:, :3, 3].copy(), _quaternions(rot), scale, valid, reason)


def decomposable(matrix: np.ndarray, tolerance: float = ORTHOGONALITY_TOLERANCE) -> bool:
    """Whether one 4x4 matrix is T * R * S with non-zero scales, negative ones allowed (what a glTF node holds).

    :func:`decompose_trs`'s rule for one matrix, in plain Python: exporters ask it for every node.
    """
    (a, b, c, _), (d, e, f, _), (g, h, i, _), last = np.asarray(matrix, np.float64).tolist()
    if last != [0.0, 0.0, 0.0, 1.0]:
        return False
    columns = ((a, d, g), (b, e, h), (c, f, i))
    lengths = [math.sqrt(x * x + y * y + z * z) for x, y, z in columns]
    if not min(lengths) > 1e-12 * max(lengths):
        return False
    for j, k in ((0, 1), (0, 2), (1, 2)):
        dot = sum(p * q for p, q in zip(columns[j], columns[k], strict=True))
        if abs(dot) > tolerance * lengths[j] * lengths[k]:
            return False
    return True


def _quaternions(rot: np.ndarray) -> np.ndarray:
    """(N, 4) unit quaternions (x, y, z, w, w >= 0) of (N, 3, 3) rotations (Shepperd's method: the largest
    of w, x, y, z is computed from the diagonal and the others from it, so no case divides by a small number)."""
    r = rot
    trace = r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2]
    # 4 * (w^2, x^2, y^2, z^2)
    big = np.stack(
        [
            1.0 + trace,
            1.0 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2],
            1.0 - r[:, 0, 0] + r[:, 1, 1] - r[:, 2, 2],
            1.0 - r[:, 0, 0] - r[:, 1, 1] + r[:, 2, 2],
        ],
        axis=1,
    )
    # 4 * (w, x, y, z) times each component in turn: column k is 4 q_k q
    wx, wy, wz = r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]
    xy, xz, yz = r[:, 0, 1] + r[:, 1, 0], r[:, 0, 2] + r[:, 2, 0], r[:, 1, 2] + r[:, 2, 1]
    products = np.stack(
        [
            np.stack([big[:, 0], wx, wy, wz], axis=1),
            np.stack([wx, big[:, 1], xy, xz], axis=1),
            np.stack([wy, xy, big[:, 2], yz], axis=1),
            np.stack([wz, xz, yz, big[:, 3]], axis=1),
        ],
        axis=1,
    )  # (N, k, 4): row k holds 4 q_k (w, x, y, z)
    k = np.argmax(big, axis=1)
    chosen = products[np.arange(len(r)), k]
    wxyz = chosen / np.sqrt(np.maximum(big[np.arange(len(r)), k], 1e-300))[:, None]
    wxyz /= np.maximum(np.linalg.norm(wxyz, axis=1, keepdims=True), 1e-300)
    wxyz *= np.where(wxyz[:, :1] < 0.0, -1.0, 1.0)
    return np.ascontiguousarray(wxyz[:, [1, 2, 3, 0]])


def compose_trs(translation: np.ndarray, rotation: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(N, 4, 4) matrices T * R * S from (N, 3) translations, (N, 4) quaternions (x, y, z, w; normalised here)
    and (N, 3) scales."""
    t = np.asarray(translation, np.float64).reshape(-1, 3)
    q = np.asarray(rotation, np.float64).reshape(-1, 4)
    s = np.asarray(scale, np.float64).reshape(-1, 3)
    q = q / np.maximum(np.linalg.norm(q, axis=1, keepdims=True), 1e-300)
    x, y, z, w = q.T
    r = np.empty((len(q), 3, 3))
    r[:, 0] = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=1)
    r[:, 1] = np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=1)
    r[:, 2] = np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=1)
    m = np.zeros((len(q), 4, 4))
    m[:, :3, :3] = r * s[:, None, :]
    m[:, :3, 3] = t
    m[:, 3, 3] = 1.0
    return m
