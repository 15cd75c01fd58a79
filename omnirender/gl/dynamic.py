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

from ..core.transform import Transform
from .layout import ROW

__all__ = ["TransformUpdater"]

_MODEL = ROW.slice("model")


class TransformUpdater:
    """Mixin of :class:`~omnirender.gl.engine.GLEngine`: the compile's fast path for moved transforms."""

    def _moved_only(self, changed: list[Any]) -> bool:
        """Whether every changed component is a static transform (the fast path applies)."""
        return bool(changed) and all(isinstance(c, Transform) and c.static for c in changed)

    def _dependents(self) -> dict[int, list[Any]]:
        """Transform id -> the installed draw items whose chain holds it (built once per compile, on demand)."""
        index = self._dependent_index
        if index is None:
            index = {}
            for item in self.draw_items:
                for t in item.chain:
                    found = index.get(id(t))
                    if found is None:
                        index[id(t)] = [item]
                    else:
                        found.append(item)
            self._dependent_index = index
        return index

    def _apply_moves(self, changed: list[Any]) -> int:
        """Recompose the model matrix of every item below a changed transform; returns how many rows changed."""
        index = self._dependents()
        affected: dict[int, Any] = {}
        for t in changed:
            for item in index.get(id(t), ()):
                affected[id(item)] = item
        if not affected:
            return 0
        for item in affected.values():
            chain = item.chain
            m = chain[0].matrix
            for t in chain[1:]:
                m = m @ t.matrix
            if item.local is not None:
                m = m @ item.local
            row = item.row
            row[_MODEL] = m.T.ravel()
            slot = item.slot
            if slot is not None:
                batch, i = slot
                batch.rows[i, _MODEL] = row[_MODEL]
                batch.mark(i)
        for scope in self.scopes:
            if scope.filtered:  # batches of pass masks and predicates copy rows: made again when next drawn
                from .renderer import _release_filtered

                _release_filtered(scope)
        self._bounds = None
        self._caster_bounds = None  # shadow maps are drawn again where the casters moved to
        self._mirrors = None  # mirror planes follow their transforms
        return len(affected)

    def _refresh_declarations(self, scene: Any) -> None:
        """Lights and the camera may sit below a moved transform: take the (incremental) pre-evaluation again."""
        self.declared = self.preevaluate(scene)
        self.camera = self.declared.camera
