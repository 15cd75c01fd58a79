"""``om.export(scene, "x.usda" | "x.usdc" | "x.usd" | "x.usdz")``: a scene as an OpenUSD stage, through ``usd-core``.

The scene is evaluated by :class:`USDEngine` (an exporting engine, like the
glTF writer's), so every shape any engine can show is written:

- nodes as ``Xform`` prims (names made valid USD identifiers; the original
  name is kept in the prim's ``customData`` when it had to change), every
  transform as one ``xformOp:transform`` matrix;
- ``Sphere``, ``Box`` (a ``Cube`` scaled), ``Cylinder`` and ``Cone`` as their
  USD prims (axis y); triangle sets (and every other shape, through its
  simplifier) as ``Mesh`` prims with vertex normals, ``st`` and
  ``displayColor``/``displayOpacity``; line sets as linear ``BasisCurves``,
  point sets as ``Points``; an ``InstanceSet`` as a ``PointInstancer`` whose
  prototype is its shape (positions, orientations, scales, invisibleIds; colours
  as a ``displayColor`` primvar per instance);
- the appearance (the one appearance model) as a ``UsdPreviewSurface``
  material with ``UsdUVTexture``/``UsdPrimvarReader_float2``/
  ``UsdTransform2d`` for textures (PNG files next to the stage, or inside
  the ``.usdz`` package); Phong materials become the nearest metallic-roughness
  surface, and omnirender's own parameters are kept as ``omnirender:*``
  attributes so :func:`~omnirender.formats.usd.load_usd` rebuilds them exactly;
- lights as ``UsdLux`` lights (directional -> ``DistantLight``, point ->
  ``SphereLight`` treated as a point, spot -> ``SphereLight`` with a shaping cone,
  rectangle -> ``RectLight``, disc -> ``DiskLight`` (radiance ``L``, the same rule),
  ambient -> ``DomeLight``) in physical units, matched at the camera's centre
  of interest like the glTF export, with omnirender's OpenGL attenuation kept as
  ``omnirender:*`` attributes; the camera as a ``Camera`` prim;
- ``om.Animation`` keyframe tracks as time samples of the transforms they move
  (sampled at the animation's frame rate and at every key).

The written stage is checked by USD's own validators (:func:`validate`).
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ...attributes import (
    AmbientLight,
    Background,
    DirectionalLight,
    DiscLight,
    LightSource,
    PBRMaterial,
    PointLight,
    RectLight,
    SpotLight,
    Texture,
)
from ...attributes.environment import is_scene_background
from ...attributes.photometry import intensity_scale, phong_roughness, srgb_to_linear
from ...attributes.surface import appearance_key, engine_appearance
from ...attributes.texturing import bake_layers
from ...core import AttributePainter, ShapePainter, default_for, version_key
from ...scene import Node
from ...shapes import Box, Cone, Cylinder, InstanceSet, LineSet, PointSet, Sphere, TriangleSet
from ..walk import NodeTrackingEngine, track_surfaces

__all__ = ["export", "USDEngine", "validate", "SUFFIXES"]

SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")
#: USD's default vertical aperture (mm, a 35 mm film back)
APERTURE = 20.955


def _gf(m: np.ndarray) -> Any:
    from pxr import Gf

    return Gf.Matrix4d(np.asarray(m, np.float64).T.tolist())


def _linear(rgb: Any) -> tuple[float, float, float]:
    a = srgb_to_linear(np.asarray(rgb, np.float64)[:3])
    return (float(a[0]), float(a[1]), float(a[2]))


def _is_identity(m: np.ndarray) -> bool:
    return bool(np.allclose(m, np.eye(4), rtol=0.0, atol=1e-12))


def _frame(direction: np.ndarray, position: np.ndarray) -> np.ndarray:
    """A rigid frame at ``position`` whose -z is ``direction``."""
    d = np.asarray(direction, np.float64)
    d = d / max(np.linalg.norm(d), 1e-300)
    z = -d
    up = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.99 else np.array([1.0, 0.0, 0.0])
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, y, z, position
    return m


class USDEngine(NodeTrackingEngine):
    """Evaluates a scene into a USD stage (see the module docstring)."""

    service = "usd.export"

    def __init__(self, stage: Any, root: str, textures: Path, size: tuple[int, int] = (640, 480), **options: Any):
        super().__init__(**options)
        from pxr import Sdf, Usd, UsdGeom, UsdLux, UsdShade

        self.Sdf, self.Usd, self.UsdGeom, self.UsdLux, self.UsdShade = Sdf, Usd, UsdGeom, UsdLux, UsdShade
        self.stage = stage
        self.size = size
        self.textures_dir = textures
        self.root = Sdf.Path("/" + _identifier(root))
        self._stack: list[tuple[Any, np.ndarray]] = []
        self._names: dict[str, set[str]] = {}
        self._materials: dict[Any, Any] = {}
        self._textures: dict[Any, str] = {}
        self._lights: list[tuple[Any, np.ndarray, Any]] = []
        self.background: Any = None
        self.matrices: dict[str, np.ndarray] = {}  # prim path -> local matrix as written (animation sampling)
        self.sampling = False
        self.last_path: Any = None

    # -- structure ----------------------------------------------------------------------
    def _parent(self) -> tuple[Any, np.ndarray]:
        return self._stack[-1] if self._stack else (self.root, np.eye(4))

    def _child_path(self, parent: Any, name: str) -> Any:
        key = str(parent)
        taken = self._names.setdefault(key, set())
        base = _identifier(name)
        candidate, k = base, 1
        while candidate in taken:
            candidate, k = f"{base}_{k}", k + 1
        taken.add(candidate)
        return parent.AppendChild(candidate)

    def define(self, schema: Any, name: str, matrix: np.ndarray | None = None, original: str | None = None) -> Any:
        """Define a prim of ``schema`` under the enclosing node, placed by ``matrix`` (relative to it)."""
        parent, _ = self._parent()
        path = self._child_path(parent, name)
        if matrix is None:
            matrix = self.local_matrix()
        self.matrices[str(path)] = matrix
        self.last_path = path
        if self.sampling:
            return None
        prim = schema.Define(self.stage, path)
        if not _is_identity(matrix):
            prim.AddTransformOp().Set(_gf(matrix))
        if original is not None and original != path.name:
            prim.GetPrim().SetCustomDataByKey("omnirender:name", original)
        return prim

    def local_matrix(self) -> np.ndarray:
        return np.linalg.solve(self._parent()[1], self.model_matrix())

    def enter_node(self, node: Any, world: np.ndarray) -> None:
        if not self._stack and node.name == self.root.name:  # the scene's root is the stage's default prim
            self.matrices[str(self.root)] = np.eye(4)
            if not self.sampling:
                self.UsdGeom.Xform.Define(self.stage, self.root)
            self._stack.append((self.root, np.array(world)))
            self._names.setdefault(str(self.root), set())
            return
        parent, parent_world = self._parent()
        prim = self.define(self.UsdGeom.Xform, node.name, np.linalg.solve(parent_world, world), node.name)
        path = self.last_path
        if prim is not None and node.groups:
            from pxr import Vt

            prim.GetPrim().SetCustomDataByKey("omnirender:groups", Vt.StringArray(sorted(node.groups)))
        self._stack.append((path, np.array(world)))

    def leave_node(self, node: Any) -> None:
        self._stack.pop()

    # -- materials ------------------------------------------------------------------------
    def bind(self, prim: Any, textured: bool, vertex_colors: bool = False) -> None:
        if self.sampling or prim is None:
            return
        material = self.material(textured, vertex_colors)
        api = self.UsdShade.MaterialBindingAPI.Apply(prim.GetPrim())
        api.Bind(material)

    def material(self, textured: bool, vertex_colors: bool) -> Any:
        """The UsdPreviewSurface material of the active appearance (shared when identical)."""
        from pxr import Sdf

        mono = self.mono
        from ...attributes import BumpMap, MultiTexture

        tex = mono(Texture) if textured else None
        key = (appearance_key(self.surface_stack, tex, mono(MultiTexture), mono(BumpMap)), textured, vertex_colors)
        found = self._materials.get(key)
        if found is not None:
            return found
        app = engine_appearance(self, texcoords=textured)
        looks = self.root.AppendChild("Looks")
        if not self.stage.GetPrimAtPath(looks):
            self.UsdGeom.Scope.Define(self.stage, looks)
        path = looks.AppendChild(f"Material_{len(self._materials)}")
        material = self.UsdShade.Material.Define(self.stage, path)
        shader = self.UsdShade.Shader.Define(self.stage, path.AppendChild("Surface"))
        shader.CreateIdAttr("UsdPreviewSurface")
        material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
        base = np.asarray(app.base, np.float64)
        if vertex_colors and app.vertex_colors == "replace":
            base = np.ones(3)
        if app.model == "pbr":
            metallic, roughness = app.metallic, app.roughness
        else:
            shiny = float(np.mean(app.specular)) > 0.0
            metallic, roughness = 0.0, phong_roughness(app.shininess) if shiny else 1.0
        F, C3 = Sdf.ValueTypeNames.Float, Sdf.ValueTypeNames.Color3f
        shader.CreateInput("metallic", F).Set(float(metallic))
        shader.CreateInput("roughness", F).Set(float(roughness))
        alpha = float(app.alpha) if app.alpha_mode != "opaque" else 1.0
        texture = app.texture
        if app.layers:
            texture = Texture(bake_layers(None if app.texture is None else app.texture.image_array(), app.layers))
        reader = None
        if texture is not None or app.metallic_roughness_texture is not None or app.normal_texture is not None:
            reader = self.UsdShade.Shader.Define(self.stage, path.AppendChild("TexCoords"))
            reader.CreateIdAttr("UsdPrimvarReader_float2")
            reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
            reader.CreateOutput("result", Sdf.ValueTypeNames.Float2)
        diffuse = shader.CreateInput("diffuseColor", C3)
        if vertex_colors and texture is None:
            colors = self.UsdShade.Shader.Define(self.stage, path.AppendChild("DisplayColor"))
            colors.CreateIdAttr("UsdPrimvarReader_float3")
            colors.CreateInput("varname", Sdf.ValueTypeNames.String).Set("displayColor")
            diffuse.ConnectToSource(colors.ConnectableAPI(), "result")
            colors.CreateOutput("result", Sdf.ValueTypeNames.Float3)
        elif texture is not None:
            node = self.uv_texture(path, "BaseColor", texture, reader, scale=(*(float(v) for v in base), 1.0))
            diffuse.ConnectToSource(node.ConnectableAPI(), "rgb")
            if app.alpha_mode != "opaque":
                shader.CreateInput("opacity", F).ConnectToSource(node.ConnectableAPI(), "a")
        else:
            diffuse.Set(tuple(float(v) for v in base))
        if app.alpha_mode != "opaque" and not (texture is not None and not vertex_colors):
            shader.CreateInput("opacity", F).Set(alpha)
        if app.alpha_mode == "mask":
            shader.CreateInput("opacityThreshold", F).Set(float(app.alpha_cutoff))
        if app.metallic_roughness_texture is not None:
            node = self.uv_texture(path, "MetallicRoughness", app.metallic_roughness_texture, reader,
                                   scale=(1.0, roughness, metallic, 1.0), raw=True)  # fmt: skip
            shader.CreateInput("roughness", F).ConnectToSource(node.ConnectableAPI(), "g")
            shader.CreateInput("metallic", F).ConnectToSource(node.ConnectableAPI(), "b")
        normal, normal_scale = app.normal_map()
        if normal is not None:
            node = self.uv_texture(path, "Normal", normal, reader, scale=(2.0 * normal_scale, 2.0 * normal_scale,
                                   2.0, 1.0), bias=(-normal_scale, -normal_scale, -1.0, 0.0), raw=True)  # fmt: skip
            shader.CreateInput("normal", Sdf.ValueTypeNames.Normal3f).ConnectToSource(node.ConnectableAPI(), "rgb")
        if app.occlusion_texture is not None:
            node = self.uv_texture(path, "Occlusion", app.occlusion_texture, reader, raw=True)
            shader.CreateInput("occlusion", F).ConnectToSource(node.ConnectableAPI(), "r")
        emission = np.asarray(app.emission, np.float64)
        if app.emits:
            linear = emission  # the appearance's colours are linear (emissive strength applied)
            if app.emissive_texture is not None:
                node = self.uv_texture(path, "Emission", app.emissive_texture, reader, scale=(*linear, 1.0))
                shader.CreateInput("emissiveColor", C3).ConnectToSource(node.ConnectableAPI(), "rgb")
            else:
                shader.CreateInput("emissiveColor", C3).Set(tuple(float(v) for v in linear))
        self.keep_source(material, vertex_colors)
        self._materials[key] = material
        return material

    def keep_source(self, material: Any, vertex_colors: bool) -> None:
        """omnirender's own surface attributes, exactly, as ``omnirender:*`` attributes of the material."""
        from pxr import Sdf

        prim = material.GetPrim()
        kinds = []
        for item in self.surface_stack:
            kind = type(item).__name__
            if kind not in ("Color", "Material", "PBRMaterial"):
                continue
            kinds.append(kind)
            for name, value in item.parameters().items():
                if isinstance(value, Texture) or value is None:
                    continue
                attr_name = f"omnirender:{kind}:{name}"
                if isinstance(value, bool):
                    prim.CreateAttribute(attr_name, Sdf.ValueTypeNames.Bool, custom=True).Set(bool(value))
                elif isinstance(value, str):
                    prim.CreateAttribute(attr_name, Sdf.ValueTypeNames.String, custom=True).Set(value)
                elif np.ndim(value) == 0:
                    prim.CreateAttribute(attr_name, Sdf.ValueTypeNames.Double, custom=True).Set(float(value))
                else:
                    values = [float(v) for v in np.asarray(value, np.float64).reshape(-1)]
                    prim.CreateAttribute(attr_name, Sdf.ValueTypeNames.DoubleArray, custom=True).Set(values)
        prim.CreateAttribute("omnirender:surface", Sdf.ValueTypeNames.StringArray, custom=True).Set(kinds)

    def uv_texture(
        self,
        material: Any,
        name: str,
        tex: Texture,
        reader: Any,
        scale: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0),
        bias: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0),
        raw: bool = False,
    ) -> Any:
        from pxr import Sdf

        node = self.UsdShade.Shader.Define(self.stage, material.AppendChild(name))
        node.CreateIdAttr("UsdUVTexture")
        node.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(self.texture_file(tex))
        node.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("raw" if raw else "sRGB")
        wrap = {"repeat": "repeat", "clamp": "clamp", "mirror": "mirror"}[tex.wrap]
        node.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set(wrap)
        node.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set(wrap)
        if any(s != 1.0 for s in scale):
            node.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(tuple(float(s) for s in scale))
        if any(b != 0.0 for b in bias):
            node.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(tuple(float(b) for b in bias))
        st = node.CreateInput("st", Sdf.ValueTypeNames.Float2)
        if tex.transformed:
            transform = self.UsdShade.Shader.Define(self.stage, material.AppendChild(name + "Transform"))
            transform.CreateIdAttr("UsdTransform2d")
            transform.CreateInput("in", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
            transform.CreateInput("scale", Sdf.ValueTypeNames.Float2).Set(tuple(float(s) for s in tex.scale))
            transform.CreateInput("rotation", Sdf.ValueTypeNames.Float).Set(float(tex.rotation))
            transform.CreateInput("translation", Sdf.ValueTypeNames.Float2).Set(tuple(float(s) for s in tex.offset))
            transform.CreateOutput("result", Sdf.ValueTypeNames.Float2)
            st.ConnectToSource(transform.ConnectableAPI(), "result")
        else:
            st.ConnectToSource(reader.ConnectableAPI(), "result")
        for output, kind in (("rgb", Sdf.ValueTypeNames.Float3), ("a", Sdf.ValueTypeNames.Float)):
            node.CreateOutput(output, kind)
        for output in ("r", "g", "b"):
            node.CreateOutput(output, Sdf.ValueTypeNames.Float)
        return node

    def texture_file(self, tex: Texture) -> str:
        """The PNG file of a texture (written once), relative to the stage."""
        key = version_key(tex)
        if key in self._textures:
            return self._textures[key]
        from PIL import Image as PILImage

        try:
            rgba = tex.image_array()
        except (FileNotFoundError, ValueError) as exc:
            raise type(exc)(f"USD export: {exc} (Texture in node {self.node_path or '/'})") from None
        self.textures_dir.mkdir(parents=True, exist_ok=True)
        name = f"texture_{len(self._textures)}.png"
        PILImage.fromarray(np.asarray(rgba), "RGBA").save(self.textures_dir / name)
        relative = f"./{self.textures_dir.name}/{name}"
        self._textures[key] = relative
        return relative

    # -- shapes ---------------------------------------------------------------------------
    def textured(self) -> bool:
        """Whether a texture applies here: primitives are then written as meshes (with texture coordinates)."""
        from ...attributes import BumpMap, MultiTexture

        if self.mono(Texture) is not None or self.mono(MultiTexture) is not None or self.mono(BumpMap) is not None:
            return True
        material = engine_appearance(self).material
        return isinstance(material, PBRMaterial) and bool(material.textures)

    def gprim(self, schema: Any, name: str, matrix: np.ndarray | None = None) -> Any:
        """Define a geometric prim placed by the current model matrix (or ``matrix``) under the enclosing node."""
        return self.define(schema, name, matrix)

    # -- lights and camera ----------------------------------------------------------------
    def add_light(self, light: Any) -> None:
        for other, m in self.lights():
            if other is light:
                self._lights.append((light, np.array(m), self.node_path))
                return
        self._lights.append((light, self.model_matrix(), self.node_path))

    def reference_point(self) -> np.ndarray:
        if self.camera is None:
            return np.zeros(3)
        camera, world = self.camera
        return (np.asarray(world, np.float64) @ np.array([*camera.center, 1.0]))[:3]

    def write_lights(self) -> None:
        from pxr import Sdf

        lights_root = self.root.AppendChild("Lights")
        for k, (light, world, _) in enumerate(self._lights):
            if k == 0:
                self.UsdGeom.Xform.Define(self.stage, lights_root)
            name = f"{type(light).__name__}_{k}"
            path = lights_root.AppendChild(name)
            color = srgb_to_linear(np.asarray(light.color, np.float64))
            if isinstance(light, AmbientLight):
                prim = self.UsdLux.DomeLight.Define(self.stage, path)
                intensity = float(light.intensity)
                matrix = np.eye(4)
            elif isinstance(light, DirectionalLight):
                prim = self.UsdLux.DistantLight.Define(self.stage, path)
                prim.CreateNormalizeAttr(True)  # E = L: a diffuse surface shows L / pi, omnirender's intensity
                intensity = float(light.intensity) * math.pi
                matrix = _frame(light.world_direction(world), np.zeros(3))
            elif isinstance(light, (PointLight, SpotLight)):
                prim = self.UsdLux.SphereLight.Define(self.stage, path)
                prim.CreateTreatAsPointAttr(True)
                prim.CreateRadiusAttr(0.0)
                position = light.world_position(world)
                # normalised point light of radiance L: radiant intensity L / 4, which intensity_scale gives per
                # unit of omnirender's intensity (GL's attenuation matched by the inverse square at the camera's
                # centre of interest, as the glTF export does)
                physical = intensity_scale(light, position, self.reference_point())
                intensity = float(light.intensity) * physical * 4.0
                prim.CreateNormalizeAttr(True)
                if isinstance(light, SpotLight):
                    matrix = _frame(light.world_direction(world), position)
                    shaping = self.UsdLux.ShapingAPI.Apply(prim.GetPrim())
                    shaping.CreateShapingConeAngleAttr(float(light.cutoff))
                else:
                    matrix = np.eye(4)
                    matrix[:3, 3] = position
            elif isinstance(light, (RectLight, DiscLight)):
                # UsdLux area lights emit radiance L = intensity * colour along their -z: the area lights' rule
                centre, hu, hv, normal = light.world_frame(world)
                lu, lv = float(np.linalg.norm(hu)), float(np.linalg.norm(hv))
                x, y, z = hu / lu, hv / lv, -normal
                if float(np.dot(np.cross(x, y), z)) < 0.0:
                    x = -x  # keep a right-handed frame (a mirrored light): the shape is symmetric
                matrix = np.eye(4)
                matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = x, y, z, centre
                if isinstance(light, RectLight):
                    prim = self.UsdLux.RectLight.Define(self.stage, path)
                    prim.CreateWidthAttr(2.0 * lu)
                    prim.CreateHeightAttr(2.0 * lv)
                else:
                    prim = self.UsdLux.DiskLight.Define(self.stage, path)
                    prim.CreateRadiusAttr(math.sqrt(lu * lv))  # an ellipse (non-uniform scaling): the same area
                prim.CreateNormalizeAttr(False)
                intensity = float(light.intensity)
            else:
                warnings.warn(f"USD export: {type(light).__name__} is not written (no UsdLux equivalent)", stacklevel=2)
                continue
            prim.CreateColorAttr(tuple(float(c) for c in color))
            prim.CreateIntensityAttr(intensity)
            if not light.casts_shadows:
                shadow = self.UsdLux.ShadowAPI.Apply(prim.GetPrim())
                shadow.CreateShadowEnableAttr(False)
            if not _is_identity(matrix):
                prim.AddTransformOp().Set(_gf(matrix))
            usd = prim.GetPrim()
            usd.CreateAttribute("omnirender:type", Sdf.ValueTypeNames.String, custom=True).Set(type(light).__name__)
            sizes = {}
            if isinstance(light, RectLight):
                sizes = {"width": 2.0 * lu, "height": 2.0 * lv}
            elif isinstance(light, DiscLight):
                sizes = {"radius": math.sqrt(lu * lv)}
            for pname, value in light.parameters().items():
                if pname in ("position", "direction", "up") or value is None:
                    continue
                value = sizes.get(pname, value)  # an area light's size in the prim's (world) frame
                attr = f"omnirender:{pname}"
                if isinstance(value, bool):
                    usd.CreateAttribute(attr, Sdf.ValueTypeNames.Bool, custom=True).Set(value)
                elif np.ndim(value) == 0:
                    usd.CreateAttribute(attr, Sdf.ValueTypeNames.Double, custom=True).Set(float(value))
                else:
                    values = [float(v) for v in np.asarray(value, np.float64).reshape(-1)]
                    usd.CreateAttribute(attr, Sdf.ValueTypeNames.DoubleArray, custom=True).Set(values)

    def write_camera(self) -> None:
        if self.camera is None:
            return
        camera, world = self.camera
        cam = self.UsdGeom.Camera.Define(self.stage, self.root.AppendChild("Camera"))
        eye_to_world = np.asarray(world, np.float64) @ np.linalg.inv(camera.view_matrix())
        cam.AddTransformOp().Set(_gf(eye_to_world))
        w, h = self.size
        if camera.is_orthographic:
            cam.CreateProjectionAttr("orthographic")
            cam.CreateVerticalApertureAttr(float(camera.height) * 10.0)
            cam.CreateHorizontalApertureAttr(float(camera.height) * 10.0 * w / h)
        else:
            focal = APERTURE / (2.0 * math.tan(math.radians(camera.fov) / 2.0))
            cam.CreateVerticalApertureAttr(APERTURE)
            cam.CreateHorizontalApertureAttr(APERTURE * w / h)
            cam.CreateFocalLengthAttr(float(focal))
        from pxr import Gf

        cam.CreateClippingRangeAttr(Gf.Vec2f(float(camera.near), float(camera.far)))
        if camera.mask is not None:
            from pxr import Sdf

            cam.GetPrim().CreateAttribute("omnirender:mask", Sdf.ValueTypeNames.String, custom=True).Set(camera.mask)

    def finish(self) -> None:
        self.write_camera()
        self.write_lights()
        if self.background is not None:
            from pxr import Sdf

            root = self.stage.GetPrimAtPath(self.root)
            values = [float(c) for c in self.background.color]
            root.CreateAttribute("omnirender:background", Sdf.ValueTypeNames.DoubleArray, custom=True).Set(values)


track_surfaces(USDEngine)


def _points(shape: Any) -> Any:
    from pxr import Vt

    return Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(shape.vertex_array(), np.float32))


