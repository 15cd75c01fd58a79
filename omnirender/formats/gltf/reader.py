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

Materials keep everything the metallic-roughness model has: base colour,
metallic-roughness, normal (with its scale), occlusion (with its strength) and
emissive textures, each with its texture coordinate set (``TEXCOORD_0``/``_1``)
and ``KHR_texture_transform``; ``alphaMode``/``alphaCutoff``, ``doubleSided``
and ``KHR_materials_emissive_strength``.  A node with ``EXT_mesh_gpu_instancing``
becomes one ``om.InstanceSet`` per primitive (matrices composed from the
instances' translation, rotation and scale; the ``_COLOR_0`` instance colours
three.js reads, times the material's base colour, as its colours).  Vertex colours (``COLOR_0``) and
tangents are kept.  Sparse accessors, ``KHR_mesh_quantization`` and
``KHR_draco_mesh_compression`` (through DracoPy) are read.  Cameras become
``om.Camera``; ``KHR_lights_punctual`` lights become lights whose OpenGL
brightness is the physical one (:func:`light_from_gltf`).  An extension the
file *requires* that is not supported raises :class:`GLTFImportError` naming
it; an unsupported optional one warns once.

Glb and glTF files are untrusted input: buffer and image URIs are resolved by
the path policy (:mod:`omnirender.core.paths`; inside the file's folder or
``allowed_roots``, unless ``trusted=True``; ``http(s):`` never fetched),
decoded sizes obey :mod:`omnirender.core.limits` (image pixels, accessor
bytes, node nesting), and what cannot be used (a missing or remote image, a
decompression bomb, an unsupported extension) is dropped with a
:class:`~omnirender.core.drops.DroppedContentWarning` naming the file and
what was dropped, or raises with ``strict=True``.  A buffer that cannot be
read is an error (the geometry needs it).

Not imported (a warning says so): skins (meshes stay in their bind pose),
morph targets and their ``weights`` channels.  Colours are converted from
glTF's linear values to the display values omnirender's attributes hold;
texture coordinates get omnirender's convention (v = 0 at the image's bottom row).
"""

from __future__ import annotations

import base64
import json
import math
import os
import struct
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ...animation.animation import Animation
from ...animation.tracks import Keyframes
from ...attributes import DirectionalLight, DiscLight, PBRMaterial, PointLight, RectLight, SpotLight, Texture
from ...attributes.imagefile import read_image
from ...attributes.photometry import srgb_to_linear
from ...core.camera import Camera
from ...core.drops import DroppedContentError, report_drop
from ...core.limits import ResourceLimitError, check_bytes, check_count, check_nesting
from ...core.paths import PathPolicy, RemoteReferenceError, UntrustedReferenceError
from ...core.transform import Matrix, Rotation, Scaling, Translation
from ...geometry.trs import compose_trs
from ...scene.node import Node
from ...shapes import InstanceSet, LineSet, PointSet, TriangleSet

__all__ = ["load_gltf", "GLTFImportError", "flatten_gltf", "SUPPORTED_EXTENSIONS", "light_from_gltf"]

#: glTF extensions the importer reads.
SUPPORTED_EXTENSIONS = frozenset(
    {
        "KHR_lights_punctual",
        "KHR_texture_transform",
        "KHR_materials_emissive_strength",
        "KHR_mesh_quantization",
        "KHR_draco_mesh_compression",
        "EXT_mesh_gpu_instancing",
        "KHR_gaussian_splatting",
    }
)
_ALPHA_MODES = {"OPAQUE": "opaque", "MASK": "mask", "BLEND": "blend"}

_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_INTERPOLATION = {"STEP": "step", "LINEAR": "linear", "CUBICSPLINE": "cubic"}
_WRAP = {10497: "repeat", 33071: "clamp", 33648: "mirror"}
_GLB_MAGIC, _JSON_CHUNK, _BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942


class GLTFImportError(ValueError):
    """A malformed or unsupported glTF file (the message names the file and the element)."""


def _linear_to_srgb_array(c: Any) -> np.ndarray:
    """glTF's linear colour values (any shape) as the display values omnirender's colours hold."""
    c = np.clip(np.asarray(c, np.float64), 0.0, 1.0)
    return np.clip(np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055), 0.0, 1.0)


def _linear_to_srgb(c: Any) -> tuple[float, ...]:
    return tuple(float(x) for x in _linear_to_srgb_array(c).reshape(-1))


class _Reader:
    def __init__(self, path: Path, policy: PathPolicy | None = None, strict: bool = False) -> None:
        self.path = path
        self.policy = policy or PathPolicy()
        self.strict = strict
        data = path.read_bytes()
        self.bin: bytes | None = None
        if data[:4] == struct.pack("<I", _GLB_MAGIC):
            self.doc = self._glb(data)
        else:
            try:
                self.doc = json.loads(data.decode("utf-8"))
            except RecursionError:
                raise self.error("the JSON is nested too deeply") from None
            except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                raise self.error(f"neither a GLB file nor glTF JSON ({exc})") from None
        if not isinstance(self.doc, dict) or str(self.doc.get("asset", {}).get("version", "")).split(".")[0] != "2":
            raise self.error("not a glTF 2.0 document (asset.version must be 2.x)")
        self._check_extensions()
        self.buffers: dict[int, bytes] = {}
        self.textures: dict[Any, Texture] = {}
        self.images: dict[int, np.ndarray] = {}
        self.materials: dict[int, list[Any]] = {}
        self.primitives: dict[tuple[int, int], Node | None] = {}
        #: glTF node index -> its Translation / Rotation / Scaling components by channel path
        self.targets: dict[int, dict[str, Any]] = {}

    def error(self, message: str) -> GLTFImportError:
        return GLTFImportError(f"load_gltf {str(self.path)!r}: {message}")

    def drop(self, message: str) -> None:
        """Warn (or raise, when strict) that part of the file was left out: see :mod:`omnirender.core.drops`."""
        report_drop(f"load_gltf {str(self.path)!r}", message, strict=self.strict, stacklevel=5)

    def _check_extensions(self) -> None:
        required = [e for e in self.doc.get("extensionsRequired", []) if e not in SUPPORTED_EXTENSIONS]
        if required:
            raise self.error(
                f"the file requires the extension(s) {', '.join(map(str, required))}, which omnirender does not "
                f"support (supported: {', '.join(sorted(SUPPORTED_EXTENSIONS))}); convert the file without them"
            )
        unknown = [e for e in self.doc.get("extensionsUsed", []) if e not in SUPPORTED_EXTENSIONS]
        if unknown:
            self.drop(f"optional extension(s) {', '.join(map(str, unknown))} are not supported and were ignored")

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
                try:
                    doc = json.loads(chunk.decode("utf-8"))
                except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
                    raise self.error(f"the GLB's JSON chunk is not valid JSON ({type(exc).__name__})") from None
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
            try:
                data = self._uri(uri, f"buffers[{index}].uri")
            except RemoteReferenceError as exc:
                raise self.error(f"buffers[{index}] cannot be read: {exc.reason}") from None
            except FileNotFoundError as exc:
                raise self.error(f"buffers[{index}]: {exc}") from None
        if len(data) < int(buf.get("byteLength", 0)):
            raise self.error(f"buffers[{index}] holds {len(data)} bytes, fewer than its byteLength")
        self.buffers[index] = data
        return data

    def _uri(self, uri: Any, where: str) -> bytes:
        """The bytes a URI names: a base64 data URI, or a file resolved by the path policy.

        Raises UntrustedReferenceError (refused path), RemoteReferenceError (a
        URL), FileNotFoundError (no such file) or GLTFImportError.
        """
        if not isinstance(uri, str):
            raise self.error(f"{where} must be a string, got {type(uri).__name__}")
        if uri.startswith("data:"):
            header, _, payload = uri.partition(",")
            if not header.endswith(";base64"):
                raise self.error(f"{where}: only base64 data URIs are supported")
            try:
                return base64.b64decode(payload, validate=True)
            except ValueError:
                raise self.error(f"{where}: the data URI is not valid base64") from None
        file = self.policy.resolve(uri, self.path, where, uri=True)
        try:
            return file.read_bytes()
        except FileNotFoundError:
            raise FileNotFoundError(f"{where} {uri!r}: the file {str(file)!r} does not exist") from None
        except OSError as exc:
            raise self.error(f"{where}: cannot read {str(file)!r}: {exc.strerror or exc}") from None

    def view(self, index: int) -> tuple[bytes, int, int | None]:
        view = self.item("bufferViews", index)
        data = self.buffer(view.get("buffer", 0))
        start, length = int(view.get("byteOffset", 0)), int(view.get("byteLength", 0))
        if start < 0 or start + length > len(data):
            raise self.error(f"bufferViews[{index}] lies outside its buffer")
        return data[start : start + length], length, view.get("byteStride")

    def _elements(self, view: int, offset: int, dtype: Any, width: int, count: int, where: str) -> np.ndarray:
        """``count`` elements of ``width`` components from a buffer view (strided rows copied once)."""
        item = np.dtype(dtype).itemsize * width
        data, length, stride = self.view(view)
        stride = int(stride or item)
        if count and (offset < 0 or stride < item or offset + stride * (count - 1) + item > length):
            raise self.error(f"{where}: {count} elements do not fit in its buffer view")
        raw = np.frombuffer(data, np.uint8, count=stride * (count - 1) + item if count else 0, offset=offset)
        rows = np.lib.stride_tricks.as_strided(raw, (count, item), (stride, 1)) if count else raw.reshape(0, item)
        return np.ascontiguousarray(rows).view(np.dtype(dtype).newbyteorder("<")).reshape(count, width)

    def accessor(self, index: int) -> np.ndarray:
        acc = self.item("accessors", index)
        where = f"accessors[{index}]"
        dtype = _COMPONENTS.get(acc.get("componentType"))
        width = _WIDTH.get(acc.get("type"))
        count = acc.get("count")
        if dtype is None or width is None or not isinstance(count, int) or count < 0:
            raise self.error(f"{where}: bad componentType, type or count")
        try:
            check_bytes(f"load_gltf {str(self.path)!r}", where, count * width * np.dtype(dtype).itemsize)
            check_count(f"load_gltf {str(self.path)!r}", where, count, "indices")
        except ResourceLimitError as exc:
            raise self.error(str(exc).split(": ", 1)[1]) from None
        if "bufferView" in acc:
            out = self._elements(acc["bufferView"], int(acc.get("byteOffset", 0)), dtype, width, count, where)
        else:
            out = np.zeros((count, width), dtype)
        sparse = acc.get("sparse")
        if sparse is not None:  # replace the listed elements (a morph target's or an edited copy's few changes)
            n = int(sparse.get("count", 0))
            idx_spec, val_spec = sparse.get("indices", {}), sparse.get("values", {})
            idx_type = _COMPONENTS.get(idx_spec.get("componentType"))
            if idx_type is None or n < 0 or "bufferView" not in idx_spec or "bufferView" not in val_spec:
                raise self.error(f"{where}: malformed sparse accessor")
            rows = self._elements(
                idx_spec["bufferView"], int(idx_spec.get("byteOffset", 0)), idx_type, 1, n, where
            ).reshape(-1)
            if n and (rows.min() < 0 or rows.max() >= count):
                raise self.error(f"{where}: a sparse index is out of range 0..{count - 1}")
            values = self._elements(val_spec["bufferView"], int(val_spec.get("byteOffset", 0)), dtype, width, n, where)
            out = np.array(out)
            out[rows.astype(np.int64)] = values
        if acc.get("normalized") and np.dtype(dtype).kind in "iu":
            info = np.iinfo(dtype)
            out = np.maximum(out.astype(np.float64) / info.max, -1.0)
        return out

    # -- scene --------------------------------------------------------------------
    def image(self, source: int) -> np.ndarray | None:
        """The pixels of ``images[source]``, or None (with a drop warning) when they cannot be used."""
        if source in self.images:
            return self.images[source]
        image = self.item("images", source)
        where = f"images[{source}]"
        pixels: np.ndarray | None = None
        if "bufferView" in image:
            data: bytes | None = self.view(image["bufferView"])[0]
        elif "uri" in image:
            try:
                data = self._uri(image["uri"], f"{where}.uri")
            except (RemoteReferenceError, FileNotFoundError) as exc:
                reason = exc.reason if isinstance(exc, RemoteReferenceError) else str(exc)
                self.drop(f"{where} dropped (textures using it are left out): {reason}")
                data = None
        else:
            raise self.error(f"{where} has neither bufferView nor uri")
        if data is not None:
            try:
                pixels = read_image(data, f"load_gltf {str(self.path)!r}", where)
            except ValueError as exc:  # not an image, or beyond core.limits (a decompression bomb)
                self.drop(f"{where} dropped (textures using it are left out): {str(exc).split(': ', 1)[-1]}")
            else:
                pixels.setflags(write=False)
        self.images[source] = pixels
        return pixels

    def texture(self, index: int, info: dict[str, Any] | None = None) -> Texture | None:
        """The texture ``index`` as a slot's ``textureInfo`` uses it (its UV set and texture transform)."""
        info = info or {}
        transform = info.get("extensions", {}).get("KHR_texture_transform", {})
        uv_set = int(transform.get("texCoord", info.get("texCoord", 0)))
        key = (index, uv_set, json.dumps(transform, sort_keys=True))
        if key in self.textures:
            return self.textures[key]
        tex = self.item("textures", index)
        source = tex.get("source")
        if source is None:
            return None
        pixels = self.image(source)
        if pixels is None:
            self.textures[key] = None
            return None
        sampler = self.item("samplers", tex["sampler"]) if "sampler" in tex else {}
        wrap = _WRAP.get(sampler.get("wrapS", 10497), "repeat")
        nearest = sampler.get("magFilter") == 9728
        if uv_set > 1:
            self.drop(f"textures[{index}] uses TEXCOORD_{uv_set}, which is not supported; set 0 used instead")
            uv_set = 0
        offset, scale, rotation = _texture_transform(transform)
        result = self.textures[key] = Texture(
            pixels,
            wrap=wrap,
            filter="nearest" if nearest else "linear",
            uv_set=uv_set,
            offset=offset,
            scale=scale,
            rotation=rotation,
        )
        return result

    def _slot(self, info: Any, textured: bool, where: str = "a texture") -> Texture | None:
        if not isinstance(info, dict) or "index" not in info:
            return None
        if not textured:
            self.drop(f"{where} dropped: a primitive using the material has no TEXCOORD_0")
            return None
        return self.texture(info["index"], info)

    def material(self, index: int | None, textured: bool) -> list[Any]:
        if index is None:
            return []
        key = index * 2 + int(textured)
        if key in self.materials:
            return self.materials[key]
        mat = self.item("materials", index)
        at = f"materials[{index}]"
        pbr = mat.get("pbrMetallicRoughness", {})
        base = list(pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0]))
        extensions = mat.get("extensions", {})
        strength = float(extensions.get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0))
        emissive = [float(c) for c in mat.get("emissiveFactor", [0.0, 0.0, 0.0])]
        peak = max(emissive) if max(emissive) > 1.0 else 1.0  # factors above 1 are kept in the strength
        normal = mat.get("normalTexture")
        occlusion = mat.get("occlusionTexture")
        mode = _ALPHA_MODES.get(str(mat.get("alphaMode", "OPAQUE")))
        if mode is None:
            raise self.error(f"materials[{index}]: unknown alphaMode {mat.get('alphaMode')!r}")
        try:
            material = PBRMaterial(
                base_color=_linear_to_srgb(base[:3]),
                metallic=float(pbr.get("metallicFactor", 1.0)),
                roughness=float(pbr.get("roughnessFactor", 1.0)),
                emission=_linear_to_srgb([c / peak for c in emissive]),
                opacity=float(base[3]),
                base_color_texture=self._slot(pbr.get("baseColorTexture"), textured, f"{at}.baseColorTexture"),
                metallic_roughness_texture=self._slot(
                    pbr.get("metallicRoughnessTexture"), textured, f"{at}.metallicRoughnessTexture"
                ),
                normal_texture=self._slot(normal, textured, f"{at}.normalTexture"),
                normal_scale=float(normal.get("scale", 1.0)) if isinstance(normal, dict) else 1.0,
                occlusion_texture=self._slot(occlusion, textured, f"{at}.occlusionTexture"),
                occlusion_strength=float(occlusion.get("strength", 1.0)) if isinstance(occlusion, dict) else 1.0,
                emissive_texture=self._slot(mat.get("emissiveTexture"), textured, f"{at}.emissiveTexture"),
                emissive_strength=strength * peak,
                alpha_mode=mode,
                alpha_cutoff=float(mat.get("alphaCutoff", 0.5)),
                double_sided=bool(mat.get("doubleSided", False)),
            )
        except (GLTFImportError, UntrustedReferenceError, DroppedContentError):
            raise
        except ValueError as exc:
            raise self.error(f"materials[{index}]: {exc}") from None
        out: list[Any] = [material]
        self.materials[key] = out
        return out

    def _draco(self, prim: dict[str, Any], where: str) -> dict[str, np.ndarray]:
        """The attributes (and "indices") of a Draco-compressed primitive, decoded with DracoPy."""
        spec = prim["extensions"]["KHR_draco_mesh_compression"]
        try:
            import DracoPy
        except ImportError:
            raise self.error(
                f"{where} is Draco-compressed (KHR_draco_mesh_compression); reading it needs DracoPy "
                "(pip install DracoPy)"
            ) from None
        try:
            mesh = DracoPy.decode(self.view(spec["bufferView"])[0])
        except Exception as exc:
            raise self.error(f"{where}: the Draco data cannot be decoded: {exc}") from None
        out: dict[str, np.ndarray] = {}
        for name, uid in spec.get("attributes", {}).items():
            attr = mesh.get_attribute_by_unique_id(int(uid))
            if attr is None:
                raise self.error(f"{where}: Draco attribute {name} (id {uid}) is missing")
            data = np.asarray(attr["data"])
            accessor = prim["attributes"].get(name)
            if data.dtype.kind in "iu" and accessor is not None and self.item("accessors", accessor).get("normalized"):
                data = data.astype(np.float64) / np.iinfo(data.dtype).max
            out[name] = data.reshape(len(data), -1)
        faces = getattr(mesh, "faces", None)
        if faces is not None and len(faces):
            out["indices"] = np.asarray(faces, np.int64).reshape(-1)
        return out

    def primitive(self, prim: dict[str, Any], where: str) -> Node | None:
        attrs = prim.get("attributes", {})
        if "POSITION" not in attrs:
            return None
        if prim.get("targets"):
            self.drop(f"{where} has morph targets; they are not imported")
        draco = self._draco(prim, where) if "KHR_draco_mesh_compression" in prim.get("extensions", {}) else {}

        def read(name: str) -> np.ndarray:
            return draco[name] if name in draco else self.accessor(attrs[name])

        mode = prim.get("mode", 4)
        splatting = prim.get("extensions", {}).get("KHR_gaussian_splatting")
        if splatting is not None and mode == 0:
            from .splats import read_splats

            return Node("primitive", [read_splats(read, attrs, splatting, lambda m: self.error(f"{where}: {m}"))])
        vertices = read("POSITION").astype(np.float32)
        if "indices" in draco:
            indices = draco["indices"]
        elif "indices" in prim:
            indices = self.accessor(prim["indices"]).reshape(-1).astype(np.int64)
        else:
            indices = np.arange(len(vertices))
        if len(indices) and (indices.min() < 0 or indices.max() >= len(vertices)):
            raise self.error(f"{where}: an index is out of range")
        colors = None
        if "COLOR_0" in attrs:
            c = read("COLOR_0").astype(np.float64)
            rgb = _linear_to_srgb_array(c[:, :3])
            colors = rgb if c.shape[1] == 3 else np.concatenate([rgb, c[:, 3:4]], axis=1)
        uv = uv1 = tangents = None
        if "TEXCOORD_0" in attrs:
            uv = read("TEXCOORD_0").astype(np.float32)
            uv[:, 1] = 1.0 - uv[:, 1]
        if "TEXCOORD_1" in attrs and uv is not None:
            uv1 = read("TEXCOORD_1").astype(np.float32)
            uv1[:, 1] = 1.0 - uv1[:, 1]
        if "TANGENT" in attrs and uv is not None:
            tangents = read("TANGENT").astype(np.float32).copy()
            tangents[:, 3] = np.where(tangents[:, 3] < 0.0, 1.0, -1.0)  # v is flipped: so is the bitangent
        items = self.material(prim.get("material"), uv is not None and mode in (4, 5, 6))
        if mode in (4, 5, 6):
            faces = _triangles(indices, mode)
            if len(faces) == 0:
                return None
            normals = read("NORMAL").astype(np.float32) if "NORMAL" in attrs else None
            if normals is not None:
                length = np.linalg.norm(normals, axis=1, keepdims=True)
                normals = np.where(length > 0.0, normals / np.maximum(length, 1e-30), normals)
            shape: Any = TriangleSet(
                vertices, faces, normals=normals, colors=colors, texcoords=uv, texcoords1=uv1, tangents=tangents
            )
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
        try:
            check_nesting(f"load_gltf {str(self.path)!r}", f"nodes[{index}]", len(active) + 1)
        except ResourceLimitError as exc:
            raise self.error(str(exc).split(": ", 1)[1]) from None
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
            self.drop(f"the skin of nodes[{index}] is not imported (the mesh stays in its bind pose)")
        if "mesh" in spec:
            parts = self.mesh(spec["mesh"])
            instancing = spec.get("extensions", {}).get("EXT_mesh_gpu_instancing")
            if instancing is not None:
                parts = self.instanced(parts, instancing, f"nodes[{index}]")
            for child in parts:
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

    def instanced(self, parts: list[Node], spec: Any, where: str) -> list[Node]:
        """A mesh's primitive nodes as ``InstanceSet``s of the node's ``EXT_mesh_gpu_instancing`` attributes."""
        attrs = spec.get("attributes") if isinstance(spec, dict) else None
        if not isinstance(attrs, dict):
            raise self.error(f"{where}: EXT_mesh_gpu_instancing needs an attributes object")
        arrays: dict[str, np.ndarray] = {}
        for name, widths in (("TRANSLATION", (3,)), ("ROTATION", (4,)), ("SCALE", (3,)), ("_COLOR_0", (3, 4))):
            if name in attrs:
                arrays[name] = self.accessor(attrs[name]).astype(np.float64)
                if arrays[name].shape[1] not in widths:
                    raise self.error(
                        f"{where}: EXT_mesh_gpu_instancing {name} must be VEC{' or VEC'.join(map(str, widths))}"
                    )
        counts = {name: len(a) for name, a in arrays.items()}
        if len(set(counts.values())) > 1:
            raise self.error(f"{where}: EXT_mesh_gpu_instancing attributes have different counts {counts}")
        if not counts:
            return parts  # nothing to instance: the mesh once
        n = next(iter(counts.values()))
        rotation = arrays.get("ROTATION", np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)))
        zero = np.nonzero(np.linalg.norm(rotation, axis=1) == 0.0)[0]
        if len(zero):
            raise self.error(f"{where}: EXT_mesh_gpu_instancing ROTATION of instance {int(zero[0])} is zero")
        matrices = compose_trs(
            arrays.get("TRANSLATION", np.zeros((n, 3))), rotation, arrays.get("SCALE", np.ones((n, 3)))
        )
        colors = arrays.get("_COLOR_0")
        out = []
        for part in parts:
            *attributes, shape = part.items
            tint = None
            if colors is not None:  # three.js multiplies the material's base colour by the instance's
                base = next((a.base_color for a in attributes if isinstance(a, PBRMaterial)), (1.0, 1.0, 1.0))
                linear = srgb_to_linear(base)
                tint = _linear_to_srgb_array(colors[:, :3] * linear)
            try:
                instances = InstanceSet(shape, matrices, colors=tint)
            except ValueError as exc:
                raise self.error(f"{where}: {exc}") from None
            out.append(Node(part.name, [*attributes, instances]))
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
        try:
            return light_from_gltf(lights[index])
        except (ValueError, TypeError) as exc:
            raise self.error(f"KHR_lights_punctual light {index}: {exc}") from None

    def animation(self, index: int) -> Animation:
        spec = self.item("animations", index)
        samplers = spec.get("samplers", [])
        tracks = []
        for c, channel in enumerate(spec.get("channels", [])):
            target = channel.get("target", {})
            path, node = target.get("path"), target.get("node")
            where = f"animations[{index}].channels[{c}]"
            if path == "weights":
                self.drop(f"{where} animates morph weights, which are not imported; skipped")
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


