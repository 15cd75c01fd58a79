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

The index also keeps a **caster journal** for the shadow maps: the world
boxes of the shadow casters' rows that moved, left or came since the shadow
stage last read it (:meth:`RenderIndex.take_caster_changes`), each with its
batch and whether it is the old or the new place.  A new structure, moves the
index cannot follow row by row, or more rows than :data:`JOURNAL_ROWS` make
it "everything changed" (None).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .drawlist import DrawItem, Scope, Segment, position_of
from .layout import ROW
from .state import casts_shadows, not_mirror

__all__ = ["RenderIndex", "CasterChange", "rows_bounds", "JOURNAL_ROWS"]

_MODEL = ROW.slice("model")
#: the most caster rows the journal holds between two reads (more: everything changed, the maps are redrawn in full)
JOURNAL_ROWS = 512


class CasterChange:
    """Boxes of a shadow-casting batch's rows that changed: ``lo``, ``hi`` world boxes ((N, 3) arrays, or for a few
    rows lists of [x, y, z] lists: :meth:`lows` and :meth:`highs` give lists either way), ``new`` (False: the
    places the rows left, True: the places they took), ``rows`` their row indices and ``edit``: False for rows
    moved in place; True for a row removed (the last row moved into its place) or appended."""

    __slots__ = ("batch", "lo", "hi", "new", "rows", "edit")

    def __init__(self, batch: Any, lo: Any, hi: Any, new: bool, rows: np.ndarray, edit: bool = False) -> None:
        self.batch, self.lo, self.hi, self.new, self.rows, self.edit = batch, lo, hi, new, rows, edit

    def lows(self) -> list[list[float]]:
        """The boxes' lower corners as lists of floats."""
        lo = self.lo
        return lo if isinstance(lo, list) else lo.tolist()

    def highs(self) -> list[list[float]]:
        """The boxes' upper corners as lists of floats."""
        hi = self.hi
        return hi if isinstance(hi, list) else hi.tolist()


