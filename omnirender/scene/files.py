"""Scene files: a declarative JSON/YAML document mirroring the object model.

A document looks like this (JSON; YAML is the same structure; the full
reference is docs/scene-files.md, and :func:`json_schema` gives a JSON Schema
of every registered type)::

    {"format": "omnirender-scene", "version": 1,
     "root": {"node": "scene", "groups": [], "contents": [
        {"type": "Camera", "eye": [4, 3, 6], "center": [0, 0, 0], ...},
        {"type": "PointLight", "position": [5, 5, 5]},
        {"node": "body", "$id": "body", "contents": [
            {"type": "Translation", "offset": [0, 1, 0]},
            {"type": "povray.Finish", "phong": 0.8},
            {"type": "Torus", "major_radius": 1, "minor_radius": 0.3}]},
        {"$ref": "body"}]}}

* A **node** is ``{"node": NAME, "groups": [...], "contents": [...]}``
  (``groups`` and ``contents`` optional); contents keep their order.
* A **component** is ``{"type": TYPE, PARAM: VALUE, ...}`` with the keyword
  parameters of its constructor (what ``component.parameters()`` returns).
  Built-in types use their class name (``Sphere``, ``Material``, ``Camera``);
  engine-specific ones a qualified name (``povray.Finish``, ``gl.DepthTest``),
  resolved by importing ``omnirender.<prefix>`` only when a file uses it.
* Objects used more than once (shared nodes of a DAG, shared materials, lights
  listed in a ``LightSwitch``) are written in full once with ``"$id"`` and then
  as ``{"$ref": ID}``.  Deep graphs put nodes in a top-level ``definitions``
  list (entries with ``$id``, each defined before it is referred to), so
  documents stay shallow however deep the graph is.
* Values: numbers, strings, booleans, null, lists and components.  Small
  arrays are lists (``{"$array": [...], "dtype": "uint8"}`` for dtypes other
  than float64); large ones are ``{"$base64": ..., "dtype", "shape"}`` or, with
  ``om.save(..., arrays="npz")``, ``{"$file": "x.arrays.npz", "key": ...}`` in
  a side-car file (see :mod:`omnirender.scene.arrays`).  Data sequences
  (``om.data``) are written as their arrays.

**Loading never executes code and stays within limits**: JSON through
:mod:`json`, YAML through a safe loader (:mod:`omnirender.scene.parse`) that
refuses duplicate keys, runaway alias expansion and nesting beyond a limit;
types only from the registry (or ``omnirender``'s own subpackages).  Content
that could reach outside the file is refused unless the caller vouches for
the file with ``trusted=True`` (:class:`UntrustedContentError`): component
classes that declare ``scene_file_trusted_only = True`` (``povray.Raw``,
whose text goes verbatim into the renderer's input), and file paths (mesh
files, textures, side-car arrays) that are absolute or lead outside the scene
file's folder.  Unknown types and bad parameters raise
:class:`SceneFileError` (a ValueError) with the JSON path of the offending
element, e.g. ``root.contents[2].contents[1].radius: must be > 0, got -1.0
(Sphere)``.  Third-party components become loadable with :func:`register_type`.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ..fileio import atomic_path, atomic_write
from .node import Node
from .parse import LIMITS, ParseError, ParseLimits, parse_json, parse_yaml
from .reader import Reader
from .registry import (
    SceneFileError,
    UntrustedContentError,
    register_type,
    registered_types,
    type_name,
    unregister_type,
)
from .writer import FORMAT, VERSION, Writer, encode, json_text

__all__ = [
    "load",
    "save",
    "loads",
    "dumps",
    "register_type",
    "unregister_type",
    "registered_types",
    "type_name",
    "json_schema",
    "SceneFileError",
    "UntrustedContentError",
    "ParseLimits",
    "FORMAT",
    "VERSION",
]

_EXTENSIONS = {".json": "json", ".yaml": "yaml", ".yml": "yaml"}


# -- writing ----------------------------------------------------------------------
def _text(doc: dict[str, Any], fmt: str) -> str:
    if fmt == "json":
        return json_text(doc) + "\n"
    yaml = _yaml()
    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)  # libyaml's emitter when PyYAML has it
    return yaml.dump(doc, Dumper=dumper, sort_keys=False, default_flow_style=None, width=120, allow_unicode=True)


def dumps(
    scene: Node, fmt: str = "json", base_dir: str | os.PathLike[str] | None = None, *, arrays: str = "auto"
) -> str:
    """The scene as JSON or YAML text; paths are made relative to ``base_dir`` when given.

    ``arrays="auto"`` writes arrays of 1,024 elements or more as base64,
    ``"lists"`` writes every array as plain lists.
    """
    fmt = _check_format(fmt)
    if arrays == "npz":
        raise ValueError("dumps: arrays='npz' writes a side-car file; use om.save(scene, path, arrays='npz')")
    writer = Writer(None if base_dir is None else os.path.abspath(os.fspath(base_dir)), arrays)
    return _text(encode(scene, writer), fmt)


def save(scene: Node, path: str | os.PathLike[str], *, arrays: str = "auto") -> Path:
    """Write ``scene`` to ``path`` (``.json``, ``.yaml`` or ``.yml``) atomically; returns the path.

    ``arrays`` chooses how arrays of 1,024 elements or more are written:
    ``"auto"`` (base64 in the file), ``"lists"`` (plain numbers) or ``"npz"``
    (a side-car ``<name>.arrays.npz`` next to the file, loaded with
    :func:`numpy.load`).  Small arrays are always plain lists.  File paths are
    stored relative to the file; a warning says when some lead outside its
    folder (loading the file then needs ``trusted=True``).
    """
    target = Path(path)
    fmt = _format_of(target)
    sidecar = f"{target.stem}.arrays.npz"
    writer = Writer(os.fspath(target.resolve().parent), arrays, sidecar_name=sidecar if arrays == "npz" else None)
    text = _text(encode(scene, writer), fmt)
    if writer.sidecar:
        with atomic_path(target.with_name(sidecar)) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, **writer.sidecar)
    with atomic_write(target, "w") as fh:
        fh.write(text)
    if writer.outside:
        shown = ", ".join(repr(p) for p in writer.outside[:3]) + (", ..." if len(writer.outside) > 3 else "")
        warnings.warn(
            f"{target}: the scene names files outside the file's folder ({shown}); scene files from elsewhere "
            "may not do that, so loading it will need om.load(path, trusted=True) (omnirender: --trusted). "
            "Copy the files next to the scene file to make it self-contained",
            stacklevel=2,
        )
    return target


# -- reading ----------------------------------------------------------------------
def loads(
    text: str,
    fmt: str = "json",
    base_dir: str | os.PathLike[str] | None = None,
    *,
    source: str | None = None,
    trusted: bool = False,
    limits: ParseLimits = LIMITS,
    allowed_roots: Iterable[str | os.PathLike[str]] | None = None,
) -> Node:
    """Parse scene-file text; relative file paths are resolved against ``base_dir`` (cwd when None).

    ``trusted=True`` allows trusted-only components (``povray.Raw``) and file
    paths outside ``base_dir``; pass it only for files you wrote yourself.
    ``allowed_roots`` lists folders file paths may lead into besides
    ``base_dir`` (the path policy of :mod:`omnirender.core.paths`).
    ``limits`` bounds nesting depth and YAML alias expansion.
    """
    fmt = _check_format(fmt)
    if not isinstance(text, str):
        raise TypeError(f"loads: text must be a str, got {type(text).__name__}")
    where = source or "<scene text>"
    try:
        if fmt == "json":
            try:
                doc = parse_json(text, limits)
            except ValueError as exc:
                if isinstance(exc, ParseError):
                    raise
                line, col = getattr(exc, "lineno", None), getattr(exc, "colno", None)
                at = f" at line {line}, column {col}" if line is not None else ""
                reason = getattr(exc, "msg", str(exc))
                raise SceneFileError("", f"invalid JSON{at}: {reason}", where) from None
        else:
            yaml = _yaml()
            try:
                doc = parse_yaml(text, limits)
            except yaml.YAMLError as exc:
                raise SceneFileError("", f"invalid YAML: {' '.join(str(exc).split())}", where) from None
    except ParseError as exc:
        raise SceneFileError(exc.path, exc.reason, where) from None
    base = None if base_dir is None else os.path.abspath(os.fspath(base_dir))
    return Reader(base, source, trusted, limits, tuple(allowed_roots or ())).document(doc)


def load(
    path: str | os.PathLike[str],
    *,
    trusted: bool = False,
    limits: ParseLimits = LIMITS,
    allowed_roots: Iterable[str | os.PathLike[str]] | None = None,
) -> Node:
    """Read a scene file (``.json``, ``.yaml``, ``.yml``) and return its root node.

    ``trusted=True`` allows trusted-only components such as ``povray.Raw``
    (hand-written SDL) and file paths outside the file's folder; without it
    they are refused with an :class:`UntrustedContentError`.  File paths obey
    the path policy of :mod:`omnirender.core.paths`: inside the file's folder
    or one of ``allowed_roots``.  Mesh files the scene names read their own
    references (materials, textures) under the same policy.
    """
    target = Path(path)
    fmt = _format_of(target)
    try:
        text = target.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"scene file {str(target)!r} does not exist") from None
    except IsADirectoryError:
        raise IsADirectoryError(f"{str(target)!r} is a folder, not a scene file") from None
    except UnicodeDecodeError as exc:
        byte = exc.object[exc.start : exc.start + 1].hex()
        raise SceneFileError(
            "",
            f"not a UTF-8 text file (byte 0x{byte} at offset {exc.start}); scene files are UTF-8 JSON or YAML",
            str(target),
        ) from None
    return loads(
        text,
        fmt,
        base_dir=target.resolve().parent,
        source=str(target),
        trusted=trusted,
        limits=limits,
        allowed_roots=allowed_roots,
    )


def json_schema() -> dict[str, Any]:
    """A JSON Schema (draft 2020-12) of scene files with every registered type (see :mod:`.schema`)."""
    from .schema import json_schema as build

    return build()


# -- helpers ----------------------------------------------------------------------
def _check_format(fmt: str) -> str:
    if fmt not in ("json", "yaml"):
        raise ValueError(f"scene file format must be 'json' or 'yaml', got {fmt!r}")
    return fmt


def _format_of(path: Path) -> str:
    fmt = _EXTENSIONS.get(path.suffix.lower())
    if fmt is None:
        raise ValueError(f"{str(path)!r}: unknown scene file extension {path.suffix!r} (use .json, .yaml or .yml)")
    return fmt


def _yaml() -> Any:
    try:
        import yaml
    except ImportError:  # pragma: no cover - pyyaml is in the 'files' extra
        raise RuntimeError("YAML scene files need PyYAML: pip install 'omnirender[files]'") from None
    return yaml
