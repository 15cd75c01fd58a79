"""The clip planes active during a traversal, for engines that cut geometry themselves.

Renderers without clip planes (Mitsuba, Radiance) clip the geometry on the CPU
(:mod:`omnirender.geometry.clip`).  Their ``ClipPlane`` painters record each
plane with its world plane row when it becomes active and drop it when its
node ends; painters then ask for the rows of the planes active now.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["ClipRecords"]


class ClipRecords:
    """``ClipPlane``\\ s in the order they became active, with their world rows ``(a, b, c, d)``.

    A row keeps the points with ``a x + b y + c z + d >= 0`` (``ClipPlane.world_plane``).
    """

    __slots__ = ("_items",)

    def __init__(self) -> None:
        self._items: list[tuple[Any, np.ndarray]] = []

    def add(self, plane: Any, matrix: np.ndarray) -> None:
        """Record ``plane`` added under the model matrix ``matrix`` (its coordinates)."""
        self._items.append((plane, plane.world_plane(matrix)))

    def remove(self, plane: Any) -> None:
        """Forget the most recent record of ``plane`` (it was removed or its node ended)."""
        for i in range(len(self._items) - 1, -1, -1):
            if self._items[i][0] is plane:
                del self._items[i]
                return

    def rows(self) -> list[np.ndarray]:
        """The world rows of the active planes."""
        return [row for _, row in self._items]