class RenderIndex:
    """The installed root scope with its derived lists; ``install`` on a new structure, ``moved`` on moves."""

    __slots__ = ("root", "version", "_items", "_mirrors", "_bounds", "_casters", "_boxes", "_find_mirrors",
                 "_journal", "_journal_rows", "_extremes")  # fmt: skip

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
        #: with the casters' bounds: per axis, how many batch rows' boxes lie on the lower and on the upper bound
        #: (a row leaving the bounds shrinks them only when it was the last there); None: not counted
        self._extremes: tuple[list[int], list[int]] | None = None
        #: id(batch) -> (batch, lo, hi, extremes): each row's world box, kept up to date row by row, and while
        #: the boxes are as made, per axis their least and greatest value with the rows on them (else None)
        self._boxes: dict[int, tuple[Any, np.ndarray, np.ndarray, Any]] = {}
        #: the casters' changed boxes since the shadow stage last read them; None: everything changed
        self._journal: list[CasterChange] | None = None
        self._journal_rows = 0

    def install(self, root: Scope | None) -> None:
        """``root`` is the draw list now (a new structure or rows replaced): every derived list is stale."""
        self.root = root
        self.version += 1
        self._items = self._mirrors = None
        self._bounds = self._casters = None
        self._boxes = {}
        self._journal = None

    def moved(self, rows: list[tuple[Any, np.ndarray | None]] | None) -> None:
        """Rows moved in place: ``(batch, row indices, a slice of them or None for all)`` pairs, or None (any row
        anywhere).

        The bounds are stale; the lists of items, mirrors and casters are not.
        The rows' boxes are made again, the others kept.
        """
        self._bounds = None  # transparent items' moves are not among the rows: the scene's bounds again
        if rows is None:
            self._boxes = {}
            self._journal = self._casters = None
            return
        boxes = self._boxes
        for batch, where in rows:
            found = boxes.get(id(batch))
            caster = casts_shadows(batch)  # a batch's items share geometry and state: the batch decides
            count = len(range(*where.indices(len(batch.rows)))) if isinstance(where, slice) else None
            if caster and where is not None and (len(where) if count is None else count) > JOURNAL_ROWS:
                self._journal = self._casters = None  # many moved: the maps in full
            if found is None or where is None or found[0] is not batch or len(found[1]) != len(batch.rows):
                if found is not None:
                    del boxes[id(batch)]
                if caster:
                    self._journal = self._casters = None  # the old places are not known
                continue
            follow = caster and (self._casters is not None or self._journal is not None)
            if follow and count is None and len(where) <= _FEW_ROWS:
                self._moved_few(batch, found, where)  # what a frame moves: Python floats, few numpy calls
                continue
            if not follow and 2 * (len(where) if count is None else count) > len(batch.rows):
                # most rows moved and no old place is needed: every row's box, read from the rows as they lie
                # (no gather of the moved rows and scatter of their boxes; the others' come out the same)
                boxes[id(batch)] = _kept_boxes(batch)
                continue
            # a run of rows (a bound array's) stays a slice: views and block copies, not gathers of every row
            lo, hi = row_boxes(batch.geometry, batch.rows[where])
            if follow:
                if count is not None:
                    where = np.arange(len(batch.rows))[where]  # the journal's row indices
                old = (found[1][where], found[2][where])  # copies (fancy index)
                self._follow_casters(old, (lo, hi))
                if self._room(len(lo)):
                    self._note(CasterChange(batch, *old, False, where))
                    self._note(CasterChange(batch, lo, hi, True, where))
            found[1][where] = lo
            found[2][where] = hi
            if found[3] is not None:
                boxes[id(batch)] = (batch, found[1], found[2], None)  # (their extremes are not known now)

    def _moved_few(self, batch: Any, found: tuple[Any, np.ndarray, np.ndarray, Any], where: np.ndarray) -> None:
        """:meth:`moved` of a few rows ``where`` of a shadow-casting batch whose boxes ``found`` are kept and whose
        moves the journal follows: the old and new boxes as lists of floats (the journal takes them so)."""
        rows = batch.rows
        places = where.tolist()
        lows, highs = _few_boxes(batch.geometry, [rows[i, _MODEL].tolist() for i in places])
        store_lo, store_hi = found[1], found[2]
        old_lo = [store_lo[i].tolist() for i in places]
        old_hi = [store_hi[i].tolist() for i in places]
        self._follow_casters((old_lo, old_hi), (lows, highs))
        if self._room(len(places)):
            self._note(CasterChange(batch, old_lo, old_hi, False, where))
            self._note(CasterChange(batch, lows, highs, True, where))
        for i, a, b in zip(places, lows, highs, strict=True):
            store_lo[i] = a
            store_hi[i] = b
        if found[3] is not None:
            self._boxes[id(batch)] = (batch, store_lo, store_hi, None)  # (their extremes are not known now)

    def _follow_casters(self, old: tuple[Any, Any] | None, new: tuple[Any, Any] | None) -> None:
        """Caster rows left the boxes ``old`` and took ``new`` ((lo, hi) (N, 3) arrays, lists of [x, y, z] lists
        for a few, or None): the casters' bounds follow without a pass over every caster while some row stays on
        each side of them.

        The rows on each bound are counted (:meth:`caster_bounds`): a box that
        left a bound takes one off its count, a box on it (or beyond: a new
        bound) adds one; the bounds are computed again only when a count falls
        to none (the last row on that side left).
        """
        cached = self._casters
        if cached is None or cached[0] is None:
            self._casters = None
            return
        lo, hi = cached[0]
        counts = self._extremes
        if counts is None:
            if old is not None and len(old[0]) and not _inside(old, lo, hi):
                self._casters = None  # a row on the bounds left: they may shrink
                return
        else:
            low, high = list(counts[0]), list(counts[1])
            if old is not None and len(old[0]):
                _uncount(low, old[0], lo.tolist())
                _uncount(high, old[1], hi.tolist())
            counts = (low, high)
        if new is not None and len(new[0]):
            bound_lo, bound_hi, grown = _grown_bounds(lo, hi, new[0], new[1])
            if counts is not None:
                low, high = counts
                was_lo, was_hi = lo.tolist(), hi.tolist()
                for k in range(3):
                    if bound_lo[k] < was_lo[k]:
                        low[k] = 0  # a new bound: the rows on it are counted below
                    if bound_hi[k] > was_hi[k]:
                        high[k] = 0
                _uncount(low, new[0], bound_lo, -1)
                _uncount(high, new[1], bound_hi, -1)
            if grown:
                lo, hi = np.array(bound_lo), np.array(bound_hi)
                cached = ((lo, hi),)  # a new tuple: the bounds changed
        if counts is not None:
            self._extremes = counts
            if min(counts[0]) <= 0 or min(counts[1]) <= 0:
                self._casters = None  # the last row on a bound left: they may shrink
                return
        self._casters = cached

    def batch_edits(self, batch: Any, edits: list[tuple[Any, ...]]) -> None:
        """Rows of ``batch`` were removed (the last row moved into the hole) or appended: the boxes follow; for a
        shadow-casting batch the journal gets a removed row's old box and an added row's box, and the casters'
        bounds follow."""
        found = self._boxes.get(id(batch))
        caster = casts_shadows(batch)
        lo = hi = None
        if found is not None and found[0] is batch:
            lo, hi = found[1], found[2]
        for op, index, _ in edits:
            if op == "remove":
                if lo is None or index >= len(lo):
                    if caster:
                        self._journal = self._casters = None  # the removed row's place is not known
                    lo = hi = None
                    continue
                if caster:  # (one box as lists of floats: what the journal and the bounds take fastest)
                    old = ([lo[index].tolist()], [hi[index].tolist()])
                    self._follow_casters(old, None)
                    if self._room(1):
                        self._note(CasterChange(batch, *old, False, np.array([index]), True))
                last = len(lo) - 1
                lo[index], hi[index] = lo[last], hi[last]
                lo, hi = lo[:-1], hi[:-1]
            else:
                a, b = _few_boxes(batch.geometry, [batch.rows[index, _MODEL].tolist()])
                if caster:
                    self._follow_casters(None, (a, b))
                    if self._room(1):
                        self._note(CasterChange(batch, a, b, True, np.array([index]), True))
                if lo is not None:
                    lo, hi = _appended(lo, a), _appended(hi, b)
        if lo is not None and len(lo) == len(batch.rows):
            self._boxes[id(batch)] = (batch, lo, hi, None)
        else:
            self._boxes.pop(id(batch), None)

    def _room(self, rows: int) -> bool:
        """Whether the journal takes ``rows`` more rows (False: it says "everything changed" now)."""
        if self._journal is None:
            return False
        if self._journal_rows + rows > JOURNAL_ROWS:
            self._journal = None
            return False
        return True

    def _note(self, change: CasterChange) -> None:
        assert self._journal is not None
        self._journal.append(change)
        self._journal_rows += len(change.lo)

    def take_caster_changes(self) -> list[CasterChange] | None:
        """The casters' changed boxes since the last call (None: everything may have changed); the journal is
        empty afterwards."""
        out = self._journal
        self._journal = []
        self._journal_rows = 0
        return out

    def caster_boxes(self) -> list[tuple[Any, np.ndarray, np.ndarray]] | None:
        """Every shadow-casting batch with its rows' world boxes ``(batch, lo, hi)``; None when some caster is
        not in a batch (a scope not planned)."""
        if self.root is None:
            return []
        out = []
        for scope in self.root.walk():
            if scope.parts is None:
                if any(not item.transparent and casts_shadows(item) for item in scope.items()):
                    return None
                continue
            for part in scope.parts:
                if isinstance(part, Segment):
                    for batch in part.batches:
                        if len(batch.rows) and casts_shadows(batch):
                            out.append((batch, *self._batch_boxes(batch)))
        return out

    def spliced(
        self, removed: list[DrawItem], added: list[DrawItem], places: list[int] | None = None, swapped: bool = False
    ) -> None:
        """Items left and came without a new plan: the item list follows, mirrors only when one is among them.

        ``places``: where each removed item was in the root scope's entries,
        removed in this order (without nested scopes the item list is in the
        same order: no search).  ``swapped``: the root's last entry took each
        removed item's place (a root of one segment), else the later entries
        moved up.  The batches' row edits reach the boxes through
        :meth:`batch_edits`.
        """
        self.version += 1
        items = self._items
        if items is not None:
            hints = places if places is not None and len(places) == len(removed) else [-1] * len(removed)
            for item, hint in zip(removed, hints, strict=True):
                if not swapped:
                    del items[position_of(items, item, hint)]
                elif 0 <= hint < len(items) and items[hint] is item:
                    items[hint] = items[-1]
                    items.pop()
                else:  # not in the root's order: made again when next asked
                    items = self._items = None
                    break
            if items is not None:
                items.extend(added)
        if any(not not_mirror(it) for it in (*removed, *added)):
            self._mirrors = None
        # the casters' bounds follow the batches' row edits (batch_edits); every caster is in a batch
        self._bounds = None

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
        """``(bounds,)`` of the opaque shadow casters (a new tuple when casters moved, left or came)."""
        if self._casters is None:
            self._casters = (self._compute(lambda item: not item.transparent and casts_shadows(item)),)
            self._extremes = self._count_extremes(self._casters[0])
        return self._casters

    def _count_extremes(self, bounds: tuple[np.ndarray, np.ndarray] | None) -> tuple[list[int], list[int]] | None:
        """Per axis, how many caster batch rows' boxes lie on the lower and the upper bound (casters outside
        batches are not counted: a bound only they hold is computed again whenever a batch row leaves it)."""
        if bounds is None or self.root is None:
            return None
        lo, hi = bounds
        low, high = [0, 0, 0], [0, 0, 0]
        for scope in self.root.walk():
            for part in scope.parts or ():
                if not isinstance(part, Segment):
                    continue
                for batch in part.batches:
                    if batch.items and len(batch.rows) and not batch.items[0].transparent and casts_shadows(batch):
                        a, b = self._batch_boxes(batch)
                        extremes = self._boxes[id(batch)][3]
                        for k in range(3):
                            if extremes is not None:  # (counted when the boxes were made)
                                low[k] += extremes[1][k] if extremes[0][k] == lo[k] else 0
                                high[k] += extremes[3][k] if extremes[2][k] == hi[k] else 0
                                continue
                            low[k] += int(np.count_nonzero(a[:, k] == lo[k]))
                            high[k] += int(np.count_nonzero(b[:, k] == hi[k]))
        return low, high

    def _compute(self, keep: Any) -> tuple[np.ndarray, np.ndarray] | None:
        parts: dict[int, tuple[Any, list[np.ndarray]]] = {}

        def add(geometry: Any, rows: np.ndarray) -> None:
            entry = parts.get(id(geometry))
            if entry is None:
                entry = parts[id(geometry)] = (geometry, [])
            entry[1].append(rows)

        if self.root is None:
            return None
        boxes: list[tuple[np.ndarray, np.ndarray, Any]] = []
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
                        boxes.append((*self._batch_boxes(batch), self._boxes[id(batch)][3]))
                for item in part.others:
                    if keep(item):
                        add(item.geometry, item.rows())
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for a, b, extremes in boxes:
            lo = np.minimum(lo, _column_min(a) if extremes is None else extremes[0])
            hi = np.maximum(hi, _column_max(b) if extremes is None else extremes[2])
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
            found = self._boxes[id(batch)] = _kept_boxes(batch)
        return found[1], found[2]


