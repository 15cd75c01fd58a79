"""Renderables: what a viewer draws (ArtiSynth's ``IsRenderable``).

A renderable is prerendered once per *rerender* (it caches the state it will
draw, and may file sub-renderables into the render list) and rendered on every
*repaint* by sending components to the renderer, which is the engine itself:
``renderer.push(...)``, ``renderer.eval(shape)``, ``renderer.pop(...)``.
``render_hints()`` tells the viewer which sublist it belongs to.

Scene-graph nodes become renderables through :class:`NodeRenderable`, which
viewers and render lists apply automatically when a Node is added
(:func:`renderable_of`): the scene graph itself knows nothing of viewers.
"""

from __future__ import annotations

import weakref
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..core.engine import Engine
from ..core.program import ADD, DEINSTALL, ENTER, EVAL, INSTALL, LEAVE, NODE, POP, PUSH, REMOVE, TECHNIQUE

__all__ = [
    "IsRenderable",
    "TRANSPARENT",
    "TWO_DIMENSIONAL",
    "HIGHLIGHT",
    "NodeRenderable",
    "NodePart",
    "split_program",
    "as_renderable",
    "renderable_of",
    "replays",
    "node_render_hints",
    "node_bounds",
]

#: Hint/flag: drawn after opaque renderables, back to front, with blending.
TRANSPARENT = 1
#: Hint/flag: drawn after every 3D renderable with the depth test off (overlays, text).
TWO_DIMENSIONAL = 2
#: Flag passed to ``render``: draw highlighted (selection).
HIGHLIGHT = 4


@runtime_checkable
class IsRenderable(Protocol):
    """The protocol a viewer needs from anything it draws."""

    def prerender(self, render_list: Any) -> None:
        """Cache the state to draw (called under the render list's lock); may add sub-renderables."""

    def render(self, renderer: Any, flags: int) -> None:
        """Send components to ``renderer`` (an engine) from the cached state."""

    def update_bounds(self, pmin: np.ndarray, pmax: np.ndarray) -> None:
        """Grow the world-space box ``pmin``/``pmax`` (float64 arrays, updated in place)."""

    def render_hints(self) -> int:
        """``TRANSPARENT`` and/or ``TWO_DIMENSIONAL`` bits, or 0."""


class NodeRenderable:
    """Adapter making an :class:`om.Node` renderable, double-buffered like any renderable.

    ``prerender`` takes a snapshot of the node: its compiled program (a list the
    node replaces, never mutates, when it changes) with the matrices of the
    core transforms (``Translation``, ``Rotation``, ``Scaling``, ``Matrix``)
    copied, so moving or replacing a transform shows only after the next
    prerender.  Other component objects are shared with the scene: changing
    one of *their* parameters in place (a colour, a radius) is visible at the
    next repaint that traverses again.  ``render`` draws the snapshot.

    The snapshot is split by render hints, shape by shape: shapes that are 2D
    (``Text``) or translucent (under a translucent ``Material``/``Color``) go
    into sub-renderables (:class:`NodePart`) filed in their own sublists, each
    replaying the node's whole attribute structure (scoped attributes and
    transforms above the shape still apply) but evaluating only its shapes.  The
    adapter itself draws the first non-empty kind (normally the opaque 3D shapes).

    ``HIGHLIGHT`` pushes a ``Highlight`` attribute around it.  Bounds come from
    ``om.bounds`` and are cached per node version.  Mutate a node drawn by a
    viewer from another thread only while holding the render list's lock.
    """

    __slots__ = ("node", "_hints", "_hints_version", "_bounds", "_bounds_version", "visible", "z_order", "_snapshot")

    def __init__(self, node: Any) -> None:
        self.node = node
        self._hints = 0
        self._hints_version = -1
        self._bounds: tuple[np.ndarray, np.ndarray] | None = None
        self._bounds_version = -1
        self.visible = True
        self.z_order = 0
        self._snapshot: _Snapshot | None = None

    def prerender(self, render_list: Any) -> None:
        parts, used = split_program(self.node.program())
        kinds = sorted(used) or [0]
        main = kinds[0]
        groups = self.node.groups
        self._snapshot = _Snapshot(groups, parts[main])
        self._hints = main
        self._hints_version = None  # type: ignore[assignment]  # fixed until the next prerender
        for kind in kinds[1:]:
            part = NodePart(self, kind, _Snapshot(groups, parts[kind]))
            if render_list is not None:
                render_list.add_if_visible(part)

    def render(self, renderer: Any, flags: int = 0) -> None:
        highlight = None
        if flags & HIGHLIGHT:
            highlight = _highlight_attribute()
            if highlight is not None:
                renderer.push(highlight)
        try:
            _draw(renderer, self._snapshot, self.node)
        finally:
            if highlight is not None:
                renderer.pop(highlight.category)

    def update_bounds(self, pmin: np.ndarray, pmax: np.ndarray) -> None:
        if self._bounds_version != self.node.version:
            self._bounds = node_bounds(self.node)
            self._bounds_version = self.node.version
        if self._bounds is not None:
            np.minimum(pmin, self._bounds[0], out=pmin)
            np.maximum(pmax, self._bounds[1], out=pmax)

    def render_hints(self) -> int:
        """The kind of what this adapter draws (fixed by prerender; before it: from the node's shapes)."""
        if self._hints_version is not None and self._hints_version != self.node.version:
            kinds = sorted(split_program(self.node.program())[1]) or [0]
            self._hints = kinds[0]
            self._hints_version = self.node.version
        return self._hints

    def __repr__(self) -> str:
        return f"NodeRenderable({self.node.path})"


