"""Installing compiled scopes as instanced batches (and the batches a pass mask or predicate keeps).

Opaque items are grouped into batches per scope segment (one instanced call
per geometry and state); a newly compiled root scope with the structure of
the installed one rewrites only the changed rows in place.  Drawing them is
the :class:`~.drawer.BatchDrawer`'s job.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ...core.mask import compile_mask
from .drawlist import Batch, DrawItem, Scope, Segment, plan_batches, position_of, uniform_material
from .geometry import Geometry
from .layout import ROW
from .passes import Composed
from .state import not_mirror

_HIGHLIGHT_ON = ROW.at("highlight", "on")

__all__ = ["BatchInstaller", "item_filter"]


class BatchInstaller:
    """Installs compiled root scopes as batches: a collaborator of the GL engine that owns the installed list.

    It holds the installed root scope, the batch pool (batches kept between
    installs by their place), the geometry it uploaded and the draw-list
    version.  It is handed the context (uploads), the render index, the
    :class:`~.dynamic.TransformUpdater` (told about new lists and splices),
    the drawer (which sweeps its transient buffers), the geometry cache, the
    engine's stats and two callbacks: placements changed (the frame runner)
    and a splice that keeps the pipelines scan (the engine).  Drawing is the
    :class:`~.drawer.BatchDrawer`'s job.
    """

    def __init__(
        self,
        ctx: Any,
        index: Any,
        updater: Any,
        drawer: Any,
        geometry_cache: Any,
        stats: dict[str, Any],
        placements_changed: Any,
        spliced: Any,
        rows_spliced: Any = None,
    ) -> None:
        self.ctx = ctx
        self.index = index
        self.updater = updater
        self.drawer = drawer
        self.geometry_cache = geometry_cache
        self.stats = stats
        self._placements_changed = placements_changed
        self._spliced = spliced
        #: tells the frame that a splice only edited rows of existing batches (it may keep its plan), or None
        self._rows_spliced = rows_spliced
        #: the installed root scope (None before the first install)
        self.root: Scope | None = None
        #: bumped whenever a compiled draw list is installed (per-frame caches of techniques key on it)
        self.version = 0
        self._batch_pool: dict[tuple, Batch] = {}
        #: (segment, root, id(item) -> place) of a one-segment root, for splices (_places_of)
        self._places: tuple[Segment, Scope, dict[int, int]] | None = None
        self._uploaded_set: weakref.WeakSet[Geometry] = weakref.WeakSet()

    # -- installing a compiled root scope ------------------------------------------------
    def install(self, root: Scope) -> None:
        """Make ``root`` the draw list: rewrite changed rows in place when the structure is the same, else re-plan."""
        old = self.root
        self.version += 1
        self.updater.forget()
        self._placements_changed()  # stages of users may derive things from placements
        if old is not None and old is not root and old.entries and _same_shape(old, root):
            self.stats["incremental"] = self._update_in_place(old, root)
            self.index.install(old)
            return
        self.stats["incremental"] = None
        pool = self._batch_pool
        self._batch_pool = {}
        self._plan(root, (), pool)
        for batch in pool.values():
            batch.release()
        if old is not None and old is not root:
            for scope in old.walk():
                _release_filtered(scope)
        self.root = root
        self.index.install(root)
        self._sweep(root)

    def live_buffers(self) -> int:
        """GPU buffers of the uploaded geometry and of the batches (pooled and filtered) held now."""
        n = sum(len(g.buffers) for g in self._uploaded_set if g.buffers is not None)
        n += sum(1 for b in self._batch_pool.values() if b.buffer is not None)
        scopes = [] if self.root is None else self.root.walk()
        n += sum(1 for s in scopes for group in s.filtered.values() for bs in group.values() for b in bs
                 if b.buffer is not None)  # fmt: skip
        return n

    def release(self) -> None:
        """Free the batches (pooled and filtered) and the uploaded geometry; nothing is installed afterwards."""
        for batch in self._batch_pool.values():
            batch.release()
        self._batch_pool.clear()
        for scope in [] if self.root is None else self.root.walk():
            for group in scope.filtered.values():
                for batches in group.values():
                    for batch in batches:
                        batch.release()
        for g in list(self._uploaded_set):
            g.release()
        self.root = None

    def _plan(self, scope: Scope, where: tuple, pool: dict[tuple, Batch]) -> None:
        parts: list[Segment | Scope] = []
        run: list[DrawItem] = []

        def flush() -> None:
            if run:
                parts.append(self._segment(list(run), (*where, len(parts)), pool))
                run.clear()

        for entry in scope.entries:
            if isinstance(entry, Scope):
                flush()
                self._plan(entry, (*where, len(parts)), pool)
                parts.append(entry)
            else:
                run.append(entry)
        flush()
        scope.parts = parts
        scope.positions = None
        scope.filtered = {}

    def _segment(self, items: list[DrawItem], where: tuple, pool: dict[tuple, Batch]) -> Segment:
        segment = Segment(items)
        groups, slots = plan_batches(items)
        batches: dict[tuple, Batch] = {}
        for key, group in groups.items():
            pool_key = (where, *key)
            batch = pool.pop(pool_key, None)
            if batch is None:
                batch = Batch(key[0], key[1])
            batch.items = group
            filtered = bool(where) and where[0] == "filtered"
            if group[0].instances is None and not filtered:
                batch.hold(np.stack([it.row for it in group]))  # spare rows: items added later keep the views
            elif not filtered:
                # an instance set's batch: its item's rows themselves, so a move writes them once (dynamic.py)
                batch.rows = group[0].rows()  # (translations a move left pending in its old batch written)
                batch.storage = None
            else:
                batch.rows = group[0].rows().copy() if len(group) == 1 else np.stack([it.row for it in group])
                batch.storage = None
            batch.dirty = (0, len(group))
            batch.sparse = None
            batch.uniform = uniform_material(batch.rows)
            batch.sorted_for = None
            batch.position = None
            batches[key] = batch
            self._batch_pool[pool_key] = batch
        segment.batches = list(batches.values())
        segment.slots = [None if s is None else (batches[s[0]], s[1]) for s in slots]
        if where and where[0] == "filtered":
            for batch in segment.batches:
                _select_from_source(batch)
        else:
            for item, slot in zip(items, segment.slots, strict=True):
                item.slot = slot
                if slot is not None and item.instances is None:
                    # the item's row becomes its batch row: a moved transform writes the row once (dynamic.py)
                    item.row = slot[0].rows[slot[1]]
        return segment

    def splice(self, removed: list[Any], added: list[Any]) -> bool:
        """Take ``removed`` out of the installed draw list and put ``added`` in, patching batch rows in place.

        A removed row is filled by its batch's last row; an added item becomes
        the last row of the batch of its geometry and state in the root
        scope's last segment (a new batch when there is none).  Only the
        changed rows are uploaded (:meth:`Batch.append_row`, :meth:`Batch.remove_row`);
        the batches that passes filter from them follow.  Returns False, with
        nothing changed, for what this does not handle: nested technique
        scopes, instance sets, states whose order matters.
        """
        root = self.root
        if root is None or not root.parts or not isinstance(root.parts[-1], Segment):
            return False
        last = root.parts[-1]
        segments = [p for p in root.parts if isinstance(p, Segment)]
        if any(b.state.special for b in last.batches):
            return False
        for item in (*removed, *added):
            if not isinstance(item, DrawItem) or item.instances is not None or item.state.special or item.techniques:
                return False
        owner: dict[int, Segment] = {id(b): seg for seg in segments for b in seg.batches}
        for item in removed:
            if item.slot is not None and id(item.slot[0]) not in owner:
                return False
            if item.slot is None and not (item.transparent or item.state.overlay):
                return False
        uniform = {id(b): b.uniform for seg in segments for b in seg.batches}  # before the edits
        ops: dict[int, tuple[Batch, list[tuple[Any, ...]]]] = {}  # id(batch) -> its row edits, in order
        moved_items: list[DrawItem] = []
        places: list[int] = []  # where each removed item was in the root's entries (the index's list follows)
        where = self._places_of(root)
        for item in removed:
            if where is not None:
                places.append(self._take_out(root, last, where, item, ops, moved_items))
            else:
                places.append(_take_out_searching(root, segments, owner, item, ops, moved_items))
        by_key = {(id(b.geometry), id(b.state)): b for b in last.batches}
        new_batch = False
        for item in added:
            if item.transparent or item.state.overlay:
                last.others.append(item)
            else:
                batch = by_key.get((id(item.geometry), id(item.state)))
                if batch is None:
                    batch = by_key[(id(item.geometry), id(item.state))] = Batch(item.geometry, item.state)
                    batch.hold(np.empty((0, ROW.stride), np.float32))
                    batch.uniform = True
                    last.batches.append(batch)
                    self._batch_pool[(("spliced", id(batch)),)] = batch
                    new_batch = True
                index = batch.append_row(item)
                ops.setdefault(id(batch), (batch, []))[1].append(("append", index, item))
            if where is not None:
                where[id(item)] = len(root.entries)
            last.items.append(item)
            last.slots.append(item.slot)
            root.entries.append(item)
        root.positions = None
        if new_batch:
            _release_filtered(root)
        else:
            self._follow_splice(root, ops)
        self.index.spliced(removed, added, places, swapped=where is not None)
        kept = {id(it.geometry) for it in added}
        # what only removed items used is released: nothing while their batches keep rows (the same geometry
        # and state: textures) and none was drawn alone (transparent, overlay: transient buffers)
        orphans = any(it.transparent or it.state.overlay for it in removed) or any(not b.size for b, _ in ops.values())
        sweep = orphans and any(id(it.geometry) not in kept or it.state.textures or it.transparent for it in removed)
        rows_only = _rows_only(
            self._rows_spliced is not None and not (new_batch or sweep), removed, added, ops, uniform
        )
        if not rows_only:
            self._placements_changed()
        if sweep:
            # what only removed items used is released now (their geometry, textures, transient buffers)
            parts = [p for scope in root.walk() for p in (scope.parts or []) if isinstance(p, Segment)]
            self._sweep(root, [b.items[0] for p in parts for b in p.batches if b.items] + [
                it for p in parts for it in p.others])  # fmt: skip
        for batch, edits in ops.values():
            self.index.batch_edits(batch, edits)
        version = self.version
        self.version += 1
        if rows_only:  # after the version moved: a kept frame plan takes the new one
            self._rows_spliced([batch for batch, _ in ops.values()])
        self._spliced(version, added)
        self.updater.splice(removed, added, moved_items)
        return True

    def _places_of(self, root: Scope) -> dict[int, int] | None:
        """id(item) -> its place in ``root.entries`` when the root is one segment (no nested scope): its items
        and slots are then the entries in the same order, and a splice removes an entry by moving the last one
        into its place (no search, no shift).  Made on the first splice after an install, then kept."""
        parts = root.parts
        if parts is None or len(parts) != 1 or not isinstance(parts[0], Segment):
            self._places = None
            return None
        held = self._places
        if held is not None and held[0] is parts[0] and held[1] is root:
            return held[2]
        segment = parts[0]
        if len(segment.items) != len(root.entries):
            return None
        where = {id(it): i for i, it in enumerate(root.entries)}
        self._places = (segment, root, where)
        return where

    def _take_out(
        self,
        root: Scope,
        segment: Segment,
        where: dict[int, int],
        item: DrawItem,
        ops: dict[int, tuple[Batch, list[tuple[Any, ...]]]],
        moved_items: list[DrawItem],
    ) -> int:
        """Remove ``item`` from a one-segment root (see :meth:`_places_of`) and from its batch; returns its
        place, which the root's last entry now takes."""
        at = where.pop(id(item))
        end = len(root.entries) - 1
        if at != end:
            tail = root.entries[end]
            root.entries[at] = segment.items[at] = tail
            segment.slots[at] = segment.slots[end]
            where[id(tail)] = at
        root.entries.pop()
        segment.items.pop()
        segment.slots.pop()
        if item.slot is None:
            segment.others.remove(item)
            return at
        batch, index = item.slot
        moved = batch.remove_row(index)
        ops.setdefault(id(batch), (batch, []))[1].append(("remove", index, moved))
        if moved is not None:
            shifted = batch.items[index]
            segment.slots[where[id(shifted)]] = shifted.slot
            moved_items.append(shifted)
        return at

    def _follow_splice(self, scope: Scope, ops: dict[int, tuple[Batch, list[tuple[Any, ...]]]]) -> None:
        """Patch the rows the scope's filtered batches select after rows of their sources were removed or added.

        A filtered batch keeps its picks (source row indices, ascending) and
        items in the same order: a removed row's pick goes, the pick of the row
        that moved into its place takes the new index, an appended row that
        the filter keeps is picked last.
        """
        for key, views in scope.filtered.items():
            keep = None
            for group in views.values():
                for batch in group:
                    found = ops.get(id(batch.source)) if batch.source is not None else None
                    if found is None or batch.picks is None:
                        continue
                    picks = batch.picks
                    for op, index, arg in found[1]:
                        if op == "remove":
                            at = int(np.searchsorted(picks, index))
                            if at < len(picks) and picks[at] == index:
                                picks = np.delete(picks, at)
                                del batch.items[at]
                            if arg is not None:  # row `arg` (the last) now sits at `index`
                                at = int(np.searchsorted(picks, arg))
                                if at < len(picks) and picks[at] == arg:
                                    item = batch.items.pop(at)
                                    picks = np.delete(picks, at)
                                    to = int(np.searchsorted(picks, index))
                                    picks = np.insert(picks, to, index)
                                    batch.items.insert(to, item)
                        else:
                            if keep is None:
                                keep = item_filter(_Selection(*key))
                            if keep(arg):  # appended: the largest index
                                picks = np.append(picks, index)
                                batch.items.append(arg)
                    batch.picks = picks
                    batch.source_version = -1  # rows taken again by the next follow()

    def _update_in_place(self, old: Scope, new: Scope) -> int:
        """Copy the rows of ``new``'s items into ``old``'s structure (checked to be the same); returns the count."""
        self._places = None  # entries are replaced: the splices' map is made again
        changed = 0
        stack = [(old, new)]
        while stack:
            a, b = stack.pop()
            differ = [i for i, (x, y) in enumerate(zip(a.entries, b.entries, strict=True)) if x is not y]
            if not differ:
                continue
            where = a.positions
            if where is None:
                where = a.positions = _positions(a)
            touched = regroup = False
            for i in differ:
                x, y = a.entries[i], b.entries[i]
                if isinstance(x, Scope):
                    stack.append((x, y))  # type: ignore[arg-type]
                    continue
                a.entries[i] = y
                segment, position = where[i]
                segment.items[position] = y
                slot = segment.slots[position]
                if slot is None:
                    segment.others = [it for it in segment.items if it.transparent or it.state.overlay]
                else:
                    batch, index = slot
                    batch.items[index] = y
                    y.slot = slot
                    if y.instances is not None:  # an instance set's array: the whole batch, maybe another length
                        if len(batch.rows) != len(y.instances):
                            batch.position = None  # sorted and culled again
                        batch.settle()  # the replaced item's rows take what a move left pending
                        batch.rows = y.rows()  # the item's rows themselves (written once by a move)
                        batch.dirty = None
                        batch.changed(0, len(batch.rows))
                        batch.uniform = uniform_material(batch.rows)
                        changed += 1
                        touched = regroup = True
                        continue
                    x.row = x.row.copy()  # the replaced item keeps its values; its batch row is y's now
                    batch.rows[index] = y.row
                    y.row = batch.rows[index]
                    batch.mark(index)
                    if x.groups != y.groups:
                        regroup = True  # what pass masks and predicates select may differ: filter again
                    else:
                        _replace_in_views(a, batch, index, y)
                    if batch.uniform and not uniform_material(batch.rows[[0, index]]):
                        batch.uniform = False
                changed += 1
                touched = True
            if touched and regroup:
                _release_filtered(a)
        return changed

    def _sweep(self, root: Scope, items: list[DrawItem] | None = None) -> None:
        """Release GPU objects the new list no longer uses (transient buffers, geometry, textures).

        ``items``: the items to keep what they use (default: every item; after a splice, one item per batch
        and the unbatched items, which use the same geometry, states and textures).
        """
        items = self.index.items() if items is None else items
        used = {id(it.geometry) for it in items}
        self.drawer.sweep(items)
        self.geometry_cache.sweep(used)
        for geom in list(self._uploaded_set):
            if id(geom) not in used and not geom.persistent:
                geom.release()

    def upload(self, geometry: Geometry) -> None:
        """Make sure ``geometry`` has its GPU buffers (drawers call it)."""
        if geometry.buffers is None:
            geometry.upload(self.ctx)
            self._uploaded_set.add(geometry)

    # -- drawing a scope's items in a pass -----------------------------------------------

    def filtered_batches(self, scope: Scope, composed: Composed) -> dict[int, list[Batch]]:
        """Batches of the opaque items a mask/predicate keeps, per segment index (cached until the scope changes)."""
        key = (composed.masks, composed.selects)
        cached = scope.filtered.get(key)
        if cached is not None:
            for batches in cached.values():
                for batch in batches:
                    batch.follow()  # rows moved or changed in place since: copied again, nothing re-planned
            return cached
        keep = item_filter(composed)
        out: dict[int, list[Batch]] = {}
        for index, part in enumerate(scope.parts or []):
            if isinstance(part, Segment):
                kept = [it for it in part.items if keep(it)]
                out[index] = self._segment(kept, ("filtered", id(scope), key, index), {}).batches if kept else []
        scope.filtered[key] = out
        return out

    # -- batches -----------------------------------------------------------------------


