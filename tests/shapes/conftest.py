"""A tiny collecting engine: simplifies shapes down to TriangleSets/LineSets/PointSets and records them."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import omnirender as om


class Collected:
    """A terminal shape as the engine met it: the shape, its model matrix and the active material."""

    def __init__(self, shape: Any, matrix: np.ndarray, material: Any) -> None:
        self.shape = shape
        self.matrix = matrix
        self.material = material

    def world_vertices(self) -> np.ndarray:
        v = self.shape.vertex_array().astype(np.float64)
        return v @ self.matrix[:3, :3].T + self.matrix[:3, 3]


class CollectEngine(om.Engine):
    service = "test.collect"

    def __init__(self) -> None:
        super().__init__(on_missing="skip")
        self.found: list[Collected] = []
        for target in (om.TriangleSet, om.LineSet, om.PointSet):
            self.install(_Painter.for_target(target))


class _Painter(om.ShapePainter):
    __slots__ = ("target",)
    service = "test.collect"

    @classmethod
    def for_target(cls, target: type) -> _Painter:
        p = cls()
        object.__setattr__(p, "target", target)
        return p

    def exec(self, shape: Any, engine: CollectEngine) -> None:
        material = engine.mono(om.Material) or engine.mono(om.PBRMaterial)
        engine.found.append(Collected(shape, engine.model_matrix().copy(), material))


def collect(components: Any, level: int | None = None) -> list[Collected]:
    """Evaluate ``components`` (a shape, a list or a Node) and return what reached the painters."""
    engine = CollectEngine()
    items = components if isinstance(components, (list, om.Node)) else [components]
    if level is not None and not isinstance(items, om.Node):
        items = [om.Tessellation(level), *items]
    engine.evaluate(items)
    return engine.found


@pytest.fixture
def simplify():
    return collect