def _display(prim: Any, shape: Any, interpolation: str = "vertex") -> bool:
    """Per-vertex colours as displayColor (linear) and displayOpacity; True when written."""
    colors = shape.color_array()
    if colors is None or prim is None:
        return colors is not None
    from pxr import Vt

    c = np.asarray(colors, np.float64)
    linear = srgb_to_linear(c[:, :3]).astype(np.float32)
    prim.CreateDisplayColorPrimvar(interpolation).Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(linear)))
    if c.shape[1] == 4 and (c[:, 3] < 1.0).any():
        prim.CreateDisplayOpacityPrimvar(interpolation).Set(Vt.FloatArray.FromNumpy(c[:, 3].astype(np.float32)))
    return True


@default_for(USDEngine)
class TriangleSetWriter(ShapePainter):
    """``TriangleSet`` -> a ``Mesh`` (triangles, vertex normals, ``st``, display colours)."""

    __slots__ = ()
    service = USDEngine.service
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: USDEngine) -> None:
        if len(shape.index_array()) == 0:
            return
        from pxr import Sdf, Vt

        prim = engine.gprim(engine.UsdGeom.Mesh, "Mesh")
        if prim is None:
            return
        faces = np.ascontiguousarray(shape.index_array(), np.int32)
        prim.CreatePointsAttr(_points(shape))
        prim.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, np.int32)))
        prim.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(faces.reshape(-1)))
        prim.CreateSubdivisionSchemeAttr("none")
        normals = np.ascontiguousarray(shape.normal_array(), np.float32)
        prim.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(normals))
        prim.SetNormalsInterpolation("vertex")
        uv = shape.texcoord_array()
        if uv is not None:
            api = engine.UsdGeom.PrimvarsAPI(prim.GetPrim())
            st = api.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, "vertex")
            st.Set(Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(uv, np.float32)))
        lo, hi = shape.vertex_array().min(axis=0), shape.vertex_array().max(axis=0)
        prim.CreateExtentAttr(Vt.Vec3fArray([tuple(map(float, lo)), tuple(map(float, hi))]))
        colored = _display(prim, shape)
        engine.bind(prim, uv is not None, colored)


