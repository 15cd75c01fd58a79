"""Installing compiled scopes as instanced batches (and the batches a pass mask or predicate keeps).

Opaque items are grouped into batches per scope segment (one instanced call
per geometry and state); a newly compiled root scope with the structure of
the installed one rewrites only the changed rows in place.  Drawing them is
the :class:`~.drawer.BatchDrawer`'s job.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...core.mask import compile_mask
from .drawlist import Batch, DrawItem, Scope, Segment, plan_batches, uniform_material
from .geometry import Geometry
from .passes import Composed

__all__ = ["BatchRenderer", "item_filter"]


class BatchRenderer:
    """Mixin of :class:`~omnirender.gl.glengine.GLEngine`: install the compiled scopes as batches.

    (The draw side is the :class:`~.drawer.BatchDrawer` collaborator; this install side becomes one with the
    render index.)
    """

    # -- installing a compiled root scope ------------------------------------------------
    def _install(self, root: Scope) -> None:
        """Make ``root`` the draw list: rewrite changed rows in place when the structure is the same, else re-plan."""
        old = self._root
        self._bounds = None
        self.frame_runner.placements_changed()
        self.draw_list_version += 1
        if old is not None and old is not root and old.entries and _same_shape(old, root):
            self.stats["incremental"] = self._update_in_place(old, root)
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
        self._root = root
        self._item_count = len(root.all_items())
        self._sweep(root)

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
            batch.rows = np.stack([it.row for it in group]) if len(group) > 1 else group[0].rows().copy()
            batch.dirty = (0, len(group))
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

    def _update_in_place(self, old: Scope, new: Scope) -> int:
        """Copy the rows of ``new``'s items into ``old``'s structure (checked to be the same); returns the count."""
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
                        batch.rows = y.instances.copy()
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

    def _sweep(self, root: Scope) -> None:
        """Release GPU objects the new list no longer uses (transient buffers, geometry, textures)."""
        items = root.all_items()
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
