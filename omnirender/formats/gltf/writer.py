"""glTF 2.0 binary export (``om.export(scene, "scene.glb")``).

:class:`GLTFEngine` (service ``"gltf.export"``) evaluates the scene graph like
any engine: every scene-graph node becomes a glTF node with its name and the
transform accumulated since its parent (a ``matrix``); every shape is
simplified down to triangle sets (line and point sets), which become meshes
under a child node carrying the transforms met inside the node.  An
``InstanceSet`` becomes one mesh instanced with ``EXT_mesh_gpu_instancing``
(:mod:`.gltf_instancing`).  Materials are
converted to metallic-roughness (``Material``'s Phong parameters approximated,
colours made linear), textures are embedded as PNG, the camera becomes a glTF
camera and lights use ``KHR_lights_punctual``.  Texture coordinates follow
OpenGL in omnirender (v = 0 at the image's bottom row) and glTF's v points
down: v is flipped.
"""

from __future__ import annotations

import io
import math
import os
import warnings
from typing import Any

import numpy as np

from ...attributes import (
    AmbientLight,
    AreaLight,
    Background,
    BumpMap,
    DirectionalLight,
    DiscLight,
    LightSource,
    Material,
    MultiTexture,
    PointLight,
    SpotLight,
    Texture,
)
from ...attributes.environment import is_scene_background
from ...attributes.photometry import intensity_scale, phong_roughness
from ...attributes.surface import appearance_key, engine_appearance
from ...attributes.texturing import bake_layers
from ...core import AttributePainter, ShapePainter, default_for, version_key
from ...fileio import atomic_write
from ...geometry.matrix import transform_points
from ...geometry.trs import decomposable
from ...scene import Node
from ...shapes import InstanceSet, LineSet, PointSet, TriangleSet
from ..colors import srgb_to_linear
from ..walk import NodeTrackingEngine, track_surfaces
from .glb import ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER, GLBBuilder
from .instancing import INSTANCING_EXTENSION, Capture, write_instance_set

__all__ = ["export", "to_bytes", "build", "GLTFEngine", "LIGHTS_EXTENSION", "INSTANCING_EXTENSION"]

LIGHTS_EXTENSION = "KHR_lights_punctual"
TRANSFORM_EXTENSION = "KHR_texture_transform"
EMISSIVE_STRENGTH = "KHR_materials_emissive_strength"


def _gltf_transform(tex: Texture) -> dict[str, Any]:
    """omnirender's texture transform (v up) as ``KHR_texture_transform`` (v down): the importer's inverse."""
    r = math.radians(float(tex.rotation))
    su, sv = (float(x) for x in tex.scale)
    ou, ov = (float(x) for x in tex.offset)
    return {"offset": [ou - math.sin(r) * sv, 1.0 - ov - math.cos(r) * sv], "rotation": r, "scale": [su, sv]}


_WRAP = {"repeat": 10497, "clamp": 33071, "mirror": 33648}
_FILTER = {"linear": 9729, "nearest": 9728}
_POINTS, _LINES, _TRIANGLES = 0, 1, 4


def unit_normals(normals: np.ndarray) -> np.ndarray:
    """float32 normals of length 1 within glTF's tolerance (zero ones become +z): the validator checks them."""
    n = np.asarray(normals, np.float64)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where(length > 1e-12, n / np.maximum(length, 1e-300), np.array([0.0, 0.0, 1.0]))
    return n.astype(np.float32)


def _column_major(m: np.ndarray) -> list[float]:
    return [float(v) for v in np.asarray(m, np.float64).T.reshape(-1)]


def _is_identity(m: np.ndarray) -> bool:
    return bool(np.allclose(m, np.eye(4), atol=1e-12))


def _transformed(shape: Any, matrix: np.ndarray) -> Any:
    """A triangle, line or point set with ``matrix`` applied to its vertices (and normals)."""
    if isinstance(shape, TriangleSet):
        return shape.transformed(matrix)
    return type(shape)(**{**shape.parameters(), "vertices": transform_points(matrix, shape.vertex_array())})


