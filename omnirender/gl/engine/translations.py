"""Where every installed item's translation column comes from when many ``om.Translation`` objects move at once.

A simulation moves thousands of nodes per frame through their plain
``Translation`` objects (``t.offset = row``) or through one
``om.TranslationArray`` (the array written, ``touch()``).  Most items then lie
below exactly one translation, and their world translation column is an affine
function of that translation's offset::

    M = P @ T(offset) @ S     =>     M[:3, 3] = L @ offset + c,  L = P[:3, :3],  c = L @ S[:3, 3] + P[:3, 3]

:class:`TranslationMap` keeps, per item of a :class:`~.dynamic.MovePlan` (in
the plan's item order), the place among the plan's matrices of its one
translation, ``c`` and, where it is not the identity, ``L``.  A frame in
which most translations moved writes the new offsets into the plan's
matrices and then, per batch, gathers them into the rows' translation
columns in one numpy operation; items below two or more translations (nested
translated nodes) are recomposed from their chains.

The map follows the plan: a splice fills the constants of the new items only
and drops the removed ones (the per-batch grouping is made again, in numpy
operations, when next applied); a change to another transform of an item's
chain (a rotation above a translation) fills that item's constants again.
Nothing here visits installed items one by one in Python.
"""

from __future__ import annotations

from itertools import repeat
from operator import is_
from typing import Any

import numpy as np

from ...core.transform import Translation
from .drawlist import set_translations
from .layout import ROW
from .spare import extend_held

__all__ = ["TranslationMap"]

_TRANSLATION = slice(ROW.offsets["model"] + 12, ROW.offsets["model"] + 15)  # rows hold M transposed
_EYE3 = np.eye(3)


