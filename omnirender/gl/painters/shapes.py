"""Shape painters of the GL engine (service ``"gl.paint"``).

Painters turn a shape into draw items through ``engine.submit``; they never
call OpenGL.  TriangleSet, LineSet, Polyline and PointSet upload their arrays
once per (shape, version).  Sphere, Box, Cylinder, Cone, Disk and Rectangle
are native: they reuse one unit mesh per Tessellation level scaled by a local
matrix, so they need no per-shape tessellation and any number of them
instance automatically.  Every other shape (Torus, Arrow, Polygon,
Heightfield, MeshFile, ...) reaches the engine through its simplifier.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...attributes import Color
from ...core.handler import ShapePainter, default_for
from ...core.program import EVAL, NODE
from ...core.transform import Transform
from ...geometry.topology import is_closed_outward
from ...shapes import (
    Box,
    Cone,
    Cylinder,
    Disk,
    InstanceSet,
    LevelOfDetail,
    LineSet,
    PointSet,
    Polyline,
    Rectangle,
    Sphere,
    TriangleSet,
)
from ..engine.geometry import Geometry, validate_mesh
from ..engine.instancing import PROBE, set_arrays
from ..engine.passes import Pass
from ..engine.technique import GLTechnique
from ..glengine import GLEngine

__all__ = [
    "TriangleSetPainter",
    "SpherePainter",
    "BoxPainter",
    "CylinderPainter",
    "ConePainter",
    "DiskPainter",
    "RectanglePainter",
    "LineSetPainter",
    "PolylinePainter",
    "PointSetPainter",
]


def _where(engine: Any) -> str:
    return engine.node_path


def _check_optional(arr: np.ndarray | None, owner: str, name: str, path: str) -> None:
    if arr is not None and not np.all(np.isfinite(arr)):
        where = f" in node {path}" if path else ""
        raise ValueError(f"{owner}{where}: {name} contain non-finite values; fix the {name}")


@default_for(GLEngine)
class TriangleSetPainter(ShapePainter):
    """Triangles with per-vertex normals, colours and texture coordinates (uploaded once per version)."""

    __slots__ = ()
    service = "gl.paint"
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: GLEngine) -> None:
        geom = engine.geometry_cache.get(shape)
        if geom is None:
            path = _where(engine)
            v = shape.vertex_array()
            idx = shape.index_array()
            validate_mesh(v, idx, "TriangleSet", path)
            normals = shape.normal_array()
            _check_optional(normals, "TriangleSet", "normals", path)
            colors = shape.color_array()
            _check_optional(colors, "TriangleSet", "colors", path)
            uv = shape.texcoord_array()
            _check_optional(uv, "TriangleSet", "texcoords", path)
            uv1 = shape.texcoord_array(1)
            _check_optional(uv1, "TriangleSet", "texcoords1", path)
            geom = Geometry(
                "triangles",
                v,
                normals,
                colors,
                uv,
                indices=idx,
                label=f"TriangleSet in {path or '/'}",
                texcoords1=uv1,
                tangents=shape.tangent_array if uv is not None else None,
                closed=is_closed_outward(v, idx),  # opaque closed meshes get their back faces culled
            )
            engine.geometry_cache.put(shape, geom)
        engine.submit(geom)


def _scale_translate(sx: float, sy: float, sz: float, center: Any = (0.0, 0.0, 0.0)) -> np.ndarray:
    m = np.diag([sx, sy, sz, 1.0])
    m[:3, 3] = center
    return m


@default_for(GLEngine)
class SpherePainter(ShapePainter):
    """Native sphere: the shared unit sphere, scaled and moved per instance."""

    __slots__ = ()
    service = "gl.paint"
    target = Sphere

    def exec(self, shape: Sphere, engine: GLEngine) -> None:
        r = shape.radius
        engine.submit(engine.unit_geometry("sphere"), _scale_translate(r, r, r, shape.center))


@default_for(GLEngine)
class BoxPainter(ShapePainter):
    """Native box: the shared unit cube, scaled and moved per instance."""

    __slots__ = ()
    service = "gl.paint"
    target = Box

    def exec(self, shape: Box, engine: GLEngine) -> None:
        sx, sy, sz = shape.size
        engine.submit(engine.unit_geometry("box"), _scale_translate(sx, sy, sz, shape.center))


@default_for(GLEngine)
class CylinderPainter(ShapePainter):
    """Native capped cylinder: the shared unit cylinder (radius 1, y in [-1, 1]) scaled per instance."""

    __slots__ = ()
    service = "gl.paint"
    target = Cylinder

    def exec(self, shape: Cylinder, engine: GLEngine) -> None:
        r = shape.radius
        engine.submit(engine.unit_geometry("cylinder"), _scale_translate(r, shape.height / 2.0, r))


@default_for(GLEngine)
class ConePainter(ShapePainter):
    """Native cone (base at y = -height/2, apex at +height/2): the shared unit cone scaled per instance."""

    __slots__ = ()
    service = "gl.paint"
    target = Cone

    def exec(self, shape: Cone, engine: GLEngine) -> None:
        r = shape.radius
        engine.submit(engine.unit_geometry("cone"), _scale_translate(r, shape.height / 2.0, r))


@default_for(GLEngine)
class DiskPainter(ShapePainter):
    """Native disk in the xz plane (double-sided through two-sided lighting)."""

    __slots__ = ()
    service = "gl.paint"
    target = Disk

    def exec(self, shape: Disk, engine: GLEngine) -> None:
        r = shape.radius
        engine.submit(engine.unit_geometry("disk"), _scale_translate(r, 1.0, r))


@default_for(GLEngine)
class RectanglePainter(ShapePainter):
    """Native rectangle in the xz plane (double-sided through two-sided lighting)."""

    __slots__ = ()
    service = "gl.paint"
    target = Rectangle

    def exec(self, shape: Rectangle, engine: GLEngine) -> None:
        sx, sz = shape.size
        engine.submit(engine.unit_geometry("rectangle"), _scale_translate(sx, 1.0, sz))


class _LinePainter(ShapePainter):
    __slots__ = ()
    service = "gl.paint"

    def exec(self, shape: Any, engine: GLEngine) -> None:
        geom = engine.geometry_cache.get(shape)
        if geom is None:
            path = _where(engine)
            name = type(shape).__name__
            v = shape.vertex_array()
            idx = shape.index_array()
            validate_mesh(v, idx, name, path, arity=2)
            colors = shape.color_array()
            _check_optional(colors, name, "colors", path)
            geom = Geometry("lines", v, colors=colors, indices=idx, label=f"{name} in {path or '/'}")
            engine.geometry_cache.put(shape, geom)
        engine.submit(geom, kind="lines")


@default_for(GLEngine)
class LineSetPainter(_LinePainter):
    """Line segments, drawn as screen-space quads (a geometry shader), so any DrawStyle.line_width works."""

    __slots__ = ()
    target = LineSet


@default_for(GLEngine)
class PolylinePainter(_LinePainter):
    """A polyline (open or closed) as wide line segments."""

    __slots__ = ()
    target = Polyline


@default_for(GLEngine)
class InstanceSetPainter(ShapePainter):
    """An instance set: its shape's draw items, each drawn once per visible instance in one instanced call."""

    __slots__ = ()
    service = "gl.paint"
    target = InstanceSet

    def exec(self, shape: InstanceSet, engine: GLEngine) -> None:
        matrices, colors, may_mirror = set_arrays(shape)
        if colors is None:
            templates = engine.capture(shape.shape)
        else:  # captured under the probe colour: the parts showing it take the instances' colours
            engine.push(_PROBE)
            try:
                templates = engine.capture(shape.shape)
            finally:
                engine.pop(Color)
        for template in templates:
            engine.submit_instances(shape, template, matrices, colors, may_mirror)


