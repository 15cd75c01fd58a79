"""Shading models (guacamole's materials): four programmable stages with declared, typed outputs.

A :class:`ShadingModel` is GLSL in four stages, each optional but ``shading``:

* **geometry** (per vertex): ``void geometry(inout vec3 world, inout vec3 normal)`` may move the
  world position and normal (displacement) and declare ``out`` variables for the visibility stage;
* **visibility** (per fragment, before the G-buffer write):
  ``void visibility(inout Surface s, inout GBuffer g, inout LBuffer l)`` gets the resolved surface
  (``s.P``, ``s.N``, ``s.V`` eye space; ``s.world``, ``s.eye`` world space; ``s.base`` colour and alpha; ``s.texel``;
  ``s.emission``; ``s.occlusion``; ``s.ambient`` the ambient light; ``s.ambient_reflectance``;
  ``s.metallic``; ``s.roughness``; ``s.uv``), may change ``s.N``, set ``s.depth`` (window depth,
  with ``depth=True``) or ``discard``, and fills the model's G-buffer outputs ``g`` and the light that
  needs no light source (ambient, emission) in ``l``;
* **lighting** (per light per pixel): ``void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l)``
  adds one light's contribution: ``p.P``, ``p.N``, ``p.V``, ``p.world``; ``light.L`` (unit, towards the
  light), ``light.diffuse`` and ``light.specular`` (the light's colours times attenuation, spot
  factor and shadow), ``light.distance``;
* **shading** (per pixel): ``vec3 shading(Pixel p, GBuffer g, LBuffer l)`` returns the linear colour.

Outputs are declared with types: G-buffer outputs ``"unorm"`` (a float in [0, 1], 8 bits),
``"color"`` (linear RGB in [0, 1], 8 bits per channel, sRGB-encoded), ``"half"`` (a 16-bit float),
``"rgb16"`` (three 16-bit floats), ``"uint8"`` (a GLSL ``uint`` 0..255, one byte) and ``"bool"``
(a GLSL ``bool``, one byte); L-buffer outputs ``"float"`` and ``"rgb"`` (non-negative, summed
over lights).  Parameters (``"float"``, ``"vec2"``, ``"vec3"``, ``"vec4"``, ``"color"``: given as
display values like every colour of a scene) are read as ``material.<name>`` in every stage.
A :class:`MaterialDescription` is a model plus parameter values; many share one model
(``toon(bands=3)`` makes one).

The built-in models reproduce the forward engine: :data:`PHONG` (``om.Material``, ``om.Color``),
:data:`PBR` (``om.PBRMaterial``) and :data:`UNLIT`; the compiler maps the existing attributes to
them, so their numbers are the forward shader's ``MODEL`` values.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...attributes.photometry import linear_rgb
from ...core.component import MonoAttribute
from ..engine.layout import PBR as _PBR_NUMBER
from ..engine.layout import PHONG as _PHONG_NUMBER
from ..engine.layout import UNLIT as _UNLIT_NUMBER

__all__ = [
    "ShadingModel",
    "MaterialDescription",
    "ShadingModelError",
    "PHONG",
    "PBR",
    "UNLIT",
    "model_by_number",
    "model_by_name",
    "G_TYPES",
    "L_TYPES",
    "PARAM_TYPES",
]

#: G-buffer output types: (GLSL type, channels, storage: "8" unorm bytes or "16" half floats, sRGB-encoded).
G_TYPES = {
    "unorm": ("float", 1, "8", False),
    "color": ("vec3", 3, "8", True),
    "half": ("float", 1, "16", False),
    "rgb16": ("vec3", 3, "16", False),
    "uint8": ("uint", 1, "8", False),  # an integer 0..255 (larger values are clamped), one byte
    "bool": ("bool", 1, "8", False),  # a flag, one byte
}
#: L-buffer output types: (GLSL type, channels); stored in unsigned 11/11/10-bit float layers, added up.
L_TYPES = {"float": ("float", 1), "rgb": ("vec3", 3)}
#: Parameter types: (GLSL type, floats).
PARAM_TYPES = {
    "float": ("float", 1),
    "vec2": ("vec2", 2),
    "vec3": ("vec3", 3),
    "vec4": ("vec4", 4),
    "color": ("vec3", 3),
}
#: The stage functions a model's code may define, and the signature each must have.
STAGES = {
    "geometry": "void geometry(inout vec3 world, inout vec3 normal)",
    "visibility": "void visibility(inout Surface s, inout GBuffer g, inout LBuffer l)",
    "lighting": "void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l)",
    "shading": "vec3 shading(Pixel p, GBuffer g, LBuffer l)",
}
_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
#: Names the generated code reserves: not usable as output or parameter names.
_RESERVED = {"unused_", "material", "material_id"}


class ShadingModelError(ValueError):
    """A shading model's declaration or GLSL is wrong (the message names the model, the stage and the line)."""


