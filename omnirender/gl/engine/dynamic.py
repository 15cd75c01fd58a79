"""Moving things without recompiling: transforms that changed rewrite only the rows that depend on them.

A simulation moves thousands of objects per frame by setting their
transforms.  The GL engine keeps a :class:`~omnirender.core.component.ChangeJournal`;
when everything that changed since the last frame is a static transform (a
``Translation``, ``Rotation``, ``Scaling`` or ``Matrix``: its matrix depends
on its parameters only) and no node's list changed, the frame skips the
traversal: each draw item remembers the transforms whose product is its model
matrix (its *chain*) and its shape-local matrix, an index maps every
transform to the items below it, and only those items' model matrices are
recomposed and written into their rows in place.  The batches upload the
changed rows as one range (or all of them when most changed).  Anything else
(a colour, a shape, a camera, a node added) goes through the compile.
"""

from __future__ import annotations

from itertools import compress, repeat
from operator import is_
from typing import Any

import numpy as np

from ...core.transform import Transform, Translation, TranslationArray
from ...shapes import InstanceSet
from .drawlist import set_translations
from .instancing import InstanceRows, held, instance_rows, mask_copies, moved_instance_rows, set_arrays
from .layout import ROW
from .spare import extend_held
from .translations import TranslationMap

__all__ = ["MovePlan", "TransformUpdater"]

_MODEL = ROW.slice("model")
_TRANSLATION = slice(ROW.offsets["model"] + 12, ROW.offsets["model"] + 15)  # rows hold M transposed
_TX, _TY, _TZ = range(ROW.offsets["model"] + 12, ROW.offsets["model"] + 15)  # its three columns, one by one
#: a 4x4 matrix's flat places of its translation column (rows 0-2, column 3)
_COLUMN3 = np.array([3, 7, 11], np.intp)
_EYE4 = np.eye(4)
_EYE3 = np.eye(3)
_EYE4_LIST = _EYE4.tolist()
#: moved transforms from which a frame of only Translations takes the translation map (translations.py)
_MANY = 64
#: moved transforms up to which a frame recomposes the rows below them one item at a time (MovePlan.apply_few)
_FEW = 8
#: splices the updater holds before its plan follows them without a frame of moves (TransformUpdater.splice)
_HELD_SPLICES = 64
#: what a plan's list of transforms holds at a place that stays the identity (the identity's old place)
_IDENTITY = object()


