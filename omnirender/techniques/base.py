"""What every non-rendering engine shares: which scene shape is evaluated, and where.

A simplifier's results are evaluated through the same engine, so a hit on a
triangle of a tessellated torus happens several calls below the torus.  The
:class:`AnalysisEngine` remembers the *outermost* shape (the one the scene
holds) and the node path where it sits, so reports name what the user put in
the graph, not intermediate geometry.

A subgraph is analysed *in place* (:func:`evaluate_in_place`): the engine
evaluates the subgraph's root with a *scope* so that only the shapes of the
subgraph are evaluated, while everything before it along the way (transforms,
Billboards, which need the root's camera, clip planes, ``Collidable`` tags,
tessellation levels) applies exactly as in a full traversal.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from ..core.component import RenderingComponent
from ..core.engine import Engine

__all__ = ["AnalysisEngine", "world_matrix_of", "evaluate_in_place", "check_scene", "root_of", "run_analysis"]


class AnalysisEngine(Engine):
    """Base of the engines in :mod:`omnirender.techniques`.

    ``scene_shape`` / ``scene_path`` name the outermost shape being evaluated;
    ``depth`` counts nested evaluations (0 outside any shape).  ``accepts``
    lets subclasses skip whole shapes before any handler (or simplifier) runs.
    ``scope(node)`` restricts the evaluated shapes to ``node``'s subgraph (its
    first-parent occurrence, ``node.path``); ``in_scope`` says whether the
    traversal is inside it (``scope_level`` 1: directly in the node, more:
    below it).
    """

    service = "analysis"

    def __init__(self, *, on_missing: str = "warn", mask: Any = None) -> None:
        super().__init__(on_missing=on_missing, mask=mask)
        self.depth = 0
        self.scene_shape: Any = None
        self.scene_path = ""
        self.scope_node: Any = None
        self.scope_path = ""
        self.scope_level = 0
        self.scope_done = False

    def scope(self, node: Any) -> None:
        """Evaluate only the shapes of ``node``'s subgraph (None: everything)."""
        self.scope_node = node
        self.scope_path = "" if node is None else node.path
        self.scope_level = 0
        self.scope_done = False

    @property
    def in_scope(self) -> bool:
        """Whether shapes met now belong to the analysed subgraph."""
        return self.scope_node is None or self.scope_level > 0

    def on_enter(self, node: Any) -> None:
        if self.scope_level:
            self.scope_level += 1
        elif node is self.scope_node and not self.scope_done and self.node_path == self.scope_path:
            self.scope_level = 1
            self.enter_scope()

    def on_leave(self, node: Any) -> None:
        if self.scope_level:
            self.scope_level -= 1
            if not self.scope_level:
                self.scope_done = True  # the first-parent occurrence only
                self.leave_scope(node)

    def enter_scope(self) -> None:
        """Called when the traversal enters the scope node (its contents not yet evaluated)."""

    def leave_scope(self, node: Any) -> None:
        """Called after the scope node's contents were evaluated and undone."""

    def accepts(self, shape: Any) -> bool:
        """Whether an outermost shape is evaluated at all (default: yes)."""
        return True

    def eval(self, shape: Any) -> None:
        if self.depth == 0:
            if self.scope_node is not None and not self.scope_level:
                return
            if not self.accepts(shape):
                return
            self.scene_shape = shape
            self.scene_path = self.node_path
        self.depth += 1
        try:
            self.technique.handle_shape(shape, self)
        finally:
            self.depth -= 1


def root_of(node: Any) -> Any:
    """The root reached through first parents (``node`` itself for a root)."""
    while node.parent is not None:
        node = node.parent
    return node


class _MatrixProbe(AnalysisEngine):
    """Records the model matrix where the scope node starts; evaluates no shape."""

    def __init__(self) -> None:
        super().__init__(on_missing="skip")
        self.matrix: np.ndarray | None = None

    def enter_scope(self) -> None:
        self.matrix = np.array(self.model_matrix())

    def eval(self, shape: Any) -> None:
        return None


def world_matrix_of(node: Any) -> np.ndarray:
    """The model matrix in effect where ``node`` starts (its first-parent occurrence).

    Evaluated through an engine from the root, so every transform before the
    node applies, including viewpoint-dependent ones (a ``Billboard`` turns
    towards the root's camera, as it does when rendered).
    """
    root = root_of(node)
    if root is node:
        return np.eye(4)
    probe = _MatrixProbe()
    probe.scope(node)
    probe.run(root)
    return np.eye(4) if probe.matrix is None else probe.matrix


def evaluate_in_place(engine: AnalysisEngine, node: Any, mask: Any = None) -> None:
    """Evaluate ``node``'s subgraph as it sits in its graph, under everything before it from the root.

    The engine runs over the root with ``node`` as its scope (lights and the
    camera are pre-evaluated from the root); a root is its own scope.
    """
    engine.scope(node)
    try:
        engine.run(root_of(node), mask=mask)
    finally:
        engine.scope(None)


def check_scene(function: str, scene: Any, argument: str = "scene") -> Any:
    """``scene`` itself when it is a Node, else its items as a list of components; TypeError otherwise."""
    if hasattr(scene, "_compile_node"):
        return scene
    fix = f"pass an om.Node (e.g. om.Node('scene', [...])) or a list of shapes and attributes as {argument}"
    if isinstance(scene, (str, bytes)) or not isinstance(scene, Iterable):
        raise TypeError(
            f"{function}: {argument} must be an om.Node or an iterable of components, "
            f"got {type(scene).__name__} {scene!r:.60}; {fix}"
        )
    items = list(scene)
    for i, item in enumerate(items):
        if not isinstance(item, RenderingComponent) and not hasattr(item, "_compile_node"):
            raise TypeError(
                f"{function}: {argument}[{i}] is a {type(item).__name__} ({item!r:.60}), not a component; {fix}"
            )
    return items


def run_analysis(engine: AnalysisEngine, function: str, scene: Any, mask: Any = None) -> None:
    """Validate ``scene`` and evaluate it with ``engine``: a node in place, a component list as given."""
    checked = check_scene(function, scene)
    if hasattr(checked, "_compile_node"):
        evaluate_in_place(engine, checked, mask)
    else:
        engine.evaluate(checked)
