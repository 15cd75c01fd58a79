"""The cross-engine asset suite (issue 23): mesh files the project writes itself, one per defect class.

:func:`write_assets` writes into a folder: glTF files with vertex colours
whose alpha an OPAQUE material must ignore, an emissive map, a texture
transform with offset, rotation and CLAMP_TO_EDGE, a MASK cut-off, a grey
metallic PBR sphere; a binary PLY with per-face colours; an OBJ with texture
coordinates and no MTL file; an OBJ with vertex colours; an OFF mesh with
mixed winding.  :func:`asset_scene` sets one up as a user would
(``om.MeshFile``, a fitted camera, one directional light, ambient 0.3, a
Background); :func:`compare` measures an engine's picture against GL's by
mask IoU and mean CIEDE2000 over the shared foreground.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from gltf_files import _Writer, png

import omnirender as om
from omnirender.colorimetry import cielab, delta_e2000

#: name -> file name
ASSETS = {
    "vertex colours (glTF)": "vertex_colors.glb",
    "emissive map": "emissive.glb",
    "texture transform": "texture_transform.glb",
    "alpha mask": "mask.glb",
    "metallic sphere": "metallic.glb",
    "face colours (PLY)": "faces.ply",
    "UVs without MTL": "uv_no_mtl.obj",
    "vertex colours (OBJ)": "vertex_colors.obj",
    "mixed winding (OFF)": "winding.off",
}


def uv_sphere(rings: int = 24, segments: int = 48) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(positions, normals, glTF texture coordinates, triangles) of a unit sphere, counter-clockwise outwards."""
    theta = np.linspace(0, math.pi, rings + 1)
    phi = np.linspace(0, 2 * math.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    pos = np.stack([np.sin(t) * np.sin(p), np.cos(t), np.sin(t) * np.cos(p)], -1).reshape(-1, 3)
    uv = np.stack([p / (2 * math.pi), t / math.pi], -1).reshape(-1, 2)
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
    tris = np.concatenate([np.stack([a, b, b + 1], -1), np.stack([a, b + 1, a + 1], -1)]).reshape(-1, 3)
    keep = ~((tris[:, 0] == tris[:, 1]) | (tris[:, 1] == tris[:, 2]) | (tris[:, 0] == tris[:, 2]))
    return pos.astype(np.float32), pos.astype(np.float32), uv.astype(np.float32), tris[keep].astype(np.uint32)


def _glb(
    path: Path,
    positions: np.ndarray,
    normals: np.ndarray | None,
    uv: np.ndarray | None,
    triangles: np.ndarray,
    material: dict[str, Any],
    images: list[np.ndarray] = (),
    colors: np.ndarray | None = None,
    wrap: int = 10497,
) -> None:
    """A glTF binary with one mesh (no camera, no light: the scene brings them, as a user would)."""
    w = _Writer()
    G = w.G
    attributes = {"POSITION": w.accessor(positions.astype(np.float32), "VEC3", G.FLOAT, minmax=True)}
    if normals is not None:
        attributes["NORMAL"] = w.accessor(normals.astype(np.float32), "VEC3", G.FLOAT)
    if uv is not None:
        attributes["TEXCOORD_0"] = w.accessor(uv.astype(np.float32), "VEC2", G.FLOAT)
    if colors is not None:
        attributes["COLOR_0"] = w.accessor(np.asarray(colors, np.float32), "VEC4", G.FLOAT)
    indices = w.accessor(triangles.reshape(-1).astype(np.uint32), "SCALAR", G.UNSIGNED_INT, target=34963)
    used = {ext for ext in ("KHR_texture_transform",) if ext in repr(material)}
    gltf = G.GLTF2(
        scene=0,
        scenes=[G.Scene(nodes=[0])],
        nodes=[G.Node(name="asset", mesh=0)],
        meshes=[G.Mesh(primitives=[G.Primitive(attributes=G.Attributes(**attributes), indices=indices, material=0)])],
        materials=[G.Material.from_dict(material)],
        images=[G.Image(bufferView=w.view(png(img)), mimeType="image/png") for img in images],
        textures=[G.Texture(source=i, sampler=0) for i in range(len(images))],
        samplers=[G.Sampler(magFilter=9728, minFilter=9728, wrapS=wrap, wrapT=wrap)] if images else [],
        accessors=w.accessors,
        bufferViews=w.views,
        buffers=[G.Buffer(byteLength=len(w.blob))],
        extensionsUsed=sorted(used),
    )
    gltf.set_binary_blob(bytes(w.blob))
    gltf.save_binary(str(path))


def _quad(tilt: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    uv = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)
    return pos, np.array([[0, 0, 1]] * 4, np.float32), uv, np.array([[0, 1, 2], [0, 2, 3]], np.uint32)


def _checker(n: int = 8, size: int = 64, a: Any = (230, 60, 40, 255), b: Any = (40, 90, 220, 255)) -> np.ndarray:
    i, j = np.meshgrid(np.arange(size), np.arange(size), indexing="ij")
    odd = ((i * n // size) + (j * n // size)) % 2 == 1
    img = np.empty((size, size, 4), np.uint8)
    img[...] = a
    img[odd] = b
    return img


def write_assets(folder: Path) -> dict[str, Path]:
    """Write every asset of :data:`ASSETS` into ``folder``; returns name -> path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    pos, nrm, uv, tris = uv_sphere()
    # vertex colours with alpha 0.3 under an OPAQUE material: the alpha must be ignored
    hue = (pos[:, 0] + 1) / 2
    colors = np.stack([hue, 0.2 + 0.6 * (pos[:, 1] + 1) / 2, 1 - hue, np.full(len(pos), 0.3)], -1)
    material = {"pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.8}, "alphaMode": "OPAQUE"}
    _glb(folder / ASSETS["vertex colours (glTF)"], pos, nrm, None, tris, material, colors=colors)
    # emissive stripes over a dark red base
    stripes = np.zeros((32, 32, 4), np.uint8)
    stripes[..., 3] = 255
    stripes[:, ::8] = stripes[:, 1::8] = stripes[:, 2::8] = (255, 255, 255, 255)
    material = {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.1, 0.1, 1], "metallicFactor": 0.0,
                                         "roughnessFactor": 0.9},
                "emissiveFactor": [1.0, 0.8, 0.2], "emissiveTexture": {"index": 0}}  # fmt: skip
    _glb(folder / ASSETS["emissive map"], pos, nrm, uv, tris, material, images=[stripes])
    # a checker through KHR_texture_transform (offset, rotation, scale) with CLAMP_TO_EDGE: the outside is the edge
    transform = {"offset": [0.25, -0.1], "rotation": 0.5, "scale": [0.8, 0.6]}
    material = {"pbrMetallicRoughness": {"metallicFactor": 0.0, "baseColorTexture": {
        "index": 0, "extensions": {"KHR_texture_transform": transform}}}}  # fmt: skip
    q = _quad()
    _glb(folder / ASSETS["texture transform"], *q, material, images=[_checker(4, 64)], wrap=33071)
    # a radial alpha ramp cut at 0.5: a disc remains
    i, j = np.meshgrid(np.arange(64), np.arange(64), indexing="ij")
    r = np.hypot(i - 31.5, j - 31.5) / 32
    ramp = np.zeros((64, 64, 4), np.uint8)
    ramp[..., :3] = (240, 200, 60)
    ramp[..., 3] = np.clip(255 * (1.2 - r), 0, 255).astype(np.uint8)
    material = {"pbrMetallicRoughness": {"metallicFactor": 0.0, "baseColorTexture": {"index": 0}},
                "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True}  # fmt: skip
    _glb(folder / ASSETS["alpha mask"], *q, material, images=[ramp])
    # a grey metal
    material = {"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 1.0,
                                         "roughnessFactor": 0.45}}  # fmt: skip
    _glb(folder / ASSETS["metallic sphere"], pos, nrm, None, tris, material)
    _write_ply_faces(folder / ASSETS["face colours (PLY)"])
    _write_obj_uv(folder / ASSETS["UVs without MTL"])
    _write_obj_colors(folder / ASSETS["vertex colours (OBJ)"])
    _write_off(folder / ASSETS["mixed winding (OFF)"])
    return {name: folder / file for name, file in ASSETS.items()}


def _icosphere() -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=2)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def _write_ply_faces(path: Path) -> None:
    """A binary little-endian PLY: an icosphere whose faces are coloured by the octant of their centre."""
    v, f = _icosphere()
    c = v[f].mean(axis=1)
    rgb = np.stack([c[:, 0] > 0, c[:, 1] > 0, c[:, 2] > 0], -1).astype(np.uint8) * 200 + 40
    # every vertex has the same default colour, as many exporters write: the faces' colours are the real ones
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
        f"element face {len(f)}\nproperty list uchar int vertex_indices\nproperty uchar red\n"
        "property uchar green\nproperty uchar blue\nend_header\n"
    )
    vertex = np.zeros(len(v), np.dtype([("p", "<f4", 3), ("rgb", "u1", 3)]))
    vertex["p"], vertex["rgb"] = v, 255
    face = np.zeros(len(f), np.dtype([("n", "u1"), ("i", "<i4", 3), ("rgb", "u1", 3)]))
    face["n"], face["i"], face["rgb"] = 3, f, rgb
    path.write_bytes(header.encode() + vertex.tobytes() + face.tobytes())


def _write_obj_uv(path: Path) -> None:
    """A sphere with ``vt`` texture coordinates and ``vn`` normals but no ``mtllib``: it has no texture."""
    pos, nrm, uv, tris = uv_sphere(12, 24)
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in pos]
    lines += [f"vt {s:.6f} {1 - t:.6f}" for s, t in uv]
    lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in nrm]
    lines += ["f " + " ".join(f"{k + 1}/{k + 1}/{k + 1}" for k in tri) for tri in tris]
    path.write_text("\n".join(lines) + "\n")


def _write_obj_colors(path: Path) -> None:
    """An icosphere with per-vertex colours (``v x y z r g b``)."""
    v, f = _icosphere()
    rgb = np.clip((v + 1) / 2, 0, 1)
    lines = [f"v {x:.6f} {y:.6f} {z:.6f} {r:.4f} {g:.4f} {b:.4f}" for (x, y, z), (r, g, b) in zip(v, rgb, strict=True)]
    lines += ["f " + " ".join(str(k + 1) for k in tri) for tri in f]
    path.write_text("\n".join(lines) + "\n")


def _write_off(path: Path) -> None:
    """An OFF icosphere with every third face wound clockwise (as many files in the wild are)."""
    v, f = _icosphere()
    f = f.copy()
    f[::3] = f[::3, ::-1]
    lines = ["OFF", f"{len(v)} {len(f)} 0"]
    lines += [f"{x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    lines += ["3 " + " ".join(str(k) for k in tri) for tri in f]
    path.write_text("\n".join(lines) + "\n")


def asset_scene(path: Path, size: tuple[int, int], background: bool = True) -> om.Node:
    """The asset as a user sets it up: ``om.MeshFile``, a fitted camera, one directional light, ambient 0.3."""
    model = om.Node("model", [om.MeshFile(path)])
    scene = om.Node("scene", [om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), om.AmbientLight(intensity=0.3)])
    if background:
        scene.add(om.Background((0.25, 0.3, 0.35)))
    scene.add(model)
    scene.insert(0, om.Camera.fitted(om.bounds(scene), size))
    return scene


#: Each engine's options in the suite (few samples: the comparison is over means)
OPTIONS = {"mitsuba": {"spp": 16}}


def compare(engine: om.Image, gl: om.Image) -> tuple[float, float]:
    """(mask IoU, mean CIEDE2000 over the pixels both masks cover) of ``engine`` against ``gl``."""
    a, b = np.asarray(engine.mask, bool), np.asarray(gl.mask, bool)
    union = np.count_nonzero(a | b)
    iou = np.count_nonzero(a & b) / union if union else 1.0
    both = a & b
    if not both.any():
        return iou, float("inf")
    de = delta_e2000(cielab(engine.array[..., :3][both]), cielab(gl.array[..., :3][both]))
    return iou, float(de.mean())


def outliers(engine: om.Image, gl: om.Image, limit: float = 25.0) -> float:
    """Fraction of the shared foreground whose CIEDE2000 to GL exceeds ``limit`` (blobs, speckles, holes)."""
    both = np.asarray(engine.mask, bool) & np.asarray(gl.mask, bool)
    if not both.any():
        return 1.0
    de = delta_e2000(cielab(engine.array[..., :3][both]), cielab(gl.array[..., :3][both]))
    return float(np.mean(de > limit))
