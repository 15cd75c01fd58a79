"""Mesh files (OBJ, PLY, STL, OFF through trimesh; glTF/GLB through the glTF importer) as ``om.MeshFile`` parts.

:func:`read_mesh` is the reader :class:`~omnirender.shapes.MeshFile` calls
(registered by :mod:`omnirender.formats`) the first time a file is used.
Trimesh is imported only then, so declaring a MeshFile needs no extra package.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..shapes.meshes import TriangleSet
from ..shapes.trimeshes import is_trimesh, is_trimesh_scene, triangle_arrays
from .obj import read_plain_obj

__all__ = ["read_mesh", "SUFFIXES"]

SUFFIXES = (".obj", ".ply", ".stl", ".off", ".gltf", ".glb")


def read_mesh(path: Any) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
    """The parts of a mesh file or trimesh object: ``[(material parameters or None, TriangleSet)]``."""
    if is_trimesh(path) or is_trimesh_scene(path):
        return _parts(path, "the trimesh object")
    if not os.path.exists(path):
        raise FileNotFoundError(f"MeshFile: no such file {path!r}")
    if path.lower().endswith((".gltf", ".glb")):
        return _load_gltf(path)
    if str(path).lower().endswith(".obj"):
        try:
            plain = read_plain_obj(path)
        except ValueError as exc:
            raise ValueError(f"MeshFile: cannot load {path!r}: {exc}") from None
        if plain is not None:  # a plain OBJ file: no trimesh import needed
            try:
                return [(None, TriangleSet(**plain))]
            except ValueError as exc:
                raise ValueError(f"MeshFile: {path!r} holds invalid geometry: {exc}") from None
    try:
        import trimesh
    except ImportError as exc:  # pragma: no cover - trimesh is in the 'mesh' extra
        raise ValueError(f"MeshFile: loading {path!r} needs trimesh (pip install omnirender[mesh]): {exc}") from None
    try:
        loaded = trimesh.load(path, process=False)
    except Exception as exc:
        raise ValueError(f"MeshFile: cannot load {path!r}: {type(exc).__name__}: {exc}") from None
    parts = _parts(loaded, repr(path))
    if str(path).lower().endswith(".obj") and not _names_materials(path):
        # texture coordinates without a material library: trimesh makes up a grey material with a tiny
        # placeholder image; the file has no appearance, so the shapes get the scene's (or the default)
        parts = [(None, ts) for _, ts in parts]
    return parts


def _names_materials(path: str) -> bool:
    """Whether an OBJ file names a material library (an ``mtllib`` line)."""
    with open(path, "rb") as fh:
        return any(line.lstrip().startswith(b"mtllib") for line in fh)


def _parts(loaded: Any, path: str) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
    """The parts of a loaded trimesh object (a Trimesh, or a Scene's meshes with their transforms)."""
    if is_trimesh_scene(loaded):
        try:
            meshes = loaded.dump(concatenate=False)
        except Exception as exc:
            raise ValueError(f"MeshFile: cannot load {path}: {type(exc).__name__}: {exc}") from None
    else:
        meshes = [loaded]
    parts = []
    for mesh in meshes:
        if not is_trimesh(mesh) or len(mesh.faces) == 0:
            continue  # point clouds, paths and empty geometry carry no triangles
        try:
            parts.append(_part(mesh))
        except ValueError as exc:
            raise ValueError(f"MeshFile: {path} holds invalid geometry: {exc}") from None
    if not parts:
        raise ValueError(f"MeshFile: {path} contains no triangles (empty or not a mesh file)")
    return parts


def _part(mesh: Any) -> tuple[dict[str, Any] | None, TriangleSet]:
    _consistent_winding(mesh)
    arrays = triangle_arrays(mesh)
    material = None
    visual = mesh.visual
    kind = getattr(visual, "kind", None)
    if kind == "face":
        fc = np.asarray(visual.face_colors, dtype=np.float32) / 255.0
        if len(np.unique(fc, axis=0)) == 1:  # one colour for all: a material, shared vertices kept
            material = {"kind": "phong", "diffuse": tuple(float(c) for c in fc[0, :3]), "opacity": float(fc[0, 3])}
            arrays["colors"] = None
    elif kind != "vertex" and (kind == "texture" or hasattr(visual, "material")):
        material = _material(getattr(visual, "material", None))
        if material is not None and arrays["texcoords"] is None:
            material.pop("texture", None)
    return material, TriangleSet(**arrays)


def _consistent_winding(mesh: Any) -> None:
    """Wind every face of a mesh without normals in the file the same way, outwards when it is closed.

    Smooth normals are computed from the winding: faces wound against their
    neighbours (common in OFF, PLY and STL files) would point their normals
    inwards and darken in wedges, and a closed surface culls them in GL.
    """
    cache = getattr(mesh, "_cache", None)
    if cache is not None and "vertex_normals" in cache:
        return  # the file's normals decide
    try:
        if not mesh.is_winding_consistent:
            mesh.fix_normals()
    except Exception:  # pragma: no cover - a mesh trimesh cannot analyse keeps its winding
        return


def _rgb(value: Any, default: tuple[float, float, float]) -> tuple[float, float, float]:
    if value is None:
        return default
    a = np.asarray(value, dtype=np.float64).reshape(-1)
    if a.size < 3:
        return default
    if a.max() > 1.0 or a.dtype.kind in "iu":
        a = a / 255.0
    return tuple(float(x) for x in np.clip(a[:3], 0.0, 1.0))


def _alpha(value: Any) -> float:
    if value is None:
        return 1.0
    a = np.asarray(value, dtype=np.float64).reshape(-1)
    if a.size < 4:
        return 1.0
    return float(np.clip(a[3] / 255.0 if a.max() > 1.0 else a[3], 0.0, 1.0))


def _texture(image: Any) -> np.ndarray | None:
    if image is None:
        return None
    try:
        return np.asarray(image.convert("RGBA"), dtype=np.uint8)
    except Exception:
        return None


def _material(mat: Any) -> dict[str, Any] | None:
    if mat is None:
        return None
    name = type(mat).__name__
    if name == "PBRMaterial":
        base = getattr(mat, "baseColorFactor", None)
        out: dict[str, Any] = {
            "kind": "pbr",
            "base_color": _rgb(base, (1.0, 1.0, 1.0)),
            "metallic": float(mat.metallicFactor) if mat.metallicFactor is not None else 1.0,
            "roughness": float(mat.roughnessFactor) if mat.roughnessFactor is not None else 1.0,
            "emission": _rgb(getattr(mat, "emissiveFactor", None), (0.0, 0.0, 0.0)),
            "opacity": _alpha(base),
        }
        tex = _texture(getattr(mat, "baseColorTexture", None))
    elif name == "SimpleMaterial":
        diffuse = getattr(mat, "diffuse", None)
        glossiness = getattr(mat, "glossiness", None)
        shininess = float(glossiness) if glossiness is not None else 1.0
        # MTL's Ns 0 (common in exported files with Ks 1) means "no highlight", as importers such as Blender read
        # it (roughness 1): a Phong lobe that wide would whiten the whole surface
        specular = _rgb(getattr(mat, "specular", None), (0.0, 0.0, 0.0)) if shininess >= 1.0 else (0.0, 0.0, 0.0)
        out = {
            "kind": "phong",
            "ambient": _rgb(getattr(mat, "ambient", None), (0.2, 0.2, 0.2)),
            "diffuse": _rgb(diffuse, (0.8, 0.8, 0.8)),
            "specular": specular,
            "shininess": max(shininess, 1.0),
            "opacity": _alpha(diffuse),
        }
        tex = _texture(getattr(mat, "image", None))
    else:
        return None
    if tex is not None:
        out["texture"] = tex
    return out


def _load_gltf(path: str) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
    """glTF through the full importer (materials, textures, Draco...), flattened to world-space parts."""
    from .gltf.reader import GLTFImportError, flatten_gltf

    try:
        flat = flatten_gltf(path)
    except GLTFImportError as exc:
        raise ValueError(f"MeshFile: {exc}") from None
    parts = [({"kind": "attributes", "attributes": attrs} if attrs else None, ts) for attrs, ts in flat]
    if not parts:
        raise ValueError(f"MeshFile: {path!r} contains no triangles (empty or not a mesh file)")
    return parts
