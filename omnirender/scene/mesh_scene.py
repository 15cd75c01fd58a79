"""A scene around one mesh: what ``omnirender view bunny.obj`` and ``omnirender render bunny.glb`` show.

Trimesh and PyVista users expect to point a viewer at a mesh file; a mesh
has no camera or lights, so :func:`mesh_scene` adds a camera fitted to the
mesh's bounds and the default key, fill and back lights placed for it.  A
glTF file with a camera is shown as ``om.load_gltf`` reads it: through its
camera, lit by its lights (or by the default lights placed for that camera).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..shapes.files import mesh_suffixes
from .node import Node

__all__ = ["mesh_scene", "mesh_suffixes", "framed", "staged_lights"]


def mesh_scene(
    mesh: str | os.PathLike[str] | Any,
    aspect: float = 4 / 3,
    fill_shadows: bool = False,
    *,
    trusted: bool = False,
    allowed_roots: Iterable[str | os.PathLike[str]] | None = None,
    strict: bool = False,
) -> Node:
    """A scene holding ``mesh`` (a mesh file or a trimesh object), a fitted camera and default lights.

    The camera looks at the mesh's bounding box from the front, a little
    above and to the right, so that the whole mesh shows in an image of
    width / height ``aspect``.  The file is read here (to measure it): a
    malformed one raises ValueError naming it.  ``fill_shadows``: see :func:`staged_lights`.
    ``trusted``, ``allowed_roots`` and ``strict`` are :class:`~omnirender.shapes.MeshFile`'s (the path
    policy for the file's references, warnings as errors).
    """
    from ..shapes import MeshFile
    from ..techniques import bounds

    if isinstance(mesh, (str, os.PathLike)) and str(mesh).lower().endswith((".glb", ".gltf")):
        kept = _gltf_scene(mesh, fill_shadows, trusted=trusted, allowed_roots=allowed_roots, strict=strict)
        if kept is not None:
            return kept
    shape = MeshFile(mesh, trusted=trusted, allowed_roots=allowed_roots, strict=strict)
    shape.load()
    name = Path(os.fspath(mesh)).stem if isinstance(mesh, (str, os.PathLike)) else "mesh"
    body = Node(_node_name(name), [shape])
    box = bounds(body)
    if box is None:  # pragma: no cover - load() refuses meshes without triangles
        raise ValueError(f"mesh_scene: {mesh!r} has no geometry to look at")
    camera = Camera.fit(box, aspect, direction=(0.45, 0.35, 1.0), margin=1.05)
    eye_to_world = np.linalg.inv(camera.view_matrix())
    return Node("scene", [camera, *staged_lights(eye_to_world, fill_shadows), body])


def staged_lights(eye_to_world: np.ndarray, fill_shadows: bool = False) -> list[Any]:
    """The default key, fill and back lights placed for a camera (``eye_to_world``).

    The fill and back lights cast no shadows, unless ``fill_shadows``: path tracers cannot turn a
    light's shadows off and warn when a scene asks for it, so the command line stages the lights for
    them with shadows, as they would draw them anyway (the user asked for nothing).
    """
    from ..attributes.lights import default_lights

    lights = default_lights(eye_to_world)
    if fill_shadows:
        for light in lights:
            light.casts_shadows = True
    return lights


def _gltf_scene(path: str | os.PathLike[str], fill_shadows: bool = False, **policy: Any) -> Node | None:
    """A glTF file with a camera as ``om.load_gltf`` reads it: its camera, its lights (default lights placed
    for its camera when it has none); None when it has no camera (then it is framed like any mesh)."""
    from .readers import scene_reader

    load_gltf = scene_reader(path)  # the registered glTF importer (formats/ registers it)
    if load_gltf is None:
        return None
    scene = load_gltf(path, animation=None, **policy)  # trusted, allowed_roots, strict
    declared = scene.declarations()
    if declared.camera is None:
        return None
    if declared.lights:
        return scene
    camera, world = declared.camera
    eye_to_world = np.asarray(world, np.float64) @ np.linalg.inv(camera.view_matrix())
    return Node("scene", [*staged_lights(eye_to_world, fill_shadows), scene])


def framed(scene: Node, aspect: float = 4 / 3, fill_shadows: bool = False) -> Node:
    """``scene`` as the command line shows a file: its own camera and lights, else a camera fitted to its
    bounds (as :func:`mesh_scene` places it) and default lights placed for the camera (``fill_shadows``: see
    :func:`staged_lights`)."""
    from ..techniques import bounds

    declared = scene.declarations()
    if declared.camera is not None and declared.lights:
        return scene
    if declared.camera is None:
        box = bounds(scene)
        if box is None:
            raise ValueError(f"{scene.name}: nothing to look at")
        camera = Camera.fit(box, aspect, direction=(0.45, 0.35, 1.0), margin=1.05)
        eye_to_world = np.linalg.inv(camera.view_matrix())
        lights = [] if declared.lights else staged_lights(eye_to_world, fill_shadows)
        return Node("scene", [camera, *lights, scene])
    camera, world = declared.camera
    eye_to_world = np.asarray(world, np.float64) @ np.linalg.inv(camera.view_matrix())
    return Node("scene", [*staged_lights(eye_to_world, fill_shadows), scene])


def _node_name(stem: str) -> str:
    cleaned = "".join(ch if ch.isprintable() and ch != "/" else "_" for ch in stem)
    return cleaned or "mesh"
