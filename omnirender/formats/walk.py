"""A base for exporting engines: the generic engine plus hooks on entering and leaving nodes.

Exporters mirror the scene graph's structure (glTF nodes, RIB attribute
blocks), so they need to know where nodes begin and end, and the model matrix
at that moment.  The core engine's ``on_enter`` / ``on_leave`` hooks provide that.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..attributes.surface import resolve_surface, track_surfaces
from ..core import Engine

__all__ = ["NodeTrackingEngine", "track_surfaces"]


class NodeTrackingEngine(Engine):
    """An engine that calls :meth:`enter_node` / :meth:`leave_node` around every node's contents.

    Exporters honour the camera's group mask as the renderers do (a hidden debug shape is not exported).
    """

    uses_camera_mask = True

    def __init__(self, **options: Any) -> None:
        super().__init__(**options)
        #: Color / Material / PBRMaterial in activation order (kept by :func:`track_surfaces` painters)
        self.surface_stack: list[Any] = []

    def surface(self) -> tuple[Any, Any]:
        """(material, colour) resolved like the GL engine (see :func:`resolve_surface`)."""
        return resolve_surface(self.surface_stack)

    def on_enter(self, node: Any) -> None:
        self.enter_node(node, self.model_matrix())

    def on_leave(self, node: Any) -> None:
        self.leave_node(node)

    def enter_node(self, node: Any, world: np.ndarray) -> None:
        """Called before a node's contents; ``world`` is the model matrix at that point."""

    def leave_node(self, node: Any) -> None:
        """Called after a node's contents were evaluated and undone."""
