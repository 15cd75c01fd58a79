"""POV-Ray-specific attributes: ``Finish``, ``Pigment``, ``Normal``, ``Interior``, ``GlobalSettings``, ``Raw``.

Other engines have no handler for these classes, so they are pushed passively
and ignored there; the POV-Ray painters read them from the context.  Parameters
are keyword arguments written as SDL ``key value`` items: numbers, vectors
(sequences), ``True`` for a bare keyword (``metallic=True``), dicts for nested
blocks (``reflection={"fresnel": True, "metallic": 0.5}``) and identifier
strings for pattern names.  Keys and strings are validated when the attribute
is made, so a scene cannot smuggle directives into the SDL; ``Raw`` is the one
deliberate exception, for trusted hand-written SDL.
"""

from __future__ import annotations

from typing import Any

from ..attributes.conversion import EngineSpecific, based_on, display_rgb
from ..core import MonoAttribute, PolyAttribute
from . import sdl

__all__ = ["SDLBlock", "Block", "Finish", "Pigment", "Normal", "Interior", "GlobalSettings", "Raw"]


class Block(dict):
    """A nested SDL block whose body starts with comma-separated arguments.

    POV-Ray writes some blocks with positional arguments, e.g. a medium's
    ``scattering { TYPE, COLOR extinction E }``.  ``Block(1, (0.1, 0.1, 0.1),
    extinction=0.5)`` as a parameter value writes ``scattering { 1,
    <0.1,0.1,0.1> extinction 0.5 }``.  Arguments are numbers, vectors or
    keywords.  It is a dict (``{"$args": [...], **params}``), so scene files
    store it as plain data.
    """

    def __init__(self, *args: Any, **params: Any) -> None:
        super().__init__({sdl.ARGS: list(args), **params})


class SDLBlock(MonoAttribute):
    """Base of attributes written as one SDL block ``keyword { params }``."""

    __slots__ = ("_params",)
    keyword = ""

    def __init__(self, **params: Any) -> None:
        super().__init__()
        self.params = params

    @property
    def params(self) -> dict[str, Any]:
        """The block's SDL parameters (validated on assignment)."""
        return dict(self._params)

    @params.setter
    def params(self, params: dict[str, Any]) -> None:
        previous = getattr(self, "_params", None)
        object.__setattr__(self, "_params", dict(params))
        try:
            self.body()  # validate now, not at render time
        except Exception:
            object.__setattr__(self, "_params", previous)
            raise

    def parameters(self) -> dict[str, Any]:
        return dict(self._params)

    def body(self) -> str:
        """The text between the braces."""
        return sdl.params_text(self._params, type(self).__name__)

    def sdl(self) -> str:
        """The whole block, e.g. ``finish { phong 0.8 }``."""
        return f"{self.keyword} {{ {self.body()} }}"


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)


def _gray_or_rgb(value: Any) -> tuple[float, float, float] | None:
    n = _number(value)
    if n is not None:
        return (n, n, n)
    if isinstance(value, (list, tuple)) and len(value) == 3 and all(_number(v) is not None for v in value):
        return (float(value[0]), float(value[1]), float(value[2]))
    return None


class Finish(EngineSpecific, SDLBlock):
    """Extra ``finish`` items, appended after those derived from the material (so they win).

    ``om.povray.Finish(phong=0.8, reflection=0.2, metallic=True)``.  Other
    engines apply what a Phong material can say (``generic``): ``phong`` (with
    ``phong_size``) or ``specular`` (with ``roughness``) as the specular colour
    and exponent, ``ambient`` and ``emission``; reflection and the rest are
    POV-Ray's only.
    """

    __slots__ = ()
    keyword = "finish"

    def generic(self, current: Any) -> list[Any] | None:
        p = self._params
        changes: dict[str, Any] = {}
        phong, specular = _number(p.get("phong")), _number(p.get("specular"))
        if phong is not None:
            changes["specular"] = (min(max(phong, 0.0), 1.0),) * 3
            changes["shininess"] = max(_number(p.get("phong_size")) or 40.0, 0.0)
        elif specular is not None:
            changes["specular"] = (min(max(specular, 0.0), 1.0),) * 3
            roughness = _number(p.get("roughness")) or 0.05
            changes["shininess"] = 1.0 / max(roughness, 1e-4)
        for key in ("ambient", "emission"):
            rgb = _gray_or_rgb(p.get(key))
            if rgb is not None:
                changes[key] = tuple(min(max(c, 0.0), 1.0) for c in rgb)
        return [based_on(current, **changes)] if changes else None


