"""Attribute conversion between engines (the VRS attribute simplifier).

A renderer-specific attribute (``om.povray.Finish``, ``om.povray.Pigment``,
``om.mitsuba.BSDF``, ``om.radiance.Material``) is read by its own engine
directly.  Every *other* engine converts it to the closest generic appearance
instead of ignoring it, through one rule: the attribute's class derives from
:class:`EngineSpecific` and says in :meth:`EngineSpecific.generic` what it
means in generic terms, given the generic material active where it sits; the
one :class:`GenericConversion` simplifier (installed for every engine) pushes
that.  The owning engine registers a passive painter for its own classes
(:func:`native_to`), so for it the handler look-up stops there and the
attribute stays on its own stack, where its engine reads it.

What cannot be expressed generically (POV-Ray reflection, patterns, Mitsuba
textures given as plugin dicts, Radiance patterns and mixtures) is left out of
the converted material: ``generic`` returns None when nothing of the attribute
can be kept, and the attribute then changes nothing, as before.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.engine import Engine
from ..core.handler import AttributePainter, AttributeSimplifier, default_for
from .appearance import Material
from .photometry import linear_to_srgb

__all__ = ["EngineSpecific", "GenericConversion", "native_to", "shininess_of_roughness", "display_rgb"]


class EngineSpecific:
    """Mixin of renderer-specific attributes: ``generic(current)`` gives their generic meaning (or None).

    ``current`` is the active ``om.Material`` (None when there is none); the
    result is a list of generic attributes pushed in the attribute's place.
    """

    __slots__ = ()

    def generic(self, current: Material | None) -> list[Any] | None:  # pragma: no cover - every class defines it
        raise NotImplementedError


@default_for(Engine)
class GenericConversion(AttributeSimplifier):
    """Push the generic meaning of a renderer-specific attribute in engines that do not read it natively."""

    __slots__ = ()
    target = EngineSpecific

    def exec(self, attribute: Any, engine: Engine) -> None:
        converted = attribute.generic(engine.mono(Material))
        for item in converted or ():
            engine.push(item)


class _Native(AttributePainter):
    """Passive: the attribute stays on its own stack for its engine to read."""

    __slots__ = ()


def native_to(engine_class: type, service: str, *classes: type) -> None:
    """Register, for ``engine_class``, passive painters of ``service`` for its own renderer-specific classes."""
    for cls in classes:
        painter = type(f"Native{cls.__name__}", (_Native,), {"__slots__": (), "service": service, "target": cls})
        default_for(engine_class)(painter)


def shininess_of_roughness(alpha: float) -> float:
    """The Phong exponent whose microfacet slope is ``alpha`` (inverse of ``phong_roughness``), in [1, 10000]."""
    a = min(max(float(alpha), 0.01), 1.0)
    return float(min(max((1.0 / (a * a) - 1.0) / 2.0, 1.0), 10000.0))


def display_rgb(linear: Any) -> tuple[float, float, float] | None:
    """A linear RGB reflectance (a number or three) as the display values generic materials hold, or None."""
    try:
        v = np.asarray(linear, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        return None
    if v.size == 1:
        v = np.repeat(v, 3)
    if v.size != 3 or not np.all(np.isfinite(v)):
        return None
    out = linear_to_srgb(np.clip(v, 0.0, 1.0))
    return (float(out[0]), float(out[1]), float(out[2]))


def based_on(current: Material | None, **changes: Any) -> Material:
    """A copy of ``current`` (or the default material) with ``changes``."""
    params = {} if current is None else dict(current.parameters())
    params.update(changes)
    return Material(**params)


def opacity_of(value: float) -> float:
    return float(min(max(value, 0.0), 1.0))
