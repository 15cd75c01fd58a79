"""Face and vertex normals of triangle meshes."""

from __future__ import annotations

import numpy as np

__all__ = ["face_normals", "smooth_normals", "triangle_areas"]


def _corners(vertices: np.ndarray, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    v = np.asarray(vertices, dtype=np.float64)
    i = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    return v[i[:, 0]], v[i[:, 1]], v[i[:, 2]]


def face_normals(vertices: np.ndarray, indices: np.ndarray, *, normalize: bool = True) -> np.ndarray:
    """(M, 3) normals of the triangles, counter-clockwise winding; unnormalised ones have length 2*area.

    Degenerate triangles get a zero normal.
    """
    a, b, c = _corners(vertices, indices)
    n = np.cross(b - a, c - a)
    if normalize:
        length = np.linalg.norm(n, axis=1, keepdims=True)
        n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    return n


def triangle_areas(vertices: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """(M,) areas of the triangles."""
    return 0.5 * np.linalg.norm(face_normals(vertices, indices, normalize=False), axis=1)


def smooth_normals(vertices: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """(N, 3) float32 unit vertex normals: area-weighted averages of the adjacent face normals.

    Vertices used by no triangle (or only by degenerate ones) get +y.
    """
    v = np.asarray(vertices)
    i = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    fn = face_normals(v, i, normalize=False)
    n = len(v)
    flat = i.reshape(-1)
    weights = np.repeat(fn, 3, axis=0)  # one row per corner, in the order of ``flat``
    acc = np.stack([np.bincount(flat, weights=weights[:, c], minlength=n) for c in range(3)], axis=1)
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    out = np.divide(acc, length, out=np.zeros_like(acc), where=length > 0)
    out[length[:, 0] == 0] = (0.0, 1.0, 0.0)
    return out.astype(np.float32)
