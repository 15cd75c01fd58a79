"""Isosurfaces of 3D scalar grids by marching cubes (scikit-image)."""

from __future__ import annotations

import numpy as np

from .tessellate import Mesh

__all__ = ["isosurface"]


def isosurface(data: np.ndarray, level: float, spacing=(1.0, 1.0, 1.0), *, closed: bool = True) -> Mesh | None:
    """The surface where ``data`` (D, H, W) indexed [z, y, x] crosses ``level``, or None if it does not.

    Coordinates follow :class:`omnirender.Volume`: voxel [k, j, i] at
    ``((i - (W-1)/2) sx, (j - (H-1)/2) sy, (k - (D-1)/2) sz)`` for ``spacing`` = (sx, sy, sz).
    Values above ``level`` are inside: normals point towards lower values and
    triangles wind counter-clockwise seen from outside.  With ``closed`` the
    surface is capped where it meets the grid's boundary (the grid is padded
    with a value far below ``level``), so it is watertight.
    """
    try:
        from skimage.measure import marching_cubes
    except ImportError as exc:  # pragma: no cover - scikit-image is in the 'mesh' extra
        raise RuntimeError(f"isosurface needs scikit-image (pip install omnirender[mesh]): {exc}") from None
    d = np.asarray(data, dtype=np.float32)
    lo, hi = float(d.min()), float(d.max())
    if not (lo < level < hi) and not (closed and lo < level <= hi):
        return None
    sx, sy, sz = (float(s) for s in spacing)
    shape = np.array(d.shape, dtype=np.float64)
    if closed:
        span = max(hi - lo, 1.0)
        # So far below that the crossing towards a pad voxel is at the boundary voxel (t < 1e-6).
        d = np.pad(d, 1, mode="constant", constant_values=level - 1e6 * span)
    verts, faces, normals, _ = marching_cubes(d, level=level, spacing=(sz, sy, sx), allow_degenerate=False)
    if len(faces) == 0:
        return None
    if closed:
        verts = verts - np.array([sz, sy, sx])
    # (z, y, x) -> (x, y, z): swapping two axes mirrors, which flips the winding back to ours.
    v = verts[:, ::-1] - (shape[::-1] - 1.0) / 2.0 * np.array([sx, sy, sz])
    n = normals[:, ::-1]
    f = faces[:, [0, 2, 1]]
    # Orient by the data: outward is towards lower values.
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    fn = np.cross(b - a, c - a)
    if np.sum(fn * n[f].mean(axis=1)) < 0:
        f = f[:, [0, 2, 1]]
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.tile([0.0, 1.0, 0.0], (len(n), 1)), where=length > 0)
    return Mesh(
        np.ascontiguousarray(v, dtype=np.float32),
        np.ascontiguousarray(f, dtype=np.uint32),
        np.ascontiguousarray(n, dtype=np.float32),
        None,
    )