def light_from_gltf(spec: dict[str, Any]) -> Any:
    """A ``KHR_lights_punctual`` light as an omnirender light of the same physical brightness.

    glTF's intensities are physical (candela for point and spot lights, lux
    for directional ones) and taken as radiometric; omnirender's lights follow
    OpenGL (:mod:`omnirender.attributes.photometry`): a diffuse surface shows
    ``kd * c * att(d)``, a physical renderer ``kd * I / (pi d^2)``.  So a point
    or spot light gets intensity ``I / pi`` with attenuation ``1 / d^2``, a
    directional one ``E / pi``; the spot's inner cone angle becomes the
    exponent whose ``cos^exponent`` is one half there.
    """
    color = _linear_to_srgb(spec.get("color", (1.0, 1.0, 1.0)))
    extras = spec.get("extras")
    record = extras.get("omnirender", {}).get("area_light") if isinstance(extras, dict) else None
    if isinstance(record, dict):  # omnirender's area light, written as its far-field spot (see the writer)
        return _area_light(record, color)
    intensity = float(spec.get("intensity", 1.0)) / math.pi
    kind = spec.get("type")
    if kind == "directional":
        return DirectionalLight(direction=(0, 0, -1), color=color, intensity=intensity)
    if kind == "spot":
        cone = spec.get("spot", {})
        outer = float(cone.get("outerConeAngle", math.pi / 4))
        inner = min(float(cone.get("innerConeAngle", 0.0)), outer)
        exponent = math.log(0.5) / math.log(math.cos(inner)) if 1e-6 < inner < math.pi / 2 else 0.0
        return SpotLight(
            position=(0, 0, 0), direction=(0, 0, -1), cutoff=math.degrees(outer), exponent=exponent,
            color=color, intensity=intensity, constant=0.0, quadratic=1.0,
        )  # fmt: skip
    if kind != "point":
        raise ValueError(f"unknown light type {kind!r}")
    return PointLight(position=(0, 0, 0), color=color, intensity=intensity, constant=0.0, quadratic=1.0)


