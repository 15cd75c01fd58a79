"""Appearance attributes: colour, Phong and PBR materials, textures, draw style.

All are mono attributes, each its own category: the innermost one applies.
Colours are finite values in [0, 1]; material and light colours are stored as
RGB (opacity is separate), :class:`Color` keeps an alpha.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.component import MonoAttribute
from ..core.limits import MAX_PIXEL_SIZE
from ._params import (
    Param,
    Parameterised,
    assign_new,
    check_bool,
    check_choice,
    check_number,
    check_rgb,
    check_vector,
    optional,
)

__all__ = [
    "Color",
    "Material",
    "PBRMaterial",
    "Texture",
    "DrawStyle",
    "BumpMap",
    "TextureLayer",
    "MultiTexture",
    "ALPHA_MODES",
    "BLEND_MODES",
    "MAX_UV_SETS",
]

_unit = check_number(0.0, 1.0)
#: How a PBR material's alpha is used (glTF's alphaMode): ignored, a cut-out at ``alpha_cutoff``, blended.
ALPHA_MODES = ("opaque", "mask", "blend")
#: How a texture layer combines with what is under it.
BLEND_MODES = ("over", "multiply", "add")
#: Texture coordinate sets a triangle set can carry (``texcoords`` is set 0).
MAX_UV_SETS = 2


class Color(Parameterised, MonoAttribute):
    """A plain RGBA colour for shapes without a material (and for per-shape tinting).

    ``Color(1, 0, 0)`` or ``Color((1, 0, 0, 0.5))``; values in [0, 1].
    """

    __slots__ = ("_r", "_g", "_b", "_a")
    r = Param(_unit, "red in [0, 1]")
    g = Param(_unit, "green in [0, 1]")
    b = Param(_unit, "blue in [0, 1]")
    a = Param(_unit, "alpha (opacity) in [0, 1]")

    def __init__(
        self, r: float | Sequence[float] = 1.0, g: float | None = None, b: float | None = None, a: float = 1.0
    ) -> None:
        super().__init__()
        if isinstance(r, (Sequence, np.ndarray)) and not isinstance(r, str):
            values = [float(x) for x in np.asarray(r, dtype=np.float64).reshape(-1)] if len(r) else []
            if len(values) not in (3, 4):
                raise ValueError(f"Color: give 3 or 4 values, got {len(values)}")
            if g is not None or b is not None:
                raise ValueError("Color: give either a sequence or r, g, b, not both")
            r, g, b = values[:3]
            if len(values) == 4:
                a = values[3]
        elif g is None or b is None:
            raise ValueError("Color: give r, g and b (or one sequence of 3 or 4 values)")
        assign_new(self, (("r", r), ("g", g), ("b", b), ("a", a)))

    @property
    def rgba(self) -> tuple[float, float, float, float]:
        return (self._r, self._g, self._b, self._a)

    @property
    def rgb(self) -> tuple[float, float, float]:
        return (self._r, self._g, self._b)


class Material(Parameterised, MonoAttribute):
    """Phong material with OpenGL's parameters.

    ``shininess`` is the specular exponent (>= 0), ``opacity`` in [0, 1]
    (1 = opaque; below 1 the shape is drawn with the transparent shapes).
    """

    __slots__ = ("_ambient", "_diffuse", "_specular", "_shininess", "_emission", "_opacity")
    ambient = Param(check_rgb, "ambient reflectance (RGB)")
    diffuse = Param(check_rgb, "diffuse reflectance (RGB)")
    specular = Param(check_rgb, "specular reflectance (RGB)")
    shininess = Param(check_number(0.0), "specular exponent >= 0")
    emission = Param(check_rgb, "emitted colour (RGB)")
    opacity = Param(_unit, "1 opaque ... 0 invisible")

    def __init__(
        self,
        ambient: Sequence[float] = (0.2, 0.2, 0.2),
        diffuse: Sequence[float] = (0.8, 0.8, 0.8),
        specular: Sequence[float] = (0.0, 0.0, 0.0),
        shininess: float = 32.0,
        emission: Sequence[float] = (0.0, 0.0, 0.0),
        opacity: float = 1.0,
    ) -> None:
        super().__init__()
        assign_new(
            self,
            (
                ("ambient", ambient),
                ("diffuse", diffuse),
                ("specular", specular),
                ("shininess", shininess),
                ("emission", emission),
                ("opacity", opacity),
            ),
        )

    @property
    def hints(self) -> frozenset[str]:  # type: ignore[override]
        return frozenset({"transparent"}) if self._opacity < 1.0 else frozenset()

    def values(self) -> tuple[Any, ...]:
        """Every parameter in one hashable tuple: materials of equal values give equal tuples (what a renderer
        keys what it made of a material on, so that a new material of the same values finds it)."""
        return (self._ambient, self._diffuse, self._specular, self._shininess, self._emission, self._opacity)


def _check_texture(owner: str, name: str, value: Any) -> Any:
    if value is None or isinstance(value, Texture):
        return value
    raise ValueError(f"{owner}: {name} must be an om.Texture or None, got {type(value).__name__}")


class PBRMaterial(Parameterised, MonoAttribute):
    """Metallic-roughness material (the glTF 2.0 model), with glTF's texture slots.

    ``metallic`` and ``roughness`` in [0, 1]; ``base_color`` is the albedo
    (dielectric) or specular colour (metal).  Texture slots (each an
    ``om.Texture`` or None; its ``uv_set`` and transform apply):

    - ``base_color_texture``: multiplies ``base_color`` (RGB) and the opacity (alpha);
    - ``metallic_roughness_texture``: blue scales ``metallic``, green ``roughness``;
    - ``normal_texture``: a tangent-space normal map (OpenGL convention, green up),
      its x and y scaled by ``normal_scale``;
    - ``occlusion_texture``: red darkens the ambient light by ``occlusion_strength``;
    - ``emissive_texture``: multiplies ``emission`` (RGB), which ``emissive_strength`` scales.

    ``alpha_mode`` is ``"opaque"`` (alpha ignored), ``"mask"`` (cut out where
    alpha < ``alpha_cutoff``, the rest opaque) or ``"blend"`` (see-through); the
    default ``None`` means blend when ``opacity`` < 1, else opaque.
    ``double_sided`` False culls back faces.  Per-vertex colours multiply the
    base colour (glTF's ``COLOR_0``).
    """

    __slots__ = (
        "_base_color",
        "_metallic",
        "_roughness",
        "_emission",
        "_opacity",
        "_base_color_texture",
        "_metallic_roughness_texture",
        "_normal_texture",
        "_normal_scale",
        "_occlusion_texture",
        "_occlusion_strength",
        "_emissive_texture",
        "_emissive_strength",
        "_alpha_mode",
        "_alpha_cutoff",
        "_double_sided",
    )
    base_color = Param(check_rgb, "albedo (RGB)")
    metallic = Param(_unit, "0 dielectric ... 1 metal")
    roughness = Param(_unit, "0 mirror ... 1 rough")
    emission = Param(check_rgb, "emitted colour (RGB)")
    opacity = Param(_unit, "1 opaque ... 0 invisible")
    base_color_texture = Param(_check_texture, "base colour (RGB) and alpha texture")
    metallic_roughness_texture = Param(_check_texture, "metallic (blue) and roughness (green) texture")
    normal_texture = Param(_check_texture, "tangent-space normal map")
    normal_scale = Param(check_number(), "scale of the normal map's x and y")
    occlusion_texture = Param(_check_texture, "ambient occlusion (red) texture")
    occlusion_strength = Param(_unit, "how much the occlusion texture darkens ambient light")
    emissive_texture = Param(_check_texture, "emission (RGB) texture")
    emissive_strength = Param(check_number(0.0), "scale of the emission (KHR_materials_emissive_strength)")
    alpha_mode = Param(optional(check_choice(*ALPHA_MODES)), "opaque, mask or blend (None: from opacity)")
    alpha_cutoff = Param(_unit, "alpha below which a masked surface is cut out")
    double_sided = Param(check_bool, "False: back faces are culled")

    def __init__(
        self,
        base_color: Sequence[float] = (0.8, 0.8, 0.8),
        metallic: float = 0.0,
        roughness: float = 0.5,
        emission: Sequence[float] = (0.0, 0.0, 0.0),
        opacity: float = 1.0,
        *,
        base_color_texture: Texture | None = None,
        metallic_roughness_texture: Texture | None = None,
        normal_texture: Texture | None = None,
        normal_scale: float = 1.0,
        occlusion_texture: Texture | None = None,
        occlusion_strength: float = 1.0,
        emissive_texture: Texture | None = None,
        emissive_strength: float = 1.0,
        alpha_mode: str | None = None,
        alpha_cutoff: float = 0.5,
        double_sided: bool = True,
    ) -> None:
        super().__init__()
        self.base_color = base_color
        self.metallic = metallic
        self.roughness = roughness
        self.emission = emission
        self.opacity = opacity
        self.base_color_texture = base_color_texture
        self.metallic_roughness_texture = metallic_roughness_texture
        self.normal_texture = normal_texture
        self.normal_scale = normal_scale
        self.occlusion_texture = occlusion_texture
        self.occlusion_strength = occlusion_strength
        self.emissive_texture = emissive_texture
        self.emissive_strength = emissive_strength
        self.alpha_mode = alpha_mode
        self.alpha_cutoff = alpha_cutoff
        self.double_sided = double_sided

    @property
    def effective_alpha_mode(self) -> str:
        """``alpha_mode``, or ``"blend"`` / ``"opaque"`` from the opacity when it is None."""
        if self._alpha_mode is not None:
            return self._alpha_mode
        return "blend" if self._opacity < 1.0 else "opaque"

    @property
    def textures(self) -> tuple[Texture, ...]:
        """The textures of the slots that are set."""
        slots = (
            self._base_color_texture,
            self._metallic_roughness_texture,
            self._normal_texture,
            self._occlusion_texture,
            self._emissive_texture,
        )
        return tuple(t for t in slots if t is not None)

    @property
    def hints(self) -> frozenset[str]:  # type: ignore[override]
        return frozenset({"transparent"}) if self.effective_alpha_mode == "blend" else frozenset()

    def parameters(self) -> dict[str, Any]:
        out = super().parameters()
        defaults = {
            "normal_scale": 1.0,
            "occlusion_strength": 1.0,
            "emissive_strength": 1.0,
            "alpha_cutoff": 0.5,
            "double_sided": True,
        }
        for name, value in list(out.items()):
            if (name.endswith("_texture") and value is None) or (name == "alpha_mode" and value is None):
                del out[name]
            elif name in defaults and value == defaults[name]:
                del out[name]
        return out


#: The largest texture image accepted (per side, and in all): GPUs stop at 16384 or 32768 per side.
MAX_TEXTURE_SIDE = 32768
MAX_TEXTURE_PIXELS = 1 << 28


def _check_image(owner: str, name: str, value: Any) -> str | np.ndarray:
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if isinstance(value, str):
        if not value or "\x00" in value:
            raise ValueError(f"{owner}: {name} must be a non-empty path (without NUL) or an image array")
        return value
    shape = getattr(value, "shape", None)  # refuse a huge image before copying it
    if isinstance(shape, tuple) and len(shape) >= 2 and all(isinstance(n, int) for n in shape[:2]):
        h, w = shape[:2]
        if h > MAX_TEXTURE_SIDE or w > MAX_TEXTURE_SIDE or h * w > MAX_TEXTURE_PIXELS:
            raise ValueError(
                f"{owner}: {name} is {w}x{h} pixels; textures are at most {MAX_TEXTURE_SIDE} per side and "
                f"{MAX_TEXTURE_PIXELS:,} pixels in all (GPUs cannot hold more); scale the image down"
            )
    try:
        arr = np.array(value)
    except Exception:
        raise ValueError(
            f"{owner}: {name} must be a path or an (H, W, 3|4) array, got {type(value).__name__}"
        ) from None
    if arr.ndim == 2:
        arr = arr[:, :, None]
    if arr.ndim != 3 or arr.shape[2] not in (1, 3, 4) or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ValueError(f"{owner}: {name} must be an (H, W), (H, W, 3) or (H, W, 4) array, got shape {arr.shape}")
    if arr.dtype == np.uint8:
        pass
    elif arr.dtype.kind in "iu":
        if arr.min() < 0 or arr.max() > 255:
            raise ValueError(f"{owner}: {name} integer values must be in [0, 255]")
        arr = arr.astype(np.uint8)
    elif arr.dtype.kind == "f":
        arr = arr.astype(np.float64)
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{owner}: {name} must be finite")
        if arr.min() < 0.0 or arr.max() > 1.0:
            raise ValueError(f"{owner}: {name} values must be uint8 or floats in [0, 1]")
    else:
        raise ValueError(f"{owner}: {name} must be uint8 or float, got dtype {arr.dtype}")
    arr.setflags(write=False)
    return arr


def _to_rgba8(arr: np.ndarray) -> np.ndarray:
    if arr.dtype != np.uint8:
        arr = np.clip(np.round(arr * 255.0), 0, 255).astype(np.uint8)
    channels = arr.shape[2]
    if channels == 1:
        arr = np.concatenate([arr, arr, arr, np.full_like(arr, 255)], axis=2)
    elif channels == 3:
        arr = np.concatenate([arr, np.full(arr.shape[:2] + (1,), 255, np.uint8)], axis=2)
    return np.ascontiguousarray(arr)


class Texture(Parameterised, MonoAttribute):
    """An image mapped onto shapes through their texture coordinates.

    ``image`` is a file path (kept as given and loaded lazily with Pillow on the
    first :meth:`image_array` call) or an (H, W), (H, W, 3) or (H, W, 4) array
    of uint8 (integers in [0, 255]) or floats in [0, 1].  Row 0 is the top of the image.  ``wrap`` is
    ``"repeat"``, ``"clamp"`` or ``"mirror"``; ``filter`` ``"linear"`` or
    ``"nearest"``; ``mipmap`` asks engines for mipmapped minification.

    ``uv_set`` picks the shape's texture coordinate set (0: ``texcoords``, 1:
    ``texcoords1``); ``offset``, ``scale`` and ``rotation`` (degrees,
    counter-clockwise) transform the coordinates before the look-up, as
    glTF's ``KHR_texture_transform``: ``uv' = offset + R(rotation) (scale * uv)``.
    """

    __slots__ = ("_image", "_wrap", "_filter", "_mipmap", "_uv_set", "_offset", "_scale", "_rotation", "_cache")
    _transient = {"_cache": lambda: None}  # a file's pixels are read again where the texture is unpickled
    image = Param(_check_image, "path or image array")
    wrap = Param(check_choice("repeat", "clamp", "mirror"), "behaviour outside [0, 1]")
    filter = Param(check_choice("linear", "nearest"), "magnification filter")
    mipmap = Param(check_bool, "use mipmaps for minification")
    uv_set = Param(check_number(0, MAX_UV_SETS - 1, integer=True), "texture coordinate set (0 or 1)")
    offset = Param(check_vector(2), "texture coordinate offset (u, v)")
    scale = Param(check_vector(2), "texture coordinate scale (u, v)")
    rotation = Param(check_number(), "texture coordinate rotation in degrees (counter-clockwise)")

    def __init__(
        self,
        image: str | os.PathLike[str] | np.ndarray,
        wrap: str = "repeat",
        filter: str = "linear",
        mipmap: bool = True,
        uv_set: int = 0,
        offset: Sequence[float] = (0.0, 0.0),
        scale: Sequence[float] = (1.0, 1.0),
        rotation: float = 0.0,
    ) -> None:
        super().__init__()
        self.image = image
        self.wrap = wrap
        self.filter = filter
        self.mipmap = mipmap
        self.uv_set = uv_set
        self.offset = offset
        self.scale = scale
        self.rotation = rotation

    def uv_matrix(self) -> np.ndarray:
        """The 3x3 matrix taking (u, v, 1) to the looked-up coordinates (identity without a transform)."""
        a = np.radians(float(self._rotation))
        c, s = np.cos(a), np.sin(a)
        su, sv = self._scale
        m = np.array([[c * su, -s * sv, self._offset[0]], [s * su, c * sv, self._offset[1]], [0.0, 0.0, 1.0]])
        return m

    @property
    def transformed(self) -> bool:
        """Whether the texture coordinates are transformed (offset, scale or rotation set)."""
        return self._offset != (0.0, 0.0) or self._scale != (1.0, 1.0) or self._rotation != 0.0

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "image":
            object.__setattr__(self, "_cache", None)
        super().__setattr__(name, value)

    @property
    def path(self) -> str | None:
        """The file path, or None for an in-memory image."""
        return self._image if isinstance(self._image, str) else None

    def image_array(self) -> np.ndarray:
        """The image as an (H, W, 4) uint8 RGBA array (loaded once and cached, read-only)."""
        cached = getattr(self, "_cache", None)
        if cached is not None:
            return cached
        source = self._image
        if isinstance(source, str):
            from .imagefile import read_image  # decompression bombs refused before decoding (core.limits)

            try:
                arr = read_image(source, f"Texture: cannot read image file {source!r}", "it")
            except FileNotFoundError:
                raise FileNotFoundError(f"Texture: image file {source!r} does not exist") from None
        else:
            arr = _to_rgba8(source)
        arr = np.ascontiguousarray(arr)
        arr.setflags(write=False)
        object.__setattr__(self, "_cache", arr)
        return arr

    def has_alpha(self) -> bool:
        """Whether some texel is not fully opaque (the surface is then drawn as see-through)."""
        return bool(self.image_array()[:, :, 3].min() < 255)

    def image_in(self, engine: str, node_path: str) -> np.ndarray:
        """:meth:`image_array`, but a missing or unreadable file raises naming the engine, the node and the fix."""
        try:
            return self.image_array()
        except (FileNotFoundError, ValueError) as exc:
            raise type(exc)(
                f"{engine}: {exc} (Texture in node {node_path or '/'}); "
                "check the path or pass an array (om.Texture(numpy_array))"
            ) from None

    def parameters(self) -> dict[str, Any]:
        out = {"image": self._image, "wrap": self._wrap, "filter": self._filter, "mipmap": self._mipmap}
        if self._uv_set:
            out["uv_set"] = self._uv_set
        if self.transformed:
            out.update(offset=self._offset, scale=self._scale, rotation=self._rotation)
        return out


def _check_cull(owner: str, name: str, value: Any) -> str:
    if value is True:
        return "back"
    if value is False or value is None:
        return "none"
    return check_choice("none", "back", "front")(owner, name, value)


class DrawStyle(Parameterised, MonoAttribute):
    """How surfaces are drawn: ``mode`` filled, wireframe or points; face culling; shading.

    ``cull`` is ``"none"``, ``"back"`` or ``"front"`` (True means back, False none);
    ``shading`` ``"smooth"`` (interpolated normals) or ``"flat"`` (face normals).
    ``line_width`` and ``point_size`` are pixels, > 0 and at most
    ``omnirender.core.limits.MAX_PIXEL_SIZE`` (4096); engines draw them no
    larger than their driver supports (GL's ``GL_POINT_SIZE_RANGE``).
    """

    __slots__ = ("_mode", "_line_width", "_point_size", "_cull", "_shading")
    mode = Param(check_choice("filled", "wireframe", "points"), "filled, wireframe or points")
    line_width = Param(check_number(0.0, MAX_PIXEL_SIZE, min_open=True), "line width in pixels")
    point_size = Param(check_number(0.0, MAX_PIXEL_SIZE, min_open=True), "point size in pixels")
    cull = Param(_check_cull, "none, back or front")
    shading = Param(check_choice("smooth", "flat"), "smooth or flat")

    def __init__(
        self,
        mode: str = "filled",
        line_width: float = 1.0,
        point_size: float = 1.0,
        cull: str | bool = "none",
        shading: str = "smooth",
    ) -> None:
        super().__init__()
        self.mode = mode
        self.line_width = line_width
        self.point_size = point_size
        self.cull = cull
        self.shading = shading


class BumpMap(Parameterised, MonoAttribute):
    """Bump mapping from a height texture (the VRS paper's third advanced technique).

    ``texture``'s luminance is a height in [0, 1]; ``scale`` is the height of
    the value 1 in texture-coordinate units (the texture spans 1), so slopes
    are ``scale * dh/du``.  Engines derive a tangent-space normal map from it
    (:func:`omnirender.attributes.texturing.height_to_normal_map`) and use their
    normal-map code; POV-Ray uses its native ``bump_map``.
    """

    __slots__ = ("_texture", "_scale")
    texture = Param(_check_texture, "height texture")
    scale = Param(check_number(), "height of the value 1 in texture-coordinate units")

    def __init__(self, texture: Texture, scale: float = 0.05) -> None:
        super().__init__()
        if texture is None:
            raise ValueError("BumpMap: give a height texture (om.Texture)")
        self.texture = texture
        self.scale = scale


class TextureLayer(Parameterised, MonoAttribute):
    """One layer of a :class:`MultiTexture`: a texture, how it blends and its opacity.

    ``blend`` ``"over"`` (alpha blending with the texture's alpha times
    ``opacity``), ``"multiply"`` or ``"add"`` (mixed in by ``opacity``).  The
    texture's own ``uv_set`` and transform apply.  Only meaningful inside a
    MultiTexture (as an attribute of its own it does nothing).
    """

    __slots__ = ("_texture", "_blend", "_opacity")
    texture = Param(_check_texture, "the layer's texture")
    blend = Param(check_choice(*BLEND_MODES), "over, multiply or add")
    opacity = Param(_unit, "layer opacity in [0, 1]")

    def __init__(self, texture: Texture, blend: str = "over", opacity: float = 1.0) -> None:
        super().__init__()
        if texture is None:
            raise ValueError("TextureLayer: give a texture (om.Texture)")
        self.texture = texture
        self.blend = blend
        self.opacity = opacity


def _check_layers(owner: str, name: str, value: Any) -> tuple[TextureLayer, ...]:
    if isinstance(value, (TextureLayer, Texture)):
        value = [value]
    try:
        items = list(value)
    except TypeError:
        raise ValueError(f"{owner}: {name} must be a list of om.TextureLayer (or om.Texture)") from None
    layers = []
    for i, item in enumerate(items):
        if isinstance(item, Texture):
            item = TextureLayer(item)
        if not isinstance(item, TextureLayer):
            kind = type(item).__name__
            raise ValueError(f"{owner}: {name}[{i}] must be an om.TextureLayer or om.Texture, got {kind}")
        layers.append(item)
    if not layers:
        raise ValueError(f"{owner}: give at least one layer")
    return tuple(layers)


class MultiTexture(Parameterised, MonoAttribute):
    """Several texture layers over the base colour, each with its own UV set, blend mode and opacity.

    The layers apply in order over the base colour (after an ``om.Texture`` or
    a base colour texture), like the VRS paper's terrain: a satellite image and
    a road network over one terrain.  The GL engine draws up to
    :data:`MAX_LAYERS` layers in one pass; offline engines and the glTF
    exporter bake the layers into one texture in the coordinates of UV set 0
    (:func:`omnirender.attributes.texturing.bake_layers`).
    """

    __slots__ = ("_layers",)
    MAX_LAYERS = 4
    layers = Param(_check_layers, "texture layers, bottom first")

    def __init__(self, layers: Sequence[TextureLayer | Texture]) -> None:
        super().__init__()
        self.layers = layers
        if len(self._layers) > self.MAX_LAYERS:
            raise ValueError(
                f"MultiTexture: at most {self.MAX_LAYERS} layers, got {len(self._layers)}; bake some of them into one "
                "image first"
            )

    def parameters(self) -> dict[str, Any]:
        return {"layers": list(self._layers)}