def _area_light_record(light: Any, world: np.ndarray) -> tuple[np.ndarray, dict[str, Any]]:
    """(node matrix, extras record) of an area light: the node's x along the width, y along the height, -z lit."""
    centre, hu, hv, normal = light.world_frame(world)
    lu, lv = float(np.linalg.norm(hu)), float(np.linalg.norm(hv))
    x, y, z = hu / lu, hv / lv, -normal
    if float(np.dot(np.cross(x, y), z)) < 0.0:
        x = -x  # a right-handed frame for a mirrored light (the shape is symmetric)
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = x, y, z, centre
    record: dict[str, Any] = {
        "shape": "disc" if isinstance(light, DiscLight) else "rect",
        "two_sided": bool(light.two_sided),
        "casts_shadows": bool(light.casts_shadows),
        "radiance": float(light.intensity),
    }
    if isinstance(light, DiscLight):
        record["radius"] = math.sqrt(lu * lv)
    else:
        record["width"], record["height"] = 2.0 * lu, 2.0 * lv
    return matrix, record


def _frame_looking(direction: np.ndarray, position: np.ndarray) -> np.ndarray:
    """A node matrix whose -z axis points along ``direction`` (glTF lights and cameras look down -z)."""
    z = -np.asarray(direction, np.float64)
    z /= np.linalg.norm(z)
    up = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.99 else np.array([1.0, 0.0, 0.0])
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, y, z, position
    return m


