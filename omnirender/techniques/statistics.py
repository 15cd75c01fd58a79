"""The ``triangles`` figure of ``om.statistics``: triangle count after simplification.

A counting engine evaluates the scene: triangle sets add their triangle
count, everything else is simplified (lines, points and shapes without any
triangles count nothing).
"""

from __future__ import annotations

from typing import Any

from ..core.handler import ShapePainter, default_for
from ..scene import register_statistic
from ..shapes import LineSet, PointSet, Polyline, TriangleSet
from .base import AnalysisEngine, run_analysis

__all__ = ["TriangleCountEngine", "count_triangles"]

COUNT = "count.triangles"


class TriangleCountEngine(AnalysisEngine):
    """Counts triangles in ``triangles``."""

    service = COUNT

    def __init__(self, *, mask: Any = None) -> None:
        super().__init__(mask=mask, on_missing="skip")
        self.triangles = 0


@default_for(TriangleCountEngine)
class TriangleSetCounter(ShapePainter):
    __slots__ = ()
    service = COUNT
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: TriangleCountEngine) -> None:
        engine.triangles += len(shape.index_array())


class _Zero(ShapePainter):
    __slots__ = ()
    service = COUNT

    def exec(self, shape: Any, engine: TriangleCountEngine) -> None:
        return None


@default_for(TriangleCountEngine)
class LineSetCounter(_Zero):
    __slots__ = ()
    target = LineSet


@default_for(TriangleCountEngine)
class PolylineCounter(_Zero):
    __slots__ = ()
    target = Polyline


@default_for(TriangleCountEngine)
class PointSetCounter(_Zero):
    __slots__ = ()
    target = PointSet


def count_triangles(scene: Any, mask: str | None = None) -> int:
    """Triangles the scene's shapes become after simplification (a subgraph as it sits in its graph)."""
    engine = TriangleCountEngine(mask=mask)
    run_analysis(engine, "count_triangles", scene, mask)
    return engine.triangles


@register_statistic
def _triangles(scene: Any, stats: dict) -> None:
    stats["triangles"] = count_triangles(scene)
