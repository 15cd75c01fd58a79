"""Mitsuba meshes built from numpy arrays in memory (no temporary files).

``build_mesh`` creates an empty ``mi.Mesh`` of the right size and fills its
buffers through ``mi.traverse`` / ``params.update()``.  Positions and normals
are transformed to world space with numpy first (Mitsuba meshes made in Python
have no ``to_world``), and the winding is reversed under mirroring matrices so
geometric normals keep pointing outwards.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._mi import mitsuba

__all__ = ["build_mesh", "transform_points", "transform_normals"]


def transform_points(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(N, 3) points under a 4x4 affine matrix, float32."""
    m = np.asarray(matrix, dtype=np.float64)
    if np.array_equal(m, np.eye(4)):
        return np.ascontiguousarray(points, dtype=np.float32)
    out = points.astype(np.float64) @ m[:3, :3].T
    out += m[:3, 3]
    return out.astype(np.float32)


def transform_normals(matrix: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(N, 3) normals under the inverse transpose of a 4x4 matrix, renormalised, float32."""
    m = np.asarray(matrix, dtype=np.float64)[:3, :3]
    if np.array_equal(m, np.eye(3)):
        return np.ascontiguousarray(normals, dtype=np.float32)
    n = normals.astype(np.float64) @ np.linalg.inv(m)  # == (inv(m).T @ n.T).T
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n /= np.where(length > 0.0, length, 1.0)
    return n.astype(np.float32)


def build_mesh(
    name: str,
    vertices: np.ndarray,
    faces: np.ndarray,
    *,
    matrix: np.ndarray | None = None,
    normals: np.ndarray | None = None,
    texcoords: np.ndarray | None = None,
    colors: np.ndarray | None = None,
    bsdf: Any = None,
    emitter: Any = None,
) -> Any:
    """An ``mi.Mesh`` from (N, 3) vertices and (M, 3) faces, optionally transformed by ``matrix``.

    ``colors`` (N, 3) linear RGB become the mesh attribute ``vertex_color``
    (read by a ``mesh_attribute`` texture); ``bsdf`` and ``emitter`` are
    Mitsuba objects.
    """
    mi = mitsuba()
    vertices = np.asarray(vertices)
    faces = np.asarray(faces, dtype=np.uint32)
    if matrix is not None:
        vertices = transform_points(matrix, vertices)
        if normals is not None:
            normals = transform_normals(matrix, np.asarray(normals))
        if np.linalg.det(np.asarray(matrix)[:3, :3]) < 0.0:
            faces = faces[:, ::-1]
    props = mi.Properties()
    if bsdf is not None:
        props["bsdf"] = bsdf
    if emitter is not None:
        props["emitter"] = emitter
    mesh = mi.Mesh(
        name,
        int(len(vertices)),
        int(len(faces)),
        props,
        has_vertex_normals=normals is not None,
        has_vertex_texcoords=texcoords is not None,
    )
    params = mi.traverse(mesh)
    params["vertex_positions"] = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1)
    params["faces"] = np.ascontiguousarray(faces, dtype=np.uint32).reshape(-1)
    if normals is not None:
        params["vertex_normals"] = np.ascontiguousarray(normals, dtype=np.float32).reshape(-1)
    if texcoords is not None:
        params["vertex_texcoords"] = np.ascontiguousarray(texcoords, dtype=np.float32).reshape(-1)
    params.update()
    if colors is not None:
        mesh.add_attribute("vertex_color", 3, np.ascontiguousarray(colors[:, :3], dtype=np.float32).reshape(-1))

    return mesh