class MovePlan:
    """The installed items' transform chains as arrays, so moved transforms recompose many rows at once.

    ``chain[i, k]`` indexes ``matrices`` (the last entry is the identity,
    padding shorter chains; after splices that brought new transforms, the
    identity's earlier places stay identities and pad older chains); ``local`` holds the shape-local matrices (the
    identity where an item has none).  Instance sets keep their per-item
    path: each is one item whose rows all move together.
    """

    def __init__(self, items: list[Any]) -> None:
        self.items = [it for it in items if it.instances is None and it.chain]
        self.instance_items = [it for it in items if it.instances is not None and it.chain]
        #: id(InstanceSet) -> its installed items (one per template and occurrence)
        self.sources: dict[int, list[Any]] = {}
        for it in items:
            if it.source is not None:
                self.sources.setdefault(id(it.source), []).append(it)
        index: dict[int, int] = {}
        transforms: list[Any] = []
        for item in (*self.items, *self.instance_items):
            for t in item.chain:
                if id(t) not in index:
                    index[id(t)] = len(transforms)
                    transforms.append(t)
        self.index = index
        self.transforms = transforms
        #: ids of the transforms above an item drawn with clip planes: the planes were placed in world coordinates
        #: when it was compiled, so a move of one of them compiles again (TransformUpdater.apply)
        self.clipping: set[int] = set()
        _note_clipping(self.clipping, (*self.items, *self.instance_items))
        identity = len(transforms)
        length = max((len(it.chain) for it in self.items), default=0)
        self.chain = np.full((len(self.items), length), identity, np.intp)
        for i, item in enumerate(self.items):
            self.chain[i, : len(item.chain)] = [index[id(t)] for t in item.chain]
        self.matrices = np.empty((identity + 1, 4, 4))
        for cls, members in _by_class(range(identity), transforms).items():
            self.matrices[members] = cls.stack_matrices([transforms[k] for k in members])
        self.matrices[identity] = np.eye(4)
        with_local = [i for i, it in enumerate(self.items) if it.local is not None]
        self.local: np.ndarray | None = None
        if with_local:
            self.local = np.broadcast_to(np.eye(4), (len(self.items), 4, 4)).copy()
            self.local[with_local] = [self.items[i].local for i in with_local]
        # where each item's row lies: its batch (index into batches, -1: no batch) and its row there
        batches: dict[int, int] = {}
        self._batch_index = batches
        self._where: dict[int, int] | None = None  # id(item) -> its index in items (made on the first splice)
        #: id(transform) -> indices in items of the items whose chain holds it (made on the first few-moved frame,
        #: followed through splices): a frame moving a few transforms finds their items without a pass over all
        self._users: dict[int, list[int]] | None = None
        #: index in items -> (the item's chain, whether its model is that chain's one Translation's matrix: one
        #: link, no shape-local matrix but the identity): asked of every item not moving on the first few-moved
        #: frame, of an item not asked then on its first few-moved frame, and again when its chain is another (a
        #: transform replaced);
        #: while the entry holds, the item's row holds that matrix (the rows follow the chains), so a move writes
        #: only its translation; an index names one item for the plan's life (splices append new items and leave
        #: removed ones' places)
        self._plain: dict[int, tuple[tuple[Any, ...], bool]] = {}
        #: per item index, whether its shape-local matrix is the identity (made from ``local`` at once when first
        #: asked; items spliced in later are asked one by one)
        self._eye_local: list[bool] | None = None
        #: (batch, row indices, a slice of them, or None: all) the last apply() rewrote, for the render index's bounds
        self.moved_rows: list[tuple[Any, Any]] = []
        #: whether :attr:`moved_rows` of the last :meth:`apply_few` names every row it rewrote
        self.rows_only = True
        #: id(TranslationArray) -> (the array, its translations' places among the matrices, the array rows of
        #: those places or None: all): made on its first touch after an install, a splice or a replacement
        self._arrays: dict[int, tuple[Any, np.ndarray, np.ndarray | None]] = {}
        #: where each item's translation column comes from, for frames that move most translations (made on the
        #: first such frame, followed through splices: translations.py)
        self._map: TranslationMap | None = None
        #: by place among the matrices: whether the identity is there (the padding of chains)
        self._identity = np.zeros(identity + 1, bool)
        self._identity[identity] = True
        #: the last frame's changed transforms and where the plan holds them (a simulation moves the same ones,
        #: in the same order, every frame: their look-ups are kept while the list is the same, object for object)
        #: (the list, the places of those found, those found, whether all are plain translations, ids of those not
        #: found): kept through splices and replacements (see :meth:`_add_transforms`, :meth:`replace`)
        self._last: tuple[list[Any], np.ndarray, list[Any], bool, set[int]] | None = None
        #: places new transforms took since (replacements): dropped from the last look-ups when they are next used
        #: (:meth:`_current_last`), not in the frame that replaced one (a pass over thousands of look-ups)
        self._taken: list[int] = []
        #: (positions, the matrices, their flat view, the flat places of those positions' translation columns):
        #: how :meth:`_put_translations` writes many translations (the objects held: compared by identity)
        self._flat: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        #: attribute name -> (storage with spare rows, the view the attribute holds): splices append in place
        self._stores: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.batches: list[Any] = []
        self.batch_of = np.full(len(self.items), -1, np.intp)
        self.row_of = np.zeros(len(self.items), np.intp)
        for i, item in enumerate(self.items):
            if item.slot is None:
                continue
            batch, row = item.slot
            b = batches.get(id(batch))
            if b is None:
                b = batches[id(batch)] = len(self.batches)
                self.batches.append(batch)
            self.batch_of[i] = b
            self.row_of[i] = row

    def splice(self, removed: list[Any], added: list[Any], moved: list[Any]) -> None:
        """Follow the draw list's splice: ``removed`` items leave, ``added`` come, ``moved`` changed rows."""
        # (the places an array's translations hold stay theirs: those of arrays with translations the plan did
        # not hold are looked up again, they may have come)
        for key in [k for k, (_, _, rows) in self._arrays.items() if rows is not None]:
            del self._arrays[key]
        first_new = len(self.items)
        gone: list[int] = []
        # (the last look-ups stay: a splice keeps every transform's place; they are forgotten below when fresh
        # transforms come, which may be some the look-ups did not find)
        where = self._where
        if where is None:
            where = self._where = {id(it): i for i, it in enumerate(self.items)}
        identity = len(self.transforms)
        users = self._users
        for item in removed:
            i = where.pop(id(item), None)
            if i is not None:
                self.chain[i] = identity  # never recomposed again
                self.batch_of[i] = -1
                gone.append(i)
                if users is not None:
                    _drop_user(users, item, i)
        new = [it for it in added if it.instances is None and it.chain]
        _note_clipping(self.clipping, new)
        fresh = [t for it in new for t in it.chain if id(t) not in self.index]
        if fresh:
            identity = self._add_transforms(fresh)
        if new:
            length = max(self.chain.shape[1], max(len(it.chain) for it in new))
            if length > self.chain.shape[1]:
                pad = np.full((len(self.chain), length - self.chain.shape[1]), identity, np.intp)
                self.chain = np.concatenate([self.chain, pad], axis=1)
            rows = np.full((len(new), length), identity, np.intp)
            for r, item in enumerate(new):
                rows[r, : len(item.chain)] = [self.index[id(t)] for t in item.chain]
            self._extend("chain", len(new))[-len(new) :] = rows
            if self.local is not None or any(it.local is not None for it in new):
                if self.local is None:
                    self.local = np.broadcast_to(np.eye(4), (len(self.items), 4, 4)).copy()
                local = self._extend("local", len(new))
                local[-len(new) :] = np.eye(4)
                for r, item in enumerate(new):
                    if item.local is not None:
                        local[len(local) - len(new) + r] = item.local
            self._extend("batch_of", len(new))[-len(new) :] = -1
            self._extend("row_of", len(new))[-len(new) :] = 0
            for item in new:
                i = where[id(item)] = len(self.items)
                self.items.append(item)
                if users is not None:
                    _add_user(users, item, i)
        for item in (*new, *moved):
            i = where.get(id(item))
            if i is None or item.slot is None:
                continue
            batch, row = item.slot
            b = self._batch_index.get(id(batch))
            if b is None:
                b = self._batch_index[id(batch)] = len(self.batches)
                self.batches.append(batch)
            self.batch_of[i] = b
            self.row_of[i] = row
        if self._map is not None:
            self._map.splice(self, gone, first_new)

    def identity_places(self) -> np.ndarray:
        """By place among :attr:`matrices`: whether the identity is there (chains' padding), read-only."""
        return self._identity

    def _add_transforms(self, fresh: list[Any]) -> int:
        """Take transforms the plan does not hold yet (their matrices now); returns the identity's new place."""
        fresh = list({id(t): t for t in fresh}.values())
        last = self._last
        if last is not None and not last[4].isdisjoint(map(id, fresh)):
            self._last = None  # (the last look-ups did not find some of them)
            self._taken = []
        identity = len(self.transforms)
        # the identity's place stays an identity (the padding of every chain and the removed items' chains
        # keep pointing at it: no pass over them); the fresh matrices and the new identity follow it
        self.transforms.append(_IDENTITY)
        for t in fresh:
            self.index[id(t)] = len(self.transforms)
            self.transforms.append(t)
        matrices = self._extend("matrices", len(fresh) + 1)
        for cls, members in _by_class(range(len(fresh)), fresh).items():
            matrices[[identity + 1 + k for k in members]] = cls.stack_matrices([fresh[k] for k in members])
        identity = len(self.transforms)
        matrices[identity] = np.eye(4)
        marks = self._extend("_identity", len(fresh) + 1)
        marks[-len(fresh) - 1 :] = False
        marks[identity] = True
        return identity

    def replace(self, swaps: list[tuple[Any, Any, Any]]) -> None:
        """Transforms replaced by transforms (the dirty bits of :mod:`.dirty`): ``(item, old, new)`` where the
        item's chain now holds ``new`` at ``old``'s place.  The item's chain indices and the transform -> items
        map follow; a transform new to the plan is taken with its matrix.  The rows are recomposed by the next
        :meth:`apply` of the new transforms."""
        self._arrays.clear()  # an array's translation may have taken another's place: looked up again
        where = self._where
        if where is None:
            where = self._where = {id(it): i for i, it in enumerate(self.items)}
        users = self._users_map()
        index = self.index
        if len(swaps) == 1 and self._take_place(*swaps[0], where, users):
            return
        below: dict[int, tuple[Any, Any, set[int]]] = {}  # id(old) -> (old, new, the items swapped)
        for item, old, new in swaps:
            i = where.get(id(item))
            if i is not None:
                below.setdefault(id(old), (old, new, set()))[2].add(i)
        general = []
        taken: list[int] = []
        for key, (old, new, swapped) in below.items():
            k = index.get(key)
            found = users.get(key, ())
            if k is None or id(new) in index or len(found) != len(swapped) or set(found) != swapped:
                general.append(old)
                continue
            # no other item lies below the old transform: the new one takes its place (no chain changes)
            del index[key]
            index[id(new)] = k
            self.transforms[k] = new
            self.matrices[k] = new.matrix
            users[id(new)] = users.pop(key)
            taken.append(k)
        if taken:
            self._taken_places(taken)
        if self._map is not None:  # (after the chains changed below)
            swapped_items = np.array(sorted({i for _, _, items in below.values() for i in items}), np.intp)
        if not general:
            if self._map is not None:
                self._map.replaced(self, taken, swapped_items)
            return
        swaps = [s for s in swaps if s[1] in general]
        fresh = [new for _, _, new in swaps if id(new) not in self.index]
        if fresh:
            self._add_transforms(fresh)
        for item, old, new in swaps:
            i = where.get(id(item))
            if i is None:
                continue  # not in the plan (an instance set's item)
            self.chain[i, : len(item.chain)] = [index[id(t)] for t in item.chain]
            found = users.get(id(old))
            if found is not None and i in found and old not in item.chain:
                found.remove(i)
            found = users.setdefault(id(new), [])
            if i not in found:
                found.append(i)
        if self._map is not None:
            self._map.replaced(self, taken, swapped_items)

    def _taken_places(self, taken: list[int]) -> None:
        """New transforms took the places ``taken`` of replaced ones: the last look-ups drop the old ones (not
        found now) when next used (:meth:`_current_last`), or are forgotten now when a new one is among those
        they did not find."""
        last = self._last
        if last is None:
            return
        if not last[4].isdisjoint(map(id, (self.transforms[k] for k in taken))):
            self._last = None
            self._taken = []
            return
        self._taken.extend(taken)

    def _current_last(self) -> tuple[list[Any], np.ndarray, list[Any], bool, set[int]] | None:
        """The last look-ups without the transforms whose places were taken since (:meth:`_taken_places`)."""
        last = self._last
        taken = self._taken
        if taken:
            self._taken = []
            if last is not None:
                changed, positions, moved, translations, missing = last
                if len(taken) <= _FEW:  # (a frame's few replacements: a comparison each, no sort of the places)
                    hit = positions == taken[0]
                    for k in taken[1:]:
                        hit |= positions == k
                else:
                    hit = np.isin(positions, taken)
                found = np.flatnonzero(hit).tolist()
                if len(found) > _FEW:
                    keep = (~hit).tolist()
                    gone = set(map(id, compress(moved, hit.tolist())))
                    moved = list(compress(moved, keep))
                elif found:  # (a few: taken out of a copy by index, no pass over the thousands kept)
                    moved = list(moved)
                    gone = {id(moved.pop(i)) for i in reversed(found)}
                if found:
                    last = self._last = (changed, np.delete(positions, found), moved, translations, missing | gone)
        return last

    def _take_place(self, item: Any, old: Any, new: Any, where: dict[int, int], users: dict[int, list[int]]) -> bool:
        """One transform replaced above one item, the only one below it (a node's transform replaced: the
        lean case of :meth:`replace`): ``new`` takes ``old``'s place among the matrices, no chain changes.
        False, with nothing changed, when that does not hold (:meth:`replace` goes the general way)."""
        i = where.get(id(item))
        key = id(old)
        k = self.index.get(key)
        found = users.get(key)
        if i is None or k is None or id(new) in self.index or found is None or len(found) != 1 or found[0] != i:
            return False
        index = self.index
        del index[key]
        index[id(new)] = k
        self.transforms[k] = new
        self.matrices[k] = new.matrix  # (whole: a translation's next moves write only its column)
        users[id(new)] = users.pop(key)
        self._taken_places([k])
        if self._map is not None:
            self._map.replaced(self, [k], [i])
        return True

    def _users_map(self) -> dict[int, list[int]]:
        """id(transform) -> the items below it (their indices), made when first asked after a plan change."""
        users = self._users
        if users is None:
            users = self._users = {}
            for i, item in enumerate(self.items):
                _add_user(users, item, i)
        return users

    def _fill_plain(self, moving: dict[int, None]) -> None:
        """Every item's :attr:`_plain` entry but those of the items ``moving`` now (a frame moving an item for the
        first time then finds it).  Every other item's row holds its chain's product: a frame that replaced
        transforms (their items' chains changed, their rows not yet) applies the new ones at once, and their
        items are among ``moving``, whose rows :meth:`apply_few` writes in full."""
        plain, translation_only = self._plain, self._translation_only
        for i, item in enumerate(self.items):
            if i not in plain and i not in moving:
                plain[i] = (item.chain, translation_only(i, item))

    def _extend(self, name: str, extra: int) -> np.ndarray:
        """The array attribute ``name`` with ``extra`` more rows, appended in place (:func:`.spare.extend_held`)."""
        return extend_held(self, self._stores, name, extra)

    def apply_arrays(self, arrays: list[Any]) -> tuple[int, list[Any]]:
        """Write the snapshots of touched ``om.TranslationArray`` objects into the rows below them.

        The array's rows go into the plan's matrices at its translations'
        places, and the translation map (:mod:`.translations`, followed
        through splices) writes the rows below them, one numpy write per
        batch; items below two or more translations are recomposed from their
        chains.  Returns the count of items moved and an empty list (what
        :meth:`apply` takes on the general path: nothing).  Call before
        :meth:`apply` of the same frame: transforms changed one by one since
        are recomposed from the matrices this leaves.
        """
        found = self._map
        if found is None:
            found = self._map = TranslationMap(self)
        count = 0
        for array in arrays:
            entry = self._arrays.get(id(array))
            if entry is None or entry[0] is not array:
                translations = array[:]
                n = len(translations)
                places = np.fromiter(map(self.index.get, map(id, translations), repeat(-1)), np.intp, n)
                rows = np.flatnonzero(places >= 0)
                entry = self._arrays[id(array)] = (array, places[rows], None if len(rows) == n else rows)
            _, positions, rows = entry
            if not len(positions):
                continue
            offsets = array.offsets
            self.matrices[positions, :3, 3] = offsets if rows is None else offsets[rows]
            hit = np.zeros(len(self.matrices), bool)
            hit[positions] = True
            count += found.apply(self, hit)
            multi = found.multi_items()
            if len(multi):
                count += self._write_items(multi[hit[self.chain[multi]].any(axis=1)])
            if self.instance_items:
                count += self._apply_instances(set(positions.tolist()))
        return count, []

    def apply(self, changed: list[Any]) -> int:
        """Take the new matrices of ``changed`` transforms and rewrite the rows below them; returns the count.

        After :meth:`apply_arrays` in the same frame, the rows it moved are kept in :attr:`moved_rows`.
        """
        if not changed:
            return 0
        if len(changed) <= _FEW:
            return self.apply_few(changed)
        last = self._current_last()
        if last is not None and last[0] is changed:  # the same transforms as last frame (same_as_last)
            _, positions, moved, translations, _ = last
        else:
            # look-ups with C-level loops: thousands of moved transforms per frame cost no Python step each
            found = np.fromiter(map(self.index.get, map(id, changed), repeat(-1)), np.intp, len(changed))
            keep = found >= 0
            positions = found[keep]
            moved = changed if keep.all() else list(compress(changed, keep.tolist()))
            translations = len(moved) >= _MANY and set(map(type, moved)) == {Translation}
            # (kept also when some are not the plan's: one that comes with a splice is a fresh transform, and a
            # splice that brings fresh ones, or a replacement, forgets these look-ups)
            if len(moved) >= _MANY:  # (a few moved, e.g. the transforms a frame's replacements brought: kept as is)
                missing = set() if moved is changed else set(map(id, compress(changed, (~keep).tolist())))
                self._last = (changed, positions, moved, translations, missing)
        if not len(positions):
            return 0
        if translations:
            count = self._apply_translations(positions, moved)
            if count is not None:
                return count
        for cls, members in _by_class(positions.tolist(), moved).items():
            self.matrices[members] = cls.stack_matrices([self.transforms[k] for k in members])
        count = self._apply_items(positions)
        return count + self._apply_instances(set(positions.tolist()))

    def same_as_last(self, changed: list[Any]) -> bool:
        """Whether ``changed`` holds the same transforms, in the same order, as the last :meth:`apply` of many.

        A C-level pass of identity tests; when True, the next :meth:`apply` of
        ``changed`` reuses the last look-ups (where the plan holds them, their classes).
        """
        last = self._last
        if last is None:
            return False
        if last[0] is changed:  # (a journal's batch drained as a whole: its own list, see ChangeJournal.drain)
            return True
        if len(last[0]) != len(changed) or not all(map(is_, changed, last[0])):
            return False
        self._last = (changed, *last[1:])
        return True

    def _apply_translations(self, positions: np.ndarray, moved: list[Any]) -> int | None:
        """Many plain ``Translation`` objects moved (a simulation's setter loop): written like an array's rows.

        The moved offsets go into the plan's matrices, and every row below one
        translation takes its translation column from them
        (:class:`~.translations.TranslationMap`, followed through splices);
        rows below several translations are recomposed from their chains.
        None when fewer than half of the plan's translations moved (the rows
        below the others would be uploaded for nothing).
        """
        found = self._map
        if found is None:
            found = self._map = TranslationMap(self)
        if 2 * len(moved) < found.translations:
            return None
        offsets = Translation.stack_offsets(moved)
        self._put_translations(positions, offsets)
        count = found.apply(self, moved=(positions, offsets))
        multi = found.multi_items()
        if len(multi):
            hit = np.zeros(len(self.matrices), bool)
            hit[positions] = True
            count += self._write_items(multi[hit[self.chain[multi]].any(axis=1)])
        return count + (self._apply_instances(set(positions.tolist())) if self.instance_items else 0)

    def _put_translations(self, positions: np.ndarray, offsets: np.ndarray) -> None:
        """``matrices[positions, :3, 3] = offsets``: through the flat places of those columns, kept while
        ``positions`` is the same object (the last look-ups, :meth:`same_as_last`) and the matrices are."""
        matrices = self.matrices
        flat = self._flat
        if flat is None or flat[0] is not positions or flat[1] is not matrices:
            if not matrices.flags.c_contiguous:  # (no flat view to write through)
                matrices[positions, :3, 3] = offsets
                return
            places = (positions[:, None] * 16 + _COLUMN3).ravel()
            flat = self._flat = (positions, matrices, matrices.reshape(-1), places)
        flat[2][flat[3]] = offsets.reshape(-1)

    def apply_few(self, changed: list[Any]) -> int:
        """A few transforms moved (an editor's drag, one simulated body): the items below them, found through
        :attr:`_users`, are recomposed one by one and their rows marked; nothing is visited per installed item.

        :attr:`rows_only` says afterwards whether :attr:`moved_rows` names every row rewritten (False when an
        item without a batch or an instance set moved)."""
        self.rows_only = True
        users = self._users
        fill = users is None  # the first few-moved frame: every other item's entry of _plain too (below)
        if fill:
            users = self._users_map()
        index = self.index
        matrices = self.matrices
        positions: list[int] = []
        affected: dict[int, None] = {}
        for t in changed:
            k = index.get(id(t))
            if k is None:
                continue
            if t.__class__ is Translation:
                # the rest of a translation's matrix is the identity already (three stores: no view of a slice)
                x, y, z = t.offset
                m = matrices[k]
                m[0, 3] = x
                m[1, 3] = y
                m[2, 3] = z
            else:
                matrices[k] = t.matrix
            positions.append(k)
            found = users.get(id(t))
            if found:
                if len(found) == 1:
                    affected[found[0]] = None
                else:
                    affected.update(dict.fromkeys(found))
        if not positions:
            return 0
        if fill:
            self._fill_plain(affected)
        found_map = self._map
        if found_map is not None and found_map.stale(positions):  # (_follow_maps, asked here: a drag's frames
            # after a simulation's, which made the map, call no method that returns at once)
            self._follow_maps(positions, affected)
        items, plain = self.items, self._plain
        rows_of: dict[int, tuple[Any, list[int]]] = {}
        for i in affected:
            item = items[i]
            chain = item.chain
            slot = item.slot  # (batch, row): what batch_of and row_of hold for it, without numpy look-ups
            only = plain.get(i)
            if only is not None and only[0] is chain and only[1] and slot is not None:
                # the item's row was written as this chain's one translation's matrix (below): only the
                # translation's three numbers change (rows hold M transposed: they lie at 12:15 of the model)
                batch, r = slot
                row = batch.rows[r]
                x, y, z = chain[0].offset
                row[_TX] = x
                row[_TY] = y
                row[_TZ] = z
            else:
                if only is None or only[0] is not chain:  # (a replaced transform gives the item another chain)
                    only = plain[i] = (chain, self._translation_only(i, item))
                values = self._model_row(i, chain, only[1])
                if slot is None:  # an item without a batch (transparent, overlay): its own row
                    item.row[_MODEL] = values
                    self.rows_only = False
                    continue
                batch, r = slot
                batch.rows[r, _MODEL] = values
            batch.row_moved(r)  # (its model alone: whether some row is highlighted holds)
            found = rows_of.get(id(batch))
            if found is None:
                rows_of[id(batch)] = (batch, [r])
            else:
                found[1].append(r)
        moved_rows = self.moved_rows
        for batch, where in rows_of.values():
            moved_rows.append((batch, np.array(where, np.intp)))
        if not self.instance_items:
            return len(affected)
        moved = self._apply_instances(set(positions))
        if moved:
            self.rows_only = False
        return len(affected) + moved

    def _model_row(self, i: int, chain: tuple[Any, ...], translation_only: bool) -> Any:
        """Item ``i``'s model matrix as the 16 numbers of its row (M transposed): with ``translation_only``, its
        chain's one translation's matrix written from its offset in plain floats (the numbers the product
        gives); the whole matrix, not only its translation: the row may hold another transform's (one replaced
        in the chain since it was written)."""
        if translation_only:
            x, y, z = chain[0].offset
            return (1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, x, y, z, 1.0)
        identity = len(self.transforms)
        matrices = self.matrices
        links = [k for k in self.chain[i].tolist() if k != identity]
        model = matrices[links[0]]
        for k in links[1:]:
            model = model @ matrices[k]
        if self.local is not None:
            model = model @ self.local[i]
        return model.ravel("F")  # (M transposed, row by row: one numpy call)

    def _translation_only(self, i: int, item: Any) -> bool:
        """Whether item ``i``'s model matrix is its chain's one ``Translation``'s matrix (no other link; no
        shape-local matrix, or the identity: a product with it changes no number)."""
        chain, local = item.chain, item.local
        if len(chain) != 1 or chain[0].__class__ is not Translation:
            return False
        if local is None:
            return True
        eye = self._eye_local
        if eye is None:  # which items' shape-local matrices are the identity, asked of all at once (C loops)
            held = self.local
            eye = self._eye_local = [] if held is None else (held == _EYE4).all(axis=(1, 2)).tolist()
        if i < len(eye):  # (``local`` holds the items' matrices in their order; spliced items come after)
            return eye[i]
        return local.tolist() == _EYE4_LIST

    def _apply_items(self, positions: np.ndarray) -> int:
        if not len(self.items):
            return 0
        hit = np.zeros(len(self.matrices), bool)
        hit[positions] = True
        affected = np.flatnonzero(hit[self.chain].any(axis=1))
        if not len(affected):
            return 0
        self._follow_maps(positions, affected)
        return self._write_items(affected)

    def _follow_maps(self, positions: Any, affected: np.ndarray | dict[int, None]) -> None:
        """Transforms at ``positions`` moved other than as translations of the map (matrices already taken): the
        translation map fills the ``affected`` items again where their c or L was made from one of them."""
        found = self._map
        if found is not None and found.stale(positions):
            if not isinstance(affected, np.ndarray):  # (a few moved: the items' indices as a dict's keys)
                affected = np.fromiter(affected, np.intp, len(affected))
            found.refill(affected)

    def _write_items(self, affected: np.ndarray) -> int:
        """Recompose the model matrices of the items ``affected`` (indices) from their chains into their rows."""
        if not len(affected):
            return 0
        chain = self.chain[affected]
        models = self.matrices[chain[:, 0]]
        for k in range(1, chain.shape[1]):
            models = models @ self.matrices[chain[:, k]]
        if self.local is not None:
            models = models @ self.local[affected]
        rows = models.transpose(0, 2, 1).reshape(len(affected), 16)  # rows hold M transposed
        owners = self.batch_of[affected]
        order = np.argsort(owners, kind="stable")
        owners = owners[order]
        cuts = np.flatnonzero(np.diff(owners)) + 1
        for part in np.split(order, cuts):
            b = self.batch_of[affected[part[0]]]
            if b < 0:  # items without a batch (transparent, overlay): their own rows
                for p in part:
                    self.items[affected[p]].row[_MODEL] = rows[p]
                continue
            batch = self.batches[b]
            where = self.row_of[affected[part]]
            batch.rows[where, _MODEL] = rows[part]
            if len(where) <= 8:  # a few rows: uploaded one by one, not the range between them
                for w in where.tolist():
                    batch.row_changed(w)
            else:
                batch.changed(int(where.min()), int(where.max()) + 1)
            self.moved_rows.append((batch, where))
        return len(affected)

    def _apply_instances(self, moved: set[int]) -> int:
        count = 0
        for item in self.instance_items:
            chain = [self.index[id(t)] for t in item.chain]
            if moved.isdisjoint(chain):
                continue
            m = self.matrices[chain[0]]
            for k in chain[1:]:
                m = m @ self.matrices[k]
            world = m @ item.instance_models
            item.rows()[:, _MODEL] = world.transpose(0, 2, 1).reshape(len(world), 16)  # (pending ones written first)
            if item.slot is not None:
                batch, _ = item.slot
                batch.rows[:, _MODEL] = item.instances[:, _MODEL]
                batch.changed(0, len(batch.rows))
                self.moved_rows.append((batch, None))
            count += 1
        return count


