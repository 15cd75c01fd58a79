"""Collision detection between the shapes tagged ``Collidable`` (triangle level).

The :class:`CollisionEngine` (service ``"collide"``) evaluates only what matters:
an outermost shape not under an enabled ``Collidable`` is skipped before any
handler runs, so untagged subgraphs are never tessellated.  Tagged shapes end
as world-space triangles (triangle sets directly, everything else through its
simplifier), grouped into *bodies* by node path: the shapes of one node form
one body and are not tested against each other.

Then a broad phase compares body boxes, keeps only the triangles inside the
other body's box, queries a BVH with triangle boxes, and the narrow phase runs
a vectorised separating-axis test on the remaining triangle pairs.  Touching
counts as colliding; one body inside another without touching does not.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..attributes import Collidable
from ..core.handler import ShapePainter, default_for
from ..geometry import intersect as gi
from ..geometry.bvh import BVH
from ..shapes import InstanceId, LineSet, PointSet, Polyline, TriangleSet
from .base import AnalysisEngine, run_analysis

__all__ = ["CollisionEngine", "collisions", "bodies_collide"]

COLLIDE = "collide"


class CollisionEngine(AnalysisEngine):
    """Collects world triangles of collidable shapes in ``bodies``, one body per outermost shape.

    A body's key is ``(node path, index, instance)``: the index of the shape
    among the shapes evaluated directly in that node (0-based, in the node's
    order, counting untagged shapes too), so it stays the same whatever else is
    tagged, and the instance of an ``om.InstanceSet`` (-1 outside one).
    """

    service = COLLIDE

    def __init__(self, *, mask: Any = None, on_missing: str = "warn") -> None:
        super().__init__(mask=mask, on_missing=on_missing)
        self.bodies: dict[tuple[str, int, int], list[np.ndarray]] = {}
        self.skipped = 0
        self._counts: dict[str, int] = {}
        self._key: tuple[str, int] = ("", 0)

    def accepts(self, shape: Any) -> bool:
        path = self.node_path
        index = self._counts.get(path, 0)
        self._counts[path] = index + 1
        tag = self.mono(Collidable)
        if tag is None or not tag.enabled:
            self.skipped += 1
            return False
        self._key = (path, index)
        return True

    def collect(self, triangles: np.ndarray) -> None:
        """Add world-space triangles (K, 3, 3) to the body of the outermost shape being evaluated.

        Each instance of an ``om.InstanceSet`` is a body of its own (its
        simplifier marks the instances with ``InstanceId``).
        """
        if len(triangles):
            ids = self.poly(InstanceId)
            key = (*self._key, ids[-1].index if ids else -1)
            self.bodies.setdefault(key, []).append(triangles)

    def labels(self) -> dict[tuple[str, int, int], str]:
        """Report names of the bodies: the node path, plus ``#index`` when several shapes of one node are
        bodies, plus ``[instance]`` for the instances of an instance set."""
        per_path: dict[str, set[int]] = {}
        for path, index, _ in self.bodies:
            per_path.setdefault(path, set()).add(index)
        out = {}
        for p, i, k in self.bodies:
            name = p if len(per_path[p]) == 1 else f"{p}#{i}"
            out[(p, i, k)] = name if k < 0 else f"{name}[{k}]"
        return out


@default_for(CollisionEngine)
class TriangleSetCollector(ShapePainter):
    """World-space triangles of a triangle set."""

    __slots__ = ()
    service = COLLIDE
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: CollisionEngine) -> None:
        m = engine.model_matrix()
        v = shape.vertex_array().astype(np.float64) @ m[:3, :3].T + m[:3, 3]
        engine.collect(v[shape.index_array()])


class _NoVolume(ShapePainter):
    __slots__ = ()
    service = COLLIDE

    def exec(self, shape: Any, engine: CollisionEngine) -> None:
        return None


@default_for(CollisionEngine)
class LineSetCollector(_NoVolume):
    __slots__ = ()
    target = LineSet


@default_for(CollisionEngine)
class PolylineCollector(_NoVolume):
    __slots__ = ()
    target = Polyline


@default_for(CollisionEngine)
class PointSetCollector(_NoVolume):
    __slots__ = ()
    target = PointSet


def bodies_collide(a: np.ndarray, b: np.ndarray, chunk: int = 65536) -> bool:
    """Whether two triangle soups (K, 3, 3) intersect or touch anywhere."""
    if not len(a) or not len(b):
        return False
    lo_a, hi_a = gi.triangle_bounds(a)
    lo_b, hi_b = gi.triangle_bounds(b)
    scale = float(max(np.ptp(np.concatenate([lo_a, hi_a, lo_b, hi_b]), axis=0).max(), 1e-300))
    eps = 1e-9 * scale
    box_a = (lo_a.min(axis=0) - eps, hi_a.max(axis=0) + eps)
    box_b = (lo_b.min(axis=0) - eps, hi_b.max(axis=0) + eps)
    if not gi.boxes_overlap(box_a[0], box_a[1], box_b[0], box_b[1]):
        return False
    # keep only the triangles inside the other body's box
    keep_a = np.nonzero(gi.boxes_overlap(lo_a, hi_a, box_b[0], box_b[1]))[0]
    keep_b = np.nonzero(gi.boxes_overlap(lo_b, hi_b, box_a[0], box_a[1]))[0]
    if not len(keep_a) or not len(keep_b):
        return False
    if len(keep_a) > len(keep_b):
        a, b, keep_a, keep_b, lo_a, hi_a = b, a, keep_b, keep_a, lo_b, hi_b
    tree = BVH(b[keep_b].reshape(-1, 3), np.arange(3 * len(keep_b)).reshape(-1, 3))
    # query in chunks so that the first intersecting pair ends the search
    for start in range(0, len(keep_a), 8192):
        part = keep_a[start : start + 8192]
        qa, qb = tree.query_boxes(lo_a[part] - eps, hi_a[part] + eps)
        for s in range(0, len(qa), chunk):
            ta = a[part[qa[s : s + chunk]]]
            tb = b[keep_b[qb[s : s + chunk]]]
            if np.any(gi.triangles_intersect(ta, tb, eps)):
                return True
    return False


def collisions(scene: Any, mask: str | None = None) -> list[tuple[str, str]]:
    """Pairs ``(a, b)``, a < b, of collidable shapes that intersect at triangle level, named by path.

    Each outermost shape tagged ``Collidable`` is one body, named by its node
    path; when several collidable shapes sit in the same node their names get
    the suffix ``#i``, the shape's 0-based index among the node's shapes
    (``"/scene/a#1"``); the instances of an ``om.InstanceSet`` are bodies of
    their own, named with their index (``"/scene/swarm[3]"``).  The parts of one
    simplified shape (an Arrow's shaft and head) never collide with each other.  A subgraph is tested where it
    sits in its graph.
    """
    engine = CollisionEngine(mask=mask)
    run_analysis(engine, "collisions", scene, mask)
    labels = engine.labels()
    keys = sorted(engine.bodies, key=lambda k: labels[k])
    soups = {k: np.concatenate(engine.bodies[k]) for k in keys}
    boxes = {k: (s.reshape(-1, 3).min(axis=0), s.reshape(-1, 3).max(axis=0)) for k, s in soups.items()}
    out = []
    for i, ka in enumerate(keys):
        for kb in keys[i + 1 :]:
            (la, ha), (lb, hb) = boxes[ka], boxes[kb]
            scale = 1e-9 * float(max(np.ptp(np.stack([la, ha, lb, hb]), axis=0).max(), 1e-300))
            if not gi.boxes_overlap(la, ha, lb, hb, scale):
                continue
            if bodies_collide(soups[ka], soups[kb]):
                out.append((labels[ka], labels[kb]))
    return out
