"""Mesh booleans of closed triangle meshes with the ``manifold3d`` library (CSG for mesh engines).

:func:`mesh_boolean` welds each operand's vertices (tessellated shapes repeat
them along seams), builds ``manifold3d.Manifold`` solids, combines them and
returns the result's vertices, triangles and normals: normals are averaged
over the faces around a vertex that turn by less than ``crease`` degrees, so
curved parts look smooth and cut edges stay sharp.
"""

from __future__ import annotations

import math

import numpy as np

from .topology import weld_ids

__all__ = ["mesh_boolean", "weld", "crease_normals", "BooleanError"]


class BooleanError(ValueError):
    """An operand is not a closed solid, or manifold3d is missing."""


def weld(vertices: np.ndarray, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices at the same position (:func:`~.topology.weld_ids`); drop triangles that collapse."""
    v = np.asarray(vertices, np.float64).reshape(-1, 3)
    f = np.asarray(indices, np.int64).reshape(-1, 3)
    if not len(f):
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    first, ids = weld_ids(v)
    f = ids[f]
    keep = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])
    return v[first], f[keep]


def mesh_boolean(
    operation: str, a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray], what: str = "CSG"
) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of ``a`` op ``b`` for two closed meshes given as (vertices, triangles)."""
    try:
        import manifold3d as m3d
    except ImportError:  # pragma: no cover - depends on the installation
        raise BooleanError(
            f"{what}: mesh booleans need the manifold3d package (pip install 'omnirender[csg]')"
        ) from None
    solids = []
    for name, (v, f) in (("a", a), ("b", b)):
        v, f = weld(v, f)
        if not len(f):
            solids.append(m3d.Manifold())
            continue
        mesh = m3d.Mesh(vert_properties=np.ascontiguousarray(v, np.float32),
                        tri_verts=np.ascontiguousarray(f, np.uint32))  # fmt: skip
        solid = m3d.Manifold(mesh)
        if solid.status() != m3d.Error.NoError:
            raise BooleanError(
                f"{what}: operand {name} is not a closed solid ({solid.status().name}); CSG operands must be closed "
                "shapes (Sphere, Box, Cylinder, Torus, closed triangle sets) or nodes holding them"
            )
        solids.append(solid)
    sa, sb = solids
    result = sa + sb if operation == "union" else (sa ^ sb if operation == "intersection" else sa - sb)
    out = result.to_mesh()
    return np.asarray(out.vert_properties, np.float64)[:, :3], np.asarray(out.tri_verts, np.int64)


def crease_normals(
    vertices: np.ndarray, indices: np.ndarray, crease: float = 40.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An unshared mesh (3 vertices per triangle) with normals smoothed within ``crease`` degrees.

    Returns (vertices, triangles, normals).  Triangles without area (a
    boolean's slivers of collinear corners) draw nothing and have no normal:
    they are left out, so every normal has a direction.
    """
    v = np.asarray(vertices, np.float64)
    f = np.asarray(indices, np.int64)
    if len(f):
        e1, e2 = v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
        scale = float(np.ptp(v, axis=0).max()) if len(v) else 0.0
        f = f[np.linalg.norm(np.cross(e1, e2), axis=1) > 1e-12 * max(scale, 1e-300) ** 2]
    n_faces = len(f)
    if not n_faces:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros((0, 3))
    e1, e2 = v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    weighted = np.cross(e1, e2)  # area-weighted face normals
    unit = weighted / np.maximum(np.linalg.norm(weighted, axis=1, keepdims=True), 1e-300)
    corner_vertex = f.reshape(-1)
    corner_face = np.repeat(np.arange(n_faces), 3)
    order = np.argsort(corner_vertex, kind="stable")
    starts = np.searchsorted(corner_vertex[order], np.arange(len(v) + 1))
    limit = math.cos(math.radians(crease))
    normals = np.zeros((n_faces * 3, 3))
    for vertex in range(len(v)):
        corners = order[starts[vertex] : starts[vertex + 1]]
        if not len(corners):
            continue
        faces = corner_face[corners]
        similar = unit[faces] @ unit[faces].T >= limit  # (k, k): which neighbours each corner averages
        normals[corners] = similar.astype(np.float64) @ weighted[faces]
    length = np.linalg.norm(normals, axis=1)
    flat = length <= 1e-300  # opposite faces cancelling at a vertex: the corner takes its own face's normal
    normals[flat] = unit[corner_face[flat]]
    normals[~flat] /= length[~flat, None]
    return v[corner_vertex], np.arange(n_faces * 3).reshape(-1, 3), normals