class _Part:
    """The rows of one batch (or the loose items, ``batch`` None) the map writes."""

    __slots__ = ("batch", "where", "span", "source", "constant", "linear", "items", "_picks")

    def __init__(
        self,
        batch: Any,
        where: np.ndarray,
        source: np.ndarray,
        constant: np.ndarray | None,
        linear: np.ndarray | None,
        items: list[Any] | None,
    ) -> None:
        self.batch = batch
        lo, hi = (int(where[0]), int(where[-1]) + 1) if len(where) else (0, 0)
        #: the batch rows, ascending; a slice when they are one contiguous range (a view, not a scatter)
        self.where: np.ndarray | slice = slice(lo, hi) if hi - lo == len(where) else where
        self.span = (lo, hi)
        #: the place among the plan's matrices of each row's translation, c (None: all zero) and L (None: all I)
        self.source = source
        self.constant = constant
        self.linear = linear
        #: the loose items themselves (no batch: each writes its own row)
        self.items = items
        #: (the places of the last moved translations, :meth:`picks_of`'s answer for that object)
        self._picks: tuple[np.ndarray, tuple[np.ndarray, np.ndarray | None]] | None = None

    def picks_of(self, positions: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Where each row's translation is among ``positions`` (places among the plan's ``places`` matrices of
        the translations that moved, in their order; 0 where it is not among them) and which rows' is not
        (indices, None: none).  Kept for the same ``positions`` object (a simulation's look-ups, kept while the
        same translations move)."""
        kept = self._picks
        if kept is not None and kept[0] is positions:
            return kept[1]
        at = np.full(places, -1, np.intp)
        at[positions] = np.arange(len(positions))
        picks = at[self.source]
        absent = picks < 0
        missing = None
        if absent.any():
            missing = np.flatnonzero(absent)
            picks[missing] = 0
        self._picks = (positions, (picks, missing))
        return picks, missing


class TranslationMap:
    """Per item of a move plan: the place of its one translation among the plan's matrices, ``c`` and ``L``.

    ``source[i]`` is -1 for an item below no translation or several (those
    are in :attr:`multi`), and for items that left the plan.
    """

    __slots__ = (
        "source",
        "constant",
        "linear",
        "multi",
        "fixed",
        "translation",
        "translations",
        "offset_constants",
        "_parts",
        "_multi_items",
        "_plan",
        "_pending",
        "_stores",
    )

    def __init__(self, plan: Any) -> None:
        n = len(plan.items)
        #: the move plan this maps (fills read its chains and matrices)
        self._plan = plan
        #: items whose chains changed (transforms replaced) or whose c or L went stale since: filled again before
        #: the map is next read (:meth:`parts`, :meth:`multi_items`), so a frame that replaces or moves a few
        #: transforms pays no fill of its own
        self._pending: list[np.ndarray] = []
        self.source = np.full(n, -1, np.intp)
        self.constant = np.zeros((n, 3))
        #: whether some item's c was ever made other than zero (until then every part's c is None: not gathered)
        self.offset_constants = False
        #: L per item, made when a first item's L is not the identity
        self.linear: np.ndarray | None = None
        #: items below two or more translations: recomposed from their chains
        self.multi = np.zeros(n, bool)
        #: by place among the plan's matrices: a transform that some item's c or L was made from (its change
        #: makes them stale: those items are filled again)
        self.fixed = np.zeros(len(plan.matrices), bool)
        #: by place among the plan's matrices: whether a plain ``Translation`` is there
        self.translation = _translations(plan.transforms, len(plan.matrices))
        #: how many places hold one
        self.translations = int(self.translation.sum())
        self._parts: list[_Part] | None = None
        self._multi_items: np.ndarray | None = None
        #: attribute name -> (storage with spare rows, the view the attribute holds): splices append in place
        self._stores: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.fill(plan, np.arange(n))

    # -- following the plan ----------------------------------------------------------
    def refill(self, items: np.ndarray | list[int]) -> None:
        """The items ``items`` (indices: an array, or a list of a few) are filled again (:meth:`fill`) before
        the map is next read (made an array then: a frame replacing one transform makes none)."""
        self._pending.append(items)
        self._parts = None
        self._multi_items = None

    def _flush(self) -> None:
        pending = self._pending
        if pending:
            items = np.asarray(pending[0], np.intp) if len(pending) == 1 else np.unique(np.concatenate(pending))
            self._pending = []
            self.fill(self._plan, items)

    def fill(self, plan: Any, items: np.ndarray) -> None:
        """Make ``source``, ``c`` and ``L`` of the plan items ``items`` (indices) from the plan's chains."""
        self._parts = None
        self._multi_items = None
        if not len(items):
            return
        chain = plan.chain[items]
        hits = self.translation[chain]
        per_item = hits.sum(axis=1)
        self.multi[items] = per_item > 1
        self.source[items] = -1
        one = per_item == 1
        if not one.any():
            return
        items, chain, hits = items[one], chain[one], hits[one]
        at = hits.argmax(axis=1)  # where the translation is in each chain
        rows = np.arange(len(items))
        self.source[items] = chain[rows, at]
        matrices = plan.matrices
        identity = plan.identity_places()
        # S's translation column: the shape-local matrix's, carried out through the links below the translation
        point = np.zeros((len(items), 3)) if plan.local is None else plan.local[items, :3, 3].copy()
        linear = np.broadcast_to(_EYE3, (len(items), 3, 3)).copy()
        any_linear = False
        for k in range(chain.shape[1] - 1, -1, -1):
            links = chain[:, k]
            use = (k != at) & ~identity[links]
            if not use.any():
                continue
            self.fixed[links[use]] = True
            m = matrices[links[use]]
            point[use] = np.einsum("nij,nj->ni", m[:, :3, :3], point[use]) + m[:, :3, 3]
            above = use & (k < at)
            if above.any():  # L = P[:3, :3]: the links above, outermost first
                linear[above] = matrices[links[above], :3, :3] @ linear[above]
                any_linear = True
        self.constant[items] = point
        if not self.offset_constants and point.any():
            self.offset_constants = True
        if any_linear and not (linear == _EYE3).all():
            if self.linear is None:
                self.linear = np.broadcast_to(_EYE3, (len(self.source), 3, 3)).copy()
            self.linear[items] = linear
        elif self.linear is not None:
            self.linear[items] = _EYE3

    def splice(self, plan: Any, removed: list[int], first_new: int) -> None:
        """Follow :meth:`MovePlan.splice`: items ``removed`` (indices) left, items from ``first_new`` on came.

        Call after the plan took them (its chains, matrices and transforms hold the new ones).  The new items
        are filled when the map is next read (:meth:`refill`: frames adding a node each pay no numpy fill; a
        removed item waiting there is filled as what it is now, below no translation).
        """
        if removed:
            gone = np.array(removed, np.intp)
            self.source[gone] = -1
            self.multi[gone] = False
        n = len(plan.items)
        self._grow(plan)
        extra = n - len(self.source)
        if extra > 0:
            self._extend("source", extra)[-extra:] = -1
            self._extend("constant", extra)[-extra:] = 0.0
            self._extend("multi", extra)[-extra:] = False
            if self.linear is not None:
                self._extend("linear", extra)[-extra:] = _EYE3
        self.refill(np.arange(first_new, n))  # (rows moved: grouped again when next read)

    def replaced(self, plan: Any, places: list[int], items: np.ndarray | list[int]) -> None:
        """Follow :meth:`MovePlan.replace`: transforms at ``places`` are others now, the chains of ``items``
        (indices) changed or hold them."""
        self._grow(plan)
        for k in places:
            now = plan.transforms[k].__class__ is Translation
            if now != self.translation[k]:  # (the count follows: no pass over every place)
                self.translation[k] = now
                self.translations += 1 if now else -1
        self.refill(items)

    def _grow(self, plan: Any) -> None:
        """Places for the transforms the plan took since (their flags)."""
        places = len(plan.matrices)
        known = len(self.translation)
        if places > known:
            flags = _translations(plan.transforms[known:], places - known)
            self._extend("translation", places - known)[known:] = flags
            self._extend("fixed", places - known)[known:] = False
            self.translations += int(flags.sum())

    def _extend(self, name: str, extra: int) -> np.ndarray:
        """The array attribute ``name`` with ``extra`` more rows, appended in place (:func:`.spare.extend_held`)."""
        return extend_held(self, self._stores, name, extra)

    def stale(self, places: np.ndarray | list[int]) -> bool:
        """Whether a transform at ``places`` (moved other than through this map) is one some item's c or L
        was made from."""
        fixed = self.fixed
        if places.__class__ is list and len(places) <= 8:  # a few moved (MovePlan.apply_few): no fancy index
            for k in places:  # (a plain loop: no generator for any() to drain, one element for a drag)
                if fixed[k]:
                    return True
            return False
        return bool(fixed[places].any())

    # -- writing rows ----------------------------------------------------------------
    def multi_items(self) -> np.ndarray:
        """The indices of the items below two or more translations."""
        self._flush()
        found = self._multi_items
        if found is None:
            found = self._multi_items = np.flatnonzero(self.multi)
        return found

    def parts(self, plan: Any) -> list[_Part]:
        """The mapped items grouped by batch, rows ascending (made again after a splice or a fill)."""
        self._flush()
        parts = self._parts
        if parts is not None:
            return parts
        parts = self._parts = []
        chosen = np.flatnonzero(self.source >= 0)
        if not len(chosen):
            return parts
        owners = plan.batch_of[chosen]
        rows = plan.row_of[chosen]
        if (owners == owners[0]).all():
            groups = [np.argsort(rows, kind="stable")]
        else:
            order = np.lexsort((rows, owners))  # by batch, then by row
            groups = np.split(order, np.flatnonzero(np.diff(owners[order])) + 1)
        for part in groups:
            items = chosen[part]
            b = int(plan.batch_of[items[0]])
            constant = self.constant[items] if self.offset_constants else None
            linear = None if self.linear is None else self.linear[items]
            parts.append(
                _Part(
                    None if b < 0 else plan.batches[b],
                    np.arange(len(items)) if b < 0 else plan.row_of[items],
                    self.source[items],
                    constant if constant is not None and constant.any() else None,
                    None if linear is None or (linear == _EYE3).all() else linear,
                    [plan.items[i] for i in items.tolist()] if b < 0 else None,
                )
            )
        return parts

    def apply(
        self, plan: Any, hit: np.ndarray | None = None, moved: tuple[np.ndarray, np.ndarray] | None = None
    ) -> int:
        """Write the translation column of the mapped items from the plan's matrices; returns how many.

        Every mapped item, or with ``hit`` (by place among the plan's matrices:
        the translations that moved, an array's) those below one of them.  The
        rows' batches are marked as moved (translation columns only) and listed
        in ``plan.moved_rows``.  Items below several translations are not
        written here (:meth:`multi_items`).  ``moved``: ``(places, offsets)`` of
        translations just written into the matrices; a part whose rows all lie
        below them reads the offsets (compact) instead of the matrices' columns.
        """
        matrices = plan.matrices
        count = 0
        for part in self.parts(plan):
            source, where = part.source, part.where
            lo, hi = part.span
            if hit is None and moved is not None:
                picks, missing = part.picks_of(moved[0], len(matrices))
                world = moved[1].take(picks, axis=0)
                if missing is not None:  # (rows below translations that did not move: their matrices' columns)
                    world[missing] = matrices[source[missing], :3, 3]
                count += self._write(plan, part, world, where, lo, hi, None)
                continue
            if hit is not None:
                chosen = hit[source]
                if not chosen.all():
                    if not chosen.any():
                        continue
                    source = source[chosen]
                    where = (np.arange(lo, hi) if isinstance(where, slice) else where)[chosen]
                    lo, hi = int(where[0]), int(where[-1]) + 1
            world = matrices[source, :3, 3]
            count += self._write(plan, part, world, where, lo, hi, None if hit is None else chosen)
        return count

    @staticmethod
    def _write(
        plan: Any, part: _Part, world: np.ndarray, where: Any, lo: int, hi: int, chosen: np.ndarray | None
    ) -> int:
        """Rows ``where`` (``lo:hi``) of ``part`` (those ``chosen`` of it) take ``world`` (the translations'
        offsets below them) through their ``L`` and ``c``; returns how many."""
        lin, constant = part.linear, part.constant
        if chosen is not None and not chosen.all():
            lin = None if lin is None else lin[chosen]
            constant = None if constant is None else constant[chosen]
        if lin is not None:  # three scaled columns rather than a batched product (see dynamic.py on BLAS)
            world = world[:, 0:1] * lin[:, :, 0] + world[:, 1:2] * lin[:, :, 1] + world[:, 2:3] * lin[:, :, 2]
        if constant is not None:
            world += constant  # (world is a copy: a fancy index, a take or the product above)
        if part.batch is None:
            items = part.items if chosen is None else [i for i, c in zip(part.items, chosen, strict=True) if c]
            for item, w in zip(items, world, strict=True):  # type: ignore[arg-type]
                item.row[_TRANSLATION] = w
            return len(world)
        batch = part.batch
        if where.__class__ is slice:  # (one range: written as 12-byte records, not three strided columns)
            set_translations(batch.rows[where], world.astype(np.float32))
        else:
            batch.rows[where, _TRANSLATION] = world
        if hi - lo <= 8 and isinstance(where, np.ndarray):
            for w in where.tolist():
                batch.row_changed(w)
        else:
            batch.moved(lo, hi)  # translation columns only: the upload rewrites just those (drawer.py)
        plan.moved_rows.append((batch, where))
        return len(world)


def _translations(transforms: list[Any], places: int) -> np.ndarray:
    """By place: whether ``transforms[k]`` is a plain ``Translation`` (places beyond the list: no)."""
    out = np.zeros(places, bool)
    out[: len(transforms)] = np.fromiter(map(is_, map(type, transforms), repeat(Translation)), bool, len(transforms))
    return out