class GLTFEngine(NodeTrackingEngine):
    """Evaluates a scene into a glTF document (see the module docstring)."""

    service = "gltf.export"

    def __init__(self, size: tuple[int, int] = (640, 480), **options: Any) -> None:
        super().__init__(**options)
        self.size = (int(size[0]), int(size[1]))
        if min(self.size) <= 0:
            raise ValueError(f"glTF export: size (camera aspect) must be positive (width, height), got {size!r}")
        self.gltf = GLBBuilder()
        self.roots: list[int] = []
        self._stack: list[tuple[int, np.ndarray]] = []
        self._materials: dict[tuple, int] = {}
        self._textures: dict[tuple, int] = {}
        self._lights: list[tuple[Any, np.ndarray]] = []
        self.triangle_count = 0
        self._origin: str | None = None
        #: while an instance set's shape is evaluated: where its primitives go (no nodes are written)
        self._capture: Capture | None = None
        #: The scene's first ``om.Background`` (glTF has none; the HTML page uses it), or None.
        self.background: Any = None
        #: lights in physical units (glTF's); False keeps omnirender's (the web page converts them itself)
        self.physical_lights = True
        #: instance sets through EXT_mesh_gpu_instancing; False writes one node per instance
        self.instancing = True

    def eval(self, shape: Any) -> None:
        """Evaluate ``shape``, remembering the class of the outermost shape for the mesh names."""
        if self._origin is not None:
            super().eval(shape)
            return
        self._origin = type(shape).__name__
        try:
            super().eval(shape)
        finally:
            self._origin = None

    # -- structure ------------------------------------------------------------
    def _attach(self, index: int) -> None:
        if self._stack:
            parent = self.gltf.doc["nodes"][self._stack[-1][0]]
            parent.setdefault("children", []).append(index)
        else:
            self.roots.append(index)

    def _parent_world(self) -> np.ndarray:
        """The world matrix of the enclosing glTF node as written (a matrix it cannot hold is not written)."""
        return self._stack[-1][1] if self._stack else np.eye(4)

    def local_matrix(self) -> np.ndarray:
        """The model matrix relative to the enclosing glTF node."""
        return np.linalg.solve(self._parent_world(), self.model_matrix())

    def enter_node(self, node: Any, world: np.ndarray) -> None:
        if self._capture is not None:
            return  # a node inside an instance set's shape: its primitives are baked into the set's frame
        entry: dict[str, Any] = {"name": node.name}
        parent_world = self._parent_world()
        local = np.linalg.solve(parent_world, world)
        written = np.array(world)
        if not _is_identity(local):
            if decomposable(local):
                entry["matrix"] = _column_major(local)
            else:  # sheared: the meshes below carry it in their vertices (see placed)
                written = parent_world
        index = self.gltf.append("nodes", entry)
        self._attach(index)
        self._stack.append((index, written))

    def leave_node(self, node: Any) -> None:
        if self._capture is None:
            self._stack.pop()

    def add_primitive(self, kind: str, primitive: dict[str, Any]) -> int:
        """Add a one-primitive mesh under a node placed by the current model matrix.

        Mesh and node are named after the shape the scene holds (``Torus``), not the
        triangle set it was simplified to.
        """
        if self._capture is not None:
            self._capture.add(primitive, self.surface())
            return -1
        kind = self._origin or kind
        mesh = self.gltf.append("meshes", {"name": kind, "primitives": [primitive]})
        return self.mesh_node(kind, mesh)

    def mesh_node(self, name: str, mesh: int, extensions: dict[str, Any] | None = None) -> int:
        """A node showing ``mesh``, placed by the current model matrix (relative to the enclosing node).

        A matrix a node cannot hold (:func:`holds`) is left out: the exporter
        wrote the mesh's vertices through :meth:`placed`, which applied it.
        """
        entry: dict[str, Any] = {"name": name, "mesh": mesh}
        local = self.local_matrix()
        if not _is_identity(local) and decomposable(local):
            entry["matrix"] = _column_major(local)
        if extensions:
            entry["extensions"] = extensions
        index = self.gltf.append("nodes", entry)
        self._attach(index)
        return index

    # -- instance sets ------------------------------------------------------------
    def capture(self, shape: Any, color: Any = None) -> Capture:
        """Evaluate ``shape`` (with ``color`` pushed) collecting its primitives in the current frame."""
        capture = self._capture = Capture(self.model_matrix(), color)
        if color is not None:
            self.push(color)
        try:
            self.eval(shape)
        finally:
            if color is not None:
                self.pop(color.category)
            self._capture = None
        return capture

    def placed(self, shape: Any) -> Any:
        """``shape`` (a triangle, line or point set) as its mesh is written: exporters call it before writing.

        Inside an instance set's shape, in the set's frame (the transforms met
        inside the shape applied to the vertices); elsewhere with a local
        matrix its node cannot hold (sheared) applied, else ``shape`` itself.
        """
        if self._capture is not None:
            matrix = self._capture.relative(self.model_matrix())
        else:
            matrix = self.local_matrix()
            if decomposable(matrix):
                return shape
        return shape if _is_identity(matrix) else _transformed(shape, matrix)

    def checkpoint(self) -> tuple[Any, ...]:
        """The document's state, to abandon what an attempt wrote with :meth:`rollback`."""
        return self.gltf.checkpoint(), self.triangle_count

    def rollback(self, mark: tuple[Any, ...]) -> None:
        document, self.triangle_count = mark
        self.gltf.rollback(document)
        for cache, key in ((self._materials, "materials"), (self._textures, "textures")):
            count = len(self.gltf.doc.get(key, ()))
            for stale in [k for k, index in cache.items() if index >= count]:
                del cache[stale]

    def vertex_attributes(self, shape: Any) -> dict[str, int]:
        """POSITION (with bounds) and COLOR_0 (linear) accessors of a shape with vertices."""
        attrs = {"POSITION": self.gltf.accessor(shape.vertex_array().astype(np.float32), ARRAY_BUFFER, bounds=True)}
        colors = shape.color_array()
        if colors is not None:
            linear = np.asarray(colors, np.float64).copy()
            linear[:, :3] = srgb_to_linear(linear[:, :3])
            attrs["COLOR_0"] = self.gltf.accessor(linear.astype(np.float32), ARRAY_BUFFER)
        return attrs

    # -- materials ------------------------------------------------------------
    def material_index(self, textured: bool = True, vertex_colors: bool = False) -> int:
        """The glTF material of the active appearance (the one appearance model), shared when identical.

        Every slot is written (base colour with its layers baked, metallic-
        roughness, normal or the normal map of a ``BumpMap``, occlusion,
        emissive), with ``KHR_texture_transform`` and the UV set; alpha mode,
        cutoff and double-sidedness; emission above 1 through
        ``KHR_materials_emissive_strength``.  Phong materials become the
        nearest metallic-roughness material (roughness from the shininess),
        their specular colour (linear) and shininess kept in the material's
        ``extras`` (``{"omnirender": {"phong": ...}}``: the web page draws them).
        Per-vertex colours replace a Phong colour (glTF multiplies: the factor
        is then white).
        """
        mono = self.mono
        layers = mono(MultiTexture) if textured else None
        bump = mono(BumpMap) if textured else None
        tex = mono(Texture) if textured else None
        key = (appearance_key(self.surface_stack, tex, layers, bump), textured, vertex_colors)
        found = self._materials.get(key)
        if found is not None:
            return found
        app = engine_appearance(self, texcoords=textured)
        base = np.asarray(app.base, np.float64)
        if vertex_colors and app.vertex_colors == "replace":
            base = np.ones(3)
        if app.model == "pbr":
            metallic, roughness, name = app.metallic, app.roughness, "PBRMaterial"
        else:
            shiny = float(np.mean(app.specular)) > 0.0
            metallic, roughness = 0.0, phong_roughness(app.shininess) if shiny else 1.0
            name = "Material" if isinstance(app.material, Material) else "Color"
        alpha = app.alpha if app.alpha_mode != "opaque" else 1.0
        pbr_block: dict[str, Any] = {
            "baseColorFactor": [*(float(v) for v in base), float(alpha)],
            "metallicFactor": float(metallic),
            "roughnessFactor": float(roughness),
        }
        material: dict[str, Any] = {"name": name, "pbrMetallicRoughness": pbr_block, "doubleSided": app.double_sided}
        if app.model == "phong" and float(np.max(app.specular)) > 0.0:
            # the Phong parameters themselves, for readers that draw Phong as GL does (the web page)
            phong = {"specular": [float(c) for c in app.specular], "shininess": float(app.shininess)}
            material["extras"] = {"omnirender": {"phong": phong}}
        if app.texture is not None or app.layers:
            if app.layers:
                image = bake_layers(None if app.texture is None else app.texture.image_array(), app.layers)
                baked = Texture(image, wrap="repeat")
                pbr_block["baseColorTexture"] = self.texture_info(baked)
            else:
                pbr_block["baseColorTexture"] = self.texture_info(app.texture)
        if app.metallic_roughness_texture is not None:
            pbr_block["metallicRoughnessTexture"] = self.texture_info(app.metallic_roughness_texture)
        normal, scale = app.normal_map()
        if normal is not None:
            material["normalTexture"] = {**self.texture_info(normal), "scale": float(scale)}
        if app.occlusion_texture is not None:
            info = self.texture_info(app.occlusion_texture)
            material["occlusionTexture"] = {**info, "strength": float(app.occlusion_strength)}
        emission = np.asarray(app.emission, np.float64)
        if app.emits:
            peak = float(emission.max())
            if peak > 1.0:
                self.gltf.use_extension(EMISSIVE_STRENGTH)
                material["extensions"] = {EMISSIVE_STRENGTH: {"emissiveStrength": peak}}
                emission = emission / peak
            material["emissiveFactor"] = [float(v) for v in emission]
            if app.emissive_texture is not None:
                material["emissiveTexture"] = self.texture_info(app.emissive_texture)
        if app.alpha_mode == "mask":
            material["alphaMode"] = "MASK"
            material["alphaCutoff"] = float(app.alpha_cutoff)
        elif app.alpha_mode == "blend":
            material["alphaMode"] = "BLEND"
        index = self._materials[key] = self.gltf.append("materials", material)
        return index

    def texture_info(self, tex: Texture) -> dict[str, Any]:
        """A glTF ``textureInfo``: the texture, its UV set and its ``KHR_texture_transform``."""
        info: dict[str, Any] = {"index": self.texture_index(tex)}
        if tex.uv_set:
            info["texCoord"] = int(tex.uv_set)
        if tex.transformed:
            self.gltf.use_extension(TRANSFORM_EXTENSION)
            info["extensions"] = {TRANSFORM_EXTENSION: _gltf_transform(tex)}
        return info

    def texture_index(self, tex: Texture) -> int:
        key = version_key(tex)
        found = self._textures.get(key)
        if found is not None:
            return found
        try:
            from PIL import Image as PILImage
        except ImportError:  # pragma: no cover - Pillow comes with the gl extra
            raise RuntimeError("glTF export of textures needs Pillow: pip install pillow") from None
        try:
            rgba = tex.image_array()
        except (FileNotFoundError, ValueError) as exc:
            raise type(exc)(
                f"glTF export: {exc} (Texture in node {self.node_path or '/'}); "
                "check the path or pass an array (om.Texture(numpy_array))"
            ) from None
        buf = io.BytesIO()
        PILImage.fromarray(np.asarray(rgba), "RGBA").save(buf, format="PNG")
        view = self.gltf.buffer_view(buf.getvalue())
        image = self.gltf.append("images", {"bufferView": view, "mimeType": "image/png"})
        wrap = _WRAP[tex.wrap]
        linear = tex.filter == "linear"
        sampler = self.gltf.append(
            "samplers",
            {
                "magFilter": _FILTER[tex.filter],
                "minFilter": (9987 if tex.mipmap else 9729) if linear else (9984 if tex.mipmap else 9728),
                "wrapS": wrap,
                "wrapT": wrap,
            },
        )
        index = self._textures[key] = self.gltf.append("textures", {"source": image, "sampler": sampler})
        return index

    # -- lights and camera ------------------------------------------------------
    def add_light(self, light: Any) -> None:
        """Queue a light with its world matrix (written as a KHR_lights_punctual node at the end)."""
        for other, m in self.lights():
            if other is light:
                self._lights.append((light, np.array(m)))
                return
        self._lights.append((light, self.model_matrix()))

    def reference_point(self) -> np.ndarray:
        """Where GL's light attenuation is matched by the inverse square: the camera's centre of interest."""
        if self.camera is None:
            return np.zeros(3)
        camera, world = self.camera
        return (np.asarray(world, np.float64) @ np.array([*camera.center, 1.0]))[:3]

    def _write_lights(self) -> None:
        ambient = [0.0, 0.0, 0.0]
        lights: list[dict[str, Any]] = []
        for light, world in self._lights:
            color = [float(c) for c in srgb_to_linear(light.color)]  # glTF colours are linear
            if isinstance(light, AmbientLight):
                ambient = [a + float(b) for a, b in zip(ambient, light.ambient, strict=True)]
                continue
            # physical units: lux (E = pi c) and candela (I = pi c att(d) d^2, matched at the camera's centre
            # of interest), so physically based importers (three.js, Blender) show GL's brightness
            if not self.physical_lights:
                physical = 1.0
            elif isinstance(light, DirectionalLight):
                physical = math.pi
            elif isinstance(light, AreaLight):
                physical = light.world_area(world)  # on-axis intensity L A (cd) of a Lambertian emitter
            else:
                physical = intensity_scale(light, light.world_position(world), self.reference_point())
            entry: dict[str, Any] = {
                "name": type(light).__name__,
                "color": color,
                "intensity": float(light.intensity) * physical,
            }
            if isinstance(light, AreaLight):
                # KHR_lights_punctual has no area lights: the closest punctual light is the emitter's far
                # field, a spot of intensity L A whose cos lobe is half as bright at 60 degrees, out to 90; the
                # area light itself is kept in the extras, which load_gltf and the HTML page read
                entry["type"] = "spot"
                entry["spot"] = {"innerConeAngle": math.radians(60.0), "outerConeAngle": math.pi / 2}
                matrix, record = _area_light_record(light, world)
                entry["extras"] = {"omnirender": {"area_light": record}}
            elif isinstance(light, DirectionalLight):
                entry["type"] = "directional"
                matrix = _frame_looking(light.world_direction(world), np.zeros(3))
            elif isinstance(light, (PointLight, SpotLight)):
                position = light.world_position(world)
                if isinstance(light, SpotLight):
                    outer = math.radians(light.cutoff)
                    inner = outer if light.exponent <= 0 else min(outer, math.acos(0.5 ** (1.0 / light.exponent)))
                    entry["type"] = "spot"
                    entry["spot"] = {"innerConeAngle": float(min(inner, outer * 0.999)), "outerConeAngle": outer}
                    matrix = _frame_looking(light.world_direction(world), position)
                else:
                    entry["type"] = "point"
                    matrix = np.eye(4)
                    matrix[:3, 3] = position
                # glTF lights fall off with the inverse square; keep omnirender's OpenGL attenuation for
                # importers that can use it (the HTML page does)
                entry["extras"] = {"omnirender": {"attenuation": [light.constant, light.linear, light.quadratic]}}
            else:
                continue
            index = len(lights)
            lights.append(entry)
            node = {
                "name": entry["name"],
                "matrix": _column_major(matrix),
                "extensions": {LIGHTS_EXTENSION: {"light": index}},
            }
            self.roots.append(self.gltf.append("nodes", node))
        if lights:
            self.gltf.use_extension(LIGHTS_EXTENSION)
            self.gltf.doc.setdefault("extensions", {})[LIGHTS_EXTENSION] = {"lights": lights}
        if any(ambient):
            # glTF has no ambient light; keep it for importers that want it.
            self.gltf.doc.setdefault("extras", {})["ambient_light"] = ambient

    def _write_camera(self) -> None:
        if self.camera is None:
            return
        camera, world = self.camera
        w, h = self.size
        if camera.is_off_axis:
            warnings.warn(
                f"glTF export: the camera's off-axis shift {camera.shift} is dropped (glTF cameras are symmetric "
                "frusta); the exported camera looks along the same axis with the same field of view",
                stacklevel=3,
            )
        if camera.is_orthographic:
            cam: dict[str, Any] = {
                "type": "orthographic",
                "orthographic": {
                    "xmag": camera.height * w / h / 2.0,
                    "ymag": camera.height / 2.0,
                    "znear": camera.near,
                    "zfar": camera.far,
                },
            }
        else:
            cam = {
                "type": "perspective",
                "perspective": {
                    "yfov": math.radians(camera.fov),
                    "aspectRatio": w / h,
                    "znear": camera.near,
                    "zfar": camera.far,
                },
            }
        index = self.gltf.append("cameras", cam)
        eye_to_world = np.asarray(world, np.float64) @ np.linalg.inv(camera.view_matrix())
        self.roots.append(
            self.gltf.append("nodes", {"name": "camera", "camera": index, "matrix": _column_major(eye_to_world)})
        )

    def finish(self, name: str = "scene") -> bytes:
        """Write camera, lights and the scene list; return the GLB bytes."""
        self._write_camera()
        self._write_lights()
        self.gltf.doc["scenes"] = [{"name": name, "nodes": list(self.roots)}]
        self.gltf.doc["scene"] = 0
        return self.gltf.to_bytes()


