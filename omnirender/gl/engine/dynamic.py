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

from typing import Any

import numpy as np

from ...core.transform import Transform
from ...shapes import InstanceSet
from .instancing import InstanceRows, instance_rows, set_arrays
from .layout import ROW

__all__ = ["MovePlan", "TransformUpdater"]

_MODEL = ROW.slice("model")


class MovePlan:
    """The installed items' transform chains as arrays, so moved transforms recompose many rows at once.

    ``chain[i, k]`` indexes ``matrices`` (the last entry is the identity,
    padding shorter chains); ``local`` holds the shape-local matrices (the
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

    def apply(self, changed: list[Any]) -> int:
        """Take the new matrices of ``changed`` transforms and rewrite the rows below them; returns the count."""
        index = self.index
        moved = [(k, t) for t in changed if (k := index.get(id(t))) is not None]
        if not moved:
            return 0
        positions = [k for k, _ in moved]
        for cls, members in _by_class(positions, [t for _, t in moved]).items():
            self.matrices[members] = cls.stack_matrices([self.transforms[k] for k in members])
        count = self._apply_items(np.array(positions, np.intp))
        return count + self._apply_instances(set(positions))

    def _apply_items(self, positions: np.ndarray) -> int:
        if not len(self.items):
            return 0
        hit = np.zeros(len(self.matrices), bool)
        hit[positions] = True
        affected = np.flatnonzero(hit[self.chain].any(axis=1))
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
            batch.changed(int(where.min()), int(where.max()) + 1)
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
            item.instances[:, _MODEL] = world.transpose(0, 2, 1).reshape(len(world), 16)
            if item.slot is not None:
                batch, _ = item.slot
                batch.rows[:, _MODEL] = item.instances[:, _MODEL]
                batch.changed(0, len(batch.rows))
            count += 1
        return count


def _by_class(positions: Any, transforms: list[Any]) -> dict[type, list[int]]:
    """Positions grouped by the class of the transform at the same place in ``transforms``."""
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
    """Mixin of :class:`~omnirender.gl.engine.GLEngine`: the compile's fast path for moved transforms and arrays."""

    def _moves(self) -> MovePlan:
        plan = self._move_plan
        if plan is None:
            plan = self._move_plan = MovePlan(self.draw_items)
        return plan

    def _apply_changes(self, changed: list[Any]) -> int | None:
        """Apply ``changed`` without a traversal when it holds only static transforms and instance sets.

        Returns how many items changed, or None when the compile must run (an
        instance set not installed, or one whose new arrays change how it is
        drawn: translucent now, or mirrored).  Nothing is modified before that
        is known.
        """
        if not changed:
            return None
        moved: list[Any] = []
        sets: list[Any] = []
        for c in changed:
            if isinstance(c, Transform) and c.static:
                moved.append(c)
            elif isinstance(c, InstanceSet):
                sets.append(c)
            else:
                return None
        updates = self._instance_updates(sets) if sets else []
        if updates is None:
            return None
        count = self._apply_moves(moved) if moved else 0
        for item, made in updates:
            _install_rows(item, made)
        if updates:
            self._invalidate_moved()
        return count + len(updates)

    def _instance_updates(self, sets: list[Any]) -> list[tuple[Any, InstanceRows]] | None:
        """New rows for every installed item of ``sets``, or None when one cannot be updated in place."""
        plan = self._moves()
        out = []
        for shape in {id(s): s for s in sets}.values():
            items = plan.sources.get(id(shape))
            if not items:
                return None
            matrices, colors, may_mirror = set_arrays(shape)
            for item in items:
                template = item.template
                model = _chain_matrix(item.chain)
                made = instance_rows(
                    template.row, template.local, template.transparent, model, matrices, colors, may_mirror
                )
                if (
                    made.transparent != item.transparent
                    or self.instance_state(template, made.mirrored) is not item.state
                ):
                    return None
                out.append((item, made))
        return out

    def _apply_moves(self, changed: list[Any]) -> int:
        """Recompose the model matrix of every item below a changed transform; returns how many rows changed."""
        count = self._moves().apply(changed)
        if count:
            self._invalidate_moved()
        return count

    def _invalidate_moved(self) -> None:
        """What depends on where items are: filtered batches, bounds, shadow maps, mirror planes."""
        # batches of pass masks and predicates follow their source batches' versions (Batch.follow)
        self._bounds = None
        self.frame_runner.placements_changed()  # shadow maps and mirror planes follow what moved

    def _refresh_declarations(self, scene: Any) -> None:
        """Lights and the camera may sit below a moved transform: take the (incremental) pre-evaluation again."""
        self.declared = self.preevaluate(scene)
        self.camera = self.declared.camera


def _chain_matrix(chain: tuple[Any, ...]) -> np.ndarray:
    m = np.eye(4)
    for t in chain:
        m = m @ t.matrix
    return m


def _install_rows(item: Any, made: InstanceRows) -> None:
    """``made`` becomes the item's rows and, where it has one, its batch's (re-culled when the count changed)."""
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