#: class -> whether it is a static transform (its matrix depends on its parameters only): the lean path's test
_STATIC: dict[type, bool] = {}


def _static_transform(cls: type) -> bool:
    return issubclass(cls, Transform) and bool(cls.static) and not issubclass(cls, TranslationArray)


def _add_user(users: dict[int, list[int]], item: Any, i: int) -> None:
    """Item ``i`` lies below each transform of its chain."""
    for t in dict.fromkeys(item.chain):
        users.setdefault(id(t), []).append(i)


def _drop_user(users: dict[int, list[int]], item: Any, i: int) -> None:
    """Item ``i`` left the plan: its transforms no longer move it."""
    for t in item.chain:
        found = users.get(id(t))
        if found is not None and i in found:
            found.remove(i)


def _by_class(positions: Any, transforms: list[Any]) -> dict[type, list[int]]:
    """Positions grouped by the class of the transform at the same place in ``transforms``."""
    classes = list(map(type, transforms))
    if classes and classes.count(classes[0]) == len(classes):  # one class, the common case: no loop
        return {classes[0]: list(positions)}
    out: dict[type, list[int]] = {}
    for k, t in zip(positions, transforms, strict=True):
        cls = t.__class__
        found = out.get(cls)
        if found is None:
            out[cls] = [k]
        else:
            found.append(k)
    return out


