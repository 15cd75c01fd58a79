"""Scene readers by file extension: whole scenes from files other than omnirender's own scene files.

:mod:`omnirender.formats` registers its importers here (``.glb``/``.gltf``
through ``om.load_gltf``), and what loads a scene from a path
(``om.render_frames``, the command line) asks this table, so no lower layer
imports a file format.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

__all__ = ["register_scene_reader", "scene_reader", "scene_suffixes"]

_readers: dict[str, str | Callable[..., Any]] = {}


def register_scene_reader(suffixes: Iterable[str], reader: str | Callable[..., Any], *, override: bool = False) -> None:
    """Make files ending in ``suffixes`` load with ``reader(path) -> Node`` (a callable or ``"module:function"``)."""
    for suffix in suffixes:
        key = suffix.lower()
        if key in _readers and not override and _readers[key] != reader:
            raise ValueError(f"a scene reader for {key!r} is already registered; pass override=True")
        _readers[key] = reader


def scene_suffixes() -> tuple[str, ...]:
    """The extensions with a registered scene reader."""
    return tuple(_readers)


def scene_reader(path: str | os.PathLike[str]) -> Callable[..., Any] | None:
    """The reader registered for ``path``'s extension, or None."""
    reader = _readers.get(Path(os.fspath(path)).suffix.lower())
    if isinstance(reader, str):
        module, _, name = reader.partition(":")
        reader = getattr(importlib.import_module(module), name)
    return reader
