"""Constructive solid geometry: ``CSG(operation, a, b)``, a shape made of two closed shapes or subgraphs.

``operation`` is ``"union"``, ``"intersection"`` or ``"difference"`` (a minus
b).  Operands are shapes (a ``Sphere``, another ``CSG``...) or nodes, whose
transforms and shapes make a solid in the CSG's coordinates; their own
materials are not used: the whole solid takes the appearance active where the
CSG is evaluated.  Every operand must be closed (a solid), as every engine
treats it as one.

How engines draw it: POV-Ray writes its native ``union``/``intersection``/
``difference``; every other engine (GL, Mitsuba, Radiance, glTF, RIB, bounds,
collisions) evaluates the mesh the default simplifier computes with the
``manifold3d`` library (:mod:`omnirender.shapes.csg_simplifier`); picking
combines the operands' ray intervals exactly.  A change of a shape operand
reaches the CSG (its version moves); after changing an operand *node*, call
``csg.touch()``.
"""

from __future__ import annotations

from typing import Any

from ..core.component import Shape

__all__ = ["CSG", "OPERATIONS"]

OPERATIONS = ("union", "intersection", "difference")


class CSG(Shape):
    """``a`` combined with ``b`` by ``operation`` (union, intersection or difference = a minus b)."""

    __slots__ = ("_operation", "_a", "_b")

    def __init__(self, operation: str, a: Any, b: Any) -> None:
        super().__init__()
        if operation not in OPERATIONS:
            raise ValueError(f"CSG: operation must be one of {OPERATIONS}, got {operation!r}")
        for name, operand in (("a", a), ("b", b)):
            if not (isinstance(operand, Shape) or hasattr(operand, "local_program")):
                raise ValueError(
                    f"CSG: operand {name} must be a shape (om.Sphere(...)) or an om.Node holding one, "
                    f"got {type(operand).__name__}"
                )
            if operand is self:
                raise ValueError("CSG: an operand cannot be the CSG itself")
        object.__setattr__(self, "_operation", operation)
        object.__setattr__(self, "_a", a)
        object.__setattr__(self, "_b", b)
        for operand in (a, b):
            if isinstance(operand, Shape):
                operand.attach_owner(self)  # a changed operand shape changes the CSG (its owners recompile)

    @property
    def operation(self) -> str:
        return self._operation

    @property
    def a(self) -> Any:
        return self._a

    @property
    def b(self) -> Any:
        return self._b

    def operands(self) -> tuple[Any, Any]:
        return (self._a, self._b)

    def operand_versions(self) -> tuple[int, int]:
        """The operands' versions (part of every cache key of the CSG's derived geometry)."""
        return (self._a.version, self._b.version)

    def parameters(self) -> dict[str, Any]:
        return {"operation": self._operation, "a": self._a, "b": self._b}

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__(state)
        for operand in (self._a, self._b):
            if isinstance(operand, Shape):
                operand.attach_owner(self)