class _Selection:
    """The masks and predicates of a filtered selection (its cache key), as :meth:`_accepts` reads them."""

    __slots__ = ("masks", "selects")

    def __init__(self, masks: Any, selects: Any) -> None:
        self.masks, self.selects = masks, selects


def item_filter(composed: Composed) -> Any:
    """The predicate of the items ``composed``'s group masks and ``select`` predicates keep."""
    masks = [compile_mask(m) for m in composed.masks]
    selects = composed.selects

    def keep(item: DrawItem) -> bool:
        for mask in masks:
            for groups in item.groups:
                if not mask(groups):
                    return False
        return all(select(item) for select in selects)

    return keep


def _take_out_searching(
    root: Scope,
    segments: list[Segment],
    owner: dict[int, Segment],
    item: DrawItem,
    ops: dict[int, tuple[Batch, list[tuple[Any, ...]]]],
    moved_items: list[DrawItem],
) -> int:
    """Remove ``item`` from a root of several segments (its place looked for near where it probably is) and
    from its batch; returns its place in the root's entries (the later entries move up)."""
    if item.slot is not None:
        batch, index = item.slot
        segment = owner[id(batch)]
        at = position_of(segment.items, item, index)  # a batch's rows keep roughly the segment's order
        del segment.items[at]
        del segment.slots[at]
        moved = batch.remove_row(index)
        ops.setdefault(id(batch), (batch, []))[1].append(("remove", index, moved))
        if moved is not None:
            shifted = batch.items[index]
            segment.slots[position_of(segment.items, shifted)] = shifted.slot
            moved_items.append(shifted)
    else:
        segment = next(seg for seg in segments if any(x is item for x in seg.others))
        at = position_of(segment.items, item)
        del segment.items[at]
        del segment.slots[at]
        segment.others.remove(item)
    place = position_of(root.entries, item, at)  # one segment: the same place
    del root.entries[place]
    return place


