"""Shared geometric algorithms: tessellation, normals, triangulation, isosurfaces, matrices.

Imports nothing but numpy and the core's matrix helper (scikit-image only inside
:func:`isosurface`).  Intersection, BVH, bounds and clipping live in the
submodules ``intersect``, ``bvh``, ``bounds`` and ``clip`` (import them explicitly).
"""

from . import tessellate
from .isosurface import isosurface
from .matrix import (
    align_y_matrix,
    normal_matrix,
    rotation_between,
    rotation_matrix,
    scaling_matrix,
    transform_directions,
    transform_normals,
    transform_points,
    translation_matrix,
)
from .normals import face_normals, smooth_normals, triangle_areas
from .tessellate import Mesh, merge_meshes
from .triangulate import newell_normal, project_to_plane, triangulate_polygon

__all__ = [
    "tessellate",
    "Mesh",
    "merge_meshes",
    "isosurface",
    "face_normals",
    "smooth_normals",
    "triangle_areas",
    "newell_normal",
    "project_to_plane",
    "triangulate_polygon",
    "translation_matrix",
    "scaling_matrix",
    "rotation_matrix",
    "rotation_between",
    "align_y_matrix",
    "transform_points",
    "transform_directions",
    "transform_normals",
    "normal_matrix",
]
