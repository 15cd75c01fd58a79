"""Analytic primitives: sphere, box, cylinder, cone, torus, disk, rectangle, arrow.

Conventions (shared by every engine): right-handed coordinates, +y up.
Cylinder and cone stand on the y axis centred at the origin; the torus ring
and the flat shapes (disk, rectangle) lie in the xz plane and face +y.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from . import _check
from .base import DeclaredShape, parameter

__all__ = ["Sphere", "Box", "Cylinder", "Cone", "Torus", "Disk", "Rectangle", "Arrow"]

Vec3 = Sequence[float]


class Sphere(DeclaredShape):
    """A sphere of ``radius`` (> 0) around ``center``."""

    __slots__ = ("_center", "_radius")
    _params = ("center", "radius")
    center = parameter("center", "Centre (x, y, z).")
    radius = parameter("radius", "Radius, > 0.")

    def __init__(self, center: Vec3 = (0.0, 0.0, 0.0), radius: float = 1.0) -> None:
        super().__init__(center=center, radius=radius)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        return {
            "center": _check.vector("Sphere", "center", p["center"], 3),
            "radius": _check.scalar("Sphere", "radius", p["radius"], positive=True),
        }, {}


class Box(DeclaredShape):
    """An axis-aligned box of edge lengths ``size`` (> 0; a single number makes a cube) around ``center``."""

    __slots__ = ("_size", "_center")
    _params = ("size", "center")
    size = parameter("size", "Edge lengths (sx, sy, sz), each > 0.")
    center = parameter("center", "Centre (x, y, z).")

    def __init__(self, size: float | Vec3 = (1.0, 1.0, 1.0), center: Vec3 = (0.0, 0.0, 0.0)) -> None:
        super().__init__(size=size, center=center)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        return {
            "size": _check.vector("Box", "size", p["size"], 3, positive=True),
            "center": _check.vector("Box", "center", p["center"], 3),
        }, {}


class _RadiusHeight(DeclaredShape):
    """Shared parameters of Cylinder and Cone (which are otherwise unrelated classes)."""

    __slots__ = ("_radius", "_height")
    _params = ("radius", "height")
    radius = parameter("radius", "Radius, > 0.")
    height = parameter("height", "Height along y, > 0 (from -height/2 to +height/2).")

    def __init__(self, radius: float = 1.0, height: float = 2.0) -> None:
        super().__init__(radius=radius, height=height)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        name = type(self).__name__
        return {
            "radius": _check.scalar(name, "radius", p["radius"], positive=True),
            "height": _check.scalar(name, "height", p["height"], positive=True),
        }, {}


class Cylinder(_RadiusHeight):
    """A capped cylinder of ``radius`` and ``height`` on the y axis, centred at the origin."""

    __slots__ = ()


class Cone(_RadiusHeight):
    """A cone on the y axis: base disk of ``radius`` at y = -height/2, apex at y = +height/2."""

    __slots__ = ()


class Torus(DeclaredShape):
    """A torus around the y axis: the ring (``major_radius``) lies in the xz plane, tube of ``minor_radius``.

    Both radii are > 0 and ``minor_radius <= major_radius`` (the usual ring
    torus; equal radii close the hole): a larger minor radius would intersect
    itself and is refused with ValueError.
    """

    __slots__ = ("_major_radius", "_minor_radius")
    _params = ("major_radius", "minor_radius")
    major_radius = parameter("major_radius", "Distance from the centre to the tube's axis, > 0.")
    minor_radius = parameter("minor_radius", "Radius of the tube, > 0.")

    def __init__(self, major_radius: float = 1.0, minor_radius: float = 0.25) -> None:
        super().__init__(major_radius=major_radius, minor_radius=minor_radius)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        major = _check.scalar("Torus", "major_radius", p["major_radius"], positive=True)
        minor = _check.scalar("Torus", "minor_radius", p["minor_radius"], positive=True)
        if minor > major:
            raise ValueError(
                f"Torus: minor_radius ({minor}) must not exceed major_radius ({major}): such a spindle torus "
                "intersects itself and encloses no well-defined inside; swap the two radii if you meant "
                f"Torus(major_radius={minor}, minor_radius={major})"
            )
        return {"major_radius": major, "minor_radius": minor}, {}


class Disk(DeclaredShape):
    """A flat disk of ``radius`` in the xz plane, centred at the origin, facing +y (double-sided)."""

    __slots__ = ("_radius",)
    _params = ("radius",)
    radius = parameter("radius", "Radius, > 0.")

    def __init__(self, radius: float = 1.0) -> None:
        super().__init__(radius=radius)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        return {"radius": _check.scalar("Disk", "radius", p["radius"], positive=True)}, {}


class Rectangle(DeclaredShape):
    """A flat rectangle of ``size`` = (extent in x, extent in z) in the xz plane, centred, facing +y (double-sided)."""

    __slots__ = ("_size",)
    _params = ("size",)
    size = parameter("size", "(width along x, depth along z), each > 0; a single number makes a square.")

    def __init__(self, size: float | Sequence[float] = (1.0, 1.0)) -> None:
        super().__init__(size=size)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        return {"size": _check.vector("Rectangle", "size", p["size"], 2, positive=True)}, {}


class Arrow(DeclaredShape):
    """An arrow from ``start`` to ``end``: a shaft (cylinder) and a head (cone) whose tip is at ``end``.

    ``radius`` is the shaft radius; ``head_radius`` defaults to 2.5 x ``radius``
    and ``head_length`` to 3 x ``head_radius``; the head is shortened to the
    arrow's length when the arrow is shorter.  The paper's example of an
    application shape: it has no painter anywhere and simplifies to a Cylinder
    and a Cone.
    """

    __slots__ = ("_start", "_end", "_radius", "_head_radius", "_head_length")
    _params = ("start", "end", "radius", "head_radius", "head_length")
    start = parameter("start", "Tail point (x, y, z).")
    end = parameter("end", "Tip point (x, y, z), different from start.")
    radius = parameter("radius", "Shaft radius, > 0.")
    head_radius = parameter("head_radius", "Head (cone base) radius, > 0, or None for 2.5 x radius.")
    head_length = parameter("head_length", "Head length, > 0, or None for 3 x head_radius.")

    def __init__(
        self,
        start: Vec3 = (0.0, 0.0, 0.0),
        end: Vec3 = (0.0, 1.0, 0.0),
        radius: float = 0.05,
        head_radius: float | None = None,
        head_length: float | None = None,
    ) -> None:
        super().__init__(start=start, end=end, radius=radius, head_radius=head_radius, head_length=head_length)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        start = _check.vector("Arrow", "start", p["start"], 3)
        end = _check.vector("Arrow", "end", p["end"], 3)
        if math.dist(start, end) == 0.0:
            raise ValueError(f"Arrow: start and end must differ, both are {start}")
        radius = _check.scalar("Arrow", "radius", p["radius"], positive=True)
        hr = p["head_radius"]
        hl = p["head_length"]
        return {
            "start": start,
            "end": end,
            "radius": radius,
            "head_radius": None if hr is None else _check.scalar("Arrow", "head_radius", hr, positive=True),
            "head_length": None if hl is None else _check.scalar("Arrow", "head_length", hl, positive=True),
        }, {}

    @property
    def length(self) -> float:
        """Distance from start to end."""
        return math.dist(self._start, self._end)

    def effective_head(self) -> tuple[float, float]:
        """(head_radius, head_length) after defaults and clamping to the arrow's length."""
        hr = self._head_radius if self._head_radius is not None else 2.5 * self._radius
        hl = self._head_length if self._head_length is not None else 3.0 * hr
        return hr, min(hl, self.length)