def _extent(prim: Any, lo: Any, hi: Any) -> None:
    from pxr import Vt

    prim.CreateExtentAttr(Vt.Vec3fArray([tuple(float(v) for v in lo), tuple(float(v) for v in hi)]))


@default_for(USDEngine)
class SphereWriter(ShapePainter):
    """``Sphere`` -> a ``Sphere`` prim."""

    __slots__ = ()
    service = USDEngine.service
    target = Sphere

    def exec(self, shape: Sphere, engine: USDEngine) -> None:
        if engine.textured():
            engine.simplify(shape)
            return
        m = engine.local_matrix() @ _translation(shape.center)
        prim = engine.gprim(engine.UsdGeom.Sphere, "Sphere", m)
        if prim is not None:
            prim.CreateRadiusAttr(float(shape.radius))
            _extent(prim, [-shape.radius] * 3, [shape.radius] * 3)
            engine.bind(prim, False)


@default_for(USDEngine)
class BoxWriter(ShapePainter):
    """``Box`` -> a unit ``Cube`` prim scaled to the box."""

    __slots__ = ()
    service = USDEngine.service
    target = Box

    def exec(self, shape: Box, engine: USDEngine) -> None:
        if engine.textured():
            engine.simplify(shape)
            return
        m = engine.local_matrix() @ _translation(shape.center) @ np.diag([*np.asarray(shape.size, float), 1.0])
        prim = engine.gprim(engine.UsdGeom.Cube, "Cube", m)
        if prim is not None:
            prim.CreateSizeAttr(1.0)
            _extent(prim, [-0.5] * 3, [0.5] * 3)
            engine.bind(prim, False)