class TransformUpdater:
    """The compile's fast path for moved transforms and instance arrays: a collaborator of the GL engine.

    It owns the :class:`MovePlan` of the installed items (made on the first
    move, followed through splices, dropped when a new list is installed) and
    is handed the render index (whose items and bounds it updates), a callback
    telling the frame that placements changed, and the compiler's
    ``instance_state`` (the draw state of an instance set's template).
    """

    def __init__(
        self,
        index: Any,
        placements_changed: Any,
        instance_state: Any,
        rows_moved: Any = None,
        rows_restyled: Any = None,
    ) -> None:
        self.index = index
        self._placements_changed = placements_changed
        #: tells the frame that only these batches' rows moved in place (it may keep its recorded plan), or None
        self._rows_moved = rows_moved
        #: tells the frame that only these batches' rows' surface fields changed (:meth:`rows_rewritten`), or None
        self._rows_restyled = rows_restyled
        self._instance_state = instance_state
        self._plan: MovePlan | None = None
        #: the draw list's splices the plan has not followed yet, as (removed, added, moved) in order: a frame
        #: that adds or removes a node leaves them to the next frame that moves rows (:meth:`_settled`)
        self._held: list[tuple[list[Any], list[Any], list[Any]]] = []
        #: whether the last :meth:`apply` moved transforms (else only instance sets' arrays changed, which
        #: place no light or camera: the compiler then keeps the scene's declarations)
        self.placed = True
        #: the transforms (and translation arrays) the last :meth:`apply` moved: the compiler asks whether they
        #: may have moved a declared component (``declarations_kept``), and empties it
        self.moved: list[Any] = []

    def forget(self) -> None:
        """A new draw list was installed: the plan is made again on the next move."""
        self._plan = None
        self._held = []

    def splice(self, removed: list[Any], added: list[Any], moved: list[Any]) -> None:
        """Follow the draw list's splice (items removed, added, moved to other rows) when a plan exists.

        The plan follows it when next asked (:meth:`_settled`: the next frame
        that moves rows), together with the splices of the frames between,
        as one :meth:`MovePlan.splice` (:func:`merged_splices`): a frame that
        only adds and removes nodes pays no update of the plan's arrays and
        its translation map.  Only the transforms above new items drawn with
        clip planes are noted now (:meth:`follows` asks them).
        """
        plan = self._plan
        if plan is None:
            return
        _note_clipping(plan.clipping, added)
        held = self._held
        held.append((removed, added, moved))
        if len(held) >= _HELD_SPLICES:  # (nothing moves for long: followed now, the held items let go)
            self._settled()

    def _settled(self) -> MovePlan | None:
        """The plan (or None), having followed the splices held since the last frame that asked."""
        plan = self._plan
        held = self._held
        if held:
            self._held = []
            if plan is not None:
                plan.splice(*merged_splices(held))
        return plan

    def replace(self, swaps: list[tuple[Any, Any, Any]]) -> None:
        """Items' transforms replaced by transforms (``(item, old, new)``, :mod:`.dirty`): each chain takes
        ``new`` at ``old``'s place, and the plan follows; :meth:`apply` of the new transforms then recomposes
        their rows."""
        plan = self._settled()  # (before the chains change: held splices take the items' chains as they were)
        for item, old, new in swaps:
            item.chain = tuple([new if t is old else t for t in item.chain])
        if plan is not None and swaps:
            plan.replace(swaps)

    def rows_rewritten(self, batches: list[Any], same: bool) -> None:
        """The surface fields of rows of ``batches`` were rewritten in place (not moved: the bounds, the
        casters and the shadow maps hold); ``same``: they draw as before, so a recorded frame plan may be
        replayed after their upload."""
        if not same:
            self._placements_changed()
        elif self._rows_restyled is not None:
            self._rows_restyled(batches)
        elif self._rows_moved is not None:
            self._rows_moved(batches)
        else:
            self._placements_changed()

    def plan(self) -> MovePlan:
        """The installed items' :class:`MovePlan` (made now when there is none)."""
        plan = self._settled()
        if plan is None:
            plan = self._plan = MovePlan(list(self.index.items()))
        return plan

    def apply(self, changed: list[Any]) -> int | None:
        """Apply ``changed`` without a traversal when it holds only static transforms and instance sets.

        Returns how many items changed, or None when the compile must run (an
        instance set not installed, or one whose new arrays change how it is
        drawn: translucent now, or mirrored).  Nothing is modified before that
        is known.
        """
        if not changed:
            return None
        if len(changed) == 1 and isinstance(changed[0], InstanceSet):  # a simulation touched its array
            updates = self._instance_updates(changed)
            if updates is None:
                return None
            self.placed = False
            self.moved = []
            return self._install(updates)
        plan = self._settled()
        if plan is not None:
            if len(changed) <= _FEW:
                # an editor's drag, one simulated body: a few static transforms (the lean path, no passes over
                # the list), else the general one below
                statics = _STATIC
                for c in changed:
                    cls = c.__class__
                    static = statics.get(cls)
                    if static is None:
                        static = statics[cls] = _static_transform(cls)
                    if not static:
                        break
                else:
                    if plan.clipping and not plan.clipping.isdisjoint(map(id, changed)):
                        return None  # a clip plane below a moved transform: placed again by a compile
                    self.placed = True
                    self.moved = changed
                    return self._apply_few(plan, changed)
            elif plan.same_as_last(changed):  # a simulation's loop: the same transforms again
                self.placed = True
                self.moved = changed
                return self._apply_moves(changed)
        classes = set(map(type, changed))  # a C-level pass: thousands of moved transforms are one class
        arrays: list[Any] = []
        if TranslationArray in classes:  # touched arrays: their rows are applied at once (the translation map)
            arrays = [c for c in changed if c.__class__ is TranslationArray]
            changed = [c for c in changed if c.__class__ is not TranslationArray]
            classes.discard(TranslationArray)
        if all(issubclass(cls, Transform) and cls.static for cls in classes):
            moved, sets = changed, []
        else:
            moved = []
            sets = []
            for c in changed:
                if isinstance(c, Transform) and c.static:
                    moved.append(c)
                elif isinstance(c, InstanceSet):
                    sets.append(c)
                else:
                    return None
        clipping = self.plan().clipping
        if clipping and (
            not clipping.isdisjoint(map(id, moved)) or any(not clipping.isdisjoint(map(id, a)) for a in arrays)
        ):
            return None  # a clip plane below a moved transform: placed again by a compile
        updates = self._instance_updates(sets) if sets else []
        if updates is None:
            return None
        self.placed = bool(moved or arrays)
        self.moved = [*moved, *arrays]
        count = self._apply_moves(moved, arrays) if self.placed else 0
        return count + (self._install(updates) if updates else 0)

    def follows(self, moves: list[Any]) -> bool:
        """Whether :meth:`apply` of ``moves`` (static transforms, translation arrays) would move rows in place
        with the plan there is (none made for it): a compile that splices new subtrees in the same frame
        leaves them to it."""
        plan = self._plan
        if plan is None:
            return False
        clipping = plan.clipping
        if not clipping:
            return True
        return clipping.isdisjoint(map(id, moves)) and not any(
            not clipping.isdisjoint(map(id, a)) for a in moves if a.__class__ is TranslationArray
        )

    def _install(self, updates: list[tuple[Any, Any]]) -> int:
        """Install instance sets' new rows or moved positions (:meth:`_instance_updates`); returns how many."""
        batches = []
        for item, made in updates:
            if made.__class__ is tuple:  # positions only
                _write_positions(item, *made)
                if item.slot is not None:
                    batches.append(item.slot[0])
            else:
                _install_rows(item, made)
        self.index.moved(None)  # instance rows replaced: every bound again
        # positions only, in opaque batches: a recorded frame plan may be replayed after their upload
        if self._rows_moved is not None and len(batches) == len(updates):
            self._rows_moved(batches)
        else:
            self._placements_changed()
        return len(updates)

    def _instance_updates(self, sets: list[Any]) -> list[tuple[Any, Any]] | None:
        """New rows for every installed item of ``sets``, or None when one cannot be updated in place."""
        plan = self.plan()
        out = []
        for shape in sets if len(sets) == 1 else {id(s): s for s in sets}.values():
            items = plan.sources.get(id(shape))
            if not items:
                return None
            moved = _transforms_only(shape, items)
            if moved is not None and moved.ndim == 2:  # positions
                moves = [_moved_world(item, moved) for item in items]
                # not finite (or beyond float32): the full path, whose compile names the instance and the node
                if _finite(moves):
                    out.extend(zip(items, moves, strict=True))
                    continue
            elif moved is not None:  # matrices: the rows' model columns written, their colours kept
                made = self._moved_matrices(items, moved)
                if made is not None:
                    out.extend(zip(items, made, strict=True))
                    continue
            try:
                matrices, colors, may_mirror = set_arrays(shape)
            except ValueError:
                return None  # a bad array: the compile raises, naming the instance and the set's node
            for item in items:
                if (colors is None) != (item.source_colors is None):
                    # colours given or taken away: the shape is captured again (under the probe colour or not)
                    return None
                template = item.template
                model = _chain_matrix(item.chain)
                try:
                    made = instance_rows(
                        template.row, template.local, template.transparent, model, matrices, colors, may_mirror
                    )
                except ValueError:
                    return None  # beyond float32: as above
                if (
                    made.transparent != item.transparent
                    or self._instance_state(template, made.mirrored) is not item.state
                ):
                    return None
                out.append((item, made))
        return out

    def _moved_matrices(self, items: list[Any], matrices: np.ndarray) -> list[InstanceRows] | None:
        """Rows for the items of a matrix instance set whose matrices alone changed (:func:`_transforms_only`):
        each item's rows with the new model columns (:func:`moved_instance_rows`), or None where the full path
        must decide (a bad matrix, or a mirroring that changes the item's GL state)."""
        matrices = np.array(matrices, dtype=np.float64)  # a copy: the items keep them as their models
        out = []
        for item in items:
            template = item.template
            made = moved_instance_rows(
                item.instances, template.local, item.transparent, _chain_matrix(item.chain), matrices
            )
            if made is None or self._instance_state(template, made.mirrored) is not item.state:
                return None
            out.append(made)
        return out

    def _apply_few(self, plan: MovePlan, changed: list[Any]) -> int:
        """:meth:`_apply_moves` of a few static transforms (no arrays): their items' rows are rewritten, the
        render index's bounds follow them, and the frame keeps its plan when every moved row lies in a batch."""
        plan.moved_rows = []
        count = plan.apply_few(changed)
        if count:
            moved_rows = plan.moved_rows
            self.index.moved(moved_rows)
            if plan.rows_only and self._rows_moved is not None:
                self._rows_moved([batch for batch, _ in moved_rows])
            else:
                self._placements_changed()
        return count

    def _apply_moves(self, changed: list[Any], arrays: list[Any] | None = None) -> int:
        """Recompose the model matrix of every item below a changed transform; returns how many rows changed.

        Touched translation arrays go first, each at once where it can (:meth:`MovePlan.apply_arrays`).
        """
        plan = self.plan()
        plan.moved_rows = []
        count = 0
        if arrays:
            count, general = plan.apply_arrays(arrays)
            if general:
                changed = [*changed, *general]
        count += plan.apply(changed)
        if count:
            # batches of pass masks and predicates follow their source batches' versions (Batch.follow); the
            # bounds follow the moved rows; mirror planes are read from the rows every frame
            self.index.moved(plan.moved_rows)
            batches = _moved_batches(plan.moved_rows, count)
            if batches is None or self._rows_moved is None:
                self._placements_changed()
            else:
                self._rows_moved(batches)
        return count


