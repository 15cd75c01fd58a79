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
from ._params import (
    Param,
    Parameterised,
    check_bool,
    check_choice,
    check_number,
    check_rgb,
)

__all__ = ["Color", "Material", "PBRMaterial", "Texture", "DrawStyle"]

_unit = check_number(0.0, 1.0)


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
        self.r = r
        self.g = g
        self.b = b
        self.a = a

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
        self.ambient = ambient
        self.diffuse = diffuse
        self.specular = specular
        self.shininess = shininess
        self.emission = emission
        self.opacity = opacity

    @property
    def hints(self) -> frozenset[str]:  # type: ignore[override]
        return frozenset({"transparent"}) if self._opacity < 1.0 else frozenset()


class PBRMaterial(Parameterised, MonoAttribute):
    """Metallic-roughness material (the glTF model).

    ``metallic`` and ``roughness`` in [0, 1]; ``base_color`` is the albedo
    (dielectric) or specular colour (metal).
    """

    __slots__ = ("_base_color", "_metallic", "_roughness", "_emission", "_opacity")
    base_color = Param(check_rgb, "albedo (RGB)")
    metallic = Param(_unit, "0 dielectric ... 1 metal")
    roughness = Param(_unit, "0 mirror ... 1 rough")
    emission = Param(check_rgb, "emitted colour (RGB)")
    opacity = Param(_unit, "1 opaque ... 0 invisible")

    def __init__(
        self,
        base_color: Sequence[float] = (0.8, 0.8, 0.8),
        metallic: float = 0.0,
        roughness: float = 0.5,
        emission: Sequence[float] = (0.0, 0.0, 0.0),
        opacity: float = 1.0,
    ) -> None:
        super().__init__()
        self.base_color = base_color
        self.metallic = metallic
        self.roughness = roughness
        self.emission = emission
        self.opacity = opacity

    @property
    def hints(self) -> frozenset[str]:  # type: ignore[override]
        return frozenset({"transparent"}) if self._opacity < 1.0 else frozenset()


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
    """

    __slots__ = ("_image", "_wrap", "_filter", "_mipmap", "_cache")
    _transient = {"_cache": lambda: None}  # a file's pixels are read again where the texture is unpickled
    image = Param(_check_image, "path or image array")
    wrap = Param(check_choice("repeat", "clamp", "mirror"), "behaviour outside [0, 1]")
    filter = Param(check_choice("linear", "nearest"), "magnification filter")
    mipmap = Param(check_bool, "use mipmaps for minification")

    def __init__(
        self,
        image: str | os.PathLike[str] | np.ndarray,
        wrap: str = "repeat",
        filter: str = "linear",
        mipmap: bool = True,
    ) -> None:
        super().__init__()
        self.image = image
        self.wrap = wrap
        self.filter = filter
        self.mipmap = mipmap

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
            try:
                from PIL import Image as PILImage
            except ImportError:  # pragma: no cover - Pillow is a dependency of the gl extra
                raise RuntimeError(f"Texture: loading {source!r} needs Pillow (pip install pillow)") from None
            try:
                with PILImage.open(source) as img:
                    arr = np.asarray(img.convert("RGBA"), dtype=np.uint8)
            except FileNotFoundError:
                raise FileNotFoundError(f"Texture: image file {source!r} does not exist") from None
            except Exception as exc:
                raise ValueError(f"Texture: cannot read image file {source!r}: {exc}") from None
        else:
            arr = _to_rgba8(source)
        arr = np.ascontiguousarray(arr)
        arr.setflags(write=False)
        object.__setattr__(self, "_cache", arr)
        return arr

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
        return {"image": self._image, "wrap": self._wrap, "filter": self._filter, "mipmap": self._mipmap}


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
    """

    __slots__ = ("_mode", "_line_width", "_point_size", "_cull", "_shading")
    mode = Param(check_choice("filled", "wireframe", "points"), "filled, wireframe or points")
    line_width = Param(check_number(0.0, min_open=True), "line width in pixels")
    point_size = Param(check_number(0.0, min_open=True), "point size in pixels")
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