class _AxialWriter(ShapePainter):
    __slots__ = ()
    service = USDEngine.service
    schema = ""

    def exec(self, shape: Any, engine: USDEngine) -> None:
        if engine.textured():
            engine.simplify(shape)
            return
        prim = engine.gprim(getattr(engine.UsdGeom, self.schema), self.schema)
        if prim is not None:
            r, h = float(shape.radius), float(shape.height)
            prim.CreateRadiusAttr(r)
            prim.CreateHeightAttr(h)
            prim.CreateAxisAttr("Y")
            _extent(prim, [-r, -h / 2, -r], [r, h / 2, r])
            engine.bind(prim, False)


@default_for(USDEngine)
class CylinderWriter(_AxialWriter):
    """``Cylinder`` -> a ``Cylinder`` prim (axis y)."""

    __slots__ = ()
    target = Cylinder
    schema = "Cylinder"


@default_for(USDEngine)
class ConeWriter(_AxialWriter):
    """``Cone`` -> a ``Cone`` prim (axis y)."""

    __slots__ = ()
    target = Cone
    schema = "Cone"


def _translation(offset: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = np.asarray(offset, np.float64)
    return m


@default_for(USDEngine)
class LineSetWriter(ShapePainter):
    """``LineSet`` -> linear ``BasisCurves`` of two vertices each."""

    __slots__ = ()
    service = USDEngine.service
    target = LineSet

    def exec(self, shape: LineSet, engine: USDEngine) -> None:
        segments = shape.index_array()
        if len(segments) == 0:
            return
        from pxr import Vt

        prim = engine.gprim(engine.UsdGeom.BasisCurves, "Curves")
        if prim is None:
            return
        v = np.asarray(shape.vertex_array(), np.float32)[segments.reshape(-1)]
        prim.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(v)))
        prim.CreateCurveVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(segments), 2, np.int32)))
        prim.CreateTypeAttr("linear")
        _extent(prim, v.min(axis=0), v.max(axis=0))
        colors = shape.color_array()
        if colors is not None:
            expanded = np.asarray(colors)[segments.reshape(-1)]
            linear = srgb_to_linear(np.asarray(expanded, np.float64)[:, :3]).astype(np.float32)
            prim.CreateDisplayColorPrimvar("vertex").Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(linear)))
        engine.bind(prim, False, colors is not None)