def merged_splices(splices: list[tuple[list[Any], list[Any], list[Any]]]) -> tuple[list[Any], list[Any], list[Any]]:
    """One splice (removed, added, moved) doing what ``splices`` do one after the other.

    An item added and removed again in between is neither; a moved item
    removed later is only removed; added and moved items are taken where
    they are now (their slots).  The lists hold every item until the merge
    is done, so no two of them share an ``id``.
    """
    if len(splices) == 1:
        return splices[0]
    removed: list[Any] = []
    added: dict[int, Any] = {}
    moved: dict[int, Any] = {}
    for gone, came, shifted in splices:
        for item in gone:
            if added.pop(id(item), None) is None:
                removed.append(item)
            moved.pop(id(item), None)
        for item in came:
            added[id(item)] = item
        for item in shifted:
            moved[id(item)] = item
    return removed, list(added.values()), list(moved.values())


def _note_clipping(clipping: set[int], items: Any) -> None:
    """Add to ``clipping`` the transforms above those of ``items`` that are drawn with clip planes."""
    for item in items:
        if getattr(item.state, "clip", None):
            clipping.update(map(id, item.chain))


def _moved_batches(moved_rows: list[tuple[Any, Any]], count: int) -> list[Any] | None:
    """The batches of ``moved_rows`` when they hold every one of the ``count`` moved items' rows (no item
    without a batch, no instance set's whole batch), else None."""
    batches: dict[int, Any] = {}
    rows = 0
    for batch, where in moved_rows:
        if where is None:
            return None
        rows += len(range(*where.indices(len(batch.rows)))) if isinstance(where, slice) else len(where)
        batches[id(batch)] = batch
    return list(batches.values()) if rows == count else None