def _area_light(record: dict[str, Any], color: Any) -> Any:
    """An ``om.RectLight`` / ``om.DiscLight`` from the exporter's ``extras.omnirender.area_light`` record.

    The light faces the node's -z, its width along x, its height along y; ``radiance`` is its intensity.
    """
    common = {
        "direction": (0, 0, -1),
        "up": (0, 1, 0),
        "color": color,
        "intensity": float(record.get("radiance", 1.0)),
        "two_sided": bool(record.get("two_sided", False)),
        "casts_shadows": bool(record.get("casts_shadows", True)),
    }
    if record.get("shape") == "disc":
        return DiscLight(radius=float(record["radius"]), **common)
    return RectLight(width=float(record["width"]), height=float(record["height"]), **common)


def _texture_transform(spec: dict[str, Any]) -> tuple[tuple[float, float], tuple[float, float], float]:
    """``KHR_texture_transform`` (glTF's v-down coordinates) as omnirender's (offset, scale, rotation in degrees).

    glTF looks up ``t + R(r) (s * uv)`` with ``R(r) = [[cos, sin], [-sin, cos]]``;
    with v flipped (v' = 1 - v) that is ``offset + R'(r) (s * uv')`` with the
    usual counter-clockwise R' and ``offset = (t_u + sin(r) s_v, 1 - t_v - cos(r) s_v)``.
    """
    tu, tv = (float(x) for x in spec.get("offset", (0.0, 0.0)))
    su, sv = (float(x) for x in spec.get("scale", (1.0, 1.0)))
    r = float(spec.get("rotation", 0.0))
    if (tu, tv, su, sv, r) == (0.0, 0.0, 1.0, 1.0, 0.0):
        return (0.0, 0.0), (1.0, 1.0), 0.0
    offset = (tu + math.sin(r) * sv, 1.0 - tv - math.cos(r) * sv)
    return offset, (su, sv), math.degrees(r)


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


