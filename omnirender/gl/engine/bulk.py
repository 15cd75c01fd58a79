"""An ``om.TranslationArray`` applied at once: its rows written into the batch rows in one numpy operation.

When an application moves thousands of nodes through one
:class:`~omnirender.core.transform.TranslationArray`, its ``touch()`` records
the array (not each translation) in the engine's change journal.  The move
plan (:class:`~.dynamic.MovePlan`) then keeps, per bound array, a
:class:`BulkMap`: for every installed item below exactly one of the array's
translations, the batch row it owns and the two constants that make its
world translation from the array row::

    M = P @ T(offset) @ S     =>     M[:3, 3] = L @ offset + c,  L = P[:3, :3],  c = L @ S[:3, 3] + P[:3, 3]

(``P`` the product of the transforms above the translation in the item's
chain, ``S`` those below it and the shape-local matrix; the linear part of
``M`` does not depend on the offset, so only the translation column is
written).  A frame is then, per batch, one gather from the array snapshot
plus ``c`` (and ``L``'s product where it is not the identity) into the rows'
translation columns, and one partial upload of the rows' range.

The map is made when an array is first applied after an install, and made
again after a splice or after a change to another transform in one of its
items' chains (``P`` or ``S`` changed).
"""

from __future__ import annotations

from itertools import repeat
from typing import Any

import numpy as np

from .layout import ROW

__all__ = ["BulkMap"]

_TRANSLATION = slice(ROW.offsets["model"] + 12, ROW.offsets["model"] + 15)  # rows hold M transposed
_EYE3 = np.eye(3)


class _Part:
    """The rows of one batch (or the loose items, ``batch`` None) that one array moves."""

    __slots__ = ("batch", "where", "source", "constant", "linear", "span", "items")

    def __init__(
        self,
        batch: Any,
        where: np.ndarray,
        source: np.ndarray,
        constant: np.ndarray,
        linear: np.ndarray | None,
        items: list[Any] | None,
    ) -> None:
        self.batch = batch
        #: the batch rows, ascending; a slice when they are one contiguous range (a view, not a gather)
        self.where: np.ndarray | slice = where
        lo, hi = (int(where[0]), int(where[-1]) + 1) if len(where) else (0, 0)
        if hi - lo == len(where):
            self.where = slice(lo, hi)
        self.span = (lo, hi)
        #: the array row of each batch row, the constant c and, where not all the identity, L
        self.source = source
        self.constant = constant
        self.linear = linear
        #: the loose items themselves (no batch: each writes its own row)
        self.items = items


class BulkMap:
    """Where one :class:`~omnirender.core.transform.TranslationArray`'s rows land in a move plan's batches.

    ``valid`` is False when an item lies below two translations of the same
    array: such an array is applied the general way (each translation as a
    moved transform).
    """

    __slots__ = ("positions", "rows", "parts", "fixed", "valid", "count")

    def __init__(self, plan: Any, array: Any) -> None:
        translations = array[:]
        n = len(translations)
        found = np.fromiter(map(plan.index.get, map(id, translations), repeat(-1)), np.intp, n)
        present = found >= 0
        #: the array rows the plan holds and their places among the plan's matrices
        self.rows = np.flatnonzero(present)
        self.positions = found[present]
        self.parts: list[_Part] = []
        #: by place among the plan's matrices: the transforms the map's L and c were made from (a change to
        #: one of them makes the map stale; the array's own translations do not)
        self.fixed = np.zeros(len(plan.matrices), bool)
        self.count = 0
        self.valid = True
        if not len(plan.items) or not len(self.rows):
            return
        lookup = np.full(len(plan.matrices), -1, np.intp)
        lookup[self.positions] = self.rows
        chosen = lookup[plan.chain]  # (items, chain length): the array row at each link, or -1
        hits = chosen >= 0
        per_item = hits.sum(axis=1)
        if (per_item > 1).any():
            self.valid = False
            return
        affected = np.flatnonzero(per_item == 1)
        if not len(affected):
            return
        self.count = len(affected)
        at = hits[affected].argmax(axis=1)  # where the array's translation is in each chain
        source = chosen[affected, at]
        chain = plan.chain[affected]
        others = chain.copy()
        others[np.arange(len(affected)), at] = len(plan.matrices) - 1  # the identity's place
        self.fixed[others.ravel()] = True
        self.fixed[-1] = False
        above = np.broadcast_to(np.eye(4), (len(affected), 4, 4)).copy()
        below = above.copy()
        for k in range(chain.shape[1]):
            m = plan.matrices[chain[:, k]]
            before, after = at > k, at < k
            if before.any():
                above[before] = above[before] @ m[before]
            if after.any():
                below[after] = below[after] @ m[after]
        if plan.local is not None:
            below = below @ plan.local[affected]
        linear = above[:, :3, :3]
        constant = np.einsum("nij,nj->ni", linear, below[:, :3, 3]) + above[:, :3, 3]
        owners = plan.batch_of[affected]
        order = np.lexsort((plan.row_of[affected], owners))  # by batch, then by row
        owners = owners[order]
        for part in np.split(order, np.flatnonzero(np.diff(owners)) + 1):
            b = int(plan.batch_of[affected[part[0]]])
            lin = linear[part]
            lin = None if (lin == _EYE3).all() else lin
            if b < 0:  # items without a batch (transparent, overlay): their own rows
                items = [plan.items[i] for i in affected[part].tolist()]
                where = np.arange(len(part))
                self.parts.append(_Part(None, where, source[part], constant[part], lin, items))
            else:
                where = plan.row_of[affected[part]]
                self.parts.append(_Part(plan.batches[b], where, source[part], constant[part], lin, None))

    def apply(self, plan: Any, offsets: np.ndarray) -> None:
        """Write the rows of ``offsets`` (the array's snapshot) into the plan's matrices and the items' rows."""
        plan.matrices[self.positions, :3, 3] = offsets[self.rows]
        for part in self.parts:
            o = offsets[part.source]
            lin = part.linear
            if lin is None:
                world = o + part.constant
            else:  # three scaled columns rather than a batched product (see dynamic.py on BLAS threads)
                world = o[:, 0:1] * lin[:, :, 0] + o[:, 1:2] * lin[:, :, 1] + o[:, 2:3] * lin[:, :, 2]
                world += part.constant
            if part.batch is None:
                for item, w in zip(part.items, world, strict=True):
                    item.row[_TRANSLATION] = w
                continue
            batch = part.batch
            batch.rows[part.where, _TRANSLATION] = world
            lo, hi = part.span
            if hi - lo <= 8 and isinstance(part.where, np.ndarray):
                for w in part.where.tolist():
                    batch.row_changed(w)
            else:
                batch.moved(lo, hi)  # translation columns only: the upload rewrites just those (drawer.py)
            plan.moved_rows.append((batch, part.where))
