"""A scene around one mesh: what ``omnirender view bunny.obj`` and ``omnirender render bunny.glb`` show.

Trimesh and PyVista users expect to point a viewer at a mesh file; a mesh
has no camera or lights, so :func:`mesh_scene` adds a camera fitted to the
mesh's bounds and the default key, fill and back lights placed for it.
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

__all__ = ["mesh_scene", "mesh_suffixes"]


def mesh_scene(
    mesh: str | os.PathLike[str] | Any,
    aspect: float = 4 / 3,
    *,
    trusted: bool = False,
    allowed_roots: Iterable[str | os.PathLike[str]] | None = None,
    strict: bool = False,
) -> Node:
    """A scene holding ``mesh`` (a mesh file or a trimesh object), a fitted camera and default lights.

    The camera looks at the mesh's bounding box from the front, a little
    above and to the right, so that the whole mesh shows in an image of
    width / height ``aspect``.  The file is read here (to measure it): a
    malformed one raises ValueError naming it.  ``trusted``, ``allowed_roots``
    and ``strict`` are :class:`~omnirender.shapes.MeshFile`'s (the path
    policy for the file's references, warnings as errors).
    """
    from ..attributes.lights import default_lights
    from ..shapes import MeshFile
    from ..techniques import bounds

    shape = MeshFile(mesh, trusted=trusted, allowed_roots=allowed_roots, strict=strict)
    shape.load()
    name = Path(os.fspath(mesh)).stem if isinstance(mesh, (str, os.PathLike)) else "mesh"
    body = Node(_node_name(name), [shape])
    box = bounds(body)
    if box is None:  # pragma: no cover - load() refuses meshes without triangles
        raise ValueError(f"mesh_scene: {mesh!r} has no geometry to look at")
    camera = Camera.fit(box, aspect, direction=(0.45, 0.35, 1.0), margin=1.05)
    eye_to_world = np.linalg.inv(camera.view_matrix())
    return Node("scene", [camera, *default_lights(eye_to_world), body])


def _node_name(stem: str) -> str:
    cleaned = "".join(ch if ch.isprintable() and ch != "/" else "_" for ch in stem)
    return cleaned or "mesh"