@default_for(USDEngine)
class PointSetWriter(ShapePainter):
    """``PointSet`` -> ``Points`` (widths from the point sizes)."""

    __slots__ = ()
    service = USDEngine.service
    target = PointSet

    def exec(self, shape: PointSet, engine: USDEngine) -> None:
        if len(shape.vertex_array()) == 0:
            return
        from pxr import Vt

        prim = engine.gprim(engine.UsdGeom.Points, "Points")
        if prim is None:
            return
        prim.CreatePointsAttr(_points(shape))
        v = shape.vertex_array()
        _extent(prim, v.min(axis=0), v.max(axis=0))
        sizes = shape.size_array() if hasattr(shape, "size_array") else None
        if sizes is not None:
            prim.CreateWidthsAttr(Vt.FloatArray.FromNumpy(np.ascontiguousarray(sizes, np.float32)))
            prim.SetWidthsInterpolation("vertex")
        colored = _display(prim, shape)
        engine.bind(prim, False, colored)


@default_for(USDEngine)
class InstanceSetWriter(ShapePainter):
    """``InstanceSet`` -> a ``PointInstancer`` with the set's shape as its one prototype."""

    __slots__ = ()
    service = USDEngine.service
    target = InstanceSet

    def exec(self, shape: InstanceSet, engine: USDEngine) -> None:
        from pxr import Vt

        from ...geometry.trs import decompose_trs

        matrices = np.asarray(shape.matrices(), np.float64)
        trs = decompose_trs(matrices)
        if not trs.valid.all():  # sheared or mirrored instances: PointInstancer cannot place them
            warnings.warn(
                f"USD export: the InstanceSet in node {engine.node_path or '/'} has {trs.reason[~trs.valid][0]} "
                "instances; written as one prim per instance",
                stacklevel=2,
            )
            engine.simplify(shape)
            return
        instancer = engine.gprim(engine.UsdGeom.PointInstancer, "Instances")
        if instancer is None:
            return
        proto_path = instancer.GetPath().AppendChild("Prototypes")
        engine.UsdGeom.Scope.Define(engine.stage, proto_path)
        engine._stack.append((proto_path, engine.model_matrix()))
        try:
            engine.eval(shape.shape)
        finally:
            engine._stack.pop()
        protos = engine.stage.GetPrimAtPath(proto_path).GetChildren()
        if not protos:
            return
        if len(protos) > 1:  # one prototype prim holding every part of the shape
            holder = engine.UsdGeom.Xform.Define(engine.stage, proto_path.AppendChild("Shape"))
            for p in protos:
                _move(engine.stage, p.GetPath(), holder.GetPath().AppendChild(p.GetName()))
            target = holder.GetPath()
        else:
            target = protos[0].GetPath()
        instancer.CreatePrototypesRel().SetTargets([target])
        n = len(matrices)
        instancer.CreateProtoIndicesAttr(Vt.IntArray.FromNumpy(np.zeros(n, np.int32)))
        instancer.CreatePositionsAttr(Vt.Vec3fArray.FromNumpy(trs.translation.astype(np.float32)))
        q = trs.rotation  # (x, y, z, w): Gf quaternions are stored (i, j, k, real) too
        instancer.CreateOrientationsfAttr(Vt.QuatfArray.FromNumpy(np.ascontiguousarray(q, np.float32)))
        instancer.CreateScalesAttr(Vt.Vec3fArray.FromNumpy(trs.scale.astype(np.float32)))
        visible = shape.visible_array()
        if visible is not None and not np.all(visible):
            instancer.CreateIdsAttr(Vt.Int64Array.FromNumpy(np.arange(n, dtype=np.int64)))
            instancer.CreateInvisibleIdsAttr(Vt.Int64Array.FromNumpy(np.flatnonzero(~np.asarray(visible, bool))))
        colors = shape.color_array()
        if colors is not None:
            linear = srgb_to_linear(np.asarray(colors, np.float64)[:, :3]).astype(np.float32)
            api = engine.UsdGeom.PrimvarsAPI(instancer.GetPrim())
            primvar = api.CreatePrimvar("displayColor", engine.Sdf.ValueTypeNames.Color3fArray, "vertex")
            primvar.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(linear)))