_PROBE = Color(*PROBE)


class _LevelSelect(GLTechnique):
    """One level of a LevelOfDetail in the GL frame: drawn only in frames whose eye is at its distance.

    Made by the painter for each compiled occurrence (not a scene component):
    it keeps the transforms above the level of detail, so the distance follows
    them when they move.
    """

    __slots__ = ("lod", "index", "chain")

    def __init__(self, lod: LevelOfDetail, index: int, chain: tuple[Any, ...]) -> None:
        super().__init__(passes=1)
        object.__setattr__(self, "lod", lod)
        object.__setattr__(self, "index", index)
        object.__setattr__(self, "chain", chain)

    def needs_pass(self, engine: Any) -> bool:
        if engine.current_pass >= 1:
            return False
        m = np.eye(4)
        for t in self.chain:
            m = m @ t.matrix
        center = (m @ np.array([*self.lod.center, 1.0]))[:3]
        return self.lod.level_at(float(np.linalg.norm(engine.eye_position - center))) == self.index

    def prepare_pass(self, engine: Any) -> None:
        engine.set_pass(Pass(f"level {self.index}"))


@default_for(GLEngine)
class LevelOfDetailPainter(ShapePainter):
    """Every level compiled once, in its own scope; the frame draws the one its eye's distance selects."""

    __slots__ = ()
    service = "gl.paint"
    target = LevelOfDetail

    def exec(self, shape: LevelOfDetail, engine: GLEngine) -> None:
        chain = tuple(engine.context.mono_stack(Transform))
        for index, level in enumerate(shape.levels):
            op = (NODE, level) if hasattr(level, "local_program") else (EVAL, level)
            engine.run_technique(_LevelSelect(shape, index, chain), [op])


@default_for(GLEngine)
class PointSetPainter(ShapePainter):
    """Round point sprites, shaded like small spheres; size per point or DrawStyle.point_size (pixels)."""

    __slots__ = ()
    service = "gl.paint"
    target = PointSet

    def exec(self, shape: PointSet, engine: GLEngine) -> None:
        geom = engine.geometry_cache.get(shape)
        if geom is None:
            path = _where(engine)
            v = shape.vertex_array()
            validate_mesh(v, None, "PointSet", path)
            colors = shape.color_array()
            _check_optional(colors, "PointSet", "colors", path)
            geom = Geometry("points", v, colors=colors, sizes=shape.size_array(), label=f"PointSet in {path or '/'}")
            engine.geometry_cache.put(shape, geom)
        engine.submit(geom, kind="points")
