"""Mesh files (``.obj``, ``.ply``, ``.stl``): a scene's surfaces as one triangle mesh, written by trimesh.

:class:`MeshEngine` (service ``"mesh.export"``) evaluates the scene like the
other exporters (the camera's group mask, every shape through its simplifier,
an ``InstanceSet`` as its instances) and collects each triangle set in world
coordinates with its base colour (the appearance every engine resolves).  The
triangles are merged into one ``trimesh.Trimesh`` with per-vertex colours
(OBJ and PLY keep them; STL holds geometry only) and written atomically.
Lines, points and text have no surface: they are left out with one warning
naming them, never silently.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..core import ShapePainter, default_for
from ..fileio import atomic_path
from ..shapes import LineSet, PointSet, Polyline, TriangleSet
from .walk import NodeTrackingEngine, track_surfaces

__all__ = ["MeshEngine", "export", "MESH_EXTENSIONS"]

#: What :func:`export` writes (trimesh's writers).
MESH_EXTENSIONS = (".obj", ".ply", ".stl")


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
