"""The CSG's default simplifier: the mesh boolean of its operands (every engine without a CSG painter).

The operands are evaluated by a small collecting engine into triangles in the
CSG's coordinates (shapes through their own simplifiers, at the tessellation
level active where the CSG is evaluated), combined with
:func:`omnirender.geometry.boolean.mesh_boolean` and returned as one
``TriangleSet``.  Results are cached per (CSG, version, operand versions,
level).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core import Engine, ShapePainter, ShapeSimplifier, default_for
from ..geometry.boolean import crease_normals, mesh_boolean
from .csg import CSG
from .meshes import LineSet, PointSet, Polyline, TriangleSet
from .simplifiers import cached, tessellation_level

__all__ = ["CSGSimplifier", "operand_triangles"]

COLLECT = "csg.collect"


class _Collector(Engine):
    """Gathers the world triangles of what it evaluates (an operand of a CSG)."""

    service = COLLECT

    def __init__(self) -> None:
        super().__init__(on_missing="skip")
        self.vertices: list[np.ndarray] = []
        self.indices: list[np.ndarray] = []
        self.count = 0


@default_for(_Collector)
class _TriangleCollector(ShapePainter):
    __slots__ = ()
    service = COLLECT
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: _Collector) -> None:
        m = engine.model_matrix()
        v = shape.vertex_array().astype(np.float64) @ m[:3, :3].T + m[:3, 3]
        f = shape.index_array().astype(np.int64)
        if np.linalg.det(m[:3, :3]) < 0.0:
            f = f[:, ::-1]  # a mirroring transform turns the solid inside out: keep it outward
        engine.vertices.append(v)
        engine.indices.append(f + engine.count)
        engine.count += len(v)


class _NoSolid(ShapePainter):
    __slots__ = ()
    service = COLLECT

    def exec(self, shape: Any, engine: _Collector) -> None:
        return None


for _cls in (LineSet, Polyline, PointSet):  # lines and points have no volume
    default_for(_Collector)(type(f"_No{_cls.__name__}", (_NoSolid,), {"__slots__": (), "target": _cls}))


def operand_triangles(operand: Any, level: int) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of a CSG operand in the CSG's coordinates, tessellated at ``level``."""
    from ..attributes import Tessellation

    engine = _Collector()
    engine.push(Tessellation(level))
    if hasattr(operand, "local_program"):
        engine.run(operand)
    else:
        engine.evaluate([operand])
    if not engine.vertices:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    return np.concatenate(engine.vertices), np.concatenate(engine.indices)


@default_for(Engine)
class CSGSimplifier(ShapeSimplifier):
    """``CSG`` -> one ``TriangleSet``: the manifold3d boolean of the operands' meshes."""

    __slots__ = ()
    target = CSG

    def exec(self, shape: CSG, engine: Engine) -> list[Any]:
        level = tessellation_level(engine)
        where = f"CSG in node {engine.node_path}" if getattr(engine, "node_path", "") else "CSG"
        # node operands do not bump the CSG's version: their versions are part of the key
        return cached(shape, (level, shape.operand_versions()), lambda: _boolean(shape, level, where))


def _boolean(shape: CSG, level: int, where: str) -> list[Any]:
    a, b = (operand_triangles(op, level) for op in shape.operands())
    v, f = mesh_boolean(shape.operation, a, b, what=where)
    if not len(f):
        return []
    v, f, n = crease_normals(v, f)
    return [TriangleSet(v, f, normals=n)]
