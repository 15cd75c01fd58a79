"""The NURBS surface's default simplifier: a trimmed triangle mesh (every engine without a NURBS painter).

The grid has ``4 * 2**level`` cells per Bézier span along each direction at the
Tessellation level (32 at the default 3), is cut along the trimming loops
(:func:`omnirender.geometry.nurbs.tessellate_surface`) and carries the normalised
``(u, v)`` as texture coordinates.  Cached per (surface, version, level).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core import Engine, ShapeSimplifier, default_for
from .meshes import TriangleSet
from .nurbs import NURBSSurface
from .simplifiers import cached, segments, tessellation_level

__all__ = ["NURBSSimplifier", "mesh_segments", "MAX_CELLS"]


#: The most grid cells a mesh gets (about 1 M triangles): many knot spans at a fine level share this budget.
MAX_CELLS = 2**19


def mesh_segments(shape: NURBSSurface, level: int) -> tuple[int, int]:
    """Grid cells along u and v of the mesh of ``shape`` at Tessellation ``level`` (at most :data:`MAX_CELLS`)."""
    ku, kv = shape.knot_vectors()
    spans_u, spans_v = len(np.unique(ku)) - 1, len(np.unique(kv)) - 1
    per_span = segments(level, 4)
    nu, nv = max(2, spans_u * per_span), max(2, spans_v * per_span)
    scale = min(1.0, (MAX_CELLS / (nu * nv)) ** 0.5)
    return max(2, int(nu * scale)), max(2, int(nv * scale))


@default_for(Engine)
class NURBSSimplifier(ShapeSimplifier):
    """NURBSSurface -> TriangleSet (trimmed, normals from the surface, (u, v) texture coordinates)."""

    __slots__ = ()
    target = NURBSSurface

    def exec(self, shape: NURBSSurface, engine: Engine) -> list[Any]:
        level = tessellation_level(engine)

        def build() -> list[Any]:
            mesh = shape.tessellate(mesh_segments(shape, level))
            if not len(mesh["indices"]):
                return []  # trimmed away completely
            return [TriangleSet(mesh["vertices"], mesh["indices"], normals=mesh["normals"],
                                texcoords=mesh["texcoords"])]  # fmt: skip

        return cached(shape, level, build)