def _chain_matrix(chain: tuple[Any, ...]) -> np.ndarray:
    m = np.eye(4)
    for t in chain:
        m = m @ t.matrix
    return m


#: "the set has no colours" in :func:`_transforms_only` (None there means "not read yet")
_NO_COLORS = np.empty((0, 4))


def _transforms_only(shape: Any, items: list[Any]) -> np.ndarray | None:
    """The set's (N, 3) positions or (N, 4, 4) matrices when only they can have changed since its rows were
    made, else None.

    That is: positions (or matrices, without scales), the same count, scales and visibility mask (both
    unwritten since, by ``written_at``, or equal to the rows' copies of them;
    then the visible instances' transforms)
    and the same colours as the items' rows were made from (colours are compared, so
    their conversion to linear is done once, not every frame, unless the set's
    touches since then named only other arrays: ``touch("transforms")``).  Whether they
    are finite is checked on what :func:`_moved_world` or :func:`moved_instance_rows` makes of them.
    """
    scaled = shape.scales is not None
    visible = shape.visible
    if scaled or visible is not None:
        # the same scales and mask as the rows were made with (only touches naming other arrays since): the
        # rows keep their 3x3 parts and the visible instances, and take the moved positions of those
        mask_at = (shape.written_at("scales"), shape.written_at("visible"))
        now = None
        for item in items:
            if scaled and _shifted(item):
                return None  # a shape's local shift would be scaled per instance
            if item.mask_at == mask_at:
                continue
            if now is None:  # a touch that may have written them (a plain one): compared with the rows' copies
                now = held(shape.scales), held(shape.visible)
            if not all(_same(a, b) for a, b in zip(item.source_mask, now, strict=True)):
                return None
            item.mask_at = mask_at  # the same: not compared again until a touch may have written them
    source = shape.transforms
    array = getattr(source, "array", None)
    t = source.array() if callable(array) and not isinstance(source, np.ndarray) else source
    t = np.asarray(t)
    if t.dtype != np.float32 and t.dtype != np.float64:  # float32 is kept: uploaded as it is (_write_positions)
        t = t.astype(np.float64)
    if not (t.ndim == 2 and t.shape[1] == 3) and not (t.ndim == 3 and t.shape[1:] == (4, 4) and not scaled):
        return None
    if visible is not None:
        try:
            v = shape.visible_array()
        except ValueError:
            return None  # the compile names the set
        if v is None or len(v) != len(t):
            return None
        t = t[v]  # the visible instances' positions: the rows are theirs
    colors_at = shape.written_at("colors")
    colors = None
    for item in items:
        if item.instances is None or len(item.instances) != len(t):
            return None
        if item.colors_at == colors_at:  # only other arrays were touched since the colours were converted
            continue
        if colors is None:
            colors = _colors_now(shape)
        before = item.source_colors
        if (before is None) != (colors is _NO_COLORS) or (before is not None and not np.array_equal(before, colors)):
            return None
        item.colors_at = colors_at  # the same colours: not compared again until a touch may have written them
    return t


