"""Mesh files (OBJ, PLY, STL, OFF through trimesh; glTF/GLB through the glTF importer) as ``om.MeshFile`` parts,
and a scene's surfaces written as one mesh (``.obj``, ``.ply``, ``.stl``).

:func:`read_mesh` is the reader :class:`~omnirender.shapes.MeshFile` calls
(registered by :mod:`omnirender.formats`) the first time a file is used.
Trimesh is imported only then, so declaring a MeshFile needs no extra package.

Mesh files are untrusted input.  The files a mesh file names (an OBJ's
``mtllib`` and texture maps, a PLY's ``TextureFile``, a glTF's buffers and
images) are resolved by the path policy (:mod:`omnirender.core.paths`): inside
the mesh file's folder or ``allowed_roots``, unless ``trusted=True``.  Decoded
sizes obey :mod:`omnirender.core.limits`.  What cannot be used (a missing
material library or texture, a remote URL, a decompression bomb, a texture map
kind the reader does not import) is dropped with a
:class:`~omnirender.core.drops.DroppedContentWarning` naming the file, or
raises with ``strict=True``.

:func:`export` (``om.export(scene, "x.obj")``): :class:`MeshEngine` (service
``"mesh.export"``) evaluates the scene like the other exporters (the camera's
group mask, every shape through its simplifier, an ``InstanceSet`` as its
instances) and collects each triangle set in world coordinates with its base
colour (the appearance every engine resolves).  The triangles are merged into
one ``trimesh.Trimesh`` with per-vertex colours (OBJ and PLY keep them; STL
holds geometry only) and written atomically.  Lines and points have no
surface: they are left out with one warning naming them, never silently.
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..core import ShapePainter, default_for
from ..core.drops import report_drop
from ..core.limits import ResourceLimitError, check_count, check_image_size
from ..core.paths import PathPolicy, RemoteReferenceError, UntrustedReferenceError
from ..fileio import atomic_path
from ..shapes import LineSet, PointSet, Polyline
from ..shapes.meshes import TriangleSet
from ..shapes.trimeshes import is_trimesh, is_trimesh_scene, triangle_arrays
from .obj import read_plain_obj
from .walk import NodeTrackingEngine, track_surfaces

__all__ = ["read_mesh", "SUFFIXES", "export", "MeshEngine", "MESH_EXTENSIONS"]

SUFFIXES = (".obj", ".ply", ".stl", ".off", ".gltf", ".glb")
#: What :func:`export` writes (trimesh's writers).
MESH_EXTENSIONS = (".obj", ".ply", ".stl")


def read_mesh(
    path: Any, *, policy: PathPolicy | None = None, strict: bool = False
) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
    """The parts of a mesh file or trimesh object: ``[(material parameters or None, TriangleSet)]``.

    ``policy`` (the path policy of :mod:`omnirender.core.paths`, default: the
    file's folder only) governs the files the mesh file names; ``strict``
    turns warnings about content left out into errors.
    """
    policy = policy or PathPolicy()
    if is_trimesh(path) or is_trimesh_scene(path):
        return _parts(path, "the trimesh object", strict)
    if not os.path.exists(path):
        raise FileNotFoundError(f"MeshFile: no such file {path!r}")
    if path.lower().endswith((".gltf", ".glb")):
        return _load_gltf(path, policy, strict)
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
    _check_header(path)
    if str(path).lower().endswith(".ply"):
        from .splats.ply import is_splat_ply

        if is_splat_ply(path):
            raise ValueError(
                f"MeshFile: {path!r} holds Gaussian splats (its vertices have scale_* and rot_* properties), not a "
                "mesh; read it with om.load_splats(path)"
            )
    resolver = _PolicyResolver(path, policy, strict)
    try:
        loaded = trimesh.load(path, process=False, resolver=resolver)
    except (UntrustedReferenceError, ResourceLimitError):
        raise
    except Exception as exc:
        resolver.finish()  # a refused reference explains the failure better
        raise ValueError(f"MeshFile: cannot load {path!r}: {type(exc).__name__}: {exc}") from None
    resolver.finish()
    parts = _parts(loaded, repr(path), strict)
    if str(path).lower().endswith(".obj") and not _names_materials(path):
        # texture coordinates without a material library: trimesh makes up a grey material with a tiny
        # placeholder image; the file has no appearance, so the shapes get the scene's (or the default)
        parts = [(None, ts) for _, ts in parts]
    return parts


def _names_materials(path: str) -> bool:
    """Whether an OBJ file names a material library (an ``mtllib`` line)."""
    with open(path, "rb") as fh:
        return any(line.lstrip().startswith(b"mtllib") for line in fh)


_PLY_COUNT = re.compile(rb"^element\s+(\S+)\s+(\S+)", re.MULTILINE)
_OFF_COUNTS = re.compile(rb"^\s*(?:[A-Z]*OFF)?\s*(\d+)\s+(\d+)", re.MULTILINE)


def _check_header(path: str) -> None:
    """Refuse a PLY or OFF file whose header announces more elements than the limits or the file can hold."""
    lower = path.lower()
    if not lower.endswith((".ply", ".off")):
        return
    with open(path, "rb") as fh:
        head = fh.read(4096)
    size = os.path.getsize(path)
    source = f"MeshFile {path!r}"
    if lower.endswith(".ply"):
        end = head.find(b"end_header")
        for name, count in _PLY_COUNT.findall(head[: end if end >= 0 else len(head)]):
            if not count.isdigit():
                raise ValueError(f"{source}: the PLY header's element {name.decode(errors='replace')!r} has no count")
            n = int(count)
            check_count(source, f"the PLY element {name.decode(errors='replace')!r}", n, "vertices")
            if n > size:  # every element takes at least one byte
                raise ValueError(
                    f"{source}: the PLY header announces {n:,} {name.decode(errors='replace')} elements "
                    f"but the file holds only {size:,} bytes (truncated or corrupt)"
                )
        return
    lines = [ln for ln in head.splitlines() if ln.strip() and not ln.lstrip().startswith(b"#")]
    text = b"\n".join(lines[:2])
    match = _OFF_COUNTS.search(text.replace(b"OFF", b"OFF ", 1))
    if match:
        vertices, faces = int(match.group(1)), int(match.group(2))
        check_count(source, "the OFF header", vertices, "vertices")
        check_count(source, "the OFF header", 3 * faces, "indices")
        if vertices + faces > size:
            raise ValueError(
                f"{source}: the OFF header announces {vertices:,} vertices and {faces:,} faces but the file holds "
                f"only {size:,} bytes (truncated or corrupt)"
            )


_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".tif", ".tiff", ".gif", ".webp", ".dds", ".ppm")
#: MTL statements naming texture maps that the OBJ reader does not import (only ``map_Kd`` is).
_UNREAD_MAPS = re.compile(
    r"^\s*(map_ka|map_ks|map_ns|map_d|map_bump|bump|disp|decal|refl|norm|map_pr|map_pm|map_ps|map_ke|map_aat)\s+(.+)$",
    re.IGNORECASE | re.MULTILINE,
)


class _PolicyResolver:
    """The files trimesh asks for (``mtllib``, texture maps), read under the path policy.

    Trimesh swallows every exception a resolver raises (an unreadable
    material just disappears), so refusals and drops are recorded here and
    reported by :meth:`finish` after the load: a refused path raises, a
    missing or unusable file warns (or raises when ``strict``).
    """

    def __init__(self, path: str, policy: PathPolicy, strict: bool) -> None:
        self.file_path = path
        self.file_name = os.path.basename(path)
        self.parent = os.path.dirname(os.path.abspath(path))
        self.policy = policy
        self.strict = strict
        self.refused: list[UntrustedReferenceError | ResourceLimitError] = []
        self.drops: list[str] = []

    def __getitem__(self, name: str) -> bytes:
        return self.get(name)

    def __contains__(self, name: str) -> bool:
        return False

    def keys(self) -> list[str]:
        return []

    def write(self, name: str, data: Any) -> None:  # pragma: no cover - loading never writes
        raise OSError("MeshFile: loading a mesh file never writes files")

    def namespaced(self, namespace: str) -> _PolicyResolver:
        return self

    def get(self, name: str) -> bytes:
        kind = "material library" if str(name).strip().lower().endswith(".mtl") else "texture"
        try:
            full = self.policy.resolve(name, self.file_path, f"the {kind}")
        except RemoteReferenceError as exc:
            self.drops.append(f"{kind} {name!r} dropped: {exc.reason}")
            raise OSError(exc.reason) from None
        except UntrustedReferenceError as exc:
            self.refused.append(exc)
            raise OSError(str(exc)) from None
        try:
            with open(full, "rb") as fh:
                data = fh.read()
        except OSError as exc:
            self.drops.append(f"{kind} {name!r} dropped: cannot read {os.fspath(full)!r} ({exc.strerror or exc})")
            raise
        if kind == "texture":
            self._check_image(name, data)
        else:
            self._note_unread_maps(name, data)
        return data

    def _check_image(self, name: str, data: bytes) -> None:
        from PIL import Image as PILImage

        try:
            import io
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                with PILImage.open(io.BytesIO(data)) as img:
                    width, height = img.size
        except Exception as exc:
            if type(exc).__name__ == "DecompressionBombError":  # Pillow refuses beyond twice its own limit
                message = f"texture {name!r} dropped: it is a decompression bomb ({exc}; see MAX_IMAGE_PIXELS)"
            else:
                message = f"texture {name!r} dropped: not a readable image ({type(exc).__name__})"
            self.drops.append(message)
            raise OSError(message) from None
        try:
            check_image_size(f"MeshFile {self.file_path!r}", f"the texture {name!r}", width, height)
        except ResourceLimitError as exc:
            self.drops.append(f"texture {name!r} dropped: {width}x{height} pixels is beyond the image limits ({exc})")
            raise OSError(str(exc)) from None

    def _note_unread_maps(self, name: str, data: bytes) -> None:
        text = data.decode("utf-8", errors="replace")
        for key, value in _UNREAD_MAPS.findall(text):
            self.drops.append(
                f"{key} {value.strip()!r} in material library {name!r} dropped: the OBJ reader imports only map_Kd "
                "(diffuse colour) textures"
            )

    def finish(self) -> None:
        """Raise the first refused reference; report every drop (warnings, or an error when strict)."""
        if self.refused:
            raise self.refused[0]
        drops, self.drops = self.drops, []
        for message in dict.fromkeys(drops):
            report_drop(f"MeshFile {self.file_path!r}", message, strict=self.strict, stacklevel=6)


def _parts(loaded: Any, path: str, strict: bool = False) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
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
            parts.append(_part(mesh, path, strict))
        except ValueError as exc:
            raise ValueError(f"MeshFile: {path} holds invalid geometry: {exc}") from None
    if not parts:
        raise ValueError(f"MeshFile: {path} contains no triangles (empty or not a mesh file)")
    return parts


def _part(mesh: Any, path: str = "", strict: bool = False) -> tuple[dict[str, Any] | None, TriangleSet]:
    _ply_face_colors(mesh)
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
        material = _material(getattr(visual, "material", None), path, strict)
        if material is not None and arrays["texcoords"] is None and material.pop("texture", None) is not None:
            report_drop(f"MeshFile {path}", "texture dropped: the mesh has no texture coordinates", strict=strict)
    return material, TriangleSet(**arrays)


def _ply_face_colors(mesh: Any) -> None:
    """Use a PLY file's per-face colours when its vertex colours are all the same.

    Many exporters write a default colour on every vertex beside the real
    colours of the faces; trimesh keeps the vertex colours and drops the
    faces', so the faces' colours were lost in every engine.
    """
    raw = (getattr(mesh, "metadata", None) or {}).get("_ply_raw")
    visual = getattr(mesh, "visual", None)
    if not raw or "face" not in raw or getattr(visual, "kind", None) != "vertex":
        return
    data = raw["face"].get("data")
    names = set(getattr(getattr(data, "dtype", None), "names", None) or ())
    if not {"red", "green", "blue"} <= names or len(data) != len(mesh.faces):
        return  # no face colours, or polygons split into more triangles than the file has faces
    if len(np.unique(np.asarray(visual.vertex_colors), axis=0)) > 1:
        return  # real vertex colours: they win, as in trimesh
    channels = [c for c in ("red", "green", "blue", "alpha") if c in names]
    fc = np.stack([np.asarray(data[c], np.float64).reshape(-1) for c in channels], -1)
    if np.asarray(data["red"]).dtype.kind == "f":
        fc = fc * 255.0  # float colours are in [0, 1]
    if len(np.unique(fc, axis=0)) < 2:
        return
    from trimesh.visual import ColorVisuals

    mesh.visual = ColorVisuals(mesh, face_colors=np.clip(np.round(fc), 0, 255).astype(np.uint8))


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


def _texture(image: Any, path: str, strict: bool) -> np.ndarray | None:
    if image is None:
        return None
    try:
        check_image_size(f"MeshFile {path}", "a texture", *map(int, image.size))
        return np.asarray(image.convert("RGBA"), dtype=np.uint8)
    except Exception as exc:
        name = getattr(image, "info", {}).get("file_path", "a texture")
        report_drop(
            f"MeshFile {path}",
            f"texture {name!r} dropped: cannot decode it ({type(exc).__name__}: {exc})",
            strict=strict,
        )
        return None


def _material(mat: Any, path: str = "", strict: bool = False) -> dict[str, Any] | None:
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
        tex = _texture(getattr(mat, "baseColorTexture", None), path, strict)
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
        tex = _texture(getattr(mat, "image", None), path, strict)
    else:
        return None
    if tex is not None:
        out["texture"] = tex
    return out


def _load_gltf(path: str, policy: PathPolicy, strict: bool) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
    """glTF through the full importer (materials, textures, Draco...), flattened to world-space parts."""
    from .gltf.reader import GLTFImportError, flatten_gltf

    try:
        flat = flatten_gltf(path, trusted=policy.trusted, allowed_roots=policy.allowed_roots, strict=strict)
    except GLTFImportError as exc:
        raise ValueError(f"MeshFile: {exc}") from None
    parts = [({"kind": "attributes", "attributes": attrs} if attrs else None, ts) for attrs, ts in flat]
    if not parts:
        raise ValueError(f"MeshFile: {path!r} contains no triangles (empty or not a mesh file)")
    return parts


# -- writing: a scene's surfaces as one mesh -----------------------------------------------------------
class MeshEngine(NodeTrackingEngine):
    """Collects world-space triangles with their linear base colour (RGBA in 0..1) in ``parts``."""

    service = "mesh.export"

    def __init__(self, *, on_missing: str = "raise", mask: Any = None) -> None:
        super().__init__(on_missing=on_missing, mask=mask)
        #: (vertices (N, 3), faces (K, 3), RGBA) per triangle set, in evaluation order
        self.parts: list[tuple[np.ndarray, np.ndarray, tuple[float, ...]]] = []
        #: shape class name -> node paths of shapes without a surface (left out)
        self.left_out: dict[str, list[str]] = {}


track_surfaces(MeshEngine)


@default_for(MeshEngine)
class TriangleSetCollector(ShapePainter):
    """A triangle set's world-space vertices and faces with its resolved base colour."""

    __slots__ = ()
    service = MeshEngine.service
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: MeshEngine) -> None:
        m = engine.model_matrix()
        vertices = shape.vertex_array().astype(np.float64) @ m[:3, :3].T + m[:3, 3]
        faces = np.asarray(shape.index_array(), dtype=np.int64).reshape(-1, 3)
        if np.linalg.det(m[:3, :3]) < 0:  # a mirroring transform: keep the faces facing out
            faces = faces[:, ::-1]
        from ..attributes.surface import engine_appearance

        appearance = engine_appearance(engine, texcoords=False)
        engine.parts.append((vertices, faces, (*appearance.base, appearance.alpha)))


