"""glTF test files built feature by feature with pygltflib (an independent writer): no downloaded assets.

:func:`quad_file` writes a unit quad (x, y in [-1, 1], facing +z) seen by a
camera in the file, lit by a light in the file, with the material, textures,
vertex colours, texture transforms, sparse, quantized or Draco-compressed
data a test asks for.
"""

from __future__ import annotations

import io
import math
from typing import Any

import numpy as np

POSITIONS = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
NORMALS = np.array([[0, 0, 1]] * 4, np.float32)
# glTF texture coordinates: v grows downwards (the image's top row is v = 0)
UV = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)
INDICES = np.array([0, 1, 2, 0, 2, 3], np.uint16)


def gltf_validator() -> list[str] | None:
    """The command that runs the Khronos glTF validator (npm package, ``tools/gltf-validator``), or None."""
    import shutil
    from pathlib import Path

    tool = Path(__file__).parent.parent / "tools" / "gltf-validator"
    node = shutil.which("node") or shutil.which("nodejs")
    if node is None or not (tool / "node_modules" / "gltf-validator").is_dir():
        return None
    return [node, str(tool / "validate.js")]


def validator_reports(files: list[Any]) -> list[dict[str, Any]]:
    """The Khronos validator's report of each file (``{"file": ..., "issues": {...}}``); asserts that it ran."""
    import json
    import subprocess

    out = subprocess.run([*gltf_validator(), *map(str, files)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return [json.loads(line) for line in out.stdout.splitlines()]


def png(rgba: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgba, np.uint8), "RGBA").save(buf, format="PNG")
    return buf.getvalue()


def halves(left: Any, right: Any, size: int = 8) -> np.ndarray:
    """An RGBA image whose left half is ``left`` and right half ``right`` (RGBA values 0..255)."""
    img = np.zeros((size, size, 4), np.uint8)
    img[:, : size // 2] = left
    img[:, size // 2 :] = right
    return img


class _Writer:
    def __init__(self) -> None:
        import pygltflib as G

        self.G = G
        self.blob = bytearray()
        self.views: list[Any] = []
        self.accessors: list[Any] = []

    def view(self, data: bytes, target: int | None = None) -> int:
        offset = len(self.blob)
        self.blob += data + b"\0" * (-len(data) % 4)
        self.views.append(self.G.BufferView(buffer=0, byteOffset=offset, byteLength=len(data), target=target))
        return len(self.views) - 1

    def accessor(self, array: np.ndarray, kind: str, component: int, *, normalized: bool = False,
                 target: int | None = 34962, minmax: bool = False, count: int | None = None) -> int:  # fmt: skip
        view = None if array is None else self.view(np.ascontiguousarray(array).tobytes(), target)
        count = len(array) if array is not None else count
        acc = self.G.Accessor(bufferView=view, componentType=component, count=count, type=kind, normalized=normalized)
        if minmax:
            acc.min, acc.max = array.min(axis=0).tolist(), array.max(axis=0).tolist()
        self.accessors.append(acc)
        return len(self.accessors) - 1


def quad_file(
    path: Any,
    *,
    material: dict[str, Any] | None = None,
    images: list[np.ndarray] = (),
    colors: np.ndarray | None = None,
    uv1: np.ndarray | None = None,
    sparse_move: tuple[int, tuple[float, float, float]] | None = None,
    quantized: bool = False,
    draco: bool = False,
    light: dict[str, Any] | None = None,
    extensions_required: tuple[str, ...] = (),
    extensions_used: tuple[str, ...] = (),
    node_scale: float = 1.0,
) -> None:
    """Write the quad as ``.glb`` (see the module docs).  ``material`` is a glTF material dict (JSON form)."""
    w = _Writer()
    G = w.G
    attributes: dict[str, int] = {}
    prim_ext: dict[str, Any] = {}
    used = set(extensions_used) | set(extensions_required)
    if draco:
        import DracoPy

        data = DracoPy.encode(
            POSITIONS.astype(np.float64), INDICES.reshape(-1, 3).astype(np.uint32),
            normals=NORMALS.astype(np.float64), tex_coord=UV.astype(np.float64), preserve_order=True,
        )  # fmt: skip
        mesh = DracoPy.decode(data)
        ids = {a["attribute_type"]: a["unique_id"] for a in mesh.attributes}  # 0 position, 1 normal, 3 texcoord
        view = w.view(data)
        attributes = {
            "POSITION": w.accessor(None, "VEC3", G.FLOAT, count=4),
            "NORMAL": w.accessor(None, "VEC3", G.FLOAT, count=4),
            "TEXCOORD_0": w.accessor(None, "VEC2", G.FLOAT, count=4),
        }
        w.accessors[attributes["POSITION"]].min = [-1, -1, 0]
        w.accessors[attributes["POSITION"]].max = [1, 1, 0]
        indices = w.accessor(None, "SCALAR", G.UNSIGNED_SHORT, count=6)
        prim_ext["KHR_draco_mesh_compression"] = {
            "bufferView": view,
            "attributes": {"POSITION": ids[0], "NORMAL": ids[1], "TEXCOORD_0": ids[3]},
        }
        used.add("KHR_draco_mesh_compression")
    elif quantized:
        q = np.round(POSITIONS * 32767).astype(np.int16)  # normalized: the node scale restores the size
        attributes["POSITION"] = w.accessor(q, "VEC3", G.SHORT, normalized=True, minmax=True)
        attributes["NORMAL"] = w.accessor(np.round(NORMALS * 127).astype(np.int8), "VEC3", G.BYTE, normalized=True)
        attributes["TEXCOORD_0"] = w.accessor(np.round(UV * 65535).astype(np.uint16), "VEC2", G.UNSIGNED_SHORT,
                                              normalized=True)  # fmt: skip
        indices = w.accessor(INDICES, "SCALAR", G.UNSIGNED_SHORT, target=34963)
        used.add("KHR_mesh_quantization")
    else:
        attributes["POSITION"] = w.accessor(POSITIONS, "VEC3", G.FLOAT, minmax=True)
        attributes["NORMAL"] = w.accessor(NORMALS, "VEC3", G.FLOAT)
        attributes["TEXCOORD_0"] = w.accessor(UV, "VEC2", G.FLOAT)
        indices = w.accessor(INDICES, "SCALAR", G.UNSIGNED_SHORT, target=34963)
    if sparse_move is not None:
        row, value = sparse_move
        acc = w.accessors[attributes["POSITION"]]
        idx_view = w.view(np.array([row], np.uint32).tobytes())
        val_view = w.view(np.array([value], np.float32).tobytes())
        acc.sparse = G.Sparse(count=1, indices={"bufferView": idx_view, "componentType": G.UNSIGNED_INT},
                              values={"bufferView": val_view})  # fmt: skip
        moved = POSITIONS.copy()
        moved[row] = value
        acc.min, acc.max = moved.min(axis=0).tolist(), moved.max(axis=0).tolist()
    if colors is not None:
        attributes["COLOR_0"] = w.accessor(np.asarray(colors, np.float32), "VEC4", G.FLOAT)
    if uv1 is not None:
        attributes["TEXCOORD_1"] = w.accessor(np.asarray(uv1, np.float32), "VEC2", G.FLOAT)
    image_items = [G.Image(bufferView=w.view(png(img)), mimeType="image/png") for img in images]
    textures = [G.Texture(source=i, sampler=0) for i in range(len(images))]
    samplers = [G.Sampler(magFilter=9728, minFilter=9728, wrapS=10497, wrapT=10497)] if images else []
    materials = []
    if material is not None:
        materials = [G.Material.from_dict(material)] if hasattr(G.Material, "from_dict") else [G.Material(**material)]
        text = repr(material)
        for ext in ("KHR_texture_transform", "KHR_materials_emissive_strength"):
            if ext in text:
                used.add(ext)
    primitive = G.Primitive(attributes=G.Attributes(**attributes), indices=indices, material=0 if materials else None)
    if prim_ext:
        primitive.extensions = prim_ext
    nodes = [
        G.Node(name="quad", mesh=0, scale=[node_scale] * 3 if node_scale != 1.0 else None),
        G.Node(name="camera", camera=0, translation=[0, 0, 3]),
    ]
    doc_ext: dict[str, Any] = {}
    if light is not None:
        nodes.append(G.Node(name="light", translation=[0, 0, 2], extensions={"KHR_lights_punctual": {"light": 0}}))
        doc_ext["KHR_lights_punctual"] = {"lights": [light]}
        used.add("KHR_lights_punctual")
    gltf = G.GLTF2(
        scene=0,
        scenes=[G.Scene(name="model", nodes=list(range(len(nodes))))],
        nodes=nodes,
        meshes=[G.Mesh(name="quad", primitives=[primitive])],
        cameras=[
            G.Camera(
                type="perspective",
                perspective=G.Perspective(yfov=math.radians(45), znear=0.1, zfar=100, aspectRatio=1.0),
            )
        ],  # fmt: skip
        materials=materials,
        images=image_items,
        textures=textures,
        samplers=samplers,
        accessors=w.accessors,
        bufferViews=w.views,
        buffers=[G.Buffer(byteLength=len(w.blob))],
        extensionsUsed=sorted(used),
        extensionsRequired=list(extensions_required),
        extensions=doc_ext,
    )
    gltf.set_binary_blob(bytes(w.blob))
    gltf.save_binary(str(path))
