"""Render lists: the prerendered, sorted list a viewer repaints from.

``prerender(renderables)`` runs each renderable's ``prerender`` — visible or
not, as ArtiSynth does, so that a hidden renderable can still add visible
sub-renderables — and files the visible ones into four sublists (opaque, transparent, 2D opaque, 2D
transparent), each sorted by ``z_order`` (stable, so insertion order breaks ties).
Prerender and repaint both hold the list's lock: renderables cache what they
will draw in ``prerender`` (like a back buffer that becomes the front one), so
a simulation thread can prerender while several viewers repaint the same list
without ever seeing half-updated state.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, Iterator
from typing import Any

from .renderable import TRANSPARENT, TWO_DIMENSIONAL, renderable_of

__all__ = ["RenderList", "PASSES"]

#: Sublist names in drawing order.
PASSES = ("opaque", "transparent", "opaque_2d", "transparent_2d")


class RenderList:
    """Sorted sublists of renderables plus the lock that guards their cached state."""

    def __init__(self) -> None:
        self.lock = threading.RLock()
        self.opaque: list[Any] = []
        self.transparent: list[Any] = []
        self.opaque_2d: list[Any] = []
        self.transparent_2d: list[Any] = []
        self._building: dict[str, list[Any]] | None = None
        #: Incremented by every completed prerender (viewers use it to see news).
        self.generation = 0

    def prerender(self, renderables: Iterable[Any]) -> None:
        """Rebuild the sublists from ``renderables`` (prerendering each) under the lock."""
        with self.lock:
            building = {name: [] for name in PASSES}
            previous, self._building = self._building, building
            try:
                for r in renderables:
                    self.add_if_visible(r)
            finally:
                self._building = previous
            for name, items in building.items():
                items.sort(key=_z_order)
                setattr(self, name, items)
            self.generation += 1

    def add_if_visible(self, renderable: Any) -> bool:
        """Prerender ``renderable``, then file it by its hints if visible; returns whether it was added.

        ``prerender`` runs whether or not the renderable is visible (ArtiSynth's
        ``RenderList.addIfVisible``): an invisible parent still gets to add its
        visible sub-renderables.  Call it from a renderable's ``prerender`` to
        add sub-renderables.  An ``om.Node`` is filed as its
        :class:`~omnirender.viewer.NodeRenderable`.
        """
        renderable = renderable_of(renderable)
        renderable.prerender(self)
        if not getattr(renderable, "visible", True):
            return False
        hints = int(renderable.render_hints() or 0)
        name = PASSES[(1 if hints & TRANSPARENT else 0) + (2 if hints & TWO_DIMENSIONAL else 0)]
        target = self._building[name] if self._building is not None else getattr(self, name)
        target.append(renderable)
        return True

    def clear(self) -> None:
        with self.lock:
            for name in PASSES:
                setattr(self, name, [])
            self.generation += 1

    def sublist(self, name: str) -> list[Any]:
        """The sublist called ``name`` (one of :data:`PASSES`)."""
        if name not in PASSES:
            raise ValueError(f"RenderList: unknown sublist {name!r}; use one of {PASSES}")
        return getattr(self, name)

    def __iter__(self) -> Iterator[Any]:
        """Every renderable in drawing order."""
        for name in PASSES:
            yield from getattr(self, name)

    def __len__(self) -> int:
        return sum(len(getattr(self, name)) for name in PASSES)

    def __repr__(self) -> str:
        sizes = ", ".join(f"{name}={len(getattr(self, name))}" for name in PASSES)
        return f"RenderList({sizes})"


def _z_order(renderable: Any) -> int:
    return getattr(renderable, "z_order", 0)
