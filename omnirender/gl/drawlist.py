"""The compiled form of a scene: draw items, interned draw states and instanced batches.

Painters do not issue GL calls: they append :class:`DrawItem` objects (a
geometry, a per-instance row of 40 floats = model matrix + material, and an
interned :class:`DrawState`).  Items with the same geometry and state form one
:class:`Batch`, drawn with a single instanced call; when only some items
changed, their rows are rewritten in place and only that region of the
instance buffer is uploaded.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .shaders import ROW

__all__ = ["DrawItem", "DrawState", "Batch", "plan_batches", "uniform_material"]


class DrawState:
    """Everything but the geometry and the per-instance row that a draw needs (interned, compared by identity)."""

    __slots__ = (
        "kind",
        "features",
        "depth_func",
        "depth_mask",
        "blend",
        "cull",
        "polygon_offset",
        "color_mask",
        "stencil",
        "wireframe",
        "line_width",
        "texture",
        "clip",
        "fog",
        "switch",
        "special",
        "extra",
        "overlay",
    )

    def __init__(self, **values: Any) -> None:
        for name in self.__slots__:
            setattr(self, name, values.get(name))
        self.special = bool(
            self.stencil is not None
            or self.color_mask != (True, True, True, True)
            or self.depth_func != "less"
            or not self.depth_mask
        )

    def key(self) -> tuple:
        return tuple(getattr(self, name) for name in self.__slots__)

    def __repr__(self) -> str:
        return f"DrawState({self.kind}, {dict(self.features)})"


class DrawItem:
    """One shape occurrence: geometry, state, instance row, transparency and the node it was evaluated in."""

    __slots__ = ("geometry", "state", "row", "transparent", "node")

    def __init__(self, geometry: Any, state: DrawState, row: np.ndarray, transparent: bool, node: Any = None) -> None:
        self.geometry = geometry
        self.state = state
        self.row = row
        self.transparent = transparent
        self.node = node

    @property
    def path(self) -> str:
        """Path of the node the shape was evaluated in ("" outside any node)."""
        node = self.node
        return "" if node is None else node.path

    def __repr__(self) -> str:
        return f"DrawItem({self.geometry.label}, {self.state.kind}, transparent={self.transparent})"


class Batch:
    """Items sharing geometry and state, drawn with one instanced call."""

    __slots__ = (
        "geometry",
        "state",
        "items",
        "rows",
        "buffer",
        "vao",
        "program",
        "capacity",
        "dirty",
        "uniform",
        "stride",
        "sorted_for",
    )

    def __init__(self, geometry: Any, state: DrawState) -> None:
        self.geometry = geometry
        self.state = state
        self.items: list[DrawItem] = []
        self.rows = np.empty((0, ROW), np.float32)
        self.buffer: Any = None
        self.vao: Any = None
        self.program: Any = None
        self.capacity = 0
        self.dirty: tuple[int, int] | None = None
        #: True when every instance has the same material apart from its colour (uniforms instead of attributes).
        self.uniform = False
        #: floats per instance in the GPU buffer (20 = matrix + colour when the material is uniform).
        self.stride = 0
        #: the view (bytes of the view matrix) the instances were last sorted front to back for, or None.
        self.sorted_for: bytes | None = None

    def mark(self, index: int) -> None:
        d = self.dirty
        self.dirty = (index, index + 1) if d is None else (min(d[0], index), max(d[1], index + 1))

    def release(self) -> None:
        if self.vao is not None:
            self.vao.release()
            self.vao = None
        if self.buffer is not None:
            self.buffer.release()
            self.buffer = None
        self.capacity = 0


def uniform_material(rows: np.ndarray) -> bool:
    """Whether all rows share the material columns (specular, emission, ambient, highlight, extra)."""
    tail = rows[:, 20:40]
    return bool(len(rows) == 1 or (tail == tail[0]).all())


def plan_batches(items: list[DrawItem]) -> tuple[dict[tuple, list[DrawItem]], list[tuple | None], list[DrawItem]]:
    """Group opaque items by (geometry, state); returns groups, per-item (key, index) slots, other items.

    Items with special raster state (stencil, colour mask, depth function or
    depth mask) are grouped only with consecutive items of the same state, so
    two stencil-writing or masking items are never merged across each other
    and their relative order is kept.  Plain items are merged freely within a
    stretch between special items (a batch draws at the position of its first
    item), never across a special item, so what is drawn after a special item
    stays after it.
    """
    groups: dict[tuple, list[DrawItem]] = {}
    slots: list[tuple | None] = []
    others: list[DrawItem] = []
    segment = 0
    previous: DrawState | None = None
    for item in items:
        state = item.state
        if item.transparent or state.overlay:
            slots.append(None)
            others.append(item)
            continue
        if state is not previous and (state.special or (previous is not None and previous.special)):
            segment += 1
        previous = state
        # plain items are keyed by the segment too: a plain shape after a special-state one stays after it
        key = (item.geometry, state, segment)
        group = groups.get(key)
        if group is None:
            group = groups[key] = []
        slots.append((key, len(group)))
        group.append(item)
    return groups, slots, others
