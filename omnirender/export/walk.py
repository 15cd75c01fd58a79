"""A base for exporting engines: the generic engine plus hooks on entering and leaving nodes.

Exporters mirror the scene graph's structure (glTF nodes, RIB attribute
blocks), so they need to know where nodes begin and end, and the model matrix
at that moment.  The hooks replace the engine's ENTER/LEAVE micro-program ops
and keep the engine's own node stack (and thus ``node_path``) intact.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core import Engine
from ..core.program import ENTER, LEAVE

__all__ = ["NodeTrackingEngine"]


class NodeTrackingEngine(Engine):
    """An engine that calls :meth:`enter_node` / :meth:`leave_node` around every node's contents."""

    def __init__(self, **options: Any) -> None:
        super().__init__(**options)
        ops = self._ops
        if not isinstance(ops, list):  # the core keeps a mutable op table; be tolerant of a tuple
            ops = self._ops = list(ops)
        ops[ENTER] = self._enter_op
        ops[LEAVE] = self._leave_op

    def _enter_op(self, node: Any) -> None:
        self._node_stack.append(node)
        self.enter_node(node, self.model_matrix())

    def _leave_op(self, _arg: Any) -> None:
        node = self._node_stack.pop()
        self.leave_node(node)

    def enter_node(self, node: Any, world: np.ndarray) -> None:
        """Called before a node's contents; ``world`` is the model matrix at that point."""

    def leave_node(self, node: Any) -> None:
        """Called after a node's contents were evaluated and undone."""
