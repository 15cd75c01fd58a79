"""Attributes about the surroundings of shapes and about how they are treated.

``ClipPlane`` (poly), ``Fog``, ``Background``, ``Tessellation``, ``Highlight``,
``PickId`` (poly) and the ``Collidable`` tag.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.component import MonoAttribute, PolyAttribute
from ._params import (
    Param,
    Parameterised,
    check_bool,
    check_choice,
    check_direction,
    check_number,
    check_rgb,
    check_rgba,
)

__all__ = [
    "ClipPlane",
    "Fog",
    "Background",
    "Tessellation",
    "Highlight",
    "PickId",
    "Collidable",
    "DEFAULT_BACKGROUND",
    "shown_background",
    "is_scene_background",
]

#: The background of a scene without an ``om.Background`` (sRGB display values, opaque), the same in every
#: engine: the GL engine's clear colour, POV-Ray's, Mitsuba's and Radiance's pictures, the web page, a
#: stand-alone ``.pov`` file.  ``om.Background((0, 0, 0, 0))`` asks for a transparent one; ``Image.mask``
#: marks the pixels shapes cover either way.
DEFAULT_BACKGROUND = (0.16, 0.16, 0.17, 1.0)


def shown_background(background: Any) -> tuple[float, ...]:
    """The RGBA display colour an engine paints behind the shapes: the ``om.Background``'s or the default."""
    if background is None:
        return DEFAULT_BACKGROUND
    color = tuple(float(c) for c in getattr(background, "color", background))
    return color if len(color) == 4 else (*color[:3], 1.0)


class ClipPlane(Parameterised, PolyAttribute):
    """Keep the half-space ``dot(normal, p) >= offset`` (the side the normal points to).

    ``normal`` is normalised at construction, so ``offset`` is the signed
    distance of the plane from the origin along the normal, in the coordinates
    where the clip plane sits in the graph.
    """

    __slots__ = ("_normal", "_offset")
    normal = Param(check_direction, "unit normal pointing to the kept side")
    offset = Param(check_number(), "signed distance of the plane from the origin")

    def __init__(self, normal: Sequence[float] = (0.0, 1.0, 0.0), offset: float = 0.0) -> None:
        super().__init__()
        self.normal = normal
        self.offset = offset

    def plane(self) -> np.ndarray:
        """(a, b, c, d) with ``a x + b y + c z + d >= 0`` on the kept side (OpenGL's glClipPlane form)."""
        return np.array([*self._normal, -self._offset], dtype=np.float64)

    def world_plane(self, matrix: np.ndarray) -> np.ndarray:
        """The plane equation in world coordinates for the model matrix where the plane was added.

        Normalised so that (a, b, c) is a unit vector.
        """
        p = np.linalg.inv(np.asarray(matrix, dtype=np.float64)).T @ self.plane()
        return p / np.linalg.norm(p[:3])

    def distance(self, points: Any) -> np.ndarray | float:
        """Signed distance(s) of point(s) to the plane, positive on the kept side."""
        p = np.asarray(points, dtype=np.float64)
        d = p @ np.asarray(self._normal) - self._offset
        return float(d) if np.ndim(d) == 0 else d

    def keeps(self, points: Any) -> np.ndarray | bool:
        """Whether point(s) lie on the kept side (on the plane counts as kept)."""
        d = self.distance(points)
        return bool(d >= 0.0) if isinstance(d, float) else d >= 0.0


class Fog(Parameterised, MonoAttribute):
    """Depth cueing with OpenGL's fog equations.

    :meth:`factor` is the fraction of a surface's own colour that survives at
    eye distance ``d`` (1 = no fog); the final colour is
    ``f * colour + (1 - f) * fog colour``.  ``mode`` ``"linear"`` uses
    ``(end - d) / (end - start)``, ``"exp"`` ``exp(-density d)``, ``"exp2"``
    ``exp(-(density d)^2)``; the result is clamped to [0, 1].
    """

    __slots__ = ("_color", "_start", "_end", "_mode", "_density")
    color = Param(check_rgb, "fog colour (RGB)")
    start = Param(check_number(0.0), "distance where linear fog begins (>= 0)")
    end = Param(check_number(0.0, min_open=True), "distance where linear fog is total (> start)")
    mode = Param(check_choice("linear", "exp", "exp2"), "linear, exp or exp2")
    density = Param(check_number(0.0), "density for exp and exp2 (>= 0)")

    def __init__(
        self,
        color: Sequence[float] = (0.5, 0.5, 0.5),
        start: float = 1.0,
        end: float = 100.0,
        mode: str = "linear",
        density: float = 0.05,
    ) -> None:
        super().__init__()
        self.color = color
        self.start = start
        self.end = end
        self.mode = mode
        self.density = density
        if self._end <= self._start:
            raise ValueError(f"Fog: end must be > start, got start={self._start}, end={self._end}")

    def factor(self, distance: Any) -> np.ndarray | float:
        """Fraction of the surface colour kept at eye distance(s) ``distance``."""
        d = np.asarray(distance, dtype=np.float64)
        if self._mode == "linear":
            f = (self._end - d) / (self._end - self._start)
        elif self._mode == "exp":
            f = np.exp(-self._density * d)
        else:
            f = np.exp(-((self._density * d) ** 2))
        f = np.clip(f, 0.0, 1.0)
        return float(f) if d.ndim == 0 else f