def _inside(boxes: tuple[Any, Any], lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether the boxes (lo, hi) ((N, 3) arrays or lists of corners) lie strictly inside the bounds [lo, hi]."""
    a, b = boxes
    if isinstance(a, list):
        low, high = lo.tolist(), hi.tolist()
        return all(r[k] > low[k] for r in a for k in range(3)) and all(r[k] < high[k] for r in b for k in range(3))
    return bool((a > lo).all() and (b < hi).all())


def _uncount(counts: list[int], boxes: Any, bound: list[float], sign: int = 1) -> None:
    """Take the rows of ``boxes`` ((N, 3), or a list of corners) that lie on ``bound`` (per axis) off ``counts``
    (``sign`` -1: add them); a few rows in Python floats, many column by column."""
    if isinstance(boxes, list) or len(boxes) <= 8:
        for row in boxes if isinstance(boxes, list) else boxes.tolist():
            for k in range(3):
                if row[k] == bound[k]:
                    counts[k] -= sign
        return
    for k in range(3):
        counts[k] -= sign * int(np.count_nonzero(boxes[:, k] == bound[k]))


def _grown_bounds(lo: np.ndarray, hi: np.ndarray, new_lo: Any, new_hi: Any) -> tuple[list[float], list[float], bool]:
    """The bounds ``[lo, hi]`` grown to take the boxes ``[new_lo, new_hi]`` ((N, 3), or lists of corners) as lists
    of floats, and whether they grew; a few boxes (what moved in a frame) in Python floats, no numpy call per
    axis."""
    if isinstance(new_lo, list) or len(new_lo) <= 8:
        was_lo, was_hi = lo.tolist(), hi.tolist()
        lows = new_lo if isinstance(new_lo, list) else new_lo.tolist()
        highs = new_hi if isinstance(new_hi, list) else new_hi.tolist()
        grown = False
        for row in lows:  # (plain loops: a few rows, no generator per axis)
            for k in range(3):
                if row[k] < was_lo[k]:
                    was_lo[k] = row[k]
                    grown = True
        for row in highs:
            for k in range(3):
                if row[k] > was_hi[k]:
                    was_hi[k] = row[k]
                    grown = True
        return was_lo, was_hi, grown
    a, b = _column_min(new_lo), _column_max(new_hi)
    grown = bool((a < lo).any() or (b > hi).any())
    return np.minimum(lo, a).tolist(), np.maximum(hi, b).tolist(), grown


def _column_min(a: np.ndarray) -> np.ndarray:
    """``a.min(axis=0)`` of an (N, 3) array, column by column (numpy's axis-0 reduction of narrow rows is slow)."""
    return np.array([a[:, 0].min(), a[:, 1].min(), a[:, 2].min()])


def _column_max(a: np.ndarray) -> np.ndarray:
    """``a.max(axis=0)`` of an (N, 3) array, column by column."""
    return np.array([a[:, 0].max(), a[:, 1].max(), a[:, 2].max()])


def _kept_boxes(batch: Any) -> tuple[Any, np.ndarray, np.ndarray, Any]:
    """The render index's entry of ``batch``'s row boxes: (batch, lo, hi, extremes) with spare rows, extremes
    counted while the boxes are made (many rows; a few: None, counted when asked)."""
    rows = batch.rows
    if len(rows) <= _FEW_ROWS:
        return (batch, *row_boxes(batch.geometry, rows), None)
    return (batch, *_many_boxes(batch.geometry, rows, True, True))


def row_boxes(geometry: Any, rows: np.ndarray, spare: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Each row's world box of ``geometry``: ``(lo, hi)``, both (N, 3) (``|M| e`` about the transformed centre).

    Column by column: numpy's batched (3,) @ (N, 3, 3) products are several times slower for thousands of rows;
    a few rows (a splice's, a moved item's) in plain floats, the same operations in the same order.  With
    ``spare`` (boxes kept while rows are appended) both are prefixes of storage with spare rows after them, where
    :func:`_appended` writes appended rows' boxes without copying the others.
    """
    if len(rows) <= _FEW_ROWS:
        return _few_row_boxes(geometry, rows)
    lo, hi, _ = _many_boxes(geometry, rows, spare, False)
    return lo, hi


def _many_boxes(
    geometry: Any, rows: np.ndarray, spare: bool, extremes: bool
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, list[int], np.ndarray, list[int]] | None]:
    """:func:`row_boxes` of many rows; with ``extremes`` also, per axis, the least lower and the greatest upper
    value and how many rows have them ((mins, counts, maxs, counts)), taken from contiguous columns before they
    are written into the (strided) boxes."""
    b0, b1 = (np.asarray(b, dtype=np.float64) for b in geometry.bounds)
    (c0, c1, c2), (e0, e1, e2) = ((b0 + b1) / 2.0).tolist(), ((b1 - b0) / 2.0).tolist()
    # each row holds M transposed: M[k, j] is column 4 j + k of the model; the model columns are copied once into
    # contiguous float64 rows (the same values), read many times; the sums go through three reused scratch rows
    # (no (12, N) array of magnitudes, no new array per product), in the order the few-row path sums
    m = rows[:, _MODEL].T.astype(np.float64)
    n = len(rows)
    if spare:  # (N, 3) prefixes of storage with spare rows, written column by column (strided: a little slower)
        lo = np.empty((n + n // 8 + 16, 3))[:n]
        hi = np.empty((n + n // 8 + 16, 3))[:n]
    else:
        lo = np.empty((3, n)).T
        hi = np.empty((3, n)).T
    center, half, term = np.empty(n), np.empty(n), np.empty(n)
    mul, add = np.multiply, np.add
    found: tuple[np.ndarray, list[int], np.ndarray, list[int]] | None = None
    if extremes:
        found = (np.empty(3), [0, 0, 0], np.empty(3), [0, 0, 0])
    for k in range(3):
        mul(m[k], c0, out=center)
        add(center, mul(m[4 + k], c1, out=term), out=center)
        add(center, mul(m[8 + k], c2, out=term), out=center)
        add(center, m[12 + k], out=center)
        mul(np.abs(m[k], out=half), e0, out=half)
        add(half, mul(np.abs(m[4 + k], out=term), e1, out=term), out=half)
        add(half, mul(np.abs(m[8 + k], out=term), e2, out=term), out=half)
        if found is None:
            np.subtract(center, half, out=lo[:, k])
            np.add(center, half, out=hi[:, k])
            continue
        for column, sign, at in ((lo, np.subtract, 0), (hi, np.add, 2)):
            sign(center, half, out=term)
            column[:, k] = term
            value = term.min() if at == 0 else term.max()
            found[at][k] = value
            found[at + 1][k] = int(np.count_nonzero(term == value))
    return lo, hi, found


#: rows up to which :func:`row_boxes` computes in Python floats (numpy's per-call cost is more for so few)
_FEW_ROWS = 4


def _few_row_boxes(geometry: Any, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`row_boxes` of a few rows: the same sums of float64 products, each row's 16 numbers as floats."""
    lo, hi = _few_boxes(geometry, rows[:, _MODEL].tolist())
    return np.array(lo).reshape(-1, 3), np.array(hi).reshape(-1, 3)


def _few_boxes(geometry: Any, models: list[list[float]]) -> tuple[list[list[float]], list[list[float]]]:
    """The world boxes of ``geometry`` placed by a few rows' ``models`` (each its 16 model numbers as floats):
    lists of [x, y, z] corners, the sums of float64 products :func:`row_boxes` makes, in the same order."""
    (x0, y0, z0), (x1, y1, z1) = (np.asarray(b, dtype=np.float64).tolist() for b in geometry.bounds)
    c0, c1, c2 = (x0 + x1) / 2.0, (y0 + y1) / 2.0, (z0 + z1) / 2.0
    e0, e1, e2 = (x1 - x0) / 2.0, (y1 - y0) / 2.0, (z1 - z0) / 2.0
    lows: list[list[float]] = []
    highs: list[list[float]] = []
    for m in models:  # each row holds M transposed: M[k, j] is m[4 j + k]
        lo, hi = [], []
        for k in range(3):
            center = m[k] * c0 + m[4 + k] * c1 + m[8 + k] * c2 + m[12 + k]
            half = abs(m[k]) * e0 + abs(m[4 + k]) * e1 + abs(m[8 + k]) * e2
            lo.append(center - half)
            hi.append(center + half)
        lows.append(lo)
        highs.append(hi)
    return lows, highs


def _appended(a: np.ndarray, new: Any) -> np.ndarray:
    """``np.concatenate([a, new])`` written into spare rows after ``a`` when its storage has them, else into new
    storage with spare rows: a splice appending one row per frame copies no list of boxes.

    ``a`` is an array of its own or a prefix ``store[:n]`` of the storage this made (the only views of it the
    index keeps: a removed row shortens the boxes the same way).
    """
    n, k = len(a), len(new)
    base = a.base
    if (
        isinstance(base, np.ndarray)
        and base.ndim == 2
        and base.dtype == a.dtype
        and base.shape[1] == a.shape[1]
        and len(base) >= n + k
    ):
        out = base[: n + k]
    else:
        out = np.empty((n + max(k, n // 8 + 16), *a.shape[1:]), a.dtype)[: n + k]
        out[:n] = a
    out[n:] = new
    return out


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