def _move(stage: Any, source: Any, target: Any) -> None:
    from pxr import Sdf

    layer = stage.GetRootLayer()
    edit = Sdf.BatchNamespaceEdit()
    edit.Add(source, target)
    layer.Apply(edit)


@default_for(USDEngine)
class LightWriter(AttributePainter):
    """Lights -> queued, written as UsdLux lights at the end."""

    __slots__ = ()
    service = USDEngine.service
    target = LightSource

    def exec(self, light: LightSource, engine: USDEngine) -> None:
        engine.add_light(light)


@default_for(USDEngine)
class BackgroundWriter(AttributePainter):
    """``Background`` -> the ``omnirender:background`` attribute of the default prim."""

    __slots__ = ()
    service = USDEngine.service
    target = Background

    def exec(self, background: Background, engine: USDEngine) -> None:
        if engine.background is None and is_scene_background(background, engine):
            engine.background = background


def _identifier(name: str) -> str:
    from pxr import Tf

    return Tf.MakeValidIdentifier(str(name)) or "node"


def build_stage(scene: Any, layer_path: Path, size: tuple[int, int] = (640, 480), mask: str | None = None) -> Any:
    """An in-memory stage of ``scene`` (textures written beside ``layer_path``)."""
    from pxr import Sdf, Usd, UsdGeom

    if not isinstance(scene, Node):
        scene = Node("scene", scene)
    layer = Sdf.Layer.CreateAnonymous(layer_path.suffix)
    stage = Usd.Stage.Open(layer)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    textures = layer_path.parent / f"{layer_path.stem}_textures"
    engine = USDEngine(stage, scene.name, textures, size, mask=mask)
    engine.run(scene)
    engine.finish()
    stage.SetDefaultPrim(stage.GetPrimAtPath(engine.root))
    _write_animation(scene, stage, engine, textures, size, mask)
    return stage


