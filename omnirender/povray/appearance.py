"""Default conversion of the generic appearance attributes to POV-Ray textures.

Colours of ``Color``, ``Material`` and ``PBRMaterial`` are display (sRGB)
values, as the GL engine shows them; the scene is written with
``assumed_gamma 1.0`` and the output encoded as sRGB, so they are converted to
linear values here and a fully lit surface gets the colour GL shows.  The
base colour comes from ``PBRMaterial``, else ``Material``, else ``Color``,
else grey 0.8.  POV-Ray multiplies ``ambient`` and ``emission`` by the
pigment, so those are divided by the pigment colour.  The renderer-specific
``Pigment`` replaces the derived pigment, ``Finish`` items are appended to the
derived finish (later items win in POV-Ray) and ``Normal`` is added.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..attributes import Color, Material, PBRMaterial, Texture
from . import sdl
from .attributes import Finish, Normal, Pigment

__all__ = ["srgb_to_linear", "surface", "texture_name", "finish_name"]

_DEFAULT_RGB = (0.8, 0.8, 0.8)


def srgb_to_linear(c: Any) -> np.ndarray:
    """sRGB-encoded values in [0, 1] to linear values."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, None)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def surface(engine: Any) -> tuple[np.ndarray, float, list[str]]:
    """(linear base colour, transmit, finish items) from the active generic attributes."""
    pbr = engine.mono(PBRMaterial)
    mat = engine.mono(Material)
    col = engine.mono(Color)
    items: list[str] = []
    if pbr is not None:
        base = srgb_to_linear(pbr.base_color)
        transmit = 1.0 - float(pbr.opacity)
        metallic, rough = float(pbr.metallic), float(pbr.roughness)
        items.append(f"ambient 0 diffuse {sdl.number(1.0 - 0.9 * metallic)}")
        items.append(f"specular {sdl.number(0.04 + 0.96 * metallic * (1 - rough) + 0.3 * (1 - rough))}")
        items.append(f"roughness {sdl.number(max(rough * rough * 0.5, 1e-4))}")
        if metallic > 0.0:
            items.append(f"metallic {sdl.number(metallic)}")
            items.append(f"reflection {{ {sdl.number(metallic * (1.0 - rough))} metallic }}")
        emission = srgb_to_linear(pbr.emission)
        base = _lift(base, emission)
    elif mat is not None:
        base = _lift(srgb_to_linear(mat.diffuse), srgb_to_linear(mat.ambient), srgb_to_linear(mat.emission))
        transmit = 1.0 - float(mat.opacity)
        items.append(f"ambient rgb {sdl.vector(_over(srgb_to_linear(mat.ambient), base))} diffuse 1")
        spec = float(np.mean(srgb_to_linear(mat.specular)))
        if spec > 0.0:
            items.append(f"phong {sdl.number(spec)} phong_size {sdl.number(max(float(mat.shininess), 1.0))}")
        emission = srgb_to_linear(mat.emission)
    else:
        rgb = _DEFAULT_RGB if col is None else col.rgb
        base = srgb_to_linear(rgb)
        transmit = 0.0 if col is None else 1.0 - float(col.a)
        # the default GL material: ambient 0.2, diffuse 0.8 -> ambient is a quarter of the base colour
        items.append("ambient 0.25 diffuse 1")
        emission = np.zeros(3)
    if np.any(emission > 0.0):
        items.append(f"emission rgb {sdl.vector(_over(emission, base))}")
    return base, transmit, items


_MIN_PIGMENT = 1e-4  # linear; 0.3/255 in sRGB: invisible under any light, yet it carries ambient and emission


def _lift(base: np.ndarray, *needs: np.ndarray) -> np.ndarray:
    """``base`` with black channels raised to a tiny value where ambient or emission needs them.

    POV-Ray multiplies ambient and emission by the pigment, so a channel that is
    black in the diffuse colour would also blacken them (a purely emissive
    ``Material(diffuse=(0, 0, 0), emission=...)`` rendered black); GL adds them.
    """
    needed = np.maximum.reduce([np.asarray(n, np.float64) for n in needs]) > 0.0
    return np.where(needed & (base < _MIN_PIGMENT), _MIN_PIGMENT, base)


def _over(value: np.ndarray, base: np.ndarray) -> np.ndarray:
    """``value / base`` per channel (POV-Ray multiplies ambient and emission by the pigment)."""
    return np.where(base > 0.0, value / np.maximum(base, _MIN_PIGMENT), value)


def _finish_text(engine: Any, items: list[str]) -> str:
    extra = engine.mono(Finish)
    body = " ".join(items)
    if extra is not None:
        body += " " + extra.body()
    return f"finish {{ {body} }}"


def _key(*attrs: Any) -> tuple:
    return tuple((id(a), a.version) if a is not None else None for a in attrs)


def _active(engine: Any) -> tuple:
    return (
        engine.mono(PBRMaterial),
        engine.mono(Material),
        engine.mono(Color),
        engine.mono(Finish),
    )


def texture_name(engine: Any, uv: bool = False) -> str:
    """The declared texture for the active attributes (declared once per combination)."""
    texture = engine.mono(Texture)
    pigment_attr = engine.mono(Pigment)
    normal = engine.mono(Normal)
    key = ("T", uv, _key(*_active(engine), texture, pigment_attr, normal))
    found = engine._declared.get(key)
    if found is not None:
        return found
    base, transmit, items = surface(engine)
    if pigment_attr is not None:
        pigment = pigment_attr.sdl()
    elif texture is not None:
        pigment = _image_pigment(engine, texture, transmit, uv)
    else:
        pigment = f"pigment {{ {sdl.color(base, transmit)} }}"
    parts = [pigment]
    if normal is not None:
        parts.append(normal.sdl())
    parts.append(_finish_text(engine, items))
    return engine.declare(key, "T", "texture { " + " ".join(parts) + " }")


def finish_name(engine: Any) -> str:
    """The declared finish of the active attributes (for per-vertex coloured meshes)."""
    key = ("F", _key(*_active(engine)))
    found = engine._declared.get(key)
    if found is not None:
        return found
    _, _, items = surface(engine)
    return engine.declare(key, "F", _finish_text(engine, items))


def _image_pigment(engine: Any, texture: Any, transmit: float, uv: bool) -> str:
    path = texture.path
    if path is not None and not os.path.isfile(path):
        raise FileNotFoundError(
            f"POV-Ray: the Texture image {path!r} in node {engine.node_path or '/'} does not exist; "
            "check the path or pass an array (om.Texture(numpy_array))"
        )
    if path is not None and _suffix(path) != "":
        name = engine.resource(("path", path), path, suffix=_suffix(path))
    else:  # arrays and files of other formats are written as PNG
        name = engine.resource(("array", id(texture), texture.version), texture.image_array(), ".png")
    kind = {".png": "png", ".jpg": "jpeg", ".jpeg": "jpeg", ".tga": "tga"}[_suffix(name)]
    interpolate = " interpolate 2" if texture.filter == "linear" else ""
    once = " once" if texture.wrap == "clamp" else ""
    mapping = "uv_mapping " if uv else ""
    filt = f" filter all {sdl.number(transmit)}" if transmit > 0 else ""
    return f"pigment {{ {mapping}image_map {{ {kind} {sdl.file_name(name)}{interpolate}{once}{filt} }} }}"


def _suffix(path: str) -> str:
    """The file's extension if POV-Ray reads that format, else ""."""
    ext = os.path.splitext(str(path))[1].lower()
    return ext if ext in (".png", ".jpg", ".jpeg", ".tga") else ""