_REGISTRY: dict[int, ShadingModel] = {}


def model_by_number(number: int) -> ShadingModel | None:
    """The shading model with the forward shader's ``MODEL`` number ``number``, or None."""
    return _REGISTRY.get(int(number))


def model_by_name(name: str) -> ShadingModel | None:
    """The most recently made shading model called ``name`` (scene files name models), or None."""
    found = [m for m in _REGISTRY.values() if m.name == name]
    return found[-1] if found else None


def _declarations(owner: str, what: str, values: Any, types: Mapping[str, tuple]) -> dict[str, Any]:
    if values is None:
        return {}
    if not isinstance(values, Mapping):
        raise ShadingModelError(f"{owner}: {what} must map names to types ({sorted(types)}), got {values!r:.60}")
    out: dict[str, Any] = {}
    for name, declared in values.items():
        if not isinstance(name, str) or not _NAME.match(name) or name in _RESERVED:
            raise ShadingModelError(
                f"{owner}: {what} name {name!r} must be a lower-case GLSL identifier and not one of {sorted(_RESERVED)}"
            )
        out[name] = declared
    return out


class ShadingModel:
    """A shading model: GLSL for the four stages plus typed G-buffer/L-buffer outputs and parameters.

    ``ShadingModel(name, gbuffer={...}, lbuffer={...}, parameters={...}, geometry=..., visibility=...,
    lighting=..., shading=..., depth=False)``; ``parameters`` maps names to a type or ``(type, default)``.
    ``depth=True`` lets the visibility stage write ``s.depth``.  Calling the model makes a
    :class:`MaterialDescription`: ``toon(bands=3)``.  See the module docstring for the stage signatures.
    """

    _next_number = 3  # 0, 1, 2: the built-in Phong, PBR and unlit models

    def __init__(
        self,
        name: str,
        *,
        gbuffer: Mapping[str, str] | None = None,
        lbuffer: Mapping[str, str] | None = None,
        parameters: Mapping[str, Any] | None = None,
        geometry: str = "",
        visibility: str = "",
        lighting: str = "",
        shading: str = "",
        depth: bool = False,
        _number: int | None = None,
    ) -> None:
        if not isinstance(name, str) or not _NAME.match(name):
            raise ShadingModelError(f"ShadingModel: name must be a lower-case identifier, got {name!r}")
        owner = f"ShadingModel {name!r}"
        self.name = name
        self.gbuffer = _declarations(owner, "gbuffer", gbuffer, G_TYPES)
        for out, kind in self.gbuffer.items():
            if kind not in G_TYPES:
                raise ShadingModelError(
                    f"{owner}: G-buffer output {out!r} has type {kind!r}; use one of {sorted(G_TYPES)}"
                )
        self.lbuffer = _declarations(owner, "lbuffer", lbuffer, L_TYPES)
        for out, kind in self.lbuffer.items():
            if kind not in L_TYPES:
                raise ShadingModelError(
                    f"{owner}: L-buffer output {out!r} has type {kind!r}; use one of {sorted(L_TYPES)}"
                )
        self.parameters: dict[str, tuple[str, Any]] = {}
        for pname, declared in _declarations(owner, "parameters", parameters, PARAM_TYPES).items():
            kind, default = (declared, None) if isinstance(declared, str) else tuple(declared)
            if kind not in PARAM_TYPES:
                raise ShadingModelError(
                    f"{owner}: parameter {pname!r} has type {kind!r}; use one of {sorted(PARAM_TYPES)}"
                )
            size = PARAM_TYPES[kind][1]
            self.parameters[pname] = (kind, _value(owner, pname, kind, (0.0,) * size if default is None else default))
        self.stages: dict[str, str] = {}
        for stage, code in (("geometry", geometry), ("visibility", visibility), ("lighting", lighting),
                            ("shading", shading)):  # fmt: skip
            if not isinstance(code, str):
                raise ShadingModelError(
                    f"{owner}: the {stage} stage must be GLSL source text, got {type(code).__name__}"
                )
            if code and not re.search(rf"\b{stage}\s*\(", code):
                raise ShadingModelError(f"{owner}: the {stage} stage must define {STAGES[stage]}")
            if code:
                self.stages[stage] = code
        if "shading" not in self.stages:
            raise ShadingModelError(f"{owner}: a model needs a shading stage: {STAGES['shading']}")
        if "lighting" in self.stages and not self.lbuffer:
            raise ShadingModelError(f"{owner}: a lighting stage needs L-buffer outputs (lbuffer={{'light': 'rgb'}})")
        self.depth = bool(depth)
        if _number is None:
            _number = ShadingModel._next_number
            ShadingModel._next_number += 1
        #: the forward shader's MODEL value and the uber-shaders' switch value
        self.number = int(_number)
        #: prefix of the generated GLSL names (unique per model)
        self.prefix = f"sm{self.number}_"
        _REGISTRY[self.number] = self

    # -- declared sizes ------------------------------------------------------------------------
    def channels(self, storage: str) -> int:
        """G-buffer channels the model writes in ``storage`` (``"8"`` bytes or ``"16"`` half floats)."""
        return sum(G_TYPES[k][1] for k in self.gbuffer.values() if G_TYPES[k][2] == storage)

    @property
    def light_channels(self) -> int:
        """L-buffer channels the model adds light into."""
        return sum(L_TYPES[k][1] for k in self.lbuffer.values())

    @property
    def parameter_slots(self) -> int:
        """vec4 slots of the model's parameters in the material table (one per parameter)."""
        return len(self.parameters)

    def pack(self, values: Mapping[str, Any], linear: bool = False) -> np.ndarray:
        """The parameter values as the material table's float32 row (one vec4 per parameter, in order).

        ``color`` values are display values converted to linear light unless ``linear`` (already linear).
        """
        out = np.zeros((max(len(self.parameters), 0), 4), np.float32)
        for k, (pname, (kind, default)) in enumerate(self.parameters.items()):
            value = values.get(pname, default)
            value = _value(f"ShadingModel {self.name!r}", pname, kind, value)
            if kind == "color" and not linear:
                value = linear_rgb(value)
            out[k, : len(value)] = value
        return out.ravel()

    def __call__(self, **values: Any) -> MaterialDescription:
        return MaterialDescription(self, **values)

    def __repr__(self) -> str:
        return f"ShadingModel({self.name!r}, stages={sorted(self.stages)})"


