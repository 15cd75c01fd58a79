"""The render index: the installed draw list and the lists derived from it, kept up to date by change kind.

The GL engine compiles a scene into draw items grouped into batches (see
:mod:`.drawlist`); frames read lists derived from them: every item, the
mirrors, the scene's bounds, the shadow casters' bounds.  The index computes
each at most once per change that can alter it (OpenUSD Hydra's render index
keeps its prims' derived data the same way):

* a new structure (a compile installed, rows replaced in place): everything
  is derived again, once, when first asked;
* moved rows (transforms, instance arrays): only what depends on where items
  are — the bounds; which items are mirrors or cast shadows does not change,
  and mirror planes are read from the rows each frame.

Bounds are computed per batch from its rows (one vectorised product per
geometry), never by visiting the items one by one.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .drawlist import DrawItem, Scope, Segment
from .layout import ROW
from .state import casts_shadows, not_mirror

__all__ = ["RenderIndex", "rows_bounds"]

_MODEL = ROW.slice("model")


class RenderIndex:
    """The installed root scope with its derived lists; ``install`` on a new structure, ``moved`` on moves."""

    __slots__ = ("root", "version", "_items", "_mirrors", "_bounds", "_casters", "_boxes", "_find_mirrors")

    def __init__(self, find_mirrors: Callable[[list[DrawItem]], list[tuple[Any, Any]]]) -> None:
        #: the mirror technique's rule: (item, pass predicate) pairs of the mirrors among the items
        self._find_mirrors = find_mirrors
        self.root: Scope | None = None
        #: bumped by every install (per-frame caches of techniques key on it)
        self.version = 0
        self._items: list[DrawItem] | None = None
        self._mirrors: list[tuple[Any, Any]] | None = None
        self._bounds: tuple[tuple[np.ndarray, np.ndarray] | None] | None = None
        self._casters: tuple[tuple[np.ndarray, np.ndarray] | None] | None = None
        #: id(batch) -> (batch, lo, hi): each row's world box, kept up to date row by row
        self._boxes: dict[int, tuple[Any, np.ndarray, np.ndarray]] = {}

    def install(self, root: Scope | None) -> None:
        """``root`` is the draw list now (a new structure or rows replaced): every derived list is stale."""
        self.root = root
        self.version += 1
        self._items = self._mirrors = None
        self._bounds = self._casters = None
        self._boxes = {}

    def moved(self, rows: list[tuple[Any, np.ndarray | None]] | None) -> None:
        """Rows moved in place: ``(batch, row indices or None for all)`` pairs, or None (any row anywhere).

        The bounds are stale; the lists of items, mirrors and casters are not.
        The rows' boxes are made again, the others kept.
        """
        self._bounds = self._casters = None
        if rows is None:
            self._boxes = {}
            return
        boxes = self._boxes
        for batch, where in rows:
            found = boxes.get(id(batch))
            if found is None:
                continue
            if where is None or found[0] is not batch or len(found[1]) != len(batch.rows):
                del boxes[id(batch)]
                continue
            lo, hi = row_boxes(batch.geometry, batch.rows[where])
            found[1][where] = lo
            found[2][where] = hi

    def batch_edits(self, batch: Any, edits: list[tuple[Any, ...]]) -> None:
        """Rows of ``batch`` were removed (the last row moved into the hole) or appended: the boxes follow."""
        found = self._boxes.get(id(batch))
        if found is None:
            return
        _, lo, hi = found
        for op, index, _ in edits:
            if op == "remove":
                lo[index], hi[index] = lo[len(lo) - 1], hi[len(hi) - 1]
                lo, hi = lo[:-1], hi[:-1]
            else:
                a, b = row_boxes(batch.geometry, batch.rows[index : index + 1])
                lo, hi = np.concatenate([lo, a]), np.concatenate([hi, b])
        if len(lo) == len(batch.rows):
            self._boxes[id(batch)] = (batch, lo, hi)
        else:
            del self._boxes[id(batch)]

    def spliced(self, removed: list[DrawItem], added: list[DrawItem]) -> None:
        """Items left and came without a new plan: the item list follows, mirrors only when one is among them.

        The batches' row edits reach the boxes through :meth:`batch_edits`.
        """
        self.version += 1
        if self._items is not None:
            for item in removed:
                self._items.remove(item)  # identity first: a scan in C
            self._items.extend(added)
        if any(not not_mirror(it) for it in (*removed, *added)):
            self._mirrors = None
        self._bounds = self._casters = None

    def items(self) -> list[DrawItem]:
        """Every item of the draw list, nested scopes included, in compile order (computed once per structure)."""
        if self._items is None:
            self._items = [] if self.root is None else self.root.all_items()
        return self._items

    def mirror_items(self) -> list[tuple[Any, Any]]:
        """The mirrors' items with their pass predicates (the rule the index was given), once per structure."""
        if self._mirrors is None:
            self._mirrors = self._find_mirrors(self.items()) if self.root is not None else []
        return self._mirrors

    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """World (min, max) of everything but overlays, or None when nothing is drawn."""
        if self._bounds is None:
            self._bounds = (self._compute(lambda item: not item.state.overlay),)
        return self._bounds[0]

    def caster_bounds(self) -> tuple[tuple[np.ndarray, np.ndarray] | None]:
        """``(bounds,)`` of the opaque shadow casters; a new tuple after every move (shadow maps compare it)."""
        if self._casters is None:
            self._casters = (self._compute(lambda item: not item.transparent and casts_shadows(item)),)
        return self._casters

    def _compute(self, keep: Any) -> tuple[np.ndarray, np.ndarray] | None:
        parts: dict[int, tuple[Any, list[np.ndarray]]] = {}

        def add(geometry: Any, rows: np.ndarray) -> None:
            entry = parts.get(id(geometry))
            if entry is None:
                entry = parts[id(geometry)] = (geometry, [])
            entry[1].append(rows)

        if self.root is None:
            return None
        boxes: list[tuple[np.ndarray, np.ndarray]] = []
        for scope in self.root.walk():
            if scope.parts is None:  # not planned (not installed): item by item
                for item in scope.items():
                    if keep(item):
                        add(item.geometry, item.rows())
                continue
            for part in scope.parts:
                if not isinstance(part, Segment):
                    continue
                for batch in part.batches:  # a batch's items share geometry and state: one test each
                    if batch.items and len(batch.rows) and keep(batch.items[0]):
                        boxes.append(self._batch_boxes(batch))
                for item in part.others:
                    if keep(item):
                        add(item.geometry, item.rows())
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for a, b in boxes:
            lo = np.minimum(lo, a.min(axis=0))
            hi = np.maximum(hi, b.max(axis=0))
        for geometry, rows in parts.values():
            found = rows_bounds(geometry, rows[0] if len(rows) == 1 else np.concatenate(rows))
            if found is not None:
                lo = np.minimum(lo, found[0])
                hi = np.maximum(hi, found[1])
        if not np.all(np.isfinite(lo)):
            return None
        return lo, hi

    def _batch_boxes(self, batch: Any) -> tuple[np.ndarray, np.ndarray]:
        found = self._boxes.get(id(batch))
        if found is None or found[0] is not batch or len(found[1]) != len(batch.rows):
            lo, hi = row_boxes(batch.geometry, batch.rows)
            found = self._boxes[id(batch)] = (batch, lo, hi)
        return found[1], found[2]


