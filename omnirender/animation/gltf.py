"""``om.load_gltf``: a glTF 2.0 file as a scene graph whose node animations are tracks.

``om.MeshFile`` reads a glTF file as one static mesh (trimesh flattens the
node hierarchy).  To play a file's animations the hierarchy must stay: here
every glTF node becomes an ``om.Node`` carrying its transform as
``Translation`` / ``Rotation`` / ``Scaling`` (or a ``Matrix``), its meshes as
triangle, line and point sets with their materials and textures, its camera
(``om.Camera``) and its ``KHR_lights_punctual`` light; each animation channel
on a node's translation, rotation or scale becomes a :class:`Keyframes` track
on the matching component (STEP, LINEAR with quaternion slerp, CUBICSPLINE
with the file's tangents), collected in an ``om.Animation`` in the root node.

Not imported (a warning says so): skins (meshes stay in their bind pose),
morph targets and their ``weights`` channels, sparse accessors, and
extensions other than the punctual lights.  Colours are converted from glTF's
linear values to the display values omnirender's attributes hold; texture
coordinates get omnirender's convention (v = 0 at the image's bottom row).
"""

from __future__ import annotations

import base64
import io
import json
import math
import os
import struct
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..attributes import DirectionalLight, PBRMaterial, PointLight, SpotLight, Texture
from ..core.camera import Camera
from ..core.transform import Matrix, Rotation, Scaling, Translation
from ..scene.node import Node
from ..shapes import LineSet, PointSet, TriangleSet
from .animation import Animation
from .tracks import Keyframes

__all__ = ["load_gltf", "GLTFImportError"]

_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_INTERPOLATION = {"STEP": "step", "LINEAR": "linear", "CUBICSPLINE": "cubic"}
_WRAP = {10497: "repeat", 33071: "clamp", 33648: "mirror"}
_GLB_MAGIC, _JSON_CHUNK, _BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942


class GLTFImportError(ValueError):
    """A malformed or unsupported glTF file (the message names the file and the element)."""


def _linear_to_srgb(c: Any) -> tuple[float, ...]:
    c = np.clip(np.asarray(c, np.float64), 0.0, 1.0)
    out = np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return tuple(float(x) for x in np.clip(out, 0.0, 1.0))