track_surfaces(GLTFEngine)


@default_for(GLTFEngine)
class TriangleSetExporter(ShapePainter):
    """``TriangleSet`` -> a TRIANGLES primitive with normals, texture coordinates and colours."""

    __slots__ = ()
    service = GLTFEngine.service
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: GLTFEngine) -> None:
        if len(shape.index_array()) == 0:
            return
        shape = engine.placed(shape)
        faces = shape.index_array()
        g = engine.gltf
        attrs = engine.vertex_attributes(shape)
        attrs["NORMAL"] = g.accessor(unit_normals(shape.normal_array()), ARRAY_BUFFER)
        uv = shape.texcoord_array()
        for index, coords in enumerate((uv, shape.texcoord_array(1) if uv is not None else None)):
            if coords is not None:
                flipped = np.array(coords, np.float32)
                flipped[:, 1] = 1.0 - flipped[:, 1]
                attrs[f"TEXCOORD_{index}"] = g.accessor(flipped, ARRAY_BUFFER)
        indices = g.accessor(faces.astype(np.uint32).reshape(-1), ELEMENT_ARRAY_BUFFER)
        primitive = {
            "attributes": attrs,
            "indices": indices,
            "mode": _TRIANGLES,
            "material": engine.material_index(uv is not None, vertex_colors=shape.color_array() is not None),
        }
        engine.add_primitive("TriangleSet", primitive)
        engine.triangle_count += len(faces)