def _write_animation(scene: Node, stage: Any, engine: USDEngine, textures: Path, size: Any, mask: Any) -> None:
    """Time samples of every prim whose matrix an ``om.Animation`` changes."""
    from ...animation.animation import animations, set_time

    found = animations(scene)
    if not found:
        return
    from pxr import Usd, UsdGeom

    duration = max(float(a.duration or 0.0) for a in found)
    fps = float(found[0].fps)
    if duration <= 0.0:
        return
    times = set(np.round(np.arange(0.0, duration + 1e-9, 1.0 / fps), 9))
    for a in found:
        for track in a.tracks:
            times.update(float(t) for t in getattr(track, "times", ()) if 0.0 <= t <= duration)
    times = sorted(times)
    samples: dict[str, list[np.ndarray]] = {p: [] for p in engine.matrices}
    try:
        for t in times:
            set_time(scene, t)
            sampler = USDEngine(stage, scene.name, textures, size, mask=mask)
            sampler.sampling = True
            sampler.run(scene)
            for path in samples:
                samples[path].append(sampler.matrices.get(path, engine.matrices[path]))
    finally:
        set_time(scene, 0.0)
    stage.SetTimeCodesPerSecond(fps)
    stage.SetFramesPerSecond(fps)
    stage.SetStartTimeCode(0.0)
    stage.SetEndTimeCode(duration * fps)
    for path, matrices in samples.items():
        if all(np.allclose(m, matrices[0], atol=1e-12) for m in matrices[1:]):
            continue
        prim = stage.GetPrimAtPath(path)
        xf = UsdGeom.Xformable(prim)
        xf.ClearXformOpOrder()
        op = xf.AddTransformOp()
        for t, m in zip(times, matrices, strict=True):
            op.Set(_gf(m), Usd.TimeCode(t * fps))


