"""The generic appearance attributes as Radiance materials (one modifier chain per combination).

The mapping (documented in the README and NOTES, matched to the GL engine's
shading under the light units of :mod:`omnirender.attributes.photometry`):

- colours are sRGB display values, converted to linear reflectances;
- ``Color`` or no appearance (grey 0.8): ``plastic`` with that colour and no
  specular part;
- Phong ``Material``: ``plastic``; the specular colour ``s`` (mean, linear) and
  the shininess ``n`` give the roughness ``a = sqrt(2 / (n + 2))`` and the
  specularity ``4 a^2 s`` (at most 0.25), which makes the highlight's peak
  equal GL's Blinn-Phong peak; the diffuse colour is divided by ``1 - spec``
  because Radiance's plastic reflects ``(1 - spec)`` of its colour diffusely;
- ``PBRMaterial``: ``plastic`` (metallic 0) or ``metal`` with specularity
  ``0.04 + 0.96 * metallic`` (diffuse ``(1 - spec) * base``, as GL's
  ``(1 - F) (1 - metallic)``) and roughness ``roughness^2`` (the GGX slope);
- opacity < 1: ``mixfunc`` of the material with ``void`` (see-through like GL's
  alpha blending, not tinted); a texture's alpha channel: ``mixpict`` with ``void``;
- emission: ``glow`` (radiance = linear emission, lighting others only through
  interreflection); with a diffuse part too, a half-and-half ``mixfunc`` of a
  doubled glow and a doubled material (the sum GL computes);
- ``Texture``: a ``colorpict`` pattern (the image as a Radiance picture, linear)
  modifying the material, looked up through the mesh's ``Lu``/``Lv``;
- ``om.radiance.Material``: replaces all of the above (a texture still modifies it).

Each distinct combination is written once and shared by the shapes using it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..attributes import Material, PBRMaterial, Texture
from ..attributes.photometry import phong_roughness, srgb_to_linear
from ..attributes.surface import engine_appearance
from ..core import version_key
from . import rad
from .attributes import Material as RadMaterial

__all__ = ["Look", "resolve_look", "modifier", "SPECULAR_LIMIT", "DEFAULT_RGB"]

#: The largest specularity a Phong material is given (Radiance calls more than ~0.1 unusually glossy).
SPECULAR_LIMIT = 0.25
#: The grey of shapes without any appearance attribute (as in GL).
DEFAULT_RGB = (0.8, 0.8, 0.8)
#: The foreground weight of a glow mixed with a reflecting material (both are scaled by its inverse).
EMISSION_WEIGHT = 0.5
#: Radiance types that let light through; the coverage pass keeps them, blackens everything else.
TRANSMITTING = frozenset({"glass", "dielectric", "interface", "trans", "trans2", "mixfunc", "mixpict", "mixdata"})
#: Picture lookup per Texture.wrap: an expression of the texture coordinate ``{c}`` (``Lu`` or ``Lv``) in [0, 1].
WRAP = {
    "repeat": "frac({c})",
    "clamp": "bound(0,{c},0.99999)",
    "mirror": "(1-abs(2*frac({c}/2)-1))",
}


@dataclass(frozen=True)
class Look:
    """A resolved surface: Radiance type, linear colour, specularity, roughness, opacity, emission."""

    kind: str
    rgb: tuple[float, float, float]
    spec: float
    rough: float
    opacity: float
    emission: tuple[float, float, float]

    def reals(self, scale: float = 1.0) -> list[float]:
        """The 5 real arguments of the plastic/metal, with the reflection scaled by ``scale``.

        ``scale`` > 1 is used inside a glow mixture: the specular fraction is
        scaled and the colour chosen so the diffuse part is scaled too.
        """
        if scale == 1.0:
            return [*self.rgb, self.spec, self.rough]
        if self.kind == "metal":  # the colour tints both parts: scaling it scales the whole reflection
            return [*(c * scale for c in self.rgb), self.spec, self.rough]
        spec = min(self.spec * scale, 0.99)
        diffuse = np.asarray(self.rgb) * (1.0 - self.spec) * scale
        return [*(diffuse / (1.0 - spec)).tolist(), spec, self.rough]


def _rgb(values: Any) -> tuple[float, float, float]:
    v = np.asarray(values, dtype=np.float64).reshape(-1)[:3]
    return (float(v[0]), float(v[1]), float(v[2]))


def resolve_look(material: Any, color: Any, vertex_rgba: Any = None) -> Look:
    """The :class:`Look` of (material, colour) as ``resolve_surface`` gives them, optionally with a vertex colour.

    A colour active after the material (or a vertex colour) replaces its
    diffuse / base colour and multiplies its opacity by its alpha.
    """
    override = None
    alpha = 1.0
    if vertex_rgba is not None:
        v = np.asarray(vertex_rgba, dtype=np.float64).reshape(-1)
        override = srgb_to_linear(v[:3])
        alpha = float(v[3]) if len(v) > 3 else 1.0
    elif color is not None and material is not None:
        override = srgb_to_linear(color.rgb)
    if color is not None:
        alpha *= float(color.a)
    if isinstance(material, PBRMaterial):
        base = srgb_to_linear(material.base_color) if override is None else override
        metallic = float(material.metallic)
        spec = 0.04 + 0.96 * metallic
        kind = "metal" if metallic > 0.0 else "plastic"
        return Look(
            kind,
            _rgb(base),
            spec,
            float(material.roughness) ** 2,
            float(material.opacity) * alpha,
            _rgb(srgb_to_linear(material.emission)),
        )
    if isinstance(material, Material):
        kd = srgb_to_linear(material.diffuse) if override is None else override
        s = float(np.mean(srgb_to_linear(material.specular)))
        rough = phong_roughness(material.shininess)
        spec = min(4.0 * rough * rough * s, SPECULAR_LIMIT) if s > 0.0 else 0.0
        return Look(
            "plastic",
            _rgb(np.asarray(kd) / (1.0 - spec)),
            spec,
            rough if spec > 0.0 else 0.0,
            float(material.opacity) * alpha,
            _rgb(srgb_to_linear(material.emission)),
        )
    if override is None:
        override = srgb_to_linear(color.rgb if color is not None else DEFAULT_RGB)
    return Look("plastic", _rgb(override), 0.0, 0.0, alpha, (0.0, 0.0, 0.0))


def _key(*attrs: Any) -> tuple:
    return tuple(version_key(a) for a in attrs)


def modifier(engine: Any, *, uv: bool = False, vertex_rgba: Any = None, sink: list[str] | None = None) -> str:
    """The identifier of the material for the active appearance attributes (declared once per combination).

    ``uv``: the surface has texture coordinates, so an active ``Texture``
    applies; ``vertex_rgba``: a per-vertex colour replacing the diffuse one;
    ``sink``: where new definitions go (a mesh's own material file) instead of
    the scene description.
    """
    if sink is not None:
        engine._sinks[id(sink)] = sink  # alive as long as the engine's caches, so its id stays unique
    user = engine.mono(RadMaterial)
    resolved = engine_appearance(engine, texcoords=uv)  # the one appearance model: which texture, which alpha
    texture = resolved.texture if uv else None
    material, color = engine.appearance()
    vertex = None if vertex_rgba is None else tuple(np.round(np.asarray(vertex_rgba, np.float64), 6).tolist())
    key = (
        "look",
        id(sink) if sink is not None else None,
        _key(user, texture, material, color),
        vertex,
        resolved.alpha_mode,
    )
    found = engine._declared.get(key)
    if found is not None:
        return found
    pattern = _texture_pattern(engine, texture, sink) if texture is not None and not engine.coverage else "void"
    if user is not None and user.kind in TRANSMITTING:
        engine.transparent = True
    if user is not None and (user.kind in TRANSMITTING or not engine.coverage):
        ident = engine.declare(
            ("user", key),
            "m",
            lambda i: rad.primitive(pattern, user.kind, i, user.strings, user.reals, engine.owner()),
            sink,
        )
    else:
        # emission as the appearance model resolves it (emissive strength included), modulated by the
        # emissive texture where the surface has texture coordinates
        look = replace(resolve_look(material, color, vertex), emission=_rgb(resolved.emission))
        glow_pattern = "void"
        if uv and resolved.emissive_texture is not None and max(look.emission) > 0.0 and not engine.coverage:
            glow_pattern = _texture_pattern(engine, resolved.emissive_texture, sink)
        if engine.coverage:  # black and unlit: only what the surface lets through counts
            look = Look("plastic", (0.0, 0.0, 0.0), 0.0, 0.0, look.opacity, (0.0, 0.0, 0.0))
        ident = _look_chain(engine, look, pattern, key, sink, glow_pattern)
    if texture is not None and resolved.alpha_mode != "opaque" and _texture_image(engine, texture)[:, :, 3].min() < 255:
        cutoff = resolved.alpha_cutoff if resolved.alpha_mode == "mask" else None
        ident = _alpha_cutout(engine, texture, ident, key, sink, cutoff)
    engine._declared[key] = ident
    return ident


def _look_chain(
    engine: Any, look: Look, pattern: str, key: Any, sink: list[str] | None, glow_pattern: str = "void"
) -> str:
    owner = engine.owner()
    emits = max(look.emission) > 0.0
    reflects = max(look.rgb) > 0.0 or look.spec > 0.0
    if emits and not reflects:
        ident = engine.declare(
            ("glow", key), "m", lambda i: rad.primitive(glow_pattern, "glow", i, (), [*look.emission, 0]), sink
        )
    elif emits:
        w = EMISSION_WEIGHT
        glow = engine.declare(
            ("glow", key),
            "m",
            lambda i: rad.primitive(glow_pattern, "glow", i, (), [*(e / w for e in look.emission), 0]),
            sink,
        )
        body = engine.declare(
            ("body", key), "m", lambda i: rad.primitive(pattern, look.kind, i, (), look.reals(1.0 / (1.0 - w))), sink
        )
        ident = engine.declare(
            ("mix", key), "m", lambda i: rad.primitive("void", "mixfunc", i, (glow, body, rad.number(w), ".")), sink
        )
    else:
        ident = engine.declare(
            ("body", key), "m", lambda i: rad.primitive(pattern, look.kind, i, (), look.reals()), sink
        )
    if look.opacity < 1.0:
        engine.transparent = True
        opaque = ident
        o = rad.number(look.opacity, owner)
        ident = engine.declare(
            ("opacity", key), "m", lambda i: rad.primitive("void", "mixfunc", i, (opaque, "void", o, ".")), sink
        )
    return ident


def _texture_image(engine: Any, texture: Texture) -> np.ndarray:
    """``texture.image_array()``; a missing or unreadable file raises naming the node and the fix."""
    return texture.image_in("Radiance", engine.node_path)


#: A ``filter="nearest"`` texture is enlarged by repeating texels until its longer side has this many
#: pixels, so Radiance's bilinear picture lookup blends only in a thin seam between texels.
NEAREST_SIZE = 512


def _picture(texture: Texture, channels: np.ndarray) -> np.ndarray:
    """The texture's (H, W, 3) linear picture data, enlarged for nearest filtering."""
    if texture.filter == "nearest":
        k = max(1, -(-NEAREST_SIZE // max(channels.shape[:2])))
        channels = np.repeat(np.repeat(channels, k, axis=0), k, axis=1)
    return channels


def _uv_expressions(texture: Texture, image: np.ndarray) -> tuple[str, str]:
    """colorpict coordinates: Radiance scales a picture so its shorter side is 1."""
    h, w = image.shape[:2]
    short = float(min(w, h))
    wrap = WRAP[texture.wrap]
    cu, cv = "Lu", "Lv"
    if texture.transformed:  # the texture transform (glTF's KHR_texture_transform) before the wrap
        (a, b, c), (d, e, f) = texture.uv_matrix()[:2].tolist()
        n = rad.number
        cu, cv = f"({n(a)}*Lu+{n(b)}*Lv+{n(c)})", f"({n(d)}*Lu+{n(e)}*Lv+{n(f)})"
    u = wrap.format(c=cu) + f"*{rad.number(w / short)}"
    v = wrap.format(c=cv) + f"*{rad.number(h / short)}"
    return u, v


def _texture_pattern(engine: Any, texture: Texture, sink: list[str] | None) -> str:
    image = _texture_image(engine, texture)
    u, v = _uv_expressions(texture, image)
    key = ("texture", version_key(texture), id(sink) if sink is not None else None)

    def make(ident: str) -> str:
        name = engine.add_picture(
            (version_key(texture), "rgb"),
            lambda: _picture(texture, srgb_to_linear(image[:, :, :3].astype(np.float64) / 255.0)),
        )
        return rad.primitive("void", "colorpict", ident, ("red", "green", "blue", name, ".", u, v))

    return engine.declare(key, "p", make, sink)


def _alpha_cutout(
    engine: Any, texture: Texture, inner: str, key: Any, sink: list[str] | None, cutoff: float | None = None
) -> str:
    """A ``mixpict`` of ``inner`` and ``void`` by the texture's alpha (0 or 1 at ``cutoff`` for masked alpha)."""
    engine.transparent = True
    image = _texture_image(engine, texture)
    u, v = _uv_expressions(texture, image)

    def make(ident: str) -> str:
        alpha = image[:, :, 3].astype(np.float32) / 255.0
        if cutoff is not None:
            alpha = (alpha >= cutoff).astype(np.float32)
        name = engine.add_picture(
            (version_key(texture), "alpha", cutoff),
            lambda: _picture(texture, np.repeat(alpha[:, :, None], 3, 2)),
        )
        return rad.primitive("void", "mixpict", ident, (inner, "void", "red", name, ".", u, v))

    return engine.declare(("cutout", key), "m", make, sink)
