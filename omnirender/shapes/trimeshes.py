"""``trimesh.Trimesh`` objects as omnirender data, without importing trimesh.

``om.TriangleSet(mesh)`` and ``om.MeshFile(mesh)`` accept a mesh trimesh
made (or a ``trimesh.Scene``), as trimesh and PyVista users expect: the
arrays are read through the object's attributes, so declaring them needs
nothing but the object.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["is_trimesh", "is_trimesh_scene", "triangle_arrays"]


def is_trimesh(value: Any) -> bool:
    """Whether ``value`` is a ``trimesh.Trimesh`` (checked by module and attributes, trimesh is not imported)."""
    return type(value).__module__.startswith("trimesh") and hasattr(value, "vertices") and hasattr(value, "faces")


def is_trimesh_scene(value: Any) -> bool:
    """Whether ``value`` is a ``trimesh.Scene``."""
    return type(value).__module__.startswith("trimesh") and hasattr(value, "dump") and hasattr(value, "geometry")


def triangle_arrays(mesh: Any) -> dict[str, Any]:
    """``vertices``, ``indices``, ``normals``, ``colors`` and ``texcoords`` of a Trimesh (None where absent).

    Normals are the file's (those in trimesh's cache) or None (then computed
    smooth); colours are per-vertex colours, or per-face colours spread to
    unshared vertices; texture coordinates come from a textured visual.
    """
    vertices = np.asarray(mesh.vertices, dtype=np.float32)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if faces.size == 0:
        raise ValueError("the trimesh object has no faces (a point cloud or an empty mesh)")
    normals = None
    cache = getattr(mesh, "_cache", None)
    if cache is not None and "vertex_normals" in cache:
        vn = np.asarray(mesh.vertex_normals, dtype=np.float32)
        if vn.shape == vertices.shape and np.all(np.isfinite(vn)) and np.all(np.einsum("ij,ij->i", vn, vn) > 0):
            normals = vn
    colors = texcoords = None
    visual = getattr(mesh, "visual", None)
    kind = getattr(visual, "kind", None)
    if kind == "vertex":
        colors = np.asarray(visual.vertex_colors, dtype=np.float32) / 255.0
    elif kind == "face":
        fc = np.asarray(visual.face_colors, dtype=np.float32) / 255.0
        if len(np.unique(fc, axis=0)) > 1:  # faces keep their colours: every face gets its own three vertices
            flat = faces.reshape(-1)
            vertices = vertices[flat]
            normals = None if normals is None else normals[flat]
            colors = np.repeat(fc, 3, axis=0)
            faces = np.arange(len(flat)).reshape(-1, 3)
        else:
            colors = np.broadcast_to(fc[0], (len(vertices), 4)).copy()
    elif kind == "texture":
        uv = getattr(visual, "uv", None)
        if uv is not None and len(uv) == len(vertices):
            texcoords = np.asarray(uv, dtype=np.float32)
    return {"vertices": vertices, "indices": faces, "normals": normals, "colors": colors, "texcoords": texcoords}
