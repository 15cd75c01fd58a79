"""The frame report: one :class:`PassRecord` per executed pass, with draw calls, instances and GPU time.

``GLEngine(timing=True)`` measures each pass's GPU time with timer queries; a
query is suspended while a nested pass runs, so a record's time is its own.
"""

from __future__ import annotations

from typing import Any

__all__ = ["PassRecord", "PassReport"]


class PassRecord(dict):
    """One executed pass of a frame: ``name`` (the path of pass names), ``technique``, ``depth``,
    ``draw_calls``, ``items`` (instances drawn), ``target`` and ``gpu_ms`` (None without timing)."""

    def __repr__(self) -> str:
        gpu = "" if self["gpu_ms"] is None else f", {self['gpu_ms']:.3f} ms"
        return f"PassRecord({self['name']!r}, {self['draw_calls']} calls, {self['items']} items{gpu})"


class PassReport:
    """The records of the frame being drawn and the timer queries that time them."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        #: measure each pass's GPU time with timer queries (``engine.timing`` at the frame's start)
        self.timing = False
        self.records: list[PassRecord] = []
        self._stack: list[PassRecord] = []
        self._pool: list[Any] = []
        self._open: Any = None
        self._used = 0

    def begin_frame(self, timing: bool) -> None:
        self.timing = bool(timing)
        self.records = []
        self._stack = []
        self._open = None
        self._used = 0

    def add(self, record: PassRecord) -> None:
        """A pass starts: its record joins the frame's (in execution order)."""
        self.records.append(record)

    def count(self, calls: int, instances: int) -> None:
        """Add draw calls and instances to the pass being drawn."""
        if self._stack:
            record = self._stack[-1]
            record["draw_calls"] += calls
            record["items"] += instances

    def enter(self, record: PassRecord) -> None:
        """``record``'s pass draws now (the enclosing pass's timer query is suspended)."""
        self._suspend()
        self._stack.append(record)
        self._resume()

    def leave(self) -> None:
        self._suspend()
        self._stack.pop()
        self._resume()

    def close(self) -> None:
        """The frame's last pass ended: no query stays open."""
        self._suspend()

    def finish(self) -> list[PassRecord]:
        """The frame's records with their GPU times (waits for the timer queries when timing)."""
        for record in self.records:
            queries = record.pop("_queries", [])
            if self.timing:
                record["gpu_ms"] = sum(q.elapsed for q in queries) / 1e6 if queries else 0.0
        return list(self.records)

    def release(self) -> None:
        for query in self._pool:
            query.mglo.release() if hasattr(query.mglo, "release") else None
        self._pool.clear()

    def _suspend(self) -> None:
        if self._open is not None:
            self._open.__exit__(None, None, None)
            self._open = None

    def _resume(self) -> None:
        if not self.timing or not self._stack or self._open is not None:
            return
        pool = self._pool
        if self._used == len(pool):
            pool.append(self.ctx.query(time=True))
        query = pool[self._used]
        self._used += 1
        query.__enter__()
        self._open = query
        self._stack[-1].setdefault("_queries", []).append(query)
