"""Mitsuba-specific attributes: Mitsuba's own plugins passed through unchanged.

Other engines have no handler for these classes, so they are pushed/added
passively and ignored there: a scene can carry Mitsuba looks next to its
generic materials.

- :class:`BSDF` (mono): the BSDF of the shapes that follow, instead of the one
  converted from ``Material``/``PBRMaterial``/``Color``.
- :class:`Emitter` (poly): an extra emitter.  ``{"type": "area", ...}`` is
  attached to every following shape while it is active; any other type (``envmap``,
  ``constant``, ``point``...) is added to the scene once, with the model
  matrix as its ``to_world`` when the plugin dict has none.
- :class:`Integrator` (mono): the integrator of the whole render; it may sit
  anywhere in the graph, the last one met wins.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

from ..core import MonoAttribute, PolyAttribute

__all__ = ["BSDF", "Emitter", "Integrator", "MitsubaPlugin"]


def _check_plugin(owner: str, plugin: Any) -> dict[str, Any]:
    if not isinstance(plugin, Mapping):
        raise TypeError(
            f"{owner}: give a Mitsuba plugin dict like {{'type': 'diffuse', ...}}, got {type(plugin).__name__}"
        )
    kind = plugin.get("type")
    if not isinstance(kind, str) or not kind:
        raise ValueError(
            f"{owner}: the plugin dict needs a non-empty 'type' entry (a Mitsuba plugin name), got {kind!r}"
        )
    for key in plugin:
        if not isinstance(key, str):
            raise TypeError(f"{owner}: plugin dict keys must be strings, got {key!r}")
    return dict(plugin)


class MitsubaPlugin:
    """Mixin: a validated Mitsuba plugin dict in ``plugin`` (copied on access by engines)."""

    __slots__ = ()

    def plugin_dict(self) -> dict[str, Any]:
        """A deep copy of the plugin dict, safe to hand to ``mi.load_dict``."""
        return copy.deepcopy(self._plugin)  # type: ignore[attr-defined]

    @property
    def plugin(self) -> dict[str, Any]:
        return self._plugin  # type: ignore[attr-defined]

    @plugin.setter
    def plugin(self, value: Mapping[str, Any]) -> None:
        object.__setattr__(self, "_plugin", _check_plugin(type(self).__name__, value))
        self.touch()  # type: ignore[attr-defined]

    @property
    def kind(self) -> str:
        """The Mitsuba plugin name (``plugin["type"]``)."""
        return self._plugin["type"]  # type: ignore[attr-defined]

    def parameters(self) -> dict[str, Any]:
        return {"plugin": dict(self._plugin)}  # type: ignore[attr-defined]


class BSDF(MitsubaPlugin, MonoAttribute):
    """A Mitsuba BSDF plugin dict for the following shapes: ``BSDF({"type": "dielectric"})``."""

    __slots__ = ("_plugin",)

    def __init__(self, plugin: Mapping[str, Any]) -> None:
        super().__init__()
        self.plugin = plugin


class Emitter(MitsubaPlugin, PolyAttribute):
    """A Mitsuba emitter plugin dict: ``Emitter({"type": "envmap", "filename": "sky.exr"})``."""

    __slots__ = ("_plugin",)

    def __init__(self, plugin: Mapping[str, Any]) -> None:
        super().__init__()
        self.plugin = plugin

    @property
    def is_area(self) -> bool:
        """Area emitters attach to shapes; the others are scene emitters."""
        return self.kind == "area"


class Integrator(MitsubaPlugin, MonoAttribute):
    """The Mitsuba integrator for the render: ``Integrator({"type": "path", "max_depth": 12})``."""

    __slots__ = ("_plugin",)

    def __init__(self, plugin: Mapping[str, Any]) -> None:
        super().__init__()
        self.plugin = plugin
