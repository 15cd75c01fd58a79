"""The one appearance model (:mod:`omnirender.attributes.surface`) as POV-Ray textures.

The scene is written with ``assumed_gamma 1.0`` and the output encoded as
sRGB, so the resolved (linear) colours go in unchanged and a fully lit surface
gets the colour GL shows.  The mapping:

- base colour: the pigment; a base colour texture (or texture layers) times
  the base colour is baked into one image (``image_map``, its PNG alpha is
  POV-Ray's transmit: cut-outs are baked as 0 or 1, opaque PBR surfaces as 1);
- ambient: ``ambient`` = ambient reflectance / pigment, for every material (PBR
  too: POV-Ray's ``ambient 0`` made shadowed PBR surfaces black), times the
  mean of an occlusion texture;
- Phong specular: ``phong`` with ``phong_size`` = shininess (the GL engine's lobe);
  PBR: ``specular`` / ``roughness`` / ``metallic`` / ``reflection`` from the
  factors (a metallic-roughness texture contributes its mean);
- emission: ``emission`` (divided by the pigment, which POV-Ray multiplies it
  with); an emissive texture makes the texture the average of the lit
  surface and a self-lit one, each doubled;
- normal maps (and the heights of a ``BumpMap``): ``normal { bump_map }``
  with heights integrated from the normal map (Frankot-Chellappa), an
  approximation: POV-Ray bumps with heights, not normals;
- per-vertex colours replace a Phong diffuse colour and multiply a PBR base colour.

The renderer-specific ``Pigment`` replaces the derived pigment, ``Finish``
items are appended to the derived finish (later items win in POV-Ray) and
``Normal`` replaces a derived normal.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..attributes.photometry import srgb_to_linear
from ..attributes.surface import Appearance, appearance_key, engine_appearance, vertex_rgba
from ..attributes.texturing import bake_layers, channel_mean, luminance, normal_to_height, scaled_image
from ..core import version_key
from . import sdl
from .attributes import Finish, Normal, Pigment

__all__ = ["srgb_to_linear", "texture_name", "finish_name", "finish_items", "vertex_colors"]

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


def _mean_texture(engine: Any, texture: Any, channel: int) -> float:
    return channel_mean(texture.image_in("POV-Ray", engine.node_path), channel)


def finish_items(engine: Any, app: Appearance, scale: float = 1.0) -> tuple[np.ndarray, list[str]]:
    """(pigment colour, finish items) of a resolved appearance; ``scale`` multiplies the reflection."""
    base = np.asarray(app.base, np.float64)
    emission = np.asarray(app.emission, np.float64)
    ambient = app.ambient_reflectance()
    if app.occlusion_texture is not None:
        ambient = ambient * (1.0 + app.occlusion_strength * (_mean_texture(engine, app.occlusion_texture, 0) - 1.0))
    base = _lift(base, ambient, emission)
    items = [f"ambient rgb {sdl.vector(_over(ambient, base) * scale)}"]
    n = sdl.number
    if app.model == "pbr":
        metallic, rough = app.metallic, app.roughness
        if app.metallic_roughness_texture is not None:
            metallic *= _mean_texture(engine, app.metallic_roughness_texture, 2)
            rough *= _mean_texture(engine, app.metallic_roughness_texture, 1)
        items.append(f"diffuse {n((1.0 - 0.9 * metallic) * scale)}")
        items.append(f"specular {n((0.04 + 0.96 * metallic * (1 - rough) + 0.3 * (1 - rough)) * scale)}")
        items.append(f"roughness {n(max(rough * rough * 0.5, 1e-4))}")
        if metallic > 0.0:
            items.append(f"metallic {n(metallic)}")
            items.append(f"reflection {{ {n(metallic * (1.0 - rough) * scale)} metallic }}")
    else:
        items.append(f"diffuse {n(scale)}")
        spec = float(np.mean(app.specular))
        if spec > 0.0:
            items.append(f"phong {n(spec * scale)} phong_size {n(max(app.shininess, 1.0))}")
    if np.any(emission > 0.0) and app.emissive_texture is None:
        items.append(f"emission rgb {sdl.vector(_over(emission, base) * scale)}")
    return base, items


def _finish_text(engine: Any, items: list[str]) -> str:
    extra = engine.mono(Finish)
    body = " ".join(items)
    if extra is not None:
        body += " " + extra.body()
    return f"finish {{ {body} }}"


def _active_key(engine: Any, uv: bool) -> tuple:
    from ..attributes import BumpMap, MultiTexture, Texture

    mono = engine.mono
    texture = (mono(Texture), mono(MultiTexture), mono(BumpMap)) if uv else (None, None, None)
    extra = tuple(version_key(a) for a in (mono(Finish), mono(Pigment), mono(Normal)))
    return (appearance_key(engine.surface_stack, *texture), extra, uv)


def texture_name(engine: Any, uv: bool = False) -> str:
    """The declared texture for the active attributes (declared once per combination).

    ``uv``: the shape has texture coordinates (``uv_mapping``), so textures apply.
    """
    key = ("T", _active_key(engine, uv))
    found = engine._declared.get(key)
    if found is not None:
        return found
    app = engine_appearance(engine, texcoords=uv)
    body = _texture_body(engine, app, uv)
    return engine.declare(key, "T", "texture { " + body + " }")


_CLEAR = "pigment { rgbt 1 } finish { ambient 0 diffuse 0 specular 0 phong 0 reflection 0 emission 0 }"


def _texture_body(engine: Any, app: Appearance, uv: bool) -> str:
    pigment_attr = engine.mono(Pigment)
    if uv and app.alpha_mode == "mask" and app.texture is not None and pigment_attr is None:
        return _cut_out(engine, app)
    mr = app.metallic_roughness_texture
    if uv and mr is not None and app.model == "pbr" and pigment_attr is None:
        return _metallic_map(engine, app, mr)
    normal = _normal(engine, app, uv)
    emissive = uv and app.emissive_texture is not None
    scale = 2.0 if emissive else 1.0
    base, items = finish_items(engine, app, scale)
    if pigment_attr is not None:
        pigment = pigment_attr.sdl()
    elif uv and (app.texture is not None or app.layers):
        pigment = _image_pigment(engine, app, base)
    else:
        transmit = 1.0 - app.alpha if app.alpha_mode == "blend" else 0.0
        pigment = f"pigment {{ {sdl.color(base, transmit)} }}"
    lit = " ".join(p for p in (pigment, normal, _finish_text(engine, items)) if p)
    if not emissive:
        return lit
    et = app.emissive_texture
    glow = _image_file(engine, et, np.append(_rgb_display(app.emission), 1.0), "emissive")
    once = " once" if _clamps(et) else ""
    self_lit = (
        f"pigment {{ uv_mapping image_map {{ png {sdl.file_name(glow)}{_interpolation(et)}{once} }}"
        f"{_uv_transform(et, engine)} }} "
        "finish { ambient 0 diffuse 0 emission 2 }"
    )
    return f"average texture_map {{ [1 {lit}] [1 {self_lit}] }}"


def _cut_out(engine: Any, app: Appearance) -> str:
    """A masked surface: nothing at all (no highlight either) where the alpha is below the cutoff.

    POV-Ray still adds highlights on fully transmitting surfaces, so the
    texture is switched off there with an ``image_pattern`` of the mask.
    """
    from dataclasses import replace

    tex = app.texture
    alpha = tex.image_in("POV-Ray", engine.node_path)[:, :, 3].astype(np.float64) / 255.0 * app.alpha
    mask = np.repeat(np.where(alpha >= app.alpha_cutoff, 255, 0).astype(np.uint8)[:, :, None], 3, 2)
    clamp = _clamps(tex)
    name = engine.resource(("mask", version_key(tex), app.alpha_cutoff), _clamp_padded(mask) if clamp else mask, ".png")
    opaque = _texture_body(engine, replace(app, alpha_mode="opaque"), True)
    once = " once" if clamp else ""
    pattern = f"uv_mapping image_pattern {{ png {sdl.file_name(name)}{once} }}{_uv_transform(tex, engine)}"
    return f"{pattern} texture_map {{ [0.5 {_CLEAR}] [0.5 {opaque}] }}"


def _metallic_map(engine: Any, app: Appearance, mr: Any) -> str:
    """Per-texel metallic: a dielectric and a metal texture blended by the texture's blue channel.

    POV-Ray's ``image_pattern`` selects between the two as the image is dark
    or bright; roughness (green) uses its mean, an approximation.
    """
    from dataclasses import replace

    pixels = mr.image_in("POV-Ray", engine.node_path)
    rough = app.roughness * channel_mean(pixels, 1)
    dielectric = replace(app, metallic=0.0, roughness=rough, metallic_roughness_texture=None)
    metal = replace(app, roughness=rough, metallic_roughness_texture=None)
    blue = np.repeat(pixels[:, :, 2:3], 3, axis=2)
    name = engine.resource(("metallic", version_key(mr)), blue, ".png")
    pattern = f"uv_mapping image_pattern {{ png {sdl.file_name(name)} interpolate 2 }}{_uv_transform(mr)}"
    low, high = _texture_body(engine, dielectric, True), _texture_body(engine, metal, True)
    return f"{pattern} texture_map {{ [0 {low}] [1 {high}] }}"


def _rgb_display(linear: Any) -> np.ndarray:
    from ..attributes.photometry import linear_to_srgb

    return linear_to_srgb(np.asarray(linear, np.float64))


def finish_name(engine: Any) -> str:
    """The declared finish of the active attributes (for per-vertex coloured meshes)."""
    key = ("F", _active_key(engine, False))
    found = engine._declared.get(key)
    if found is not None:
        return found
    app = engine_appearance(engine, texcoords=False)
    _, items = finish_items(engine, app)
    return engine.declare(key, "F", _finish_text(engine, items))


def vertex_colors(engine: Any, colors: np.ndarray) -> np.ndarray:
    """Linear RGBA per-vertex colours as the appearance model applies them (``surface.vertex_rgba``)."""
    return vertex_rgba(engine_appearance(engine, texcoords=False), colors)


def _normal(engine: Any, app: Appearance, uv: bool) -> str:
    user = engine.mono(Normal)
    if user is not None:
        return user.sdl()
    if not uv or not app.has_normal_map:
        return ""
    if app.bump is not None and app.normal_texture is None:
        tex = app.bump.texture
        heights, size = luminance(tex.image_in("POV-Ray", engine.node_path)), float(app.bump.scale)
        key = ("bump", version_key(tex))
    else:
        tex = app.normal_texture
        heights, size = normal_to_height(tex.image_in("POV-Ray", engine.node_path), app.normal_scale)
        key = ("normal", version_key(tex), app.normal_scale)
    if size <= 0.0:
        return ""
    image = np.repeat(np.round(heights * 255.0).astype(np.uint8)[:, :, None], 3, axis=2)
    name = engine.resource(key, image, ".png")
    # POV-Ray's bump_map takes its slopes per pixel and raises the surface where the image is dark: the size
    # is the height range in texture-coordinate units times the pixels per unit, negated
    size *= float(np.sqrt(heights.shape[0] * heights.shape[1]))
    bump = f"png {sdl.file_name(name)} interpolate 2 bump_size {sdl.number(-size)}"
    return f"normal {{ uv_mapping bump_map {{ {bump} }} }}"


def _image_file(
    engine: Any, texture: Any, factor: Any, role: str, layers: tuple = (), mode: str = "blend", cutoff: float = 0.5
) -> str:
    """A PNG of ``texture`` (and layers) times ``factor`` (display RGBA), alpha per ``mode``; its resource name."""
    path = texture.path if texture is not None else None
    if path is not None and not os.path.isfile(path):
        raise FileNotFoundError(
            f"POV-Ray: the Texture image {path!r} in node {engine.node_path or '/'} does not exist; "
            "check the path or pass an array (om.Texture(numpy_array))"
        )
    clamp = _clamps(texture, layers)
    plain = not layers and mode == "blend" and np.allclose(factor, 1.0, atol=1e-6) and not clamp
    if plain and path is not None and _suffix(path) != "":
        return engine.resource(("path", path), path, suffix=_suffix(path))
    key = (role, id(texture), getattr(texture, "version", 0), tuple(np.round(factor, 6)), mode, cutoff)
    key += tuple((version_key(x.texture), x.blend, x.opacity) for x in layers)
    found = engine._resource_names.get(key)
    if found is not None:
        return found
    base = None if texture is None else texture.image_in("POV-Ray", engine.node_path)
    image = bake_layers(base, layers) if layers else base
    image = scaled_image(image, factor)
    if mode != "blend":
        image = np.array(image)
        if mode == "mask":
            image[:, :, 3] = np.where(image[:, :, 3] >= 255 * cutoff, 255, 0)
        else:
            image[:, :, 3] = 255
    if clamp:
        image = _clamp_padded(image)
    return engine.resource(key, image, ".png")


def _image_pigment(engine: Any, app: Appearance, base: np.ndarray) -> str:
    tex = app.texture
    factor = np.append(_rgb_display(base), app.alpha if app.alpha_mode == "blend" else 1.0)
    mode = app.alpha_mode if app.model == "pbr" else "blend"
    name = _image_file(engine, tex, factor, "base", app.layers, mode, app.alpha_cutoff)
    kind = {".png": "png", ".jpg": "jpeg", ".jpeg": "jpeg", ".tga": "tga"}[_suffix(name)]
    interpolate = _interpolation(tex)
    once = " once" if _clamps(tex, app.layers) else ""
    transform = _uv_transform(tex, engine) if tex is not None and not app.layers else ""
    return f"pigment {{ uv_mapping image_map {{ {kind} {sdl.file_name(name)}{interpolate}{once} }}{transform} }}"


def _interpolation(texture: Any) -> str:
    """POV-Ray's image interpolation for the texture's filter (bilinear, or none for ``"nearest"``)."""
    return " interpolate 2" if texture is None or texture.filter == "linear" else ""


#: A clamped texture's image is extended by this fraction of its size on every side with its edge texels
#: (POV-Ray's ``once`` leaves the outside transparent; OpenGL's CLAMP_TO_EDGE repeats the edge), at most
#: CLAMP_PAD_PIXELS texels: looked-up coordinates in [-1, 2] show the edge, as in every other engine.
CLAMP_PAD = 1.0
CLAMP_PAD_PIXELS = 1024


def _clamps(texture: Any, layers: tuple = ()) -> bool:
    return texture is not None and texture.wrap == "clamp" and not layers


def _pad(size: int) -> int:
    return min(int(round(size * CLAMP_PAD)), CLAMP_PAD_PIXELS)


def _clamp_padded(image: np.ndarray) -> np.ndarray:
    """The image with :func:`_pad` edge texels added on every side."""
    h, w = image.shape[:2]
    return np.pad(image, ((_pad(h), _pad(h)), (_pad(w), _pad(w)), (0, 0)), mode="edge")


def _uv_transform(texture: Any, engine: Any = None) -> str:
    """POV-Ray's pattern transform for a texture transform (the pattern maps the looked-up coordinates back).

    A clamped texture's image is padded (:func:`_clamp_padded`): the looked-up coordinates are mapped into
    the padded image too.
    """
    m = texture.uv_matrix()
    if texture.wrap == "clamp" and engine is not None:
        h, w = texture.image_in("POV-Ray", engine.node_path).shape[:2]
        ph, pw = _pad(h), _pad(w)
        into = np.array([[w / (w + 2 * pw), 0.0, pw / (w + 2 * pw)], [0.0, h / (h + 2 * ph), ph / (h + 2 * ph)],
                         [0.0, 0.0, 1.0]])  # fmt: skip
        m = into @ m
    elif not texture.transformed:
        return ""
    m = np.linalg.inv(m)
    full = np.eye(4)
    full[:2, :2], full[:2, 3] = m[:2, :2], m[:2, 2]
    return " " + sdl.matrix(full)


def _suffix(path: str) -> str:
    """The file's extension if POV-Ray reads that format, else ""."""
    ext = os.path.splitext(str(path))[1].lower()
    return ext if ext in (".png", ".jpg", ".jpeg", ".tga") else ""
