"""Shadows and mirrors as generic attributes: every engine gives them the same meaning.

``Shadowing(cast=..., receive=...)`` says whether the shapes that follow cast
shadows and whether shadows fall on them; lights say whether they cast shadows
at all (``casts_shadows``, default True).  ``Mirror(reflectance, plane=...)``
makes the planar shapes that follow reflect the scene.  What each engine does
with them:

* GL: shadow maps (on by default, ``om.gl.ShadowMaps``) or stencil shadow
  volumes (``om.gl.ShadowVolumes``); a Mirror is drawn with the stencil
  technique of the VRS paper (``om.gl.Mirrors``, implied by the attribute).
* POV-Ray: ``shadowless`` lights, ``no_shadow`` objects; objects that do not
  receive shadows sit in a ``light_group`` with shadowless copies of the
  lights; a Mirror adds ``reflection`` to the finish.
* Mitsuba and Radiance: a path tracer's lights always cast shadows and every
  surface receives them; they warn once (naming the node) when a scene asks
  otherwise.  A Mirror blends the surface with a perfect conductor (Mitsuba)
  or adds a ``mirror`` material (Radiance).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.component import MonoAttribute
from ._params import Param, Parameterised, check_bool, check_number

__all__ = ["Shadowing", "Mirror"]


class Shadowing(Parameterised, MonoAttribute):
    """Whether the shapes that follow ``cast`` shadows and ``receive`` them (both True by default)."""

    __slots__ = ("_cast", "_receive")
    cast = Param(check_bool, "the shapes that follow cast shadows")
    receive = Param(check_bool, "shadows fall on the shapes that follow")

    def __init__(self, cast: bool = True, receive: bool = True) -> None:
        super().__init__()
        self.cast = cast
        self.receive = receive


def _check_plane(owner: str, name: str, value: Any) -> tuple[tuple[float, float, float], float]:
    fix = "give plane=((nx, ny, nz), offset): the points p of the plane have dot(n, p) = offset"
    try:
        normal, offset = value
        n = np.asarray(normal, dtype=np.float64).reshape(-1)
        d = float(offset)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: {name} must be (normal, offset), got {value!r}; {fix}") from None
    if n.shape != (3,) or not np.all(np.isfinite(n)) or not np.isfinite(d):
        raise ValueError(f"{owner}: {name} needs a finite 3D normal and offset, got {value!r}; {fix}")
    length = float(np.linalg.norm(n))
    if length == 0.0:
        raise ValueError(f"{owner}: {name} normal must not be the zero vector; {fix}")
    return (float(n[0] / length), float(n[1] / length), float(n[2] / length)), d / length


class Mirror(Parameterised, MonoAttribute):
    """The planar shapes that follow reflect the scene: ``reflectance`` (0..1) of the mirrored image.

    ``plane`` is ``(normal, offset)`` in the coordinates of the shapes (the
    points p with ``dot(normal, p) == offset``); the default is the plane
    y = 0 facing +y, where ``Rectangle`` and ``Disk`` lie.  The shape's own
    colour shows with weight ``1 - reflectance``.
    """

    __slots__ = ("_reflectance", "_plane")
    reflectance = Param(check_number(0.0, 1.0), "fraction of the mirrored image (0..1)")
    plane = Param(_check_plane, "(normal, offset) of the mirror plane in the shape's coordinates")

    def __init__(
        self, reflectance: float = 0.8, plane: tuple[Sequence[float], float] = ((0.0, 1.0, 0.0), 0.0)
    ) -> None:
        super().__init__()
        self.reflectance = reflectance
        self.plane = plane

    def world_plane(self, matrix: np.ndarray) -> np.ndarray:
        """(a, b, c, d) of the plane in world coordinates (a x + b y + c z + d = 0, unit normal)."""
        n, offset = self._plane
        p = np.linalg.inv(np.asarray(matrix, dtype=np.float64)).T @ np.array([*n, -offset])
        return p / np.linalg.norm(p[:3])
