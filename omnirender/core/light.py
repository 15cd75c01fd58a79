"""Lights and the light switch, which the engine pre-evaluates.

Lights are poly attributes that share the category :class:`Light`.  Before the
main traversal an engine collects every light with its world transform, so a
light placed anywhere in the graph (even after the shapes) lights everything,
unless a :class:`LightSwitch` turns it off for a subgraph.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from .component import MonoAttribute, PolyAttribute

__all__ = ["Light", "LightSwitch", "light_on"]


def light_on(light: Any) -> bool:
    """Whether ``light`` shines at all (``enabled``); a ``LightSwitch`` may still turn it off for a subgraph."""
    return bool(light.enabled)


class Light(PolyAttribute):
    """Base of all lights; every subclass shares the category ``Light``."""

    __slots__ = ()
    shares_category = True
    declared = "all"  # every light shines wherever it sits (declarative pre-evaluation)
    #: False: the light is off in every engine, as if absent (``om.PointLight(enabled=False)``; ArtiSynth)
    enabled = True


class LightSwitch(MonoAttribute):
    """Turn lights on or off for the subgraph that follows.

    ``LightSwitch(on=False)`` turns every light off, ``LightSwitch(on=False,
    lights=[a])`` only ``a``; ``LightSwitch(on=True, lights=[a])`` leaves only
    ``a`` on.  Being a mono attribute, the innermost switch decides alone.
    """

    __slots__ = ("on", "lights")

    def __init__(self, on: bool = False, lights: Iterable[Any] | None = None) -> None:
        super().__init__()
        self.on = bool(on)
        self.lights = None if lights is None else tuple(lights)
        if self.lights is not None:
            for i, light in enumerate(self.lights):
                if not isinstance(light, Light):
                    raise ValueError(f"LightSwitch: lights[{i}] must be a light, got {type(light).__name__}")

    def allows(self, light: Light) -> bool:
        """Whether ``light`` is on under this switch."""
        if not light.enabled:
            return False
        if self.lights is None:
            return self.on
        listed = any(light is other for other in self.lights)
        return listed if self.on else not listed