def _plain_value(value: Any, size: int, unit: bool) -> tuple[float, ...] | None:
    """``value`` as ``size`` floats when it is a Python number or a flat tuple or list of them, finite (and in
    [0, 1] when ``unit``); None otherwise: :func:`_value`'s general check decides and words the error."""
    items = (value,) if type(value) is float or type(value) is int else value
    if (type(items) is not tuple and type(items) is not list) or len(items) != size:
        return None
    out = []
    for v in items:
        if type(v) is not int and not isinstance(v, float):
            return None
        x = float(v)
        if not math.isfinite(x) or (unit and not 0.0 <= x <= 1.0):
            return None
        out.append(x)
    return tuple(out)


def _value(owner: str, name: str, kind: str, value: Any) -> tuple[float, ...]:
    size = PARAM_TYPES[kind][1]
    plain = _plain_value(value, size, kind == "color")
    if plain is not None:
        return plain
    try:
        arr = np.asarray(value, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        arr = np.array([np.nan])
    if arr.size != size or not np.all(np.isfinite(arr)):
        raise ShadingModelError(
            f"{owner}: parameter {name!r} ({kind}) needs {size} finite number(s), got {value!r:.60}"
        )
    if kind == "color" and not np.all((arr >= 0.0) & (arr <= 1.0)):
        raise ShadingModelError(f"{owner}: colour parameter {name!r} needs values in [0, 1], got {value!r:.60}")
    return tuple(float(v) for v in arr)


class MaterialDescription(MonoAttribute):
    """A shading model with parameter values (GL; other engines use the shape's Color/Material).

    Put it in a node like a material: the shapes after it are drawn with ``model``.  Their base
    colour, texture, emission and ambient reflectance still come from the active ``om.Color`` /
    ``om.Material`` (the one appearance model), so other engines and the forward pipeline show the
    same colours; the model decides how they are lit.  The forward pipeline draws custom models with
    the Phong model of that appearance.
    """

    __slots__ = ("model", "values", "_packed")

    def __init__(self, model: ShadingModel | str, **values: Any) -> None:
        super().__init__()
        if isinstance(model, str):  # a scene file names the model: it must be made (registered) in this process
            found = model_by_name(model)
            if found is None:
                raise ValueError(
                    f"MaterialDescription: no shading model called {model!r}; make it (om.gl.ShadingModel({model!r}, "
                    "...)) before loading a scene that uses it"
                )
            model = found
        if not isinstance(model, ShadingModel):
            raise ValueError(f"MaterialDescription: model must be an om.gl.ShadingModel, got {model!r:.60}")
        if model.number in (_PHONG_NUMBER, _PBR_NUMBER):
            raise ValueError(
                f"MaterialDescription: the built-in {model.name!r} model takes its values from "
                f"om.{'Material' if model.number == _PHONG_NUMBER else 'PBRMaterial'}; use that attribute instead"
            )
        unknown = sorted(set(values) - set(model.parameters))
        if unknown:
            raise ValueError(
                f"MaterialDescription: model {model.name!r} has no parameter(s) {unknown}; it has "
                f"{sorted(model.parameters)}"
            )
        packed = model.pack(values)  # validates
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "values", dict(values))
        object.__setattr__(self, "_packed", packed)

    @property
    def packed(self) -> np.ndarray:
        """The values as the material table's row (float32)."""
        return self._packed

    def parameters(self) -> dict[str, Any]:
        """The model's name and the values (scene files store the name: models are GLSL made by programs)."""
        return {"model": self.model.name, **self.values}

    def __repr__(self) -> str:
        return f"MaterialDescription({self.model.name!r}, {self.values})"


