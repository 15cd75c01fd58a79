"""Clipping meshes, segments and points against half-spaces (what ``ClipPlane`` does in engines without it).

OpenGL clips in the rasteriser; renderers that only get geometry (Mitsuba, the
RIB exporter for planes RenderMan cannot scope) need the clipped geometry
itself.  A plane is ``(normal, offset)`` and keeps the points ``p`` with
``dot(normal, p) >= offset`` (``om.ClipPlane``'s convention; a point on the
plane is kept); a 4-vector ``(a, b, c, d)`` keeping ``a x + b y + c z + d >= 0``
(``ClipPlane.world_plane``) is accepted too.

:func:`clip_triangles` is Sutherland–Hodgman per triangle and plane, vectorised
over all triangles: a triangle with one vertex inside becomes one triangle, one
with two inside a quad (two triangles), the winding is kept.  Each cut edge gets
one new vertex, shared by the triangles on both sides, so a connected mesh stays
connected; per-vertex normals, texture coordinates and colours are interpolated
linearly along the edge (normals renormalised).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any, NamedTuple

import numpy as np

__all__ = ["ClippedMesh", "clip_triangles", "clip_segments", "keep_points", "plane_rows"]


class ClippedMesh(NamedTuple):
    """The result of :func:`clip_triangles`; attribute arrays are None when not given."""

    vertices: np.ndarray  # (N, 3)
    indices: np.ndarray  # (M, 3) uint32
    normals: np.ndarray | None  # (N, 3)
    texcoords: np.ndarray | None  # (N, 2)
    colors: np.ndarray | None  # (N, C)


def plane_rows(planes: Iterable[Any]) -> np.ndarray:
    """(K, 4) float64 rows ``(a, b, c, d)`` keeping ``a x + b y + c z + d >= 0``, normals of unit length.

    Each plane is ``(normal, offset)`` (keeps ``dot(normal, p) >= offset``) or a 4-vector ``(a, b, c, d)``.
    """
    rows = []
    for plane in planes:
        if len(plane) == 2:
            normal, offset = plane
            row = np.array([*np.asarray(normal, np.float64).reshape(3), -float(offset)])
        else:
            row = np.asarray(plane, np.float64).reshape(-1)
            if row.size != 4:
                raise ValueError(f"clip: a plane is (normal, offset) or (a, b, c, d), got {plane!r}")
        length = float(np.linalg.norm(row[:3]))
        if not np.isfinite(row).all() or length == 0.0:
            raise ValueError(f"clip: plane {plane!r} needs a finite non-zero normal")
        rows.append(row / length)
    return np.array(rows, np.float64).reshape(-1, 4)


def _signed(points: np.ndarray, row: np.ndarray) -> np.ndarray:
    return points @ row[:3] + row[3]


def clip_triangles(
    vertices: Any,
    indices: Any,
    planes: Sequence[Any],
    normals: Any = None,
    texcoords: Any = None,
    colors: Any = None,
) -> ClippedMesh:
    """The part of the mesh on the kept side of every plane (see the module docstring).

    ``vertices`` (N, 3), ``indices`` (M, 3); the optional per-vertex arrays have
    N rows.  Without planes the mesh comes back unchanged; vertices no triangle
    uses any more are dropped.
    """
    v = np.asarray(vertices)
    dtype = v.dtype if v.dtype in (np.float32, np.float64) else np.dtype(np.float64)
    v = v.astype(np.float64).reshape(-1, 3)
    faces = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    extras = [
        None if a is None else np.asarray(a, np.float64).reshape(len(v), -1) for a in (normals, texcoords, colors)
    ]
    rows = plane_rows(planes)
    if len(rows) == 0:
        return _result(v, faces, extras, dtype, compact=False)
    for row in rows:
        if len(faces) == 0:
            break
        d = _signed(v, row)
        v, faces, extras = _clip_one(v, faces, extras, d)
    return _result(v, faces, extras, dtype, compact=True)


def _clip_one(
    v: np.ndarray, faces: np.ndarray, extras: list[np.ndarray | None], d: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray | None]]:
    inside = d[faces] >= 0.0
    count = inside.sum(axis=1)
    keep = faces[count == 3]
    one = faces[count == 1]
    two = faces[count == 2]
    if len(one) == 0 and len(two) == 0:
        return v, keep, extras
    # rotate so that the odd vertex comes first: the inside one of `one`, the outside one of `two`
    k1 = np.argmax(inside[count == 1], axis=1)
    k2 = np.argmin(inside[count == 2], axis=1)
    cols = np.arange(3)
    one = np.take_along_axis(one, (k1[:, None] + cols) % 3, axis=1)
    two = np.take_along_axis(two, (k2[:, None] + cols) % 3, axis=1)
    # cut edges: of `one` (a in): a-b, c-a; of `two` (rotated to c, a, b with c out): b-c, c-a
    edges = np.concatenate([one[:, [0, 1]], one[:, [2, 0]], two[:, [2, 0]], two[:, [0, 1]]])
    lo, hi = np.minimum(edges[:, 0], edges[:, 1]), np.maximum(edges[:, 0], edges[:, 1])
    n = len(v)
    unique, inverse = np.unique(lo * n + hi, return_inverse=True)
    ea, eb = unique // n, unique % n
    t = d[ea] / (d[ea] - d[eb])
    new_index = n + inverse.reshape(-1)
    v = np.concatenate([v, v[ea] + t[:, None] * (v[eb] - v[ea])])
    out_extras: list[np.ndarray | None] = []
    for i, a in enumerate(extras):
        if a is None:
            out_extras.append(None)
            continue
        added = a[ea] + t[:, None] * (a[eb] - a[ea])
        if i == 0:  # normals
            length = np.linalg.norm(added, axis=1, keepdims=True)
            added = added / np.where(length > 0.0, length, 1.0)
        out_extras.append(np.concatenate([a, added]))
    m1, m2 = len(one), len(two)
    x_ab, x_ca = new_index[:m1], new_index[m1 : 2 * m1]
    # `two` was rotated to (c, a, b) with c outside: the kept polygon is a, b, X(b->c), X(c->a)
    x_bc, x_cax = new_index[2 * m1 : 2 * m1 + m2], new_index[2 * m1 + m2 :]
    tri_one = np.stack([one[:, 0], x_ab, x_ca], axis=1)
    a, b = two[:, 1], two[:, 2]
    tri_two = np.concatenate([np.stack([a, b, x_bc], axis=1), np.stack([a, x_bc, x_cax], axis=1)])
    return v, np.concatenate([keep, tri_one, tri_two]), out_extras


def _result(v, faces, extras, dtype, compact: bool) -> ClippedMesh:
    if compact:
        used, faces = np.unique(faces.reshape(-1), return_inverse=True)
        faces = faces.reshape(-1, 3)
        v = v[used]
        extras = [None if a is None else a[used] for a in extras]
    normals, texcoords, colors = (None if a is None else a.astype(dtype) for a in extras)
    return ClippedMesh(v.astype(dtype), faces.astype(np.uint32).reshape(-1, 3), normals, texcoords, colors)


def clip_segments(a: Any, b: Any, planes: Sequence[Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments from ``a`` to ``b`` ((K, 3) each) cut to the kept side of every plane.

    Returns ``(a, b, kept)``: the shortened end points of the surviving segments
    and the indices of the input segments they come from.
    """
    a = np.array(a, np.float64).reshape(-1, 3)
    b = np.array(b, np.float64).reshape(-1, 3)
    kept = np.arange(len(a))
    for row in plane_rows(planes):
        da, db = _signed(a, row), _signed(b, row)
        alive = (da >= 0.0) | (db >= 0.0)
        a, b, da, db, kept = a[alive], b[alive], da[alive], db[alive], kept[alive]
        span = da - db  # non-zero wherever one end is outside
        t = np.divide(da, span, out=np.zeros_like(da), where=span != 0.0)[:, None]
        cut = a + t * (b - a)  # where the segment crosses the plane (one end is outside at most)
        a, b = np.where((da < 0.0)[:, None], cut, a), np.where((db < 0.0)[:, None], cut, b)
    return a, b, kept


def keep_points(points: Any, planes: Sequence[Any]) -> np.ndarray:
    """Boolean mask of the points on the kept side of every plane."""
    p = np.asarray(points, np.float64).reshape(-1, 3)
    mask = np.ones(len(p), bool)
    for row in plane_rows(planes):
        mask &= _signed(p, row) >= 0.0
    return mask
