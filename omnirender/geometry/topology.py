"""Mesh topology: whether a triangle set is a closed surface wound outwards.

A closed, consistently wound surface whose triangles face outwards never shows
its back faces when it is opaque, so renderers may cull them (half the
fragments of a mesh seen from outside).  Vertices are welded by position first:
meshes with per-face normals (a cube with 24 vertices) repeat positions along
their edges.
"""

from __future__ import annotations

import numpy as np

__all__ = ["is_closed_outward", "adjacency_indices", "weld_ids"]


def weld_ids(positions: np.ndarray, tolerance: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """(first index of each welded position, welded id of every vertex): positions closer than ``tolerance``
    times the mesh's size are one vertex (the seams of tessellated shapes repeat positions)."""
    pos = np.asarray(positions, dtype=np.float64)
    size = float(np.max(pos.max(axis=0) - pos.min(axis=0))) or 1.0
    _, first, weld = np.unique(np.round(pos / (size * tolerance)), axis=0, return_index=True, return_inverse=True)
    return first, weld.reshape(-1)


def is_closed_outward(positions: np.ndarray, triangles: np.ndarray) -> bool:
    """True when every edge joins exactly two triangles with opposite directions and the volume is positive.

    ``positions`` is (N, 3), ``triangles`` (M, 3) indices.  Positions closer
    than a millionth of the mesh's size are welded (seams of tessellated
    shapes); triangles that collapse when welded (at a sphere's poles) are
    ignored.  Open borders, non-manifold edges, inconsistent winding and
    inward winding give False.
    """
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(tris) < 4:
        return False
    pos = np.asarray(positions, dtype=np.float64)
    t = weld_ids(pos)[1][tris]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 2] != t[:, 0])
    t, tris = t[keep], tris[keep]
    if len(t) < 4:
        return False
    n = int(t.max()) + 1
    starts = t.reshape(-1)
    ends = t[:, [1, 2, 0]].reshape(-1)
    directed = starts * n + ends
    if len(np.unique(directed)) != len(directed):  # an edge used twice in one direction: not consistently wound
        return False
    reverse = ends * n + starts
    if not np.array_equal(np.sort(directed), np.sort(reverse)):  # some edge has no opposite: a border
        return False
    p = pos[tris]
    volume = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0
    return bool(volume > 0.0)


def adjacency_indices(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Indices for OpenGL's ``triangles_adjacency``: per triangle (a, n_ab, b, n_bc, c, n_ca), flat uint32.

    ``n_ab`` is the vertex opposite the edge a-b in the neighbouring triangle
    (vertices welded by position, as in :func:`is_closed_outward`); an edge
    without a neighbour gets the triangle's own third vertex (a degenerate
    neighbour, which a shadow-volume shader treats as facing away).
    """
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if not len(tris):
        return np.zeros(0, np.uint32)
    t = weld_ids(positions)[1][tris]
    n = int(t.max()) + 1
    corners = np.arange(3)
    starts, ends = t[:, corners], t[:, (corners + 1) % 3]
    thirds = tris[:, (corners + 2) % 3]  # original index of the vertex opposite each edge
    key = (starts * n + ends).reshape(-1)
    opposite_key = (ends * n + starts).reshape(-1)
    order = np.argsort(key, kind="stable")
    found = np.searchsorted(key[order], opposite_key)
    found = np.minimum(found, len(key) - 1)
    has = key[order][found] == opposite_key
    neighbour = np.where(has, thirds.reshape(-1)[order][found], thirds.reshape(-1))
    out = np.empty((len(tris), 6), np.uint32)
    out[:, 0::2] = tris
    out[:, 1::2] = neighbour.reshape(-1, 3)
    return out.reshape(-1)