def _rows_only(
    possible: bool,
    removed: list[DrawItem],
    added: list[DrawItem],
    ops: dict[int, tuple[Batch, list[tuple[Any, ...]]]],
    uniform: dict[int, bool],
) -> bool:
    """Whether a splice only edited rows of batches that are drawn the same way (``possible``: no batch made,
    nothing released): opaque plain items (no mirror, no highlight), batches of two rows or more before and
    after whose material sharing did not change (their program, vertex arrays and uniforms stay the ones a
    recorded frame plan holds)."""
    if not possible:
        return False
    for item in (*removed, *added):
        if item.transparent or item.state.overlay:
            return False
        if not not_mirror(item) or item.row[_HIGHLIGHT_ON] > 0.0:
            return False
    for batch, edits in ops.values():
        n = batch.size
        if n < 2 or n + sum(1 if op == "remove" else -1 for op, _, _ in edits) < 2:
            return False
        if uniform.get(id(batch)) is not batch.uniform:
            return False
    return True


def _same_shape(old: Scope, new: Scope) -> bool:
    """Whether ``new`` has ``old``'s structure: same techniques, and per item the same geometry, state, class."""
    stack = [(old, new)]
    while stack:
        a, b = stack.pop()
        if a.technique is not b.technique or len(a.entries) != len(b.entries):
            return False
        for x, y in zip(a.entries, b.entries, strict=True):
            if x is y:
                continue
            if isinstance(x, Scope):
                if not isinstance(y, Scope):
                    return False
                stack.append((x, y))
            elif (
                isinstance(y, Scope)
                or x.geometry is not y.geometry
                or x.state is not y.state
                or x.transparent != y.transparent
            ):
                return False
    return True


