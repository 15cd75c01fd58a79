"""What every non-rendering engine shares: knowing which scene shape is being evaluated.

A simplifier's results are evaluated through the same engine, so a hit on a
triangle of a tessellated torus happens several calls below the torus.  The
:class:`AnalysisEngine` remembers the *outermost* shape (the one the scene
holds) and the node path where it sits, so reports name what the user put in
the graph, not intermediate geometry.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.engine import Engine
from ..core.transform import Matrix, Transform

__all__ = ["AnalysisEngine", "world_matrix_of", "evaluate_in_place"]


class AnalysisEngine(Engine):
    """Base of the engines in :mod:`omnirender.techniques`.

    ``scene_shape`` / ``scene_path`` name the outermost shape being evaluated;
    ``depth`` counts nested evaluations (0 outside any shape).  ``accepts``
    lets subclasses skip whole shapes before any handler (or simplifier) runs.
    """

    service = "analysis"

    def __init__(self, *, on_missing: str = "warn", mask: Any = None) -> None:
        super().__init__(on_missing=on_missing, mask=mask)
        self.depth = 0
        self.scene_shape: Any = None
        self.scene_path = ""

    def accepts(self, shape: Any) -> bool:
        """Whether an outermost shape is evaluated at all (default: yes)."""
        return True

    def eval(self, shape: Any) -> None:
        if self.depth == 0:
            if not self.accepts(shape):
                return
            self.scene_shape = shape
            self.scene_path = self.node_path
        self.depth += 1
        try:
            self._technique.handle_shape(shape, self)
        finally:
            self.depth -= 1


def world_matrix_of(node: Any) -> np.ndarray:
    """The model matrix in effect where ``node`` starts: transforms before it along its first-parent chain."""
    chain = []
    current = node
    while current.parent is not None:
        chain.append((current.parent, current))
        current = current.parent
    m = np.eye(4)
    for parent, child in reversed(chain):
        for item in parent:
            if item is child:
                break
            if isinstance(item, Transform):
                m = m @ item.matrix
    return m


def evaluate_in_place(engine: Engine, node: Any, mask: Any = None) -> None:
    """Evaluate ``node`` as it sits in its graph: under the transforms of its first-parent chain."""
    m = world_matrix_of(node)
    if np.array_equal(m, np.eye(4)):
        engine.run(node, mask=mask)
        return
    engine.push(Matrix(m))
    engine.run(node, mask=mask)  # on error the engine resets itself, dropping the pushed matrix too
    engine.pop(Transform)
