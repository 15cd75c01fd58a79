"""A scene around one mesh: what ``omnirender view bunny.obj`` and ``omnirender render bunny.glb`` show.

Trimesh and PyVista users expect to point a viewer at a mesh file; a mesh
has no camera or lights, so :func:`mesh_scene` adds a camera fitted to the
mesh's bounds and the default key, fill and back lights placed for it.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..shapes.files import mesh_suffixes
from .node import Node

__all__ = ["mesh_scene", "staged", "mesh_suffixes"]


def mesh_scene(mesh: str | os.PathLike[str] | Any, aspect: float = 4 / 3, fill_shadows: bool = False) -> Node:
    """A scene holding ``mesh`` (a mesh file or a trimesh object), a fitted camera and default lights.

    The camera looks at the mesh's bounding box from the front, a little
    above and to the right, so that the whole mesh shows in an image of
    width / height ``aspect``.  The file is read here (to measure it): a
    malformed one raises ValueError naming it.  ``fill_shadows``: see :func:`staged`.
    """
    from ..shapes import MeshFile

    shape = MeshFile(mesh)
    shape.load()
    name = Path(os.fspath(mesh)).stem if isinstance(mesh, (str, os.PathLike)) else "mesh"
    return staged(Node(_node_name(name), [shape]), aspect, fill_shadows)


def staged(body: Node, aspect: float = 4 / 3, fill_shadows: bool = False) -> Node:
    """``body`` in a new root node with a camera fitted to it and the default key, fill and back lights
    (as :func:`mesh_scene` places them), unless ``body`` has a camera already; then ``body`` itself.

    The fill and back lights cast no shadows, unless ``fill_shadows`` (for path tracers, which cannot
    turn a light's shadows off and warn when a scene asks for it: the command line stages the lights
    for them with shadows, as they would draw them anyway).
    """
    from ..attributes.lights import default_lights
    from ..techniques import bounds

    if body.preevaluate()[1] is not None:
        return body
    box = bounds(body)
    if box is None:
        raise ValueError(f"{body.path} has no geometry to look at")
    camera = Camera.fit(box, aspect, direction=(0.45, 0.35, 1.0), margin=1.05)
    eye_to_world = np.linalg.inv(camera.view_matrix())
    lights = default_lights(eye_to_world) if not body.preevaluate()[0] else []
    if fill_shadows:
        for light in lights:
            light.casts_shadows = True
    return Node("scene", [camera, *lights, body])


def _node_name(stem: str) -> str:
    cleaned = "".join(ch if ch.isprintable() and ch != "/" else "_" for ch in stem)
    return cleaned or "mesh"