def load_gltf(
    path: str | os.PathLike[str],
    animation: int | str | None = 0,
    *,
    trusted: bool = False,
    allowed_roots: Iterable[str | os.PathLike[str]] | None = None,
    strict: bool = False,
) -> Node:
    """The scene of a glTF 2.0 file (``.glb`` or ``.gltf``) as an ``om.Node``, with its animation as tracks.

    ``animation`` picks the clip (glTF files may hold several): an index, a
    name, ``"all"`` (every clip at once) or None (none).  See the module docs
    for what is imported.  ``trusted`` and ``allowed_roots`` set where the
    file's buffer and image URIs may lead (the path policy of
    :mod:`omnirender.core.paths`); ``strict=True`` turns the warnings about
    content that was left out into :class:`~omnirender.core.drops.DroppedContentError`.
    """
    source = Path(path)
    if not source.is_file():
        raise FileNotFoundError(f"load_gltf: no such file {str(source)!r}")
    if not (animation is None or isinstance(animation, str) or type(animation) is int):
        raise TypeError(f"load_gltf: animation must be an index, a name, 'all' or None, got {animation!r}")
    try:
        return _load(source, animation, PathPolicy.of(trusted, allowed_roots), strict)
    except (TypeError, KeyError, AttributeError, IndexError, RecursionError, struct.error, OverflowError) as exc:
        # a value of the wrong JSON type somewhere the importer does not check it one by one
        raise GLTFImportError(
            f"load_gltf {str(source)!r}: malformed glTF ({type(exc).__name__}: {exc}); the file does not follow "
            "the glTF 2.0 schema (check it with the Khronos glTF validator)"
        ) from None


