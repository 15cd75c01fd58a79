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

from ..attributes.appearance import PBRMaterial
from ..attributes.conversion import EngineSpecific, based_on, display_rgb, shininess_of_roughness
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


def _value(spec: Any) -> Any:
    """The number or RGB list of a reflectance given as a number, a list or ``{"type": "rgb", "value": ...}``."""
    if isinstance(spec, Mapping):
        return spec.get("value") if spec.get("type") in ("rgb", "spectrum") else None
    return spec


class BSDF(EngineSpecific, MitsubaPlugin, MonoAttribute):
    """A Mitsuba BSDF plugin dict for the following shapes: ``BSDF({"type": "dielectric"})``.

    Other engines use the closest generic material (``generic``): ``diffuse``
    and the plastics as a Phong material (roughness as exponent), the
    conductors and ``principled`` as a metallic-roughness material, the
    dielectrics as a mostly transparent glossy material; ``twosided`` wraps are
    looked through.  Textured parameters keep the current colour.
    """

    __slots__ = ("_plugin",)

    def __init__(self, plugin: Mapping[str, Any]) -> None:
        super().__init__()
        self.plugin = plugin

    def generic(self, current: Any) -> list[Any] | None:
        p = self._plugin
        while p.get("type") in ("twosided", "mask", "bumpmap", "normalmap"):
            nested = [v for v in p.values() if isinstance(v, Mapping) and "type" in v and v["type"] != "bitmap"]
            if not nested:
                return None
            p = nested[-1]
        kind = p.get("type")
        alpha = float(p["alpha"]) if isinstance(p.get("alpha"), (int, float)) else 0.1
        if kind == "diffuse":
            rgb = display_rgb(_value(p.get("reflectance", 0.5)))
            return [based_on(current, diffuse=rgb, specular=(0.0, 0.0, 0.0))] if rgb else None
        if kind in ("plastic", "roughplastic"):
            rgb = display_rgb(_value(p.get("diffuse_reflectance", 0.5)))
            shininess = shininess_of_roughness(alpha) if kind == "roughplastic" else 200.0
            changes = {"specular": (0.5, 0.5, 0.5), "shininess": shininess}
            if rgb:
                changes["diffuse"] = rgb
            return [based_on(current, **changes)]
        if kind in ("conductor", "roughconductor"):
            rgb = display_rgb(_value(p.get("specular_reflectance", 1.0))) or (1.0, 1.0, 1.0)
            roughness = alpha**0.5 if kind == "roughconductor" else 0.05
            return [PBRMaterial(base_color=rgb, metallic=1.0, roughness=min(max(roughness, 0.0), 1.0))]
        if kind == "principled":
            rgb = display_rgb(_value(p.get("base_color", 0.5))) or (0.5, 0.5, 0.5)
            metallic = p.get("metallic", 0.0)
            roughness = p.get("roughness", 0.5)
            if not isinstance(metallic, (int, float)) or not isinstance(roughness, (int, float)):
                return [PBRMaterial(base_color=rgb)]
            return [PBRMaterial(base_color=rgb, metallic=float(metallic), roughness=float(roughness))]
        if kind in ("dielectric", "thindielectric", "roughdielectric"):
            return [based_on(current, specular=(1.0, 1.0, 1.0), shininess=200.0, opacity=0.2)]
        return None


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