class NodePart:
    """The 2D and/or translucent shapes of a prerendered node, filed in their own sublist.

    ``owner`` is the node's :class:`NodeRenderable` (a highlighted owner
    highlights its parts too; a hidden owner's parts are hidden too).
    """

    __slots__ = ("owner", "hints", "visible", "z_order", "_snapshot")

    def __init__(self, owner: NodeRenderable, hints: int, snapshot: _Snapshot) -> None:
        self.owner = owner
        self.hints = hints
        self.visible = owner.visible  # the node's own shapes: hidden with it
        self.z_order = owner.z_order
        self._snapshot = snapshot

    @property
    def node(self) -> Any:
        return self.owner.node

    def prerender(self, render_list: Any) -> None:
        pass  # made by the owner's prerender

    def render(self, renderer: Any, flags: int = 0) -> None:
        highlight = _highlight_attribute() if flags & HIGHLIGHT else None
        if highlight is not None:
            renderer.push(highlight)
        try:
            _draw(renderer, self._snapshot, None)
        finally:
            if highlight is not None:
                renderer.pop(highlight.category)

    def update_bounds(self, pmin: np.ndarray, pmax: np.ndarray) -> None:
        pass  # the owner's bounds cover the whole node

    def render_hints(self) -> int:
        return self.hints

    def __repr__(self) -> str:
        return f"NodePart({self.owner.node.path}, hints={self.hints})"


class _Snapshot:
    """A frozen program with the groups of its node: what ``engine.run`` needs inside a traversal."""

    __slots__ = ("groups", "_program")

    def __init__(self, groups: frozenset[str], program: list[tuple[int, Any]]) -> None:
        self.groups = groups
        self._program = program

    def program(self) -> list[tuple[int, Any]]:
        return self._program


def _draw(renderer: Any, snapshot: _Snapshot | None, node: Any) -> None:
    """Run ``snapshot`` inside the renderer's traversal (a viewer frame); outside one, evaluate ``node``."""
    if snapshot is None or not getattr(renderer, "running", False):
        if node is not None:
            renderer.evaluate(node)  # not prerendered, or drawn on its own: the live node with its lights
        elif snapshot is not None:
            renderer.run_program(snapshot.program())
        return
    renderer.run(snapshot)


def _snapshot_transform(attribute: Any, memo: dict[int, Any]) -> Any:
    """A ``Matrix`` with the current matrix of a core transform (same object for its push and pop)."""
    from ..core.transform import Matrix, Rotation, Scaling, Translation

    if type(attribute) not in (Translation, Rotation, Scaling, Matrix):
        return attribute  # engine-dependent transforms (Billboard, LookAt) stay live
    frozen = memo.get(id(attribute))
    if frozen is None:
        frozen = memo[id(attribute)] = Matrix(np.array(attribute.matrix, dtype=np.float64))
    return frozen


class _Splitter(Engine):
    """Runs a compiled program through the core interpreter and files its ops by render hints.

    Attributes are only recorded and kept on the context's stacks (never
    applied: a ``Billboard`` must stay live for the engine that draws the
    snapshot), so translucency is known where each shape is met.  Every op
    goes to all four programs except a shape's, which goes to its kind.
    """

    service = "viewer.split"

    def __init__(self) -> None:
        super().__init__(on_missing="skip")
        self._outputs: list[dict[int, list[tuple[int, Any]]]] = [{k: [] for k in range(4)}]
        self.used: set[int] = set()
        self._memo: dict[int, Any] = {}

    def _all(self, op: tuple[int, Any]) -> None:
        for program in self._outputs[-1].values():
            program.append(op)

    def _nested(self, program: list[tuple[int, Any]]) -> dict[int, list[tuple[int, Any]]]:
        self._outputs.append({k: [] for k in range(4)})
        try:
            self.run_program(program)
        finally:
            nested = self._outputs.pop()
        return nested

    # -- the ops, recorded --------------------------------------------------------------
    def on_enter(self, node: Any) -> None:
        self._all((ENTER, node))

    def on_leave(self, node: Any) -> None:
        self._all((LEAVE, -1))

    def push(self, attribute: Any) -> None:
        self.context.mono_stack(attribute.category).append(attribute)
        self._all((PUSH, _snapshot_transform(attribute, self._memo)))

    def pop(self, category: type) -> Any:
        attribute = self.context.mono_stack(category).pop()
        self._all((POP, _snapshot_transform(attribute, self._memo)))
        return attribute

    def add(self, attribute: Any) -> None:
        self.context.poly_set(attribute.category).append(attribute)
        self._all((ADD, attribute))

    def remove(self, attribute: Any) -> None:
        items = self.context.poly_set(attribute.category)
        for i in range(len(items) - 1, -1, -1):
            if items[i] is attribute:
                del items[i]
                break
        self._all((REMOVE, attribute))

    def install(self, handler: Any) -> None:
        self._all((INSTALL, handler))

    def deinstall(self, handler: Any) -> None:
        self._all((DEINSTALL, handler))

    def eval(self, shape: Any) -> None:
        tags = getattr(shape, "hints", ()) or ()
        kind = TWO_DIMENSIONAL if "2d" in tags else 0
        if "transparent" in tags or self._translucent_state():
            kind |= TRANSPARENT
        self.used.add(kind)
        self._outputs[-1][kind].append((EVAL, shape))

    def _translucent_state(self) -> bool:
        ctx = self.context
        for category in ctx.categories():
            stack = ctx.mono_stack(category)  # the attributes themselves (ctx.mono gives a matrix for transforms)
            if (stack and _translucent(stack[-1])) or any(_translucent(p) for p in ctx.poly(category)):
                return True
        return False

    def eval_node(self, node: Any) -> None:
        nested = self._nested(node.program())
        for k, program in self._outputs[-1].items():
            program.append((NODE, _Snapshot(node.groups, nested[k])))

    def run_technique(self, technique: Any, program: list[tuple[int, Any]]) -> None:
        nested = self._nested(program)
        for k, out in self._outputs[-1].items():
            out.append((TECHNIQUE, (technique, nested[k])))


