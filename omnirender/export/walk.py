"""A base for exporting engines: the generic engine plus hooks on entering and leaving nodes.

Exporters mirror the scene graph's structure (glTF nodes, RIB attribute
blocks), so they need to know where nodes begin and end, and the model matrix
at that moment.  The core engine's ``on_enter`` / ``on_leave`` hooks provide that.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..attributes import Color, Material, PBRMaterial
from ..core import AttributePainter, Engine, default_for

__all__ = ["NodeTrackingEngine", "track_surfaces"]


class NodeTrackingEngine(Engine):
    """An engine that calls :meth:`enter_node` / :meth:`leave_node` around every node's contents."""

    def __init__(self, **options: Any) -> None:
        super().__init__(**options)
        #: Color / Material / PBRMaterial in activation order (kept by :func:`track_surfaces` painters)
        self.surface_stack: list[Any] = []

    def surface(self) -> tuple[Any, Any]:
        """(material, colour) resolved like the GL engine: the innermost Material or PBRMaterial,
        and a Color only if it became active after it (it replaces the material's colour)."""
        material = color = None
        for attr in reversed(self.surface_stack):
            if isinstance(attr, Color):
                if color is None:
                    color = attr
            else:
                material = attr
                break
        return material, color

    def on_enter(self, node: Any) -> None:
        self.enter_node(node, self.model_matrix())

    def on_leave(self, node: Any) -> None:
        self.leave_node(node)

    def enter_node(self, node: Any, world: np.ndarray) -> None:
        """Called before a node's contents; ``world`` is the model matrix at that point."""

    def leave_node(self, node: Any) -> None:
        """Called after a node's contents were evaluated and undone."""


class _SurfaceTracker(AttributePainter):
    __slots__ = ()

    def exec(self, attribute: Any, engine: NodeTrackingEngine) -> None:
        engine.surface_stack.append(attribute)

    def unexec(self, attribute: Any, engine: NodeTrackingEngine) -> None:
        stack = engine.surface_stack
        for i in range(len(stack) - 1, -1, -1):
            if stack[i] is attribute:
                del stack[i]
                return


def track_surfaces(engine_cls: type) -> None:
    """Register painters keeping ``surface_stack`` for ``engine_cls`` (its ``service``)."""
    for target in (Color, Material, PBRMaterial):
        name = f"{engine_cls.__name__}{target.__name__}Tracker"
        cls = type(name, (_SurfaceTracker,), {"__slots__": (), "service": engine_cls.service, "target": target})
        default_for(engine_cls)(cls)