@default_for(GLTFEngine)
class LineSetExporter(ShapePainter):
    """``LineSet`` -> a LINES primitive."""

    __slots__ = ()
    service = GLTFEngine.service
    target = LineSet

    def exec(self, shape: LineSet, engine: GLTFEngine) -> None:
        segments = shape.index_array()
        if len(segments) == 0:
            return
        shape = engine.placed(shape)
        indices = engine.gltf.accessor(segments.astype(np.uint32).reshape(-1), ELEMENT_ARRAY_BUFFER)
        primitive = {
            "attributes": engine.vertex_attributes(shape),
            "indices": indices,
            "mode": _LINES,
            "material": engine.material_index(False),
        }
        engine.add_primitive("LineSet", primitive)


@default_for(GLTFEngine)
class PointSetExporter(ShapePainter):
    """``PointSet`` -> a POINTS primitive."""

    __slots__ = ()
    service = GLTFEngine.service
    target = PointSet

    def exec(self, shape: PointSet, engine: GLTFEngine) -> None:
        if len(shape.vertex_array()) == 0:
            return
        shape = engine.placed(shape)
        primitive = {
            "attributes": engine.vertex_attributes(shape),
            "mode": _POINTS,
            "material": engine.material_index(False),
        }
        engine.add_primitive("PointSet", primitive)


