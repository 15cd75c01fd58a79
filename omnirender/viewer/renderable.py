"""Renderables: what a viewer draws (ArtiSynth's ``IsRenderable``).

A renderable is prerendered once per *rerender* (it caches the state it will
draw, and may file sub-renderables into the render list) and rendered on every
*repaint* by sending components to the renderer, which is the engine itself:
``renderer.push(...)``, ``renderer.eval(shape)``, ``renderer.pop(...)``.
``render_hints()`` tells the viewer which sublist it belongs to.

Scene-graph nodes become renderables through :class:`NodeRenderable`, which the
viewer applies automatically when a Node is added.
"""

from __future__ import annotations

import weakref
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = [
    "IsRenderable",
    "TRANSPARENT",
    "TWO_DIMENSIONAL",
    "HIGHLIGHT",
    "NodeRenderable",
    "as_renderable",
    "node_render_hints",
    "node_bounds",
    "node_prerender",
    "node_render",
    "node_update_bounds",
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
    """Adapter making an :class:`om.Node` renderable.

    ``render`` evaluates the node with the renderer (so its lights and
    attributes apply as in ``om.render``); ``HIGHLIGHT`` pushes a
    ``Highlight`` attribute around it.  Bounds come from ``om.bounds`` and are
    cached per node version, like the render hints.  Mutate a node drawn by a
    viewer from another thread only while holding the render list's lock.
    """

    __slots__ = ("node", "_hints", "_hints_version", "_bounds", "_bounds_version", "visible", "z_order")

    def __init__(self, node: Any) -> None:
        self.node = node
        self._hints = 0
        self._hints_version = -1
        self._bounds: tuple[np.ndarray, np.ndarray] | None = None
        self._bounds_version = -1
        self.visible = True
        self.z_order = 0

    def prerender(self, render_list: Any) -> None:
        # Nodes keep their compiled program per version; nothing else to cache.
        self.node.program()

    def render(self, renderer: Any, flags: int = 0) -> None:
        highlight = None
        if flags & HIGHLIGHT:
            highlight = _highlight_attribute()
            if highlight is not None:
                renderer.push(highlight)
        try:
            renderer.evaluate(self.node)
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
        if self._hints_version != self.node.version:
            self._hints = node_render_hints(self.node)
            self._hints_version = self.node.version
        return self._hints

    def __repr__(self) -> str:
        return f"NodeRenderable({self.node.path})"


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


# -- the IsRenderable methods of om.Node delegate to these -----------------------------------
_node_cache: weakref.WeakKeyDictionary[Any, NodeRenderable] = weakref.WeakKeyDictionary()


def _adapter(node: Any) -> NodeRenderable:
    adapter = _node_cache.get(node)
    if adapter is None:
        adapter = _node_cache[node] = NodeRenderable(node)
    return adapter


def node_prerender(node: Any, render_list: Any) -> None:
    """``Node.prerender``: what :meth:`NodeRenderable.prerender` does."""
    _adapter(node).prerender(render_list)


def node_render(node: Any, renderer: Any, flags: int = 0) -> None:
    """``Node.render``: evaluate the node with ``renderer`` (highlighted with the HIGHLIGHT flag)."""
    _adapter(node).render(renderer, flags)


def node_update_bounds(node: Any, pmin: np.ndarray, pmax: np.ndarray) -> None:
    """``Node.update_bounds``: grow ``pmin``/``pmax`` by the node's world box (cached per version)."""
    _adapter(node).update_bounds(pmin, pmax)


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
