"""UsdPreviewSurface networks as ``om.PBRMaterial`` (the one appearance model), with their textures.

Mapped inputs: ``diffuseColor`` (base colour, or a ``UsdUVTexture``'s rgb as
``base_color_texture`` scaled by the texture's ``scale``; a
``UsdPrimvarReader_float3`` of ``displayColor`` as per-vertex colours),
``opacity`` (a value, or the alpha of the diffuse texture),
``opacityThreshold`` (> 0: alpha mode ``mask``), ``metallic`` and
``roughness`` (values or texture channels, combined into
``metallic_roughness_texture`` as glTF does: roughness green, metallic
blue), ``emissiveColor``, ``normal`` (a tangent-space normal map) and
``occlusion``.  Texture coordinates come from the ``UsdPrimvarReader_float2``
feeding a texture's ``st`` (its ``varname`` names the mesh primvar), through a
``UsdTransform2d`` (scale, rotation in degrees, translation: omnirender's
texture transform).  Inputs omnirender has no equivalent for
(``useSpecularWorkflow``, ``clearcoat``, ``ior``, ``displacement``, texture
``bias`` other than the normal map's) are warned about, naming the material; a
material whose surface is not a UsdPreviewSurface (MDL, MaterialX, a
renderer's own shader) falls back to its ``displayColor`` with a warning
naming the material and its shader.
"""

from __future__ import annotations

import io
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ...attributes import PBRMaterial, Texture
from ...attributes.photometry import linear_to_srgb
from .policy import check_asset

__all__ = ["MaterialReader"]

#: Hydra's fallback diffuse colour (linear) for gprims without a material or displayColor.
FALLBACK_COLOR = (0.18, 0.18, 0.18)
_WRAP = {"repeat": "repeat", "mirror": "mirror", "clamp": "clamp", "black": "clamp", "useMetadata": "repeat"}
_DEFAULTS = {"clearcoat": 0.0, "ior": 1.5, "displacement": 0.0, "useSpecularWorkflow": 0}


def _srgb(rgb: Any) -> tuple[float, float, float]:
    a = np.clip(linear_to_srgb(np.clip(np.asarray(rgb, np.float64)[:3], 0.0, None)), 0.0, 1.0)
    return (float(a[0]), float(a[1]), float(a[2]))


