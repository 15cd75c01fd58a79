"""Picking through CSG shapes by ray-interval arithmetic on the operands' intersectors.

Each operand is intersected on its own (with every crossing, not only the
nearest): along the ray its crossings, nearest first, alternate between
entering and leaving the solid, so they make a list of inside intervals.
Union, intersection and difference of the two lists give the CSG's inside
intervals, whose ends are its surface crossings, with the normals of the
operand surfaces they come from.  The result is exact for analytic operands
(a sphere minus a box hits at the analytic distances), without tessellating
anything.  The ray is assumed to start outside the operands.
"""

from __future__ import annotations

import math
from typing import Any

from ..core.handler import RayIntersector, default_for
from ..shapes import CSG
from .picking import RAY, Hit, PickEngine

__all__ = ["CSGIntersector", "combine"]

Interval = tuple[float, float, Any, Any]  # start, end, hit at the start, hit at the end


def _intervals(hits: list[Hit]) -> list[Interval]:
    hits = sorted(hits, key=lambda h: h.distance)
    if len(hits) % 2:  # started inside (or a grazing hit): the first interval opens at the origin
        hits = [None, *hits]  # type: ignore[list-item]
    out = []
    for enter, leave in zip(hits[0::2], hits[1::2], strict=True):
        start = 0.0 if enter is None else enter.distance
        out.append((start, leave.distance, enter, leave))
    return out


def combine(operation: str, a: list[Interval], b: list[Interval]) -> list[Interval]:
    """Inside intervals of ``a`` op ``b`` (sorted lists of (start, end, start hit, end hit))."""
    events = sorted([(s, 0, e, hs, he) for s, e, hs, he in a] + [(s, 1, e, hs, he) for s, e, hs, he in b])
    # sweep the interval ends in order, tracking whether the ray is inside a and inside b
    points: list[tuple[float, int, bool, Any]] = []
    for s, which, e, hs, he in events:
        points.append((s, which, True, hs))
        points.append((e, which, False, he))
    points.sort(key=lambda p: (p[0], not p[2]))
    inside = [False, False]
    rule = {
        "union": lambda x, y: x or y,
        "intersection": lambda x, y: x and y,
        "difference": lambda x, y: x and not y,
    }[operation]
    out: list[Interval] = []
    start: tuple[float, Any] | None = None
    for t, which, entering, hit in points:
        inside[which] = entering
        now = rule(*inside)
        if now and start is None:
            start = (t, hit)
        elif not now and start is not None:
            if t > start[0]:
                out.append((start[0], t, start[1], hit))
            start = None
    if start is not None:
        out.append((start[0], math.inf, start[1], None))
    return out


@default_for(PickEngine)
class CSGIntersector(RayIntersector):
    """``CSG``: the operands' crossings combined by interval arithmetic (exact for analytic operands)."""

    __slots__ = ()
    service = RAY
    target = CSG

    def exec(self, shape: CSG, engine: PickEngine) -> None:
        saved = (engine.hits, engine.tmax, engine.nearest)
        lists = []
        try:
            for operand in shape.operands():
                engine.hits, engine.tmax, engine.nearest = [], math.inf, False
                if hasattr(operand, "local_program"):
                    engine.evaluate(operand)
                else:
                    engine.evaluate([operand])
                lists.append(_intervals(engine.hits))
        finally:
            engine.hits, engine.tmax, engine.nearest = saved
        for _start, _end, enter, leave in combine(shape.operation, *lists):
            for hit in (enter, leave):
                if hit is not None and 0.0 < hit.distance <= engine.tmax:
                    engine.hits.append(Hit(hit.distance, hit.point, hit.normal, engine.scene_shape,
                                           engine.scene_path, hit.primitive, hit.part,
                                           pick_ids=engine.pick_ids()))  # fmt: skip
        if engine.nearest and engine.hits:
            best = min(engine.hits, key=lambda h: h.distance)
            engine.hits = [best]
            engine.tmax = best.distance