class Background(Parameterised, MonoAttribute):
    """The colour behind everything (RGBA; alpha 0 gives a transparent background).

    Engines read the active Background at the root; its position in the graph
    otherwise does not matter.
    """

    __slots__ = ("_color",)
    declared = "first"  # the scene's Background is found by the declarative pre-evaluation
    color = Param(check_rgba, "background colour (RGB or RGBA)")

    def __init__(self, color: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        super().__init__()
        self.color = color


def is_scene_background(background: Background, engine: Any) -> bool:
    """Whether ``background`` is the scene's, for an engine that meets it during its traversal.

    The one rule every engine follows: the Background the engine's last
    pre-evaluation declared (the first in traversal order; of two in one node,
    the later, as on a stack).  Without a pre-evaluation (components evaluated
    by hand) every Background met counts.
    """
    declared = getattr(engine, "declared", None)
    found = declared.first(Background) if declared is not None else None
    return found is None or found[0] is background


class Tessellation(Parameterised, MonoAttribute):
    """How finely simplifiers tessellate curved shapes: ``level`` 0 (coarse) ... 8 (fine).

    The number of segments a simplifier uses for a quantity that has ``base``
    segments at level 0 is :meth:`segments` = ``max(3, base * 2**level)``; the
    default level 3 gives 8x the base, so a sphere with base 4 gets 32 segments
    around.  Simplifiers without a Tessellation in the context use
    :data:`DEFAULT_LEVEL`.
    """

    DEFAULT_LEVEL = 3

    __slots__ = ("_level",)
    level = Param(check_number(0, 8, integer=True), "integer 0 ... 8")

    def __init__(self, level: int = DEFAULT_LEVEL) -> None:
        super().__init__()
        self.level = level

    def segments(self, base: int) -> int:
        """``max(3, base * 2**level)``: segment count for ``base`` segments at level 0."""
        return max(3, int(base) * 2**self._level)

    @staticmethod
    def segments_for(engine: Any, base: int) -> int:
        """Segments for ``base`` under the engine's active Tessellation (default level if none)."""
        t = engine.mono(Tessellation)
        return max(3, int(base) * 2 ** (Tessellation.DEFAULT_LEVEL if t is None else t._level))


class Highlight(Parameterised, MonoAttribute):
    """Draw the following shapes highlighted (e.g. a picked shape) in ``color``."""

    __slots__ = ("_color",)
    color = Param(check_rgb, "highlight colour (RGB)")

    def __init__(self, color: Sequence[float] = (1.0, 1.0, 0.0)) -> None:
        super().__init__()
        self.color = color


def _check_id(owner: str, name: str, value: Any) -> int | str:
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{owner}: {name} must be an integer >= 0 or a non-empty string, got {value!r}")
    if isinstance(value, str):
        if not value:
            raise ValueError(f"{owner}: {name} must be an integer >= 0 or a non-empty string, got ''")
        return value
    if isinstance(value, (int, np.integer)) and value >= 0:
        return int(value)
    if isinstance(value, float) and math.isfinite(value) and value == int(value) and value >= 0:
        return int(value)
    raise ValueError(f"{owner}: {name} must be an integer >= 0 or a non-empty string, got {value!r}")


class PickId(Parameterised, PolyAttribute):
    """An application id reported by picking for the shapes that follow (poly: ids nest)."""

    __slots__ = ("_id",)
    id = Param(_check_id, "integer >= 0 or string")

    def __init__(self, id: int | str) -> None:  # noqa: A002 - the natural name
        super().__init__()
        self.id = id


class Collidable(Parameterised, MonoAttribute):
    """Tag: the shapes that follow take part in collision detection (``enabled=False`` opts out)."""

    __slots__ = ("_enabled",)
    enabled = Param(check_bool, "True to take part in collision detection")

    def __init__(self, enabled: bool = True) -> None:
        super().__init__()
        self.enabled = enabled
