"""Vertex-based shapes: triangle sets, polygons, line sets, polylines, point sets.

Per-vertex data may be given as ``om.data`` sequences or any array-likes; the
shape validates it at construction and keeps the arrays engines need behind
cached accessors (``vertex_array()`` and friends).  The parameters themselves
keep what was given.  To change data, assign the parameter again (or call
``update(...)`` to change several at once); after changing an array in place,
call ``shape.touch()`` so the accessors rebuild.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..geometry.normals import smooth_normals, vertex_tangents
from ..geometry.triangulate import best_fit_plane, crossing_edges, project_to_plane, triangulate_polygon
from . import _check
from .base import DeclaredShape, parameter
from .trimeshes import is_trimesh, triangle_arrays

__all__ = ["TriangleSet", "Polygon", "LineSet", "Polyline", "PointSet"]

_TRANSPARENT = frozenset({"transparent"})
_NONE: frozenset[str] = frozenset()


class _VertexShape(DeclaredShape):
    """Accessors common to vertex-based shapes."""

    __slots__ = ()

    def vertex_array(self) -> np.ndarray:
        """(N, 3) float32, read-only."""
        return self._cached("vertices")

    def color_array(self) -> np.ndarray | None:
        """(N, 4) float32 RGBA per vertex, read-only, or None (the context's colour applies)."""
        return self._cached("colors")

    @property
    def hints(self) -> frozenset[str]:  # type: ignore[override]
        """``{"transparent"}`` when a per-vertex alpha is below 1."""

        def compute() -> frozenset[str]:
            c = self.color_array()
            return _TRANSPARENT if c is not None and bool(np.any(c[:, 3] < 1.0)) else _NONE

        return self._cached("hints", compute)


class TriangleSet(_VertexShape):
    """Triangles over a vertex array.

    ``vertices`` (N, 3); ``indices`` (M, 3) or flat, None meaning consecutive
    triples; ``normals`` (N, 3), computed smooth (area-weighted) when None;
    ``colors`` (N, 3|4) or one RGB(A) colour for all; ``texcoords`` (N, 2)
    (UV set 0) and ``texcoords1`` (N, 2) (UV set 1, for textures with
    ``uv_set=1``); ``tangents`` (N, 4): xyz along increasing u, w the sign of
    the bitangent (along increasing v), for normal maps (generated from the
    texture coordinates when None).  Winding is counter-clockwise seen from the
    front.  At least one triangle.  ``TriangleSet(mesh)`` with a ``trimesh.Trimesh`` takes its
    vertices, faces, vertex normals (when the mesh has them), colours and texture coordinates.
    """

    __slots__ = ("_vertices", "_indices", "_normals", "_colors", "_texcoords", "_texcoords1", "_tangents")
    _params = ("vertices", "indices", "normals", "colors", "texcoords", "texcoords1", "tangents")
    vertices = parameter("vertices", "Vertex positions (N, 3).")
    indices = parameter("indices", "Triangle indices (M, 3) or None for consecutive triples.")
    normals = parameter("normals", "Vertex normals (N, 3) or None for smooth normals.")
    colors = parameter("colors", "Vertex colours (N, 3|4) or None.")
    texcoords = parameter("texcoords", "Texture coordinates (N, 2) or None.")
    texcoords1 = parameter("texcoords1", "Second texture coordinate set (N, 2) or None.")
    tangents = parameter("tangents", "Tangents (N, 4) or None (generated for normal maps).")

    def __init__(
        self,
        vertices: Any,
        indices: Any = None,
        normals: Any = None,
        colors: Any = None,
        texcoords: Any = None,
        texcoords1: Any = None,
        tangents: Any = None,
    ) -> None:
        if is_trimesh(vertices):
            given = {"indices": indices, "normals": normals, "colors": colors, "texcoords": texcoords}
            arrays = triangle_arrays(vertices)
            arrays.update({k: v for k, v in given.items() if v is not None})  # explicit arguments win
            vertices, indices, normals, colors, texcoords = (
                arrays[k] for k in ("vertices", "indices", "normals", "colors", "texcoords")
            )
        super().__init__(
            vertices=vertices,
            indices=indices,
            normals=normals,
            colors=colors,
            texcoords=texcoords,
            texcoords1=texcoords1,
            tangents=tangents,
        )

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        name = "TriangleSet"
        v = self._reuse(
            "vertices", p["vertices"], "vertices", lambda x: _check.float_array(name, "vertices", x, (3,), minimum=3)
        )
        n = len(v)
        if p["indices"] is None:
            if n % 3:
                raise ValueError(
                    f"{name}: without indices the vertex count must be a multiple of 3, got {n} "
                    "(pass indices to share vertices)"
                )
            idx = np.arange(n, dtype=np.uint32).reshape(-1, 3)
            idx.setflags(write=False)
        else:
            idx = _check.index_array(name, "indices", p["indices"], 3, n)
        derived = {
            "vertices": v,
            "indices": idx,
            "colors": _check.colors(name, "colors", p["colors"], n),
            "texcoords": None
            if p["texcoords"] is None
            else _check.float_array(name, "texcoords", p["texcoords"], (2,), count=n),
            "texcoords1": None
            if p.get("texcoords1") is None
            else _check.float_array(name, "texcoords1", p["texcoords1"], (2,), count=n),
            "tangents": None
            if p.get("tangents") is None
            else _check.float_array(name, "tangents", p["tangents"], (4,), count=n),
        }
        if p["normals"] is not None:
            derived["normals"] = _check.normals(name, "normals", p["normals"], n)
        return p, derived

    def index_array(self) -> np.ndarray:
        """(M, 3) uint32, read-only."""
        return self._cached("indices")

    def normal_array(self) -> np.ndarray:
        """(N, 3) float32 unit normals: the given ones, else smooth normals computed once per version."""

        def compute() -> np.ndarray:
            out = smooth_normals(self.vertex_array(), self.index_array())
            out.setflags(write=False)
            return out

        if self._normals is not None:
            return self._cached("normals")
        return self._cached("normals", compute)

    def texcoord_array(self, uv_set: int = 0) -> np.ndarray | None:
        """(N, 2) float32 of UV set 0 (``texcoords``) or 1 (``texcoords1``), or None."""
        return self._cached("texcoords1" if uv_set else "texcoords")

    def tangent_array(self) -> np.ndarray | None:
        """(N, 4) float32 tangents: the given ones, else generated from UV set 0 (None without texcoords)."""
        if self._tangents is not None:
            return self._cached("tangents")
        uv = self.texcoord_array()
        if uv is None:
            return None

        def compute() -> np.ndarray:
            out = vertex_tangents(self.vertex_array(), self.index_array(), self.normal_array(), uv)
            out.setflags(write=False)
            return out

        return self._cached("generated_tangents", compute)

    @property
    def triangle_count(self) -> int:
        return len(self.index_array())

    def transformed(self, matrix: Any) -> TriangleSet:
        """This set with the 4x4 ``matrix`` applied to its vertices, normals and tangents (itself for the identity).

        Normals take the inverse transpose; a mirroring matrix reverses the
        winding (and the bitangent sign) so fronts stay fronts.  For flattening
        a hierarchy into one mesh (glTF import, instanced export).
        """
        m = np.asarray(matrix, np.float64)
        if np.array_equal(m, np.eye(4)):
            return self
        linear = m[:3, :3]
        mirrored = np.linalg.det(linear) < 0.0
        vertices = self.vertex_array() @ linear.T + m[:3, 3]
        normals = self.normal_array() @ np.linalg.inv(linear)
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
        tangents = self._tangents
        if tangents is not None:
            t = np.asarray(self.tangent_array(), np.float64)
            xyz = t[:, :3] @ linear.T
            xyz /= np.maximum(np.linalg.norm(xyz, axis=1, keepdims=True), 1e-30)
            tangents = np.column_stack([xyz, -t[:, 3] if mirrored else t[:, 3]])
        return TriangleSet(
            vertices,
            self.index_array()[:, ::-1] if mirrored else self.index_array(),
            normals=normals,
            colors=self._colors,
            texcoords=self._texcoords,
            texcoords1=self._texcoords1,
            tangents=tangents,
        )


class Polygon(_VertexShape):
    """One planar polygon (convex or simple concave) given by its outline ``vertices`` (N >= 3, no repeat of the first).

    Counter-clockwise seen from the front.  ``normals`` is one normal (3,) or
    one per vertex (N, 3); when None the plane's normal (Newell's method) is
    used.  ``colors`` (N, 3|4) or one colour.  Simplifies to a TriangleSet by ear
    clipping.
    """

    __slots__ = ("_vertices", "_normals", "_colors")
    _params = ("vertices", "normals", "colors")
    vertices = parameter("vertices", "Outline (N, 3), N >= 3.")
    normals = parameter("normals", "One normal (3,), one per vertex (N, 3), or None.")
    colors = parameter("colors", "Vertex colours (N, 3|4), one colour, or None.")

    def __init__(self, vertices: Any, normals: Any = None, colors: Any = None) -> None:
        super().__init__(vertices=vertices, normals=normals, colors=colors)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        name = "Polygon"
        v = _check.float_array(name, "vertices", p["vertices"], (3,), minimum=3)
        n = len(v)
        derived: dict[str, Any] = {"vertices": v, "colors": _check.colors(name, "colors", p["colors"], n)}
        if p["normals"] is not None:
            normals = _check.normals(name, "normals", _broadcast_row(p["normals"], 3, n, name, "normals"), n)
            derived["normals"] = normals
        _check_polygon_outline(v)
        derived["triangles"] = triangulate_polygon(v, owner=name)
        return p, derived

    def triangle_indices(self) -> np.ndarray:
        """(N - 2, 3) uint32 triangulation of the outline, counter-clockwise like the outline."""
        return self._cached("triangles")

    def normal_array(self) -> np.ndarray | None:
        """(N, 3) float32 given normals, or None (the plane normal applies)."""
        return self._cached("normals", lambda: None)


def _check_polygon_outline(v: np.ndarray) -> None:
    """ValueError for a non-planar or self-intersecting outline (before triangulation, which says "zero area")."""
    p = np.asarray(v, dtype=np.float64)
    extent = float(np.max(np.ptp(p, axis=0)))
    if extent == 0.0:
        return  # all vertices equal: triangulation reports the zero area
    _, normal, deviation = best_fit_plane(p)
    tolerance = 1e-6 * extent
    if deviation > tolerance:
        worst = int(np.argmax(np.abs((p - p.mean(axis=0)) @ normal)))
        raise ValueError(
            f"Polygon: the {len(p)} vertices are not planar: vertex {worst} deviates by {deviation:.6g} from their "
            f"best-fit plane (tolerance {tolerance:.3g} = 1e-6 x extent {extent:.6g}); split it into planar polygons "
            f"or use a TriangleSet"
        )
    crossing = crossing_edges(project_to_plane(p, normal))
    if crossing is not None:
        i, j = crossing
        n = len(p)
        raise ValueError(
            f"Polygon: the outline is self-intersecting: edge {i}-{(i + 1) % n} crosses edge {j}-{(j + 1) % n}; "
            f"give a simple outline (e.g. reorder the vertices) or split it into several polygons"
        )


class LineSet(_VertexShape):
    """Line segments over a vertex array: ``indices`` (K, 2) or flat, None meaning consecutive pairs."""

    __slots__ = ("_vertices", "_indices", "_colors")
    _params = ("vertices", "indices", "colors")
    vertices = parameter("vertices", "Vertex positions (N, 3).")
    indices = parameter("indices", "Segment indices (K, 2) or None for consecutive pairs.")
    colors = parameter("colors", "Vertex colours (N, 3|4), one colour, or None.")

    def __init__(self, vertices: Any, indices: Any = None, colors: Any = None) -> None:
        super().__init__(vertices=vertices, indices=indices, colors=colors)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        name = "LineSet"
        v = _check.float_array(name, "vertices", p["vertices"], (3,), minimum=2)
        n = len(v)
        if p["indices"] is None:
            if n % 2:
                raise ValueError(f"{name}: without indices the vertex count must be even, got {n}")
            idx = np.arange(n, dtype=np.uint32).reshape(-1, 2)
            idx.setflags(write=False)
        else:
            idx = _check.index_array(name, "indices", p["indices"], 2, n)
        return p, {"vertices": v, "indices": idx, "colors": _check.colors(name, "colors", p["colors"], n)}

    def index_array(self) -> np.ndarray:
        """(K, 2) uint32, read-only."""
        return self._cached("indices")


class Polyline(_VertexShape):
    """A connected line through ``vertices`` (N >= 2); ``closed`` joins the last vertex to the first."""

    __slots__ = ("_vertices", "_colors", "_closed")
    _params = ("vertices", "colors", "closed")
    vertices = parameter("vertices", "Points (N, 3), N >= 2.")
    colors = parameter("colors", "Vertex colours (N, 3|4), one colour, or None.")
    closed = parameter("closed", "Whether the last point connects back to the first.")

    def __init__(self, vertices: Any, colors: Any = None, closed: bool = False) -> None:
        super().__init__(vertices=vertices, colors=colors, closed=closed)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        name = "Polyline"
        v = _check.float_array(name, "vertices", p["vertices"], (3,), minimum=2)
        if not isinstance(p["closed"], (bool, np.bool_)):
            raise ValueError(f"{name}: closed must be True or False, got {p['closed']!r}")
        p["closed"] = bool(p["closed"])
        n = len(v)
        i = np.arange(n, dtype=np.uint32)
        idx = np.stack([i[:-1], i[1:]], axis=1)
        if p["closed"] and n > 2:
            idx = np.concatenate([idx, [[n - 1, 0]]]).astype(np.uint32)
        idx.setflags(write=False)
        return p, {"vertices": v, "indices": idx, "colors": _check.colors(name, "colors", p["colors"], n)}

    def index_array(self) -> np.ndarray:
        """(K, 2) uint32 segments (N - 1, or N when closed)."""
        return self._cached("indices")


class PointSet(_VertexShape):
    """Points: ``vertices`` (N, 3), ``colors`` (N, 3|4) or one colour, ``sizes`` (N,) or one size (> 0, pixels)."""

    __slots__ = ("_vertices", "_colors", "_sizes")
    _params = ("vertices", "colors", "sizes")
    vertices = parameter("vertices", "Point positions (N, 3), N >= 1.")
    colors = parameter("colors", "Point colours (N, 3|4), one colour, or None.")
    sizes = parameter("sizes", "Point sizes (N,) or one size, > 0, or None (the draw style's point size).")

    def __init__(self, vertices: Any, colors: Any = None, sizes: Any = None) -> None:
        super().__init__(vertices=vertices, colors=colors, sizes=sizes)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        name = "PointSet"
        v = _check.float_array(name, "vertices", p["vertices"], (3,), minimum=1)
        n = len(v)
        sizes = None
        if p["sizes"] is not None:
            s = _broadcast_row(p["sizes"], 0, n, name, "sizes")
            sizes = _check.float_array(name, "sizes", s, (1,), count=n).reshape(-1)
            if np.any(sizes <= 0):
                raise ValueError(f"{name}: sizes must be > 0, got minimum {float(sizes.min())}")
        return p, {"vertices": v, "colors": _check.colors(name, "colors", p["colors"], n), "sizes": sizes}

    def size_array(self) -> np.ndarray | None:
        """(N,) float32 point sizes, or None."""
        return self._cached("sizes")


def _broadcast_row(value: Any, width: int, count: int, owner: str, name: str) -> Any:
    """Broadcast a single row (a (width,) vector, or a scalar when width is 0) to ``count`` rows."""
    from ..data import as_array

    a = as_array(value, None, name=f"{owner}: {name}")
    if width == 0 and a.ndim == 0:
        return np.broadcast_to(a, (count,))
    if width and a.ndim == 1 and a.shape[0] == width:
        return np.broadcast_to(a, (count, width))
    return a