def split_program(program: list[tuple[int, Any]]) -> tuple[dict[int, list[tuple[int, Any]]], set[int]]:
    """Split a compiled node program by the render hints of its shapes.

    Returns ``({hints: program} for hints 0..3, hints present)``, hints being 0,
    TRANSPARENT, TWO_DIMENSIONAL or both: every program keeps all the attribute,
    handler and node ops (with core transforms frozen into matrices) and only
    the shapes of its kind.  The program runs through the core interpreter
    (:class:`_Splitter`), so scoping, nodes and techniques mean what they mean
    for every engine.
    """
    splitter = _Splitter()
    splitter.run_program(program)
    return splitter._outputs[0], splitter.used


def replays(renderable: Any) -> bool:
    """Whether a viewer may replay what ``renderable`` drew last time instead of calling its ``render``.

    Only node renderables (whose ``render`` draws the snapshot of their last
    prerender); every other renderable's ``render`` runs on every repaint.
    """
    return type(renderable) in (NodeRenderable, NodePart)


def as_renderable(obj: Any) -> Any:
    """``obj`` itself if it is renderable, a :class:`NodeRenderable` for a Node, else TypeError."""
    from ..scene.node import Node

    if isinstance(obj, Node):
        return NodeRenderable(obj)
    if isinstance(obj, IsRenderable):
        return obj
    missing = [m for m in ("prerender", "render", "update_bounds", "render_hints") if not hasattr(obj, m)]
    raise TypeError(
        f"{type(obj).__name__} is not renderable: it lacks {', '.join(missing)}; implement the "
        f"om.IsRenderable protocol or add an om.Node"
    )


# -- nodes given to render lists directly -----------------------------------------------------
_node_cache: weakref.WeakKeyDictionary[Any, NodeRenderable] = weakref.WeakKeyDictionary()


def renderable_of(obj: Any) -> Any:
    """What a render list files for ``obj``: one lasting :class:`NodeRenderable` per Node, else ``obj``."""
    from ..scene.node import Node

    if not isinstance(obj, Node):
        return obj
    adapter = _node_cache.get(obj)
    if adapter is None:
        adapter = _node_cache[obj] = NodeRenderable(obj)
    return adapter


def node_render_hints(node: Any) -> int:
    """TRANSPARENT if anything below ``node`` is translucent, TWO_DIMENSIONAL if a shape is 2D."""
    hints = 0
    for n in node.walk():
        for c in n.components:
            tags = getattr(c, "hints", ())
            if "2d" in tags:
                hints |= TWO_DIMENSIONAL
            if "transparent" in tags or _translucent(c):
                hints |= TRANSPARENT
    return hints


def _translucent(component: Any) -> bool:
    opacity = getattr(component, "opacity", None)
    if isinstance(opacity, (int, float)) and opacity < 1.0:
        return True
    alpha = getattr(component, "a", None) if type(component).__name__ == "Color" else None
    return isinstance(alpha, (int, float)) and alpha < 1.0


def node_bounds(node: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """World-space (min, max) of ``node`` via ``om.bounds``; None when empty or unavailable."""
    try:
        from ..techniques import bounds
    except ImportError:
        return None
    try:
        box = bounds(node)
    except Exception:
        return None
    if box is None:
        return None
    lo, hi = (np.asarray(v, dtype=np.float64) for v in box)
    if lo.shape != (3,) or not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        return None
    return lo, hi


def _highlight_attribute() -> Any:
    try:
        from ..attributes import Highlight
    except ImportError:
        return None
    return Highlight()
