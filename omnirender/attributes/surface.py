"""The one appearance model: how Color, Material, PBRMaterial, Texture, MultiTexture and BumpMap combine.

Every engine and exporter resolves the active appearance attributes with
:func:`resolve_appearance`, so the same scene means the same surface
everywhere.  The rules:

1. The innermost ``Material`` or ``PBRMaterial`` is the material.  A
   ``Color`` that became active *after* it replaces its base colour (diffuse
   or ``base_color``) and multiplies its opacity by the colour's alpha; a
   Color active before the material does nothing.  Without a material, the
   innermost Color (or grey 0.8) is a diffuse colour material.
2. The base colour texture is the PBR material's ``base_color_texture``, else
   the active ``om.Texture``; it *multiplies* the base colour (RGB) and the
   opacity (alpha), as OpenGL's ``GL_MODULATE`` and glTF's
   ``baseColorFactor``.  ``MultiTexture`` layers are blended over it in order.
3. Per-vertex colours replace a Phong material's diffuse colour (OpenGL's
   colour material) and multiply a PBR material's base colour (glTF's
   ``COLOR_0``).  Their alpha follows the alpha mode (:func:`vertex_rgba`):
   ignored by an ``"opaque"`` PBR material, cut at the cutoff by ``"mask"``,
   multiplied into the opacity otherwise.
4. Ambient light (GL's global ambient 0.2 plus the lights' ambient terms,
   :func:`~.photometry.ambient_total`) is reflected with the *ambient
   reflectance*: a Phong material's ``ambient`` colour, or the base colour
   where the ambient follows it (a Color, no material, a Color after a
   Material, every PBR material: ``base (1 - m) + F0 m``).  Textures modulate
   it; a PBR occlusion texture darkens it.  Every engine adds it as a constant
   term (POV-Ray's ``ambient``, an emitter in Mitsuba), so shadowed parts are
   never black.
5. Alpha: ``"opaque"``, ``"mask"`` (cut-out at ``alpha_cutoff``) or
   ``"blend"``; Phong materials and colours blend when their opacity is below 1.
6. Emission adds, scaled by ``emissive_strength`` and the emissive texture.
7. A ``BumpMap`` becomes a tangent-space normal map
   (:func:`~.texturing.height_to_normal_map`) unless the material has one.

Colours in :class:`Appearance` are linear (the display values converted with
the sRGB curve), ready for lighting.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import MISSING, dataclass, field, fields
from typing import Any

import numpy as np

from ..core import AttributePainter, default_for, version_key
from .appearance import BumpMap, Color, Material, MultiTexture, PBRMaterial, Texture
from .photometry import linear_rgb, srgb_to_linear

__all__ = [
    "Appearance",
    "resolve_appearance",
    "appearance_key",
    "decided_by",
    "resolve_surface",
    "track_surfaces",
    "SurfaceTracker",
    "DEFAULT_RGB",
    "DIELECTRIC_F0",
]

#: The display colour of shapes without any appearance attribute.
DEFAULT_RGB = (0.8, 0.8, 0.8)
#: Specular reflectance of a dielectric at normal incidence (the metallic-roughness model's F0).
DIELECTRIC_F0 = 0.04
_DEFAULT_SHININESS = 32.0


@dataclass(frozen=True)
class Appearance:
    """A resolved surface (see the module's rules); colours linear RGB."""

    #: "phong" or "pbr"
    model: str
    material: Any
    color: Any
    base: tuple[float, float, float]
    alpha: float
    specular: tuple[float, float, float] = (0.0, 0.0, 0.0)
    shininess: float = _DEFAULT_SHININESS
    metallic: float = 0.0
    roughness: float = 1.0
    emission: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: the ambient reflectance when it does not follow the base colour (Phong's ``ambient``)
    ambient: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ambient_follows_base: bool = True
    texture: Texture | None = None
    layers: tuple[Any, ...] = ()
    metallic_roughness_texture: Texture | None = None
    normal_texture: Texture | None = None
    normal_scale: float = 1.0
    occlusion_texture: Texture | None = None
    occlusion_strength: float = 1.0
    emissive_texture: Texture | None = None
    bump: BumpMap | None = None
    alpha_mode: str = "opaque"
    alpha_cutoff: float = 0.5
    double_sided: bool = True
    #: per-vertex colours "replace" the base colour (Phong) or "multiply" it (PBR)
    vertex_colors: str = "replace"
    extras: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def textures(self) -> tuple[Texture, ...]:
        """Every texture the surface samples (base, layers, slots, bump)."""
        out = [self.texture] + [layer.texture for layer in self.layers]
        out += [self.metallic_roughness_texture, self.normal_texture, self.occlusion_texture, self.emissive_texture]
        if self.bump is not None:
            out.append(self.bump.texture)
        return tuple(t for t in out if t is not None)

    @property
    def ambient_weight(self) -> float:
        """Factor of the base colour in the ambient reflectance when it follows the base colour."""
        m = self.metallic if self.model == "pbr" else 0.0
        return 1.0 - m + m * m

    @property
    def ambient_offset(self) -> float:
        """Constant added to the ambient reflectance (the dielectric F0 share of a part-metal)."""
        m = self.metallic if self.model == "pbr" else 0.0
        return DIELECTRIC_F0 * m * (1.0 - m)

    def ambient_reflectance(self, base: Any = None) -> np.ndarray:
        """Linear RGB ambient reflectance for the base colour ``base`` (default: the resolved one), no texture."""
        b = np.asarray(self.base if base is None else base, np.float64)[:3]
        if not self.ambient_follows_base:
            return np.asarray(self.ambient, np.float64)
        return b * self.ambient_weight + self.ambient_offset

    @property
    def emits(self) -> bool:
        return max(self.emission) > 0.0

    @property
    def has_normal_map(self) -> bool:
        return self.normal_texture is not None or self.bump is not None

    def normal_map(self) -> tuple[Texture | None, float]:
        """(tangent-space normal map, its xy scale): the material's, or the one derived from the BumpMap."""
        if self.normal_texture is not None:
            return self.normal_texture, self.normal_scale
        if self.bump is not None:
            from .texturing import bump_normal_texture

            return bump_normal_texture(self.bump), 1.0
        return None, 1.0

    @property
    def transparent(self) -> bool:
        """Whether the surface is drawn blended (see-through), not opaque or cut out."""
        return self.alpha_mode == "blend"


def resolve_surface(stack: Sequence[Any]) -> tuple[Any, Any]:
    """(material, colour) from appearance attributes in activation order (either may be None) - rule 1."""
    material = color = None
    for attr in reversed(stack):
        if isinstance(attr, Color):
            if color is None:
                color = attr
        else:
            material = attr
            break
    return material, color


def appearance_key(stack: Sequence[Any], texture: Any = None, layers: Any = None, bump: Any = None) -> tuple:
    """A hashable key that changes when anything :func:`resolve_appearance` reads changes."""
    material, color = resolve_surface(stack)
    slots = material.textures if isinstance(material, PBRMaterial) else ()
    return (
        version_key(material),
        version_key(color),
        version_key(texture),
        version_key(layers),
        None if layers is None else tuple(version_key(layer.texture) for layer in layers.layers),
        version_key(bump),
        None if bump is None else version_key(bump.texture),
        tuple(version_key(t) for t in slots),
    )


def decided_by(app: Appearance, material: Any) -> Appearance:
    """``app`` as decided by ``material``, a material of the values of the one that decided it (resolving
    ``material`` gives an equal appearance): the same appearance naming ``material``, made without resolving."""
    out = object.__new__(Appearance)
    out.__dict__.update(app.__dict__)
    out.__dict__["material"] = material  # (a frozen dataclass: what __init__ would have set)
    return out


def _texture_has_alpha(texture: Texture | None) -> bool:
    if texture is None:
        return False
    try:
        return texture.has_alpha()
    except (OSError, ValueError):
        return False  # the engine reports the unreadable file where it uses it


def resolve_appearance(
    stack: Sequence[Any],
    texture: Texture | None = None,
    layers: MultiTexture | None = None,
    bump: BumpMap | None = None,
) -> Appearance:
    """The :class:`Appearance` of the active attributes.

    ``stack``: Color / Material / PBRMaterial in activation order (what the
    surface trackers keep); ``texture``, ``layers``, ``bump``: the active
    ``om.Texture``, ``om.MultiTexture`` and ``om.BumpMap`` (or None).
    """
    material, color = resolve_surface(stack)
    layer_list = tuple(layers.layers) if layers is not None else ()
    if isinstance(material, PBRMaterial):
        base = material.base_color if color is None else color.rgb
        alpha = float(material.opacity) * (1.0 if color is None else float(color.a))
        base_texture = material.base_color_texture or texture
        mode = material.alpha_mode
        if mode is None:
            mode = "blend" if alpha < 1.0 else "opaque"
        strength = float(material.emissive_strength)
        emission = tuple(c * strength for c in linear_rgb(material.emission))
        return _appearance(
            model="pbr",
            material=material,
            color=color,
            base=linear_rgb(base),
            alpha=alpha,
            metallic=float(material.metallic),
            roughness=float(material.roughness),
            emission=emission,  # type: ignore[arg-type]
            texture=base_texture,
            layers=layer_list,
            metallic_roughness_texture=material.metallic_roughness_texture,
            normal_texture=material.normal_texture,
            normal_scale=float(material.normal_scale),
            occlusion_texture=material.occlusion_texture,
            occlusion_strength=float(material.occlusion_strength),
            emissive_texture=material.emissive_texture,
            bump=bump if material.normal_texture is None else None,
            alpha_mode=mode,
            alpha_cutoff=float(material.alpha_cutoff),
            double_sided=bool(material.double_sided),
            vertex_colors="multiply",
        )
    if isinstance(material, Material):
        base = material.diffuse if color is None else color.rgb
        alpha = float(material.opacity) * (1.0 if color is None else float(color.a))
        specular, shininess = linear_rgb(material.specular), float(material.shininess)
        emission, ambient = linear_rgb(material.emission), linear_rgb(material.ambient)
        follows = color is not None  # a Color after the material: colour material, ambient follows it
    else:
        base = DEFAULT_RGB if color is None else color.rgb
        alpha = 1.0 if color is None else float(color.a)
        specular, shininess, emission, ambient = (0.0, 0.0, 0.0), _DEFAULT_SHININESS, (0.0, 0.0, 0.0), (0.0,) * 3
        follows = True
    # a layer's alpha only blends the layer in; the base texture's alpha is the surface's
    see_through = alpha < 1.0 or _texture_has_alpha(texture)
    return _appearance(
        model="phong",
        material=material,
        color=color,
        base=linear_rgb(base),
        alpha=alpha,
        specular=specular,
        shininess=shininess,
        emission=emission,
        ambient=ambient,  # type: ignore[arg-type]
        ambient_follows_base=follows,
        texture=texture,
        layers=layer_list,
        bump=bump,
        alpha_mode="blend" if see_through else "opaque",
        vertex_colors="replace",
    )


#: Appearance's defaults by field name (the mutable ``extras`` made per appearance)
_DEFAULTS = {f.name: f.default for f in fields(Appearance) if f.default is not MISSING}


def _appearance(**values: Any) -> Appearance:
    """``Appearance(**values)`` without the frozen dataclass's per-field ``object.__setattr__`` (resolving a
    new material is on the path of a frame that replaced one): the same fields, equality, hash and repr."""
    out = object.__new__(Appearance)
    state = dict(_DEFAULTS)
    state["extras"] = {}
    state.update(values)
    out.__dict__.update(state)
    return out


def vertex_rgba(app: Appearance, colors: Any) -> np.ndarray:
    """Linear RGBA per-vertex colours as rule 3 applies them: (N, 3 or 4) sRGB display values in, (N, 4) out.

    RGB replaces (Phong) or multiplies (PBR) the base colour.  Alpha: an
    ``"opaque"`` PBR material ignores it (glTF: the alpha of ``COLOR_0`` is
    coverage only when the material says so), ``"mask"`` makes it 1 at or
    above the cutoff and 0 below, otherwise it multiplies the opacity.
    """
    c = np.asarray(colors, dtype=np.float64)
    out = np.ones((len(c), 4), np.float64)
    out[:, :3] = srgb_to_linear(np.clip(c[:, :3], 0.0, 1.0))
    if app.vertex_colors == "multiply":
        out[:, :3] *= np.asarray(app.base, np.float64)
    a = c[:, 3] if c.shape[1] > 3 else np.ones(len(c))
    if app.model == "pbr" and app.alpha_mode == "opaque":
        a = np.ones(len(c))
    elif app.model == "pbr" and app.alpha_mode == "mask":
        a = (a * app.alpha >= app.alpha_cutoff).astype(np.float64)
    else:
        a = a * app.alpha
    out[:, 3] = a
    return out


class SurfaceTracker(AttributePainter):
    """Keeps ``engine.surface_stack`` (a list) in activation order."""

    __slots__ = ()

    def exec(self, attribute: Any, engine: Any) -> None:
        engine.surface_stack.append(attribute)

    def unexec(self, attribute: Any, engine: Any) -> None:
        stack = engine.surface_stack
        for i in range(len(stack) - 1, -1, -1):
            if stack[i] is attribute:
                del stack[i]
                return


def track_surfaces(engine_cls: type) -> None:
    """Register surface trackers for Color, Material and PBRMaterial as defaults of ``engine_cls``."""
    for target in (Color, Material, PBRMaterial):
        name = f"{engine_cls.__name__}{target.__name__}Tracker"
        cls = type(name, (SurfaceTracker,), {"__slots__": (), "service": engine_cls.service, "target": target})
        default_for(engine_cls)(cls)


def engine_appearance(engine: Any, stack: Sequence[Any] | None = None, texcoords: bool = True) -> Appearance:
    """:func:`resolve_appearance` of an engine's active attributes (``engine.surface_stack`` by default).

    ``texcoords`` False: the shape has no texture coordinates, so textures do not apply.
    """
    if stack is None:
        stack = engine.surface_stack
    if not texcoords:
        app = resolve_appearance(stack)
        material = app.material
        if isinstance(material, PBRMaterial) and material.textures:
            app = _without_textures(app)
        return app
    mono = engine.mono
    return resolve_appearance(stack, mono(Texture), mono(MultiTexture), mono(BumpMap))


def _without_textures(app: Appearance) -> Appearance:
    from dataclasses import replace

    return replace(
        app,
        texture=None,
        layers=(),
        metallic_roughness_texture=None,
        normal_texture=None,
        occlusion_texture=None,
        emissive_texture=None,
        bump=None,
    )


__all__ += ["engine_appearance", "vertex_rgba"]