# -- the built-in models: the forward engine's shading, written as users write models ----------------------------
PHONG = ShadingModel(
    "phong",
    parameters={"specular": "color", "shininess": "float"},
    gbuffer={"diffuse": "color"},
    lbuffer={"light": "rgb"},
    visibility="""
void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) {
    g.diffuse = s.base.rgb;
    l.light = s.emission + s.occlusion * s.ambient_reflectance * s.ambient;
}""",
    lighting="""
void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l) {
    float NdL = dot(p.N, light.L);
    if (NdL <= 0.0) return;
    // Phong's lobe (the reflected light against the eye), shininess below 1 acts as 1: the forward shader's
    float s = pow(clamp(dot(reflect(-light.L, p.N), p.V), 0.0, 1.0), max(material.shininess, 1.0));
    l.light += g.diffuse * NdL * light.diffuse + material.specular * s * light.specular;
}""",
    shading="vec3 shading(Pixel p, GBuffer g, LBuffer l) { return l.light; }",
    _number=_PHONG_NUMBER,
)

PBR = ShadingModel(
    "pbr",
    gbuffer={"base": "color", "roughness": "unorm", "metallic": "unorm"},
    lbuffer={"light": "rgb"},
    visibility="""
void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) {
    g.base = s.base.rgb;
    g.roughness = s.roughness;
    g.metallic = s.metallic;
    vec3 F0 = mix(vec3(0.04), s.base.rgb, s.metallic);
    l.light = s.emission + s.occlusion * s.ambient * (s.base.rgb * (1.0 - s.metallic) + F0 * s.metallic);
}""",
    lighting="""
void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l) {
    float NdL = dot(p.N, light.L);
    if (NdL <= 0.0) return;
    float rough = clamp(g.roughness, 0.04, 1.0);
    float metallic = g.metallic;
    float a2 = rough * rough * rough * rough;
    float k = (rough + 1.0) * (rough + 1.0) / 8.0;
    vec3 F0 = mix(vec3(0.04), g.base, metallic);
    float NdV = max(dot(p.N, p.V), 1e-4);
    vec3 h = light.L + p.V;
    float hh = dot(h, h);
    vec3 H = hh > 1e-12 ? h * inversesqrt(hh) : p.N;
    float NdH = clamp(dot(p.N, H), 0.0, 1.0);
    float dd = NdH * NdH * (a2 - 1.0) + 1.0;
    float D = a2 / (3.14159265 * max(dd * dd, 1e-12));
    float G = (NdV / (NdV * (1.0 - k) + k)) * (NdL / (NdL * (1.0 - k) + k));
    vec3 F = F0 + (1.0 - F0) * pow(clamp(1.0 - dot(H, p.V), 0.0, 1.0), 5.0);
    vec3 spec = D * G * F / (4.0 * NdV * NdL);
    vec3 kd = (1.0 - F) * (1.0 - metallic);
    l.light += (kd * g.base + 3.14159265 * spec) * light.diffuse * NdL;
}""",
    shading="vec3 shading(Pixel p, GBuffer g, LBuffer l) { return l.light; }",
    _number=_PBR_NUMBER,
)

UNLIT = ShadingModel(
    "unlit",
    gbuffer={"color": "color"},
    visibility="void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) { g.color = s.base.rgb; }",
    shading="vec3 shading(Pixel p, GBuffer g, LBuffer l) { return g.color; }",
    _number=_UNLIT_NUMBER,
)