def validate(path: str | os.PathLike[str]) -> list[str]:
    """USD's own validators (``pxr.UsdValidation``, what ``usdchecker`` runs) on a file: the error messages."""
    from pxr import Usd, UsdValidation

    stage = Usd.Stage.Open(str(path))
    registry = UsdValidation.ValidationRegistry()
    validators = registry.GetOrLoadAllValidators()
    context = UsdValidation.ValidationContext(validators)
    errors = context.Validate(stage)
    return [
        f"{e.GetName()}: {e.GetMessage()}" for e in errors if e.GetType() == UsdValidation.ValidationErrorType.Error
    ]


def export(scene: Any, path: str | os.PathLike[str], *, size: tuple[int, int] = (640, 480), mask: str | None = None):
    """Write ``scene`` as a USD stage: ``.usda`` (text), ``.usdc``/``.usd`` (binary) or ``.usdz`` (a package).

    The file is written atomically; textures go to ``<stem>_textures/`` beside
    it (inside the package for ``.usdz``).  ``size`` gives the camera's aspect.
    """
    try:
        from pxr import UsdUtils
    except ImportError as exc:  # pragma: no cover - usd-core is the 'usd' extra
        raise ImportError(f"USD export needs usd-core (pip install omnirender[usd]): {exc}") from None
    target = Path(os.fspath(path))
    suffix = target.suffix.lower()
    if suffix not in SUFFIXES:
        raise ValueError(f"USD export: {target.name!r} must end in one of {', '.join(SUFFIXES)}")
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=f".{target.stem}.") as tmp:
        tmp_dir = Path(tmp)
        if suffix == ".usdz":
            layer_path = tmp_dir / f"{target.stem}.usdc"
        else:
            layer_path = tmp_dir / f"{target.stem}{suffix}"
        stage = build_stage(scene, layer_path, size=size, mask=mask)
        stage.GetRootLayer().Export(str(layer_path))
        if suffix == ".usdz":
            package = tmp_dir / target.name
            if not UsdUtils.CreateNewUsdzPackage(str(layer_path), str(package)):
                raise RuntimeError(f"USD export: could not package {target.name!r}")
            os.replace(package, target)
        else:
            textures = tmp_dir / f"{target.stem}_textures"
            if textures.exists():
                final = target.parent / textures.name
                if final.exists():
                    shutil.rmtree(final)
                shutil.move(str(textures), final)
            os.replace(layer_path, target)
    return target


from . import splats as _splats  # noqa: E402,F401  (registers the ParticleField3DGaussianSplat writer)
