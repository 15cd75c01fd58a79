"""Declarative pre-evaluation results: what a scene declares wherever it sits in the graph.

Before the main traversal every engine needs the lights (with their world
matrices, one entry per placement), the first camera, and other *declarative*
components: the first ``Background``, for example.  A component class takes
part by setting ``declared`` (a class attribute of
:class:`~omnirender.core.component.RenderingComponent`): ``"all"`` collects
every placement (lights), ``"first"`` only the first in traversal order
(camera, background).  Within one node's list the stack semantics of mono
attributes hold: a later declaration of the same category replaces an earlier
one (it is on top for the rest of the node), so of two Backgrounds in
one node the later one is the scene's, in every engine.  Graphs compute a :class:`Declarations` once per
version and mask (nodes cache theirs per node, so a change re-walks only the
changed path) and every engine uses that one result.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["Declarations", "ALL", "FIRST"]

#: ``declared`` values: collect every placement, or only the first one met.
ALL, FIRST = "all", "first"


class Declarations:
    """Placements ``(component, world matrix)`` of declared components, in traversal order.

    ``lights`` are the placements of every light; ``camera`` the first
    camera's, or None; :meth:`first` and :meth:`all` answer for any declared
    class.
    """

    __slots__ = ("placements", "lights", "camera")

    def __init__(self, placements: list[tuple[Any, np.ndarray]]) -> None:
        from .camera import Camera
        from .light import Light

        self.placements = placements
        self.lights: list[tuple[Any, np.ndarray]] = [(c, m) for c, m in placements if isinstance(c, Light)]
        self.camera: tuple[Any, np.ndarray] | None = self.first(Camera)

    @classmethod
    def of(cls, lights: list[tuple[Any, np.ndarray]], camera: tuple[Any, np.ndarray] | None) -> Declarations:
        """Declarations made of a light list and a camera (for roots that only offer ``preevaluate``)."""
        return cls([*([camera] if camera is not None else []), *lights])

    def first(self, cls: type) -> tuple[Any, np.ndarray] | None:
        """The first placement of a component of ``cls``, or None."""
        for component, matrix in self.placements:
            if isinstance(component, cls):
                return component, matrix
        return None

    def all(self, cls: type) -> list[tuple[Any, np.ndarray]]:
        """Every placement of components of ``cls``."""
        return [(c, m) for c, m in self.placements if isinstance(c, cls)]

    def __repr__(self) -> str:
        names = ", ".join(type(c).__name__ for c, _ in self.placements)
        return f"Declarations({names})"
