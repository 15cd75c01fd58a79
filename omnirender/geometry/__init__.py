"""Shared geometric algorithms: tessellation, normals, triangulation, isosurfaces, matrices.

Imports nothing but numpy (scikit-image only inside :func:`isosurface`).
Intersection, BVH and bounds live in :mod:`.intersect`, :mod:`.bvh`, :mod:`.bounds`.
"""

from .normals import face_normals, smooth_normals, triangle_areas
from .triangulate import newell_normal, project_to_plane, triangulate_polygon

__all__ = [
    "face_normals",
    "smooth_normals",
    "triangle_areas",
    "newell_normal",
    "project_to_plane",
    "triangulate_polygon",
]
