"""Bounds: the world-space axis-aligned box of a scene or subgraph (service ``"bounds"``).

Analytic shapes have exact handlers (support functions of
:mod:`omnirender.geometry.bounds`); triangle, line and point sets transform
their vertices; anything else falls back to its simplifier through the usual
handler look-up.  ``om.bounds(node)`` of a subgraph is in world coordinates:
the transforms before the node along its first-parent chain apply.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..core.handler import ShapePainter, default_for
from ..geometry import bounds as gb
from ..shapes import (
    Box,
    Cone,
    Cylinder,
    Disk,
    LineSet,
    PointSet,
    Polygon,
    Polyline,
    Rectangle,
    Sphere,
    Text,
    Torus,
    TriangleSet,
    Volume,
)
from .base import AnalysisEngine, run_analysis

__all__ = ["BoundsEngine", "BoundsHandler", "bounds", "analytic_bounds"]

BOUNDS = "bounds"

#: local support-function bounds per analytic shape class: fn(shape, matrix) -> (lo, hi)
_ANALYTIC: dict[type, Callable[[Any, np.ndarray], gb.Bounds]] = {
    Sphere: lambda s, m: gb.sphere_bounds(s.center, s.radius, m),
    Box: lambda s, m: gb.box_bounds(s.center, s.size, m),
    Cylinder: lambda s, m: gb.cylinder_bounds(s.radius, s.height, m),
    Cone: lambda s, m: gb.cone_bounds(s.radius, s.height, m),
    Disk: lambda s, m: gb.disk_bounds(s.radius, m),
    Rectangle: lambda s, m: gb.rectangle_bounds(s.size, m),
    Torus: lambda s, m: gb.torus_bounds(s.major_radius, s.minor_radius, m),
}


def analytic_bounds(shape: Any, matrix: np.ndarray) -> gb.Bounds | None:
    """Exact world AABB of an analytic shape under ``matrix``, or None for other classes."""
    fn = _ANALYTIC.get(type(shape))
    return None if fn is None else fn(shape, matrix)


class BoundsEngine(AnalysisEngine):
    """Accumulates the world AABB of everything it evaluates in ``box`` (None while empty)."""

    service = BOUNDS

    def __init__(self, *, mask: Any = None, on_missing: str = "warn") -> None:
        super().__init__(mask=mask, on_missing=on_missing)
        self.box: gb.Bounds | None = None

    def include(self, box: gb.Bounds | None) -> None:
        """Grow the accumulated box by ``box`` (world coordinates)."""
        self.box = gb.union(self.box, box)


class BoundsHandler(ShapePainter):
    """Base of the bounds handlers: ``exec`` adds the shape's world box to the engine."""

    __slots__ = ()
    service = BOUNDS


def _analytic_handler(cls: type) -> type:
    class Handler(BoundsHandler):
        __slots__ = ()
        target = cls

        def exec(self, shape: Any, engine: BoundsEngine) -> None:
            engine.include(_ANALYTIC[cls](shape, engine.model_matrix()))

    Handler.__name__ = Handler.__qualname__ = f"{cls.__name__}Bounds"
    Handler.__doc__ = f"Exact world AABB of a transformed {cls.__name__} (support function)."
    return default_for(BoundsEngine)(Handler)


SphereBounds = _analytic_handler(Sphere)
BoxBounds = _analytic_handler(Box)
CylinderBounds = _analytic_handler(Cylinder)
ConeBounds = _analytic_handler(Cone)
DiskBounds = _analytic_handler(Disk)
RectangleBounds = _analytic_handler(Rectangle)
TorusBounds = _analytic_handler(Torus)


class _VertexBounds(BoundsHandler):
    __slots__ = ()

    def exec(self, shape: Any, engine: BoundsEngine) -> None:
        engine.include(gb.points_bounds(shape.vertex_array(), engine.model_matrix()))


@default_for(BoundsEngine)
class TriangleSetBounds(_VertexBounds):
    """World AABB of a triangle set's transformed vertices."""

    __slots__ = ()
    target = TriangleSet


@default_for(BoundsEngine)
class LineSetBounds(_VertexBounds):
    __slots__ = ()
    target = LineSet


@default_for(BoundsEngine)
class PolylineBounds(_VertexBounds):
    __slots__ = ()
    target = Polyline


@default_for(BoundsEngine)
class PointSetBounds(_VertexBounds):
    __slots__ = ()
    target = PointSet


@default_for(BoundsEngine)
class PolygonBounds(_VertexBounds):
    __slots__ = ()
    target = Polygon


@default_for(BoundsEngine)
class TextBounds(BoundsHandler):
    """A label's anchor point: its glyphs have a size in pixels, not in world units."""

    __slots__ = ()
    target = Text

    def exec(self, shape: Text, engine: BoundsEngine) -> None:
        engine.include(gb.points_bounds(np.asarray([shape.position], dtype=np.float64), engine.model_matrix()))


@default_for(BoundsEngine)
class VolumeBounds(BoundsHandler):
    """The whole grid box (``Volume.bounds()``), not just the isosurface other engines show."""

    __slots__ = ()
    target = Volume

    def exec(self, shape: Volume, engine: BoundsEngine) -> None:
        lo, hi = shape.bounds()
        engine.include(gb.box_bounds((lo + hi) / 2.0, hi - lo, engine.model_matrix()))


def bounds(scene_or_node: Any, mask: str | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """World-space axis-aligned bounds ``(min, max)`` of a scene or subgraph, None when empty.

    A node that is not a root is measured where it sits: the transforms before
    it along its first-parent chain apply (evaluated from the root, so a
    ``Billboard`` above it turns towards the root's camera).  A list of
    components is measured in world coordinates as given.  Texts count as
    their anchor point; volumes as their whole grid box.  Anything else raises
    TypeError.
    """
    engine = BoundsEngine(mask=mask)
    run_analysis(engine, "bounds", scene_or_node, mask)
    if engine.box is None:
        return None
    return engine.box[0].copy(), engine.box[1].copy()