def _positions(scope: Scope) -> dict[int, tuple[Segment, int]]:
    """Entry index -> (segment, position in it) for the items of a planned scope."""
    out: dict[int, tuple[Segment, int]] = {}
    parts = iter(scope.parts or [])
    segment: Segment | None = None
    position = 0
    for i, entry in enumerate(scope.entries):
        if isinstance(entry, Scope):
            segment = None
            continue
        if segment is None or position == len(segment.items):
            part = next(parts)
            while isinstance(part, Scope):
                part = next(parts)
            segment, position = part, 0
        out[i] = (segment, position)
        position += 1
    return out


def _select_from_source(batch: Batch) -> None:
    """Make a filtered batch follow the batch its items come from (their slots), when they all come from one."""
    first = batch.items[0].slot
    if first is None or any(it.slot is None or it.slot[0] is not first[0] for it in batch.items):
        return  # not from one planned batch: made again when the scope is
    source = first[0]
    if batch.items[0].instances is not None:
        batch.picks = None  # an instance set: all its rows
    else:
        batch.picks = np.fromiter((it.slot[1] for it in batch.items), np.int64, len(batch.items))
    batch.source = source
    batch.source_version = source.version


def _replace_in_views(scope: Scope, source: Batch, index: int, item: DrawItem) -> None:
    """``item`` replaced row ``index`` of ``source``: put it into the scope's filtered batches that select it."""
    for batches in scope.filtered.values():
        for group in batches.values():
            for batch in group:
                if batch.source is not source or batch.picks is None:
                    continue
                j = int(np.searchsorted(batch.picks, index))
                if j < len(batch.picks) and batch.picks[j] == index:
                    batch.items[j] = item


def _release_filtered(scope: Scope) -> None:
    for batches in scope.filtered.values():
        for group in batches.values():
            for batch in group:
                batch.release()
    scope.filtered = {}