@default_for(GLTFEngine)
class InstanceSetExporter(ShapePainter):
    """``InstanceSet`` -> its shape's mesh once, instanced with ``EXT_mesh_gpu_instancing`` (see
    :mod:`.gltf_instancing`); one node per instance (with a warning saying why) where that cannot hold it."""

    __slots__ = ()
    service = GLTFEngine.service
    target = InstanceSet

    def exec(self, shape: InstanceSet, engine: GLTFEngine) -> None:
        if engine._capture is not None:  # inside another instance set's shape: that one falls back
            engine._capture.fail("its shape holds another instance set")
            return
        if not engine.instancing:
            engine.simplify(shape)
            return
        problem = write_instance_set(engine, shape)
        if problem is None:
            return
        warnings.warn(
            f"glTF export: the InstanceSet in node {engine.node_path or '/'} is written as one node per instance: "
            f"{problem}",
            stacklevel=2,
        )
        engine.simplify(shape)


@default_for(GLTFEngine)
class LightExporter(AttributePainter):
    """Lights -> queued for ``KHR_lights_punctual`` (ambient goes to ``extras``)."""

    __slots__ = ()
    service = GLTFEngine.service
    target = LightSource

    def exec(self, light: LightSource, engine: GLTFEngine) -> None:
        engine.add_light(light)