def row_boxes(geometry: Any, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each row's world box of ``geometry``: ``(lo, hi)``, both (N, 3) (``|M| e`` about the transformed centre)."""
    b0, b1 = (np.asarray(b, dtype=np.float64) for b in geometry.bounds)
    models = rows[:, _MODEL].reshape(-1, 4, 4).astype(np.float64)  # each row holds M transposed
    linear = models[:, :3, :3]  # (M^T)[:3, :3]: row j holds column j of M
    center = (b0 + b1) / 2.0 @ linear + models[:, 3, :3]
    half = (b1 - b0) / 2.0 @ np.abs(linear)
    return center - half, center + half


def rows_bounds(geometry: Any, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """World (min, max) of ``geometry`` placed by each of ``rows`` (instance rows), or None for no rows.

    Each box is transformed at once by its centre and half extent (``|M| e``).
    """
    if not len(rows):
        return None
    b0, b1 = (np.asarray(b, dtype=np.float64) for b in geometry.bounds)
    models = rows[:, _MODEL].reshape(-1, 4, 4).astype(np.float64)  # each row holds M transposed
    linear = models[:, :3, :3]  # (M^T)[:3, :3]: row j holds column j of M
    center = (b0 + b1) / 2.0 @ linear + models[:, 3, :3]
    half = (b1 - b0) / 2.0 @ np.abs(linear)
    return (center - half).min(axis=0), (center + half).max(axis=0)
