"""``LevelOfDetail``: one of several versions of an object, chosen by its distance from the camera.

``LevelOfDetail([fine, coarser, coarsest], distances=[10, 30])`` shows
``fine`` closer than 10 units to the eye, ``coarser`` up to 30, ``coarsest``
beyond.  Levels are shapes or nodes (as CSG operands); the distance is
measured from the camera's eye to ``center`` (in the coordinates where the
level-of-detail sits).

The GL engine compiles every level once and picks one per frame at draw time
(:class:`~omnirender.gl.painters.shapes.LevelOfDetailPainter`), also when only the
camera moved.  Every other engine evaluates one level through the default
simplifier: the finest, or with ``offline="distance"`` the one the engine's
camera sees (engines without a camera take the finest).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.component import Shape
from ..core.engine import Engine
from ..core.handler import ShapeSimplifier, default_for

__all__ = ["LevelOfDetail"]

_OFFLINE = ("finest", "distance")


class LevelOfDetail(Shape):
    """Levels finest first, switched at increasing ``distances`` (one fewer than the levels)."""

    __slots__ = ("_levels", "_distances", "_center", "_offline")

    def __init__(
        self,
        levels: Any,
        distances: Any,
        center: Any = (0.0, 0.0, 0.0),
        offline: str = "finest",
    ) -> None:
        super().__init__()
        levels = tuple(levels)
        if not levels:
            raise ValueError("LevelOfDetail: give at least one level (a shape or a node)")
        for i, level in enumerate(levels):
            if not (isinstance(level, Shape) or hasattr(level, "local_program")) or level is self:
                raise ValueError(f"LevelOfDetail: level {i} must be a shape or an om.Node, got {type(level).__name__}")
        d = np.asarray(distances, dtype=np.float64).reshape(-1)
        if len(d) != len(levels) - 1:
            raise ValueError(
                f"LevelOfDetail: {len(levels)} levels need {len(levels) - 1} switching distances, got {len(d)}"
            )
        if not np.all(np.isfinite(d)) or np.any(d <= 0) or np.any(np.diff(d) <= 0):
            raise ValueError(f"LevelOfDetail: distances must be positive and increasing, got {d.tolist()}")
        c = np.asarray(center, dtype=np.float64).reshape(-1)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise ValueError(f"LevelOfDetail: center must be 3 finite numbers, got {center!r}")
        if offline not in _OFFLINE:
            raise ValueError(f"LevelOfDetail: offline must be one of {_OFFLINE}, got {offline!r}")
        object.__setattr__(self, "_levels", levels)
        object.__setattr__(self, "_distances", tuple(float(x) for x in d))
        object.__setattr__(self, "_center", tuple(float(x) for x in c))
        object.__setattr__(self, "_offline", offline)
        for level in levels:
            if isinstance(level, Shape):
                level.attach_owner(self)

    @property
    def levels(self) -> tuple[Any, ...]:
        return self._levels

    @property
    def distances(self) -> tuple[float, ...]:
        return self._distances

    @property
    def center(self) -> tuple[float, float, float]:
        return self._center

    @property
    def offline(self) -> str:
        return self._offline

    def level_at(self, distance: float) -> int:
        """The index of the level shown at ``distance`` from the eye."""
        return int(np.searchsorted(self._distances, distance, side="right"))

    def parameters(self) -> dict[str, Any]:
        return {
            "levels": list(self._levels),
            "distances": list(self._distances),
            "center": list(self._center),
            "offline": self._offline,
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__(state)
        for level in self._levels:
            if isinstance(level, Shape):
                level.attach_owner(self)


@default_for(Engine)
class LevelOfDetailSimplifier(ShapeSimplifier):
    """One level: the finest, or (``offline="distance"``) the one at the engine's camera distance."""

    __slots__ = ()
    target = LevelOfDetail

    def exec(self, shape: LevelOfDetail, engine: Engine) -> list[Any]:
        index = 0
        view = engine.view_matrix() if shape.offline == "distance" else None
        if view is not None:
            eye = np.linalg.inv(view)[:3, 3]
            center = (engine.model_matrix() @ np.array([*shape.center, 1.0]))[:3]
            index = shape.level_at(float(np.linalg.norm(eye - center)))
        return [shape.levels[index]]