@default_for(GLTFEngine)
class BackgroundRecorder(AttributePainter):
    """``Background`` -> remembered as ``engine.background`` (the scene's, see ``is_scene_background``)."""

    __slots__ = ()
    service = GLTFEngine.service
    target = Background

    def exec(self, background: Background, engine: GLTFEngine) -> None:
        if engine.background is None and is_scene_background(background, engine):
            engine.background = background


def build(
    scene: Any,
    *,
    size: tuple[int, int] = (640, 480),
    on_missing: str = "raise",
    mask: str | None = None,
    physical_lights: bool = True,
    instancing: bool = True,
) -> tuple[bytes, GLTFEngine]:
    """The GLB bytes of ``scene`` and the engine that wrote them (its camera, lights and background)."""
    if not isinstance(scene, Node):
        scene = Node("scene", scene)
    engine = GLTFEngine(size, on_missing=on_missing, mask=mask)
    engine.physical_lights = physical_lights
    engine.instancing = instancing
    engine.run(scene)
    return engine.finish(scene.name), engine


def to_bytes(
    scene: Any,
    *,
    size: tuple[int, int] = (640, 480),
    on_missing: str = "raise",
    mask: str | None = None,
    instancing: bool = True,
) -> bytes:
    """The GLB file of ``scene`` as bytes (``size`` gives the camera's aspect ratio).

    ``on_missing``: what a shape without a handler does — ``"raise"`` (the
    default, as in every engine: an export must not silently lose geometry),
    ``"warn"`` or ``"skip"``.  ``instancing=False`` writes every ``InstanceSet``
    as one node per instance, for viewers without ``EXT_mesh_gpu_instancing``.
    """
    return build(scene, size=size, on_missing=on_missing, mask=mask, instancing=instancing)[0]


def export(scene: Any, path: str | os.PathLike[str], **options: Any) -> None:
    """Write ``scene`` as glTF 2.0 binary to ``path`` atomically (options: see :func:`to_bytes`)."""
    data = to_bytes(scene, **options)
    with atomic_write(path, "wb") as fh:
        fh.write(data)


from . import splats as _splats  # noqa: E402,F401  (registers the KHR_gaussian_splatting exporter)