def _same(before: np.ndarray | None, now: np.ndarray | None) -> bool:
    """Whether an array the rows were made with (a copy, or None) equals the application's now."""
    if before is None or now is None:
        return before is now
    return before.shape == now.shape and bool(np.array_equal(before, now))


def _shifted(item: Any) -> bool:
    """Whether the instance set item's shape has a local matrix that moves it (a translation)."""
    local = item.template.local
    return local is not None and bool(local[:3, 3].any())


def _colors_now(shape: Any) -> np.ndarray:
    """The set's colours as the application holds them (no copy), or :data:`_NO_COLORS`."""
    colors = shape.colors
    if colors is None:
        return _NO_COLORS
    array = getattr(colors, "array", None)
    return np.asarray(colors.array() if callable(array) and not isinstance(colors, np.ndarray) else colors)


def _moved_world(item: Any, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An instance set item's world translations for ``positions`` (the chain, the position, the shape's local).

    Returns a new (N, 3) float32 array of them (the rows' translations, and
    what the next draw uploads as it is) and the translations its
    ``instance_models`` take (float64 where a chain multiplies them later).
    """
    local = item.template.local
    shift = None if local is None or not local[:3, 3].any() else local[:3, 3]
    model = _chain_matrix(item.chain) if item.chain else None
    if model is not None and (model == _EYE4).all():
        model = None
    if model is None:
        # the common case: the application's array (shifted by the shape's local) is the world translations
        world = np.array(positions, dtype=np.float32) if shift is None else np.add(positions, shift, dtype=np.float32)
        # the matrices take them when next read (a transform above the set moved: only items with a chain);
        # without a chain nothing reads them but a fresh compile, so float32 (what the rows hold) is kept
        if not item.chain and shift is None:
            return world, world
        return world, np.array(positions, dtype=np.float64) if shift is None else positions + shift
    offset = positions if shift is None else positions + shift
    if (model[:3, :3] == _EYE3).all():
        world = offset + model[:3, 3]
    else:  # three scaled columns rather than a (N, 3) @ (3, 3) product (BLAS threads cost more than they save)
        world = offset[:, 0:1] * model[:3, 0] + offset[:, 1:2] * model[:3, 1] + offset[:, 2:3] * model[:3, 2]
        world += model[:3, 3]
    return np.ascontiguousarray(world, dtype=np.float32), offset if offset is not positions else np.array(offset)


def _finite(moves: list[tuple[np.ndarray, np.ndarray]]) -> bool:
    """Whether every moved world translation (float32, C-contiguous) is finite: one dot product with zeros each
    (0 unless some value is infinite or NaN; no temporary array)."""
    global _ZEROS
    for world, _ in moves:
        flat = world.reshape(-1)
        if len(_ZEROS) < len(flat):
            _ZEROS = np.zeros(max(len(flat), 2 * len(_ZEROS)), np.float32)
        if np.dot(flat, _ZEROS[: len(flat)]) != 0.0:
            return False
    return True


_ZEROS = np.zeros(0, np.float32)


def _write_positions(item: Any, world: np.ndarray, translations: np.ndarray) -> None:
    """Move an instance set's rows to ``world`` (from :func:`_moved_world`).

    The batch keeps ``world`` as its rows' pending translations and as what the
    next draw uploads to the set's offsets buffer (:meth:`Batch.move_to`); the
    rows themselves are written only when something reads them.
    """
    item.moved_translations = translations
    if item.slot is not None and item.slot[0].holds(item.instances):
        item.slot[0].move_to(world)  # the rows are the item's: written when next read
        return
    set_translations(item.instances, world)
    if item.slot is not None:
        item.slot[0].move_to(world)


def _install_rows(item: Any, made: InstanceRows) -> None:
    """``made`` becomes the item's rows and, where it has one, its batch's (re-culled when the count changed)."""
    item.source_colors = _colors_of(item.source)
    item.colors_at = item.source.written_at("colors")
    item.mask_at = (item.source.written_at("scales"), item.source.written_at("visible"))
    item.source_mask = mask_copies(item.source)
    item.instances = made.rows
    item.instance_models = made.models
    if item.slot is None:
        return
    batch, _ = item.slot
    if len(batch.rows) != len(made.rows):
        batch.position = None  # another count: sorted and culled again
    batch.rows = made.rows
    batch.dirty = None
    if len(made.rows):
        batch.changed(0, len(made.rows))
    else:
        batch.version += 1


def _colors_of(source: Any) -> np.ndarray | None:
    colors = getattr(source, "colors", None)
    if colors is None:
        return None
    array = getattr(colors, "array", None)
    return np.array(colors.array() if callable(array) and not isinstance(colors, np.ndarray) else colors)