class Pigment(EngineSpecific, SDLBlock):
    """A ``pigment`` that replaces the one derived from the colour or material.

    ``color`` (3 to 5 numbers: rgb, rgbf, rgbft) is written first; other
    parameters follow, e.g. ``Pigment(pattern="checker", scale=0.5)`` writes
    ``pigment { checker scale 0.5 }`` (``pattern`` is written as a bare
    pattern name).
    """

    __slots__ = ()
    keyword = "pigment"

    def generic(self, current: Any) -> list[Any] | None:
        """Other engines: the colour as the diffuse colour (filter + transmit as transparency); patterns are lost."""
        colour = self._params.get("color")
        if colour is None:
            return None
        values = [min(max(float(v), 0.0), 1.0) for v in colour]
        changes: dict[str, Any] = {"diffuse": display_rgb(values[:3])}  # POV-Ray colours are linear
        if len(values) > 3:
            changes["opacity"] = max(0.0, 1.0 - sum(values[3:]))
        return [based_on(current, **changes)]

    def body(self) -> str:
        params = dict(self._params)
        parts = []
        pattern = params.pop("pattern", None)
        if pattern is not None:
            parts.append(sdl.identifier(pattern, "Pigment"))
        colour = params.pop("color", None)
        if colour is not None:
            values = [float(v) for v in colour]
            kinds = {3: "rgb", 4: "rgbf", 5: "rgbft"}
            if len(values) not in kinds:
                raise sdl.SDLError(f"Pigment: color needs 3, 4 or 5 numbers, got {len(values)}")
            parts.append(f"color {kinds[len(values)]} {sdl.vector(values, 'Pigment')}")
        rest = sdl.params_text(params, "Pigment")
        if rest:
            parts.append(rest)
        return " ".join(parts)


class Normal(SDLBlock):
    """A ``normal`` perturbation, e.g. ``Normal(pattern="bumps", amount=0.4, scale=0.1)``."""

    __slots__ = ()
    keyword = "normal"

    def body(self) -> str:
        params = dict(self._params)
        pattern = params.pop("pattern", None)
        amount = params.pop("amount", None)
        parts = []
        if pattern is not None:
            parts.append(sdl.identifier(pattern, "Normal"))
            if amount is not None:
                parts.append(sdl.number(amount, "Normal"))
        rest = sdl.params_text(params, "Normal")
        if rest:
            parts.append(rest)
        return " ".join(parts)


class Interior(SDLBlock):
    """An object's ``interior`` (``ior``, ``caustics``, ``fade_distance``, ``media={...}``).

    Nested blocks are dicts; blocks that take arguments use :class:`Block`::

        Interior(ior=1.3, media={"absorption": (0.2, 0.4, 0.6),
                                 "scattering": Block(1, (0.1, 0.1, 0.1), extinction=0.5)})

    writes ``interior { ior 1.3 media { absorption <0.2,0.4,0.6> scattering
    { 1, <0.1,0.1,0.1> extinction 0.5 } } }``.  A bare value for
    ``scattering`` is rejected (it would be invalid SDL); anything this form
    cannot express can be written with :class:`Raw` (``placement="object"``).
    The object must be ``hollow`` for media to show: add
    ``Raw("hollow", placement="object")``.
    """

    __slots__ = ()
    keyword = "interior"


class GlobalSettings(SDLBlock):
    """Items of ``global_settings``: ``radiosity`` (True or a dict), ``photons`` (dict), ``max_trace_level``...

    ``GlobalSettings(radiosity={"count": 200}, max_trace_level=8)``.  The last
    one pushed anywhere in the scene applies to the whole image.
    """

    __slots__ = ()
    keyword = "global_settings"

    def body(self) -> str:
        params = dict(self._params)
        parts = []
        for name in ("radiosity", "photons"):
            value = params.pop(name, None)
            if value is True:
                parts.append(f"{name} {{ }}")
            elif isinstance(value, dict):
                parts.append(sdl.block(name, value, "GlobalSettings"))
            elif value not in (None, False):
                raise sdl.SDLError(f"GlobalSettings: {name} must be True or a dict of parameters, got {value!r}")
        rest = sdl.params_text(params, "GlobalSettings")
        if rest:
            parts.append(rest)
        return " ".join(parts)


class Raw(PolyAttribute):
    """Trusted, hand-written SDL, written verbatim (never build it from untrusted input).

    ``placement="scene"`` (default) writes the text at the top level of the
    scene file where the attribute is met; ``placement="object"`` appends it
    inside every object that follows while the attribute is active (object
    modifiers such as ``no_shadow`` or ``hollow``).

    Scene files refuse it unless loaded with ``om.load(path, trusted=True)``
    (``scene_file_trusted_only``): its text could hold any SDL directive.
    """

    __slots__ = ("text", "placement")
    #: scene files load this type only with ``trusted=True`` (see omnirender.scene.files)
    scene_file_trusted_only = True

    def __init__(self, text: str, placement: str = "scene") -> None:
        super().__init__()
        if not isinstance(text, str):
            raise TypeError(f"Raw: text must be a string, got {type(text).__name__}")
        if placement not in ("scene", "object"):
            raise ValueError(f"Raw: placement must be 'scene' or 'object', got {placement!r}")
        self.text = text
        self.placement = placement