class _Reader:
    def __init__(self, path: Path) -> None:
        self.path = path
        data = path.read_bytes()
        self.bin: bytes | None = None
        if data[:4] == struct.pack("<I", _GLB_MAGIC):
            self.doc = self._glb(data)
        else:
            try:
                self.doc = json.loads(data.decode("utf-8"))
            except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                raise self.error(f"neither a GLB file nor glTF JSON ({exc})") from None
        if not isinstance(self.doc, dict) or str(self.doc.get("asset", {}).get("version", "")).split(".")[0] != "2":
            raise self.error("not a glTF 2.0 document (asset.version must be 2.x)")
        self.buffers: dict[int, bytes] = {}
        self.textures: dict[int, Texture] = {}
        self.materials: dict[int, list[Any]] = {}
        self.primitives: dict[tuple[int, int], Node | None] = {}
        #: glTF node index -> its Translation / Rotation / Scaling components by channel path
        self.targets: dict[int, dict[str, Any]] = {}

    def error(self, message: str) -> GLTFImportError:
        return GLTFImportError(f"load_gltf {str(self.path)!r}: {message}")

    def _glb(self, data: bytes) -> dict[str, Any]:
        if len(data) < 20:
            raise self.error("truncated GLB header")
        _, version, length = struct.unpack_from("<III", data, 0)
        if version != 2 or length > len(data):
            raise self.error(f"unsupported or truncated GLB (version {version}, length {length} of {len(data)} bytes)")
        offset, doc = 12, None
        while offset + 8 <= length:
            size, kind = struct.unpack_from("<II", data, offset)
            chunk = data[offset + 8 : offset + 8 + size]
            if len(chunk) != size:
                raise self.error("truncated GLB chunk")
            if kind == _JSON_CHUNK and doc is None:
                doc = json.loads(chunk.decode("utf-8"))
            elif kind == _BIN_CHUNK and self.bin is None:
                self.bin = chunk
            offset += 8 + size + (-size % 4)
        if doc is None:
            raise self.error("the GLB has no JSON chunk")
        return doc

    def items(self, key: str) -> list[Any]:
        value = self.doc.get(key, [])
        if not isinstance(value, list):
            raise self.error(f"{key} must be a list")
        return value

    def item(self, key: str, index: Any) -> dict[str, Any]:
        items = self.items(key)
        if not isinstance(index, int) or not 0 <= index < len(items) or not isinstance(items[index], dict):
            raise self.error(f"{key}[{index!r}] does not exist")
        return items[index]

    # -- binary data ------------------------------------------------------------
    def buffer(self, index: int) -> bytes:
        found = self.buffers.get(index)
        if found is not None:
            return found
        buf = self.item("buffers", index)
        uri = buf.get("uri")
        if uri is None:
            if index != 0 or self.bin is None:
                raise self.error(f"buffers[{index}] has no uri and there is no GLB binary chunk")
            data = self.bin
        else:
            data = self._uri(uri, f"buffers[{index}]")
        if len(data) < int(buf.get("byteLength", 0)):
            raise self.error(f"buffers[{index}] holds {len(data)} bytes, fewer than its byteLength")
        self.buffers[index] = data
        return data

    def _uri(self, uri: str, where: str) -> bytes:
        if uri.startswith("data:"):
            header, _, payload = uri.partition(",")
            if not header.endswith(";base64"):
                raise self.error(f"{where}: only base64 data URIs are supported")
            return base64.b64decode(payload)
        from urllib.parse import unquote

        file = self.path.parent / unquote(uri)
        try:
            return file.read_bytes()
        except OSError as exc:
            raise self.error(f"{where}: cannot read {str(file)!r}: {exc}") from None

    def view(self, index: int) -> tuple[bytes, int, int | None]:
        view = self.item("bufferViews", index)
        data = self.buffer(view.get("buffer", 0))
        start, length = int(view.get("byteOffset", 0)), int(view.get("byteLength", 0))
        if start < 0 or start + length > len(data):
            raise self.error(f"bufferViews[{index}] lies outside its buffer")
        return data[start : start + length], length, view.get("byteStride")

    def accessor(self, index: int) -> np.ndarray:
        acc = self.item("accessors", index)
        where = f"accessors[{index}]"
        if "sparse" in acc:
            raise self.error(f"{where}: sparse accessors are not supported")
        dtype = _COMPONENTS.get(acc.get("componentType"))
        width = _WIDTH.get(acc.get("type"))
        count = acc.get("count")
        if dtype is None or width is None or not isinstance(count, int) or count < 0:
            raise self.error(f"{where}: bad componentType, type or count")
        item = np.dtype(dtype).itemsize * width
        if "bufferView" not in acc:
            return np.zeros((count, width), np.float32 if acc.get("normalized") else dtype)
        data, length, stride = self.view(acc["bufferView"])
        offset = int(acc.get("byteOffset", 0))
        stride = int(stride or item)
        if count and (offset < 0 or stride < item or offset + stride * (count - 1) + item > length):
            raise self.error(f"{where}: {count} elements do not fit in its buffer view")
        raw = np.frombuffer(data, np.uint8, count=stride * (count - 1) + item if count else 0, offset=offset)
        rows = np.lib.stride_tricks.as_strided(raw, (count, item), (stride, 1)) if count else raw.reshape(0, item)
        out = np.ascontiguousarray(rows).view(np.dtype(dtype).newbyteorder("<")).reshape(count, width)
        if acc.get("normalized") and np.dtype(dtype).kind in "iu":
            info = np.iinfo(dtype)
            out = np.maximum(out.astype(np.float64) / info.max, -1.0)
        return out

    # -- scene --------------------------------------------------------------------
    def texture(self, index: int) -> Texture | None:
        if index in self.textures:
            return self.textures[index]
        tex = self.item("textures", index)
        source = tex.get("source")
        if source is None:
            return None
        image = self.item("images", source)
        where = f"images[{source}]"
        if "bufferView" in image:
            data = self.view(image["bufferView"])[0]
        elif "uri" in image:
            data = self._uri(image["uri"], where)
        else:
            raise self.error(f"{where} has neither bufferView nor uri")
        from PIL import Image as PILImage

        try:
            with PILImage.open(io.BytesIO(data)) as img:
                pixels = np.asarray(img.convert("RGBA"), np.uint8)
        except OSError as exc:
            raise self.error(f"{where} is not a readable image: {exc}") from None
        sampler = self.item("samplers", tex["sampler"]) if "sampler" in tex else {}
        wrap = _WRAP.get(sampler.get("wrapS", 10497), "repeat")
        nearest = sampler.get("magFilter") == 9728
        result = self.textures[index] = Texture(pixels, wrap=wrap, filter="nearest" if nearest else "linear")
        return result

    def material(self, index: int | None, textured: bool) -> list[Any]:
        if index is None:
            return []
        key = index * 2 + int(textured)
        if key in self.materials:
            return self.materials[key]
        mat = self.item("materials", index)
        pbr = mat.get("pbrMetallicRoughness", {})
        base = list(pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0]))
        out: list[Any] = [
            PBRMaterial(
                base_color=_linear_to_srgb(base[:3]),
                metallic=float(pbr.get("metallicFactor", 1.0)),
                roughness=float(pbr.get("roughnessFactor", 1.0)),
                emission=_linear_to_srgb(mat.get("emissiveFactor", [0.0, 0.0, 0.0])),
                opacity=float(base[3]) if mat.get("alphaMode", "OPAQUE") != "OPAQUE" else 1.0,
            )
        ]
        info = pbr.get("baseColorTexture")
        if textured and isinstance(info, dict) and "index" in info:
            tex = self.texture(info["index"])
            if tex is not None:
                out.append(tex)
        self.materials[key] = out
        return out

    def primitive(self, prim: dict[str, Any], where: str) -> Node | None:
        attrs = prim.get("attributes", {})
        if "POSITION" not in attrs:
            return None
        if prim.get("targets"):
            warnings.warn(f"load_gltf {self.path.name}: {where} has morph targets; they are not imported", stacklevel=4)
        vertices = self.accessor(attrs["POSITION"]).astype(np.float32)
        mode = prim.get("mode", 4)
        indices = (
            self.accessor(prim["indices"]).reshape(-1).astype(np.int64)
            if "indices" in prim
            else np.arange(len(vertices))
        )
        if len(indices) and (indices.min() < 0 or indices.max() >= len(vertices)):
            raise self.error(f"{where}: an index is out of range")
        colors = None
        if "COLOR_0" in attrs:
            c = self.accessor(attrs["COLOR_0"]).astype(np.float64)
            rgb = np.array([_linear_to_srgb(row) for row in c[:, :3]]) if len(c) else c[:, :3]
            colors = rgb if c.shape[1] == 3 else np.concatenate([rgb, c[:, 3:4]], axis=1)
        uv = None
        if "TEXCOORD_0" in attrs:
            uv = self.accessor(attrs["TEXCOORD_0"]).astype(np.float32)
            uv[:, 1] = 1.0 - uv[:, 1]
        items = self.material(prim.get("material"), uv is not None and mode in (4, 5, 6))
        if mode in (4, 5, 6):
            faces = _triangles(indices, mode)
            if len(faces) == 0:
                return None
            normals = self.accessor(attrs["NORMAL"]).astype(np.float32) if "NORMAL" in attrs else None
            shape: Any = TriangleSet(vertices, faces, normals=normals, colors=colors, texcoords=uv)
        elif mode in (1, 2, 3):
            shape = LineSet(vertices, indices=_segments(indices, mode), colors=colors)
        elif mode == 0:
            shape = PointSet(vertices[indices], colors=None if colors is None else colors[indices])
        else:
            raise self.error(f"{where}: unknown primitive mode {mode}")
        return Node("primitive", [*items, shape])

    def node(self, index: int, names: dict[int, str], built: dict[int, Node], transforms: dict, active: set) -> Node:
        if index in active:
            raise self.error(f"nodes[{index}] is its own ancestor")
        if index in built:  # glTF nodes have one parent; a repeat reference is shared, as in a DAG
            return built[index]
        spec = self.item("nodes", index)
        active.add(index)
        node = Node(names[index])
        parts: dict[str, Any] = {}
        if "matrix" in spec:
            m = np.array(spec["matrix"], np.float64).reshape(4, 4).T  # column-major in the file
            node.add(Matrix(m))
        else:
            if "translation" in spec or index in transforms.get("translation", ()):
                parts["translation"] = node.add(Translation(spec.get("translation", (0.0, 0.0, 0.0))))
            if "rotation" in spec or index in transforms.get("rotation", ()):
                x, y, z, w = spec.get("rotation", (0.0, 0.0, 0.0, 1.0))
                parts["rotation"] = node.add(Rotation.from_quaternion(w, x, y, z))
            if "scale" in spec or index in transforms.get("scale", ()):
                parts["scale"] = node.add(Scaling(spec.get("scale", (1.0, 1.0, 1.0))))
        self.targets[index] = parts
        if "camera" in spec:
            node.add(self.camera(spec["camera"]))
        light = spec.get("extensions", {}).get("KHR_lights_punctual", {}).get("light")
        if light is not None:
            node.add(self.light(light))
        if "skin" in spec:
            warnings.warn(f"load_gltf {self.path.name}: skin of nodes[{index}] ignored (bind pose)", stacklevel=3)
        if "mesh" in spec:
            for child in self.mesh(spec["mesh"]):
                node.add(child)
        for child in spec.get("children", []):
            node.add(self.node(child, names, built, transforms, active))
        active.discard(index)
        built[index] = node
        return node

    def mesh(self, index: int) -> list[Node]:
        """One node per primitive (shared by every glTF node using the mesh)."""
        mesh = self.item("meshes", index)
        primitives = mesh.get("primitives", [])
        out = []
        for p, prim in enumerate(primitives):
            if (index, p) not in self.primitives:
                child = self.primitive(prim, f"meshes[{index}].primitives[{p}]")
                if child is not None:
                    name = _name(mesh.get("name"), "mesh")
                    child.name = f"{name}-{p}" if len(primitives) > 1 else name
                self.primitives[index, p] = child
            if self.primitives[index, p] is not None:
                out.append(self.primitives[index, p])
        return out

    def camera(self, index: int) -> Camera:
        cam = self.item("cameras", index)
        # the camera looks down its node's -z axis with +y up
        if cam.get("type") == "orthographic":
            o = cam.get("orthographic", {})
            return Camera.orthographic(
                eye=(0, 0, 0), center=(0, 0, -1), height=2.0 * float(o.get("ymag", 1.0)),
                near=float(o.get("znear", 0.1)), far=float(o.get("zfar", 1000.0)),
            )  # fmt: skip
        p = cam.get("perspective", {})
        return Camera.look_at(
            eye=(0, 0, 0), center=(0, 0, -1), fov=math.degrees(float(p.get("yfov", math.radians(35)))),
            near=float(p.get("znear", 0.1)), far=float(p.get("zfar") or 1000.0),
        )  # fmt: skip

    def light(self, index: int) -> Any:
        lights = self.doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
        if not isinstance(index, int) or not 0 <= index < len(lights):
            raise self.error(f"KHR_lights_punctual light {index!r} does not exist")
        spec = lights[index]
        color = _linear_to_srgb(spec.get("color", (1.0, 1.0, 1.0)))
        intensity = float(spec.get("intensity", 1.0))
        kind = spec.get("type")
        if kind == "directional":
            return DirectionalLight(direction=(0, 0, -1), color=color, intensity=intensity)
        if kind == "spot":
            outer = math.degrees(float(spec.get("spot", {}).get("outerConeAngle", math.pi / 4)))
            return SpotLight(position=(0, 0, 0), direction=(0, 0, -1), cutoff=outer, color=color, intensity=intensity)
        return PointLight(position=(0, 0, 0), color=color, intensity=intensity)

    def animation(self, index: int) -> Animation:
        spec = self.item("animations", index)
        samplers = spec.get("samplers", [])
        tracks = []
        for c, channel in enumerate(spec.get("channels", [])):
            target = channel.get("target", {})
            path, node = target.get("path"), target.get("node")
            where = f"animations[{index}].channels[{c}]"
            if path == "weights":
                warnings.warn(f"load_gltf {self.path.name}: {where} animates morph weights; skipped", stacklevel=3)
                continue
            component = self.targets.get(node, {}).get(path)
            if component is None:
                if node in self.targets:
                    raise self.error(f"{where}: nodes[{node}] has a matrix, which glTF forbids animating")
                continue  # a node outside the imported scene
            if not isinstance(channel.get("sampler"), int) or not 0 <= channel["sampler"] < len(samplers):
                raise self.error(f"{where}: bad sampler index")
            sampler = samplers[channel["sampler"]]
            mode = _INTERPOLATION.get(sampler.get("interpolation", "LINEAR"))
            if mode is None:
                raise self.error(f"{where}: unknown interpolation {sampler.get('interpolation')!r}")
            times = self.accessor(sampler["input"]).reshape(-1).astype(np.float64)
            values = self.accessor(sampler["output"]).astype(np.float64)
            tangents = None
            if mode == "cubic":  # (in-tangent, value, out-tangent) per key
                if len(values) != 3 * len(times):
                    raise self.error(f"{where}: a CUBICSPLINE sampler needs 3 outputs per key")
                tangents = (values[0::3], values[2::3])
                values = values[1::3]
            if path == "rotation":  # glTF (x, y, z, w) -> omnirender (w, x, y, z)
                values = values[:, [3, 0, 1, 2]]
                tangents = None if tangents is None else tuple(t[:, [3, 0, 1, 2]] for t in tangents)
            parameter = {"translation": "offset", "rotation": "quaternion", "scale": "factors"}[path]
            if path == "scale":  # omnirender's Scaling refuses 0 (a vanishing object): keep it tiny instead
                values = np.where(np.abs(values) < 1e-9, 1e-9, values)
            try:
                tracks.append(Keyframes(component, parameter, times, values, mode, tangents))
            except ValueError as exc:
                raise self.error(f"{where}: {exc}") from None
        return Animation(tracks)