def _load(source: Path, animation: int | str | None, policy: PathPolicy, strict: bool) -> Node:
    reader = _Reader(source, policy, strict)
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


def flatten_gltf(
    path: str | os.PathLike[str],
    *,
    trusted: bool = False,
    allowed_roots: Iterable[str | os.PathLike[str]] | None = None,
    strict: bool = False,
) -> list[tuple[list[Any], Any]]:
    """The triangle primitives of a glTF file's default scene in world coordinates, with their attributes.

    ``[(attributes, TriangleSet)]``: what ``om.MeshFile`` needs (one static
    mesh per primitive, materials and textures kept), read with the full
    importer (:func:`load_gltf`), so Draco, sparse accessors, quantization and
    every material slot behave as in ``load_gltf``.
    """
    from ...core.transform import Transform

    root = load_gltf(path, animation=None, trusted=trusted, allowed_roots=allowed_roots, strict=strict)
    out: list[tuple[list[Any], Any]] = []

    def walk(node: Node, matrix: np.ndarray) -> None:
        attrs: list[Any] = []
        for item in node.items:
            if isinstance(item, Transform):
                matrix = matrix @ item.matrix
            elif isinstance(item, Node):
                walk(item, matrix)
            elif isinstance(item, TriangleSet):
                out.append((list(attrs), item.transformed(matrix)))
            elif isinstance(item, (PBRMaterial, Texture)):
                attrs.append(item)

    walk(root, np.eye(4))
    return out
