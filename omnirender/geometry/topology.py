"""Mesh topology: whether a triangle set is a closed surface wound outwards.

A closed, consistently wound surface whose triangles face outwards never shows
its back faces when it is opaque, so renderers may cull them (half the
fragments of a mesh seen from outside).  Vertices are welded by position first:
meshes with per-face normals (a cube with 24 vertices) repeat positions along
their edges.
"""

from __future__ import annotations

import numpy as np

__all__ = ["is_closed_outward"]


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
    size = float(np.max(pos.max(axis=0) - pos.min(axis=0))) or 1.0
    _, weld = np.unique(np.round(pos / (size * 1e-6)), axis=0, return_inverse=True)
    t = weld.reshape(-1)[tris]
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
