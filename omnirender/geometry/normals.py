"""Face and vertex normals of triangle meshes."""

from __future__ import annotations

import numpy as np

__all__ = ["face_normals", "smooth_normals", "triangle_areas", "vertex_tangents"]


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


def vertex_tangents(
    vertices: np.ndarray, indices: np.ndarray, normals: np.ndarray, texcoords: np.ndarray
) -> np.ndarray:
    """(N, 4) float32 per-vertex tangents for tangent-space normal maps (Lengyel's method).

    xyz is the direction of increasing u, orthogonalised against the normal;
    w (+1 or -1) gives the bitangent ``w * cross(n, t)``, the direction of
    increasing v.  Per-triangle directions are accumulated weighted by the
    triangle's area in texture space; a vertex without a usable direction gets
    any unit vector perpendicular to its normal.
    """
    v = np.asarray(vertices, np.float64)
    f = np.asarray(indices, np.int64).reshape(-1, 3)
    n = np.asarray(normals, np.float64)
    uv = np.asarray(texcoords, np.float64)
    p0, p1, p2 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    w0, w1, w2 = uv[f[:, 0]], uv[f[:, 1]], uv[f[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    d1, d2 = w1 - w0, w2 - w0
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    sign = np.where(det < 0.0, -1.0, 1.0)
    # (e1 d2v - e2 d1v) / det, scaled by |det| (the texture-space area): well-conditioned accumulation
    sdir = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * sign[:, None]
    tdir = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * sign[:, None]
    t_acc = np.zeros_like(v)
    b_acc = np.zeros_like(v)
    for k in range(3):
        np.add.at(t_acc, f[:, k], sdir)
        np.add.at(b_acc, f[:, k], tdir)
    t = t_acc - n * np.sum(n * t_acc, axis=1, keepdims=True)
    length = np.linalg.norm(t, axis=1)
    bad = length < 1e-12
    if bad.any():  # no texture-space extent: any perpendicular
        other = np.where(np.abs(n[bad, 0:1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        t[bad] = np.cross(n[bad], other)
        length[bad] = np.linalg.norm(t[bad], axis=1)
    t /= np.maximum(length, 1e-30)[:, None]
    w = np.where(np.sum(np.cross(n, t) * b_acc, axis=1) < 0.0, -1.0, 1.0)
    return np.column_stack([t, w]).astype(np.float32)