def _name(value: Any, default: str) -> str:
    text = str(value) if isinstance(value, str) and value.strip() else default
    return text.replace("/", "_")


def _triangles(indices: np.ndarray, mode: int) -> np.ndarray:
    if mode == 4:
        return indices[: len(indices) // 3 * 3].reshape(-1, 3)
    if len(indices) < 3:
        return np.zeros((0, 3), np.int64)
    k = np.arange(len(indices) - 2)
    if mode == 5:  # strip: every other triangle flipped to keep the winding
        a, b = np.where(k % 2 == 0, indices[k], indices[k + 1]), np.where(k % 2 == 0, indices[k + 1], indices[k])
        return np.stack([a, b, indices[k + 2]], axis=1)
    return np.stack([np.full_like(k, indices[0]), indices[k + 1], indices[k + 2]], axis=1)  # fan


def _segments(indices: np.ndarray, mode: int) -> np.ndarray:
    if mode == 1:
        return indices[: len(indices) // 2 * 2].reshape(-1, 2)
    pairs = np.stack([indices[:-1], indices[1:]], axis=1)
    if mode == 2 and len(indices) > 2:  # loop
        pairs = np.concatenate([pairs, [[indices[-1], indices[0]]]])
    return pairs


def load_gltf(path: str | os.PathLike[str], animation: int | str | None = 0) -> Node:
    """The scene of a glTF 2.0 file (``.glb`` or ``.gltf``) as an ``om.Node``, with its animation as tracks.

    ``animation`` picks the clip (glTF files may hold several): an index, a
    name, ``"all"`` (every clip at once) or None (none).  See the module docs
    for what is imported.
    """
    source = Path(path)
    if not source.is_file():
        raise FileNotFoundError(f"load_gltf: no such file {str(source)!r}")
    reader = _Reader(source)
    scenes = reader.items("scenes")
    scene_index = reader.doc.get("scene", 0)
    if scenes:
        spec = reader.item("scenes", scene_index)
        roots = spec.get("nodes", [])
        root = Node(_name(spec.get("name"), source.stem))
    else:  # no scene: every node that is nobody's child
        children = {c for n in reader.items("nodes") for c in n.get("children", [])}
        roots = [i for i in range(len(reader.items("nodes"))) if i not in children]
        root = Node(_name(None, source.stem))
    names = {}
    used: dict[str, int] = {}
    for i, spec in enumerate(reader.items("nodes")):
        base = _name(spec.get("name") if isinstance(spec, dict) else None, f"node{i}")
        used[base] = used.get(base, 0) + 1
        names[i] = base if used[base] == 1 else f"{base}-{used[base]}"
    transforms: dict[str, set[int]] = {"translation": set(), "rotation": set(), "scale": set()}
    for anim in reader.items("animations"):
        for channel in anim.get("channels", []) if isinstance(anim, dict) else []:
            target = channel.get("target", {}) if isinstance(channel, dict) else {}
            if target.get("path") in transforms and isinstance(target.get("node"), int):
                transforms[target["path"]].add(target["node"])
    built: dict[int, Node] = {}
    for index in roots:
        root.add(reader.node(index, names, built, transforms, set()))
    clips = reader.items("animations")
    chosen: list[int] = []
    if animation == "all":
        chosen = list(range(len(clips)))
    elif isinstance(animation, str):
        chosen = [i for i, clip in enumerate(clips) if clip.get("name") == animation]
        if not chosen:
            known = [clip.get("name") for clip in clips]
            raise GLTFImportError(f"load_gltf {str(source)!r}: no animation named {animation!r} (animations: {known})")
    elif isinstance(animation, int) and not isinstance(animation, bool):
        if clips and not 0 <= animation < len(clips):
            raise GLTFImportError(f"load_gltf {str(source)!r}: no animation {animation} ({len(clips)} animations)")
        chosen = [animation] if clips else []
    elif animation is not None:
        raise TypeError(f"load_gltf: animation must be an index, a name, 'all' or None, got {animation!r}")
    for index in chosen:
        anim = reader.animation(index)
        if anim.tracks:
            root.add(anim)
    return root