class MaterialReader:
    """Materials of one stage, each read once (cached by material path)."""

    def __init__(self, stage: Any, name: str, folder: Path | None, trusted: bool) -> None:
        from pxr import UsdShade

        self.UsdShade = UsdShade
        self.stage = stage
        self.name = name
        self.folder = folder
        self.trusted = trusted
        self.cache: dict[Any, list[Any]] = {}
        self.images: dict[str, np.ndarray | None] = {}
        self.uv_cache: dict[str, list[str]] = {}

    def warn(self, message: str) -> None:
        warnings.warn(f"load_usd {self.name}: {message}", stacklevel=5)

    # -- bindings ----------------------------------------------------------------------
    def binding(self, prim: Any) -> Any:
        """The material bound to ``prim`` (USD's binding resolution: inherited, strongest), or None."""
        material, _ = self.UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        return material if material and material.GetPrim().IsValid() else None

    def uv_names(self, prim: Any) -> list[str]:
        """The texture coordinate primvars the materials of ``prim`` (and its subsets) read, then ``st``."""
        names: list[str] = []
        prims = [prim]
        try:
            from pxr import UsdGeom

            if prim.IsA(UsdGeom.Mesh):
                prims += [s.GetPrim() for s in UsdGeom.Subset.GetAllGeomSubsets(UsdGeom.Imageable(prim))]
        except Exception:  # pragma: no cover - defensive
            pass
        for p in prims:
            material = self.binding(p)
            if material is not None:
                key = str(material.GetPath())
                if key not in self.uv_cache:
                    self.uv_cache[key] = self._varnames(material)
                names += [n for n in self.uv_cache[key] if n not in names]
        return [*names, "st"] if "st" not in names else names

    def uses_display_color(self, prim: Any) -> bool:
        """Whether the material bound to ``prim`` reads the ``displayColor`` primvar (or there is none)."""
        material = self.binding(prim)
        if material is None:
            return True
        shader = self._surface(material)
        if shader is None:
            return True
        source = self._source(shader.GetInput("diffuseColor"))
        return source is not None and self._is_display_reader(source[0])

    def bound(
        self,
        prim: Any,
        display_color: tuple[Any, Any] = (None, None),
        vertex_colors: bool = False,
        fallback: Any = None,
    ) -> list[Any]:
        """The attributes that draw ``prim`` as its bound material (or its displayColor) says."""
        material = self.binding(prim)
        if material is None and fallback is not None and fallback is not prim:
            material = self.binding(fallback)
        color, opacity = display_color
        if material is not None:
            key = (str(material.GetPath()), vertex_colors)
            if key not in self.cache:
                self.cache[key] = self.read(material, vertex_colors, color, opacity)
            return self.cache[key]
        base = (1.0, 1.0, 1.0) if vertex_colors else _srgb(FALLBACK_COLOR if color is None else color)
        key = ("display", base, opacity)
        if key not in self.cache:
            self.cache[key] = [
                PBRMaterial(base_color=base, metallic=0.0, roughness=0.5, opacity=1.0 if opacity is None else opacity)
            ]
        return self.cache[key]

    # -- networks ----------------------------------------------------------------------
    def _surface(self, material: Any) -> Any:
        shader = material.ComputeSurfaceSource()[0]
        if not shader or shader.GetIdAttr().Get() != "UsdPreviewSurface":
            return None
        return shader

    def _source(self, inp: Any) -> tuple[Any, str] | None:
        """(shader, output name) feeding ``inp``, following node-graph interfaces; None for a value."""
        if not inp:
            return None
        for attr in inp.GetValueProducingAttributes():
            if self.UsdShade.Output.IsOutput(attr):
                return self.UsdShade.Shader(attr.GetPrim()), self.UsdShade.Output(attr).GetBaseName()
        return None

    def _value(self, shader: Any, name: str, default: Any) -> Any:
        inp = shader.GetInput(name)
        if not inp:
            return default
        for attr in inp.GetValueProducingAttributes():
            if not self.UsdShade.Output.IsOutput(attr):
                value = attr.Get()
                return default if value is None else value
        return default

    def _is_display_reader(self, shader: Any) -> bool:
        ident = str(shader.GetIdAttr().Get() or "")
        return ident.startswith("UsdPrimvarReader") and self._value(shader, "varname", "") == "displayColor"

    def _varnames(self, material: Any) -> list[str]:
        shader = self._surface(material)
        if shader is None:
            return []
        names = []
        for inp in shader.GetInputs():
            source = self._source(inp)
            if source is None or source[0].GetIdAttr().Get() != "UsdUVTexture":
                continue
            reader = self._st_reader(source[0])[0]
            if reader is not None:
                name = str(self._value(reader, "varname", "st"))
                if name and name not in names:
                    names.append(name)
        return names

    def _st_reader(self, texture: Any) -> tuple[Any, Any]:
        """(the primvar reader feeding a texture's ``st``, the UsdTransform2d between them or None)."""
        source = self._source(texture.GetInput("st"))
        transform = None
        if source is not None and source[0].GetIdAttr().Get() == "UsdTransform2d":
            transform = source[0]
            source = self._source(transform.GetInput("in"))
        if source is not None and str(source[0].GetIdAttr().Get() or "").startswith("UsdPrimvarReader"):
            return source[0], transform
        return None, transform

    def read(self, material: Any, vertex_colors: bool, color: Any, opacity: Any) -> list[Any]:
        where = str(material.GetPath())
        shader = self._surface(material)
        if shader is None:
            found = material.ComputeSurfaceSource()[0]
            ident = found.GetIdAttr().Get() if found else None
            outputs = [o.GetBaseName() for o in material.GetOutputs()]
            self.warn(
                f"material {where}: its surface is not a UsdPreviewSurface "
                f"(shader {ident!r}, outputs {outputs}); drawn with its displayColor"
            )
            base = (1.0, 1.0, 1.0) if vertex_colors else _srgb(FALLBACK_COLOR if color is None else color)
            return [PBRMaterial(base_color=base, metallic=0.0, roughness=0.5, opacity=opacity or 1.0)]
        params: dict[str, Any] = {}
        ignored = []
        for name, default in _DEFAULTS.items():
            inp = shader.GetInput(name)
            if inp and (self._source(inp) is not None or self._value(shader, name, default) != default):
                ignored.append(name)
        if ignored:
            self.warn(f"material {where}: {', '.join(ignored)} not supported by omnirender's materials; ignored")
        diffuse = self._source(shader.GetInput("diffuseColor"))
        if diffuse is None:
            params["base_color"] = _srgb(self._value(shader, "diffuseColor", FALLBACK_COLOR))
        elif self._is_display_reader(diffuse[0]):
            params["base_color"] = (
                (1.0, 1.0, 1.0) if vertex_colors else _srgb(FALLBACK_COLOR if color is None else color)
            )
        elif diffuse[0].GetIdAttr().Get() == "UsdUVTexture":
            texture, scale = self.texture(diffuse[0], where)
            params["base_color"] = _srgb(scale[:3]) if texture is not None else _srgb(FALLBACK_COLOR)
            params["base_color_texture"] = texture
        else:
            self.warn(f"material {where}: diffuseColor comes from {diffuse[0].GetIdAttr().Get()!r}; not supported")
        opacity_source = self._source(shader.GetInput("opacity"))
        if opacity_source is None:
            params["opacity"] = float(np.clip(self._value(shader, "opacity", 1.0), 0.0, 1.0))
        elif not (diffuse and opacity_source[0].GetPath() == diffuse[0].GetPath() and opacity_source[1] == "a"):
            self.warn(
                f"material {where}: opacity is read only from the alpha of the diffuse texture; other inputs ignored"
            )
        threshold = float(self._value(shader, "opacityThreshold", 0.0))
        if threshold > 0.0:
            params["alpha_mode"], params["alpha_cutoff"] = "mask", min(threshold, 1.0)
        elif opacity_source is not None or params.get("opacity", 1.0) < 1.0:
            params["alpha_mode"] = "blend"
        params.update(self._metallic_roughness(shader, where))
        emissive = self._source(shader.GetInput("emissiveColor"))
        if emissive is None:
            e = np.asarray(self._value(shader, "emissiveColor", (0.0, 0.0, 0.0)), np.float64)
            peak = max(float(e.max()), 1.0)
            params["emission"] = _srgb(e / peak)
            params["emissive_strength"] = peak
        elif emissive[0].GetIdAttr().Get() == "UsdUVTexture":
            texture, scale = self.texture(emissive[0], where)
            peak = max(float(np.max(scale[:3])), 1.0)
            params["emission"] = _srgb(np.asarray(scale[:3]) / peak) if texture is not None else (0.0, 0.0, 0.0)
            params["emissive_texture"], params["emissive_strength"] = texture, peak
        normal = self._source(shader.GetInput("normal"))
        if normal is not None and normal[0].GetIdAttr().Get() == "UsdUVTexture":
            params["normal_texture"] = self.texture(normal[0], where, normal_map=True)[0]
        occlusion = self._source(shader.GetInput("occlusion"))
        if occlusion is not None and occlusion[0].GetIdAttr().Get() == "UsdUVTexture":
            params["occlusion_texture"] = self.channel_texture([(occlusion, 0)], where)
        own = self.omnirender_surface(material, params)
        if own is not None:
            return own
        try:
            return [PBRMaterial(**params)]
        except ValueError as exc:
            self.warn(f"material {where}: {exc}; a default material is used")
            return [PBRMaterial()]

    def omnirender_surface(self, material: Any, params: dict[str, Any]) -> list[Any] | None:
        """The surface attributes an omnirender export kept as ``omnirender:*`` attributes, rebuilt exactly."""
        prim = material.GetPrim()
        kinds_attr = prim.GetAttribute("omnirender:surface")
        if not kinds_attr or kinds_attr.Get() is None:
            return None
        from ...attributes import Color, Material

        classes = {"Color": Color, "Material": Material, "PBRMaterial": PBRMaterial}
        out: list[Any] = []
        for kind in kinds_attr.Get():
            cls = classes.get(str(kind))
            if cls is None:
                continue
            prefix = f"omnirender:{kind}:"
            values: dict[str, Any] = {}
            for attr in prim.GetAttributes():
                name = attr.GetName()
                if name.startswith(prefix):
                    value = attr.Get()
                    values[name[len(prefix) :]] = (
                        tuple(value) if hasattr(value, "__len__") and not isinstance(value, str) else value
                    )
            if kind == "PBRMaterial":
                for slot in ("base_color_texture", "metallic_roughness_texture", "normal_texture",
                             "occlusion_texture", "emissive_texture"):  # fmt: skip
                    if params.get(slot) is not None:
                        values[slot] = params[slot]
            elif kind == "Color" and "r" not in values and "rgba" in values:
                values = {"r": values["rgba"]}
            try:
                out.append(cls(**values))
            except (TypeError, ValueError) as exc:
                self.warn(f"material {material.GetPath()}: omnirender:{kind} attributes unusable ({exc})")
                return None
        if out and not isinstance(out[-1], PBRMaterial) and params.get("base_color_texture") is not None:
            out.append(params["base_color_texture"])
        return out

    def _metallic_roughness(self, shader: Any, where: str) -> dict[str, Any]:
        out: dict[str, Any] = {}
        sources = {}
        for name in ("metallic", "roughness"):
            source = self._source(shader.GetInput(name))
            default = 0.0 if name == "metallic" else 0.5
            if source is None:
                out[name] = float(np.clip(self._value(shader, name, default), 0.0, 1.0))
            elif source[0].GetIdAttr().Get() == "UsdUVTexture":
                sources[name] = source
                scale = np.asarray(self._value(source[0], "scale", (1.0, 1.0, 1.0, 1.0)), np.float64)
                channel = "rgba".index(source[1]) if source[1] in ("r", "g", "b", "a") else 0
                out[name] = float(np.clip(scale[channel], 0.0, 1.0))
            else:
                out[name] = default
        if sources:
            layers = []
            if "roughness" in sources:
                layers.append((sources["roughness"], 1))
            if "metallic" in sources:
                layers.append((sources["metallic"], 2))
            out["metallic_roughness_texture"] = self.channel_texture(layers, where, fill=255)
        return out

    # -- textures ----------------------------------------------------------------------
    def texture(self, shader: Any, where: str, normal_map: bool = False) -> tuple[Texture | None, np.ndarray]:
        """A UsdUVTexture as an ``om.Texture`` (None when its file cannot be used) and its ``scale``."""
        scale = np.asarray(self._value(shader, "scale", (1.0, 1.0, 1.0, 1.0)), np.float64)
        bias = np.asarray(self._value(shader, "bias", (0.0, 0.0, 0.0, 0.0)), np.float64)
        if not normal_map and np.any(bias != 0.0):
            self.warn(f"material {where}: texture {shader.GetPath()} has a bias; ignored")
        pixels = self.pixels(shader, where)
        if pixels is None:
            return None, scale
        return self._texture(shader, pixels), scale

    def channel_texture(self, layers: list[tuple[tuple[Any, str], int]], where: str, fill: int = 0) -> Texture | None:
        """A texture whose channel ``k`` is the ``(shader, output)`` channel of each layer (others ``fill``)."""
        first = layers[0][0][0]
        images = [(self.pixels(shader, where), output, k) for (shader, output), k in layers]
        if any(p is None for p, _, _ in images):
            return None
        h, w = images[0][0].shape[:2]
        same = all(s.GetPath() == first.GetPath() for (s, _), _ in layers)
        if same and all("rgba".find(o) == k for _, o, k in images):
            return self._texture(first, images[0][0])
        out = np.full((h, w, 4), fill, np.uint8)
        out[..., 3] = 255
        for pixels, output, k in images:
            if pixels.shape[:2] != (h, w):
                from PIL import Image as PILImage

                pixels = np.asarray(PILImage.fromarray(pixels).resize((w, h)), np.uint8)
            out[..., k] = pixels[..., "rgba".index(output) if output in ("r", "g", "b", "a") else 0]
        return self._texture(first, out)

    def _texture(self, shader: Any, pixels: np.ndarray) -> Texture:
        wrap = _WRAP.get(str(self._value(shader, "wrapS", "useMetadata")), "repeat")
        reader, transform = self._st_reader(shader)
        offset, scale, rotation = (0.0, 0.0), (1.0, 1.0), 0.0
        if transform is not None:
            offset = tuple(float(x) for x in self._value(transform, "translation", (0.0, 0.0)))
            scale = tuple(float(x) for x in self._value(transform, "scale", (1.0, 1.0)))
            rotation = float(self._value(transform, "rotation", 0.0))
        return Texture(pixels, wrap=wrap, offset=offset, scale=scale, rotation=rotation)

    def pixels(self, shader: Any, where: str) -> np.ndarray | None:
        """The RGBA pixels of a UsdUVTexture's file (read once per resolved path), None with a warning."""
        asset = self._value(shader, "file", None)
        if asset is None or not getattr(asset, "path", ""):
            self.warn(f"material {where}: texture {shader.GetPath()} has no file; left out")
            return None
        return self.pixels_of_asset(asset, f"material {where}")

    def pixels_of_asset(self, asset: Any, where: str) -> np.ndarray | None:
        """The RGBA pixels of an ``Sdf.AssetPath`` (checked against the path policy), None with a warning."""
        authored, resolved = str(asset.path), str(asset.resolvedPath or "")
        if "<UDIM>" in authored:
            self.warn(f"{where}: UDIM texture {authored!r} is not supported; left out")
            return None
        if not resolved:
            self.warn(f"{where}: texture {authored!r} not found; left out")
            return None
        check_asset(authored, resolved, self.folder, self.trusted, f"load_usd {self.name}: {where}")
        if resolved in self.images:
            return self.images[resolved]
        pixels = None
        try:
            from pxr import Ar

            data = Ar.GetResolver().OpenAsset(Ar.ResolvedPath(resolved))
            raw = bytes(memoryview(data.GetBuffer())) if data else Path(resolved).read_bytes()
            from PIL import Image as PILImage

            with PILImage.open(io.BytesIO(raw)) as img:
                if img.mode in ("I;16", "I;16B", "I"):
                    img = img.point(lambda v: v / 256).convert("L")
                pixels = np.asarray(img.convert("RGBA"), np.uint8)
        except Exception as exc:  # Pillow reads PNG, JPEG, TGA, BMP...; not EXR or HDR
            self.warn(f"{where}: texture {authored!r} cannot be read ({type(exc).__name__}: {exc}); left out")
        if pixels is not None:
            pixels.setflags(write=False)
        self.images[resolved] = pixels
        return pixels