class _NoSurface(ShapePainter):
    __slots__ = ()
    service = MeshEngine.service

    def exec(self, shape: Any, engine: MeshEngine) -> None:
        engine.left_out.setdefault(type(shape).__name__, []).append(engine.node_path or "/")


for _target in (LineSet, Polyline, PointSet):
    default_for(MeshEngine)(type(f"{_target.__name__}Skipper", (_NoSurface,), {"__slots__": (), "target": _target}))


def _srgb8(linear: np.ndarray) -> np.ndarray:
    from ..attributes.photometry import linear_to_srgb

    return np.clip(np.round(linear_to_srgb(np.clip(linear, 0.0, 1.0)) * 255.0), 0, 255).astype(np.uint8)


def export(scene: Any, path: str | os.PathLike[str], *, mask: str | None = None, on_missing: str = "raise") -> None:
    """Write the triangles of ``scene`` to ``path`` (.obj, .ply or .stl, by its extension) in world coordinates.

    Colours: each shape's base colour as vertex colours in sRGB (OBJ and PLY;
    STL has none).  Shapes without a surface (lines, points) are left out with
    a warning naming their nodes.
    """
    import trimesh

    target = Path(path)
    ext = target.suffix.lower()
    if ext not in MESH_EXTENSIONS:
        raise ValueError(f"mesh export: cannot write {target.name!r}; use one of {', '.join(MESH_EXTENSIONS)}")
    if not hasattr(scene, "preevaluate"):  # a list of components
        from ..scene import Node

        scene = Node("scene", list(scene))
    engine = MeshEngine(on_missing=on_missing, mask=mask)
    engine.run(scene)
    if engine.left_out:
        what = "; ".join(f"{name} in {', '.join(sorted(set(paths))[:3])}" for name, paths in engine.left_out.items())
        warnings.warn(f"mesh export {target.name}: shapes without a surface are left out ({what})", stacklevel=2)
    if not engine.parts:
        raise ValueError(f"mesh export {target.name}: the scene {scene.path} has no triangles to write")
    offsets = np.cumsum([0] + [len(v) for v, _, _ in engine.parts])
    vertices = np.concatenate([v for v, _, _ in engine.parts])
    faces = np.concatenate([f + offsets[i] for i, (_, f, _) in enumerate(engine.parts)])
    rgba = np.concatenate([np.repeat([c], len(v), axis=0) for v, _, c in engine.parts])
    colors = np.concatenate([_srgb8(rgba[:, :3]), np.clip(np.round(rgba[:, 3:] * 255), 0, 255).astype(np.uint8)], 1)
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, vertex_colors=colors, process=False)
    with atomic_path(target) as tmp:
        mesh.export(tmp, file_type=ext[1:])
