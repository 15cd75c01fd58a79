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
  otherwise.  Mitsuba blends a Mirror's surface with a perfect conductor
  (``blendbsdf``; the background is composited behind the image, so a mirror
  does not show it); Radiance draws the surface without the mirror, with a
  warning.
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

    def __init__(self, reflectance: float = 0.8, plane: tuple[Sequence[float], float] = ((0.0, 1.0, 0.0), 0.0)) -> None:
        super().__init__()
        self.reflectance = reflectance
        self.plane = plane

    def world_plane(self, matrix: np.ndarray) -> np.ndarray:
        """(a, b, c, d) of the plane in world coordinates (a x + b y + c z + d = 0, unit normal)."""
        n, offset = self._plane
        p = np.linalg.inv(np.asarray(matrix, dtype=np.float64)).T @ np.array([*n, -offset])
        return p / np.linalg.norm(p[:3])


def warn_unsupported(engine: Any, label: str, what: str, fix: str) -> None:
    """Warn once per engine run and kind of request that ``label`` cannot honour ``what`` (naming the node)."""
    seen = engine.__dict__.setdefault("_shadowing_warned", set())
    if what in seen:
        return
    seen.add(what)
    import warnings

    warnings.warn(f"{label}: {what} in node {engine.node_path or '/'} is ignored: {fix}", stacklevel=3)


def check_light_shadows(engine: Any, light: Any, label: str) -> None:
    """Warn (once) that a light with ``casts_shadows=False`` still casts shadows in a path tracer."""
    if not getattr(light, "casts_shadows", True) and getattr(light, "ambient", None) is not None:
        from .lights import AmbientLight

        if not isinstance(light, AmbientLight):
            warn_unsupported(engine, label, "casts_shadows=False on a light",
                             "its shadows stay (render with GL or POV-Ray for shadowless lights)")  # fmt: skip


def register_shadowing_warnings(engine_cls: type, label: str, mirror: bool) -> None:
    """Default painters of ``engine_cls`` that warn about ``Shadowing`` (and ``Mirror`` unless it is supported)."""
    from ..core import AttributePainter, default_for

    class _ShadowingWarning(AttributePainter):
        __slots__ = ()
        service = engine_cls.service
        target = Shadowing

        def exec(self, attribute: Shadowing, engine: Any) -> None:
            if not (attribute.cast and attribute.receive):
                warn_unsupported(engine, label, "Shadowing(cast=False) or Shadowing(receive=False)",
                                 "every shape casts and receives shadows here (GL and POV-Ray honour it)")  # fmt: skip

    default_for(engine_cls)(type(f"{engine_cls.__name__}ShadowingWarning", (_ShadowingWarning,), {"__slots__": ()}))
    if mirror:
        return

    class _MirrorWarning(AttributePainter):
        __slots__ = ()
        service = engine_cls.service
        target = Mirror

        def exec(self, attribute: Mirror, engine: Any) -> None:
            warn_unsupported(engine, label, "Mirror", "the surface is drawn with its material only")

    default_for(engine_cls)(type(f"{engine_cls.__name__}MirrorWarning", (_MirrorWarning,), {"__slots__": ()}))
