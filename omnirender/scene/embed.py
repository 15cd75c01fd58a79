"""A copy of a scene that carries its files' contents: for workers without the files.

Pickled scenes keep mesh and texture *paths* (the files are read where the
scene is rendered), so worker processes on other machines need the files at
the same paths or a shared folder.  :func:`embed_files` is the alternative: a
deep copy in which every ``om.MeshFile`` is replaced by the shapes its
simplifier makes (triangle sets with their materials and textures) and every
``om.Texture`` read from a file holds the pixels instead.
"""

from __future__ import annotations

import copy
from typing import Any

from ..core.engine import Engine
from ..core.handler import SIMPLIFY
from .node import Node

__all__ = ["embed_files"]


def embed_files(scene: Node) -> Node:
    """A deep copy of ``scene`` whose mesh files and texture images are held in memory (see the module docs).

    The user's graph is not changed.  Pickles of the copy are larger (they hold
    the triangles) but render anywhere.
    """
    if not isinstance(scene, Node):
        raise TypeError(f"embed_files: scene must be an om.Node, got {type(scene).__name__}")
    from ..attributes import Texture
    from ..shapes import MeshFile

    result = copy.deepcopy(scene)
    engine = Engine()
    for node in list(result.walk()):
        for item in list(node.items):
            if isinstance(item, MeshFile):
                simplifier = engine.find_handler(SIMPLIFY, MeshFile)
                try:
                    parts = list(simplifier.exec(item, engine))
                except (OSError, ValueError) as exc:
                    raise type(exc)(f"embed_files: {exc} (MeshFile in node {node.path})") from None
                _replace(node, item, parts)
            elif isinstance(item, Texture) and item.path is not None:
                try:
                    pixels = item.image_array()
                except (OSError, ValueError) as exc:
                    raise type(exc)(f"embed_files: {exc} (Texture in node {node.path})") from None
                embedded = Texture(pixels, wrap=item.wrap, filter=item.filter, mipmap=item.mipmap)
                _replace(node, item, [embedded])
    return result


def _replace(node: Node, old: Any, new: list[Any]) -> None:
    """Put the items ``new`` where ``old`` is in ``node``."""
    at = next(i for i, existing in enumerate(node.items) if existing is old)
    node.remove(old)
    for offset, item in enumerate(new):
        node.insert(at + offset, item)
