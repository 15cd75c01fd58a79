"""Writing scene files: a graph to the document of :mod:`omnirender.scene.files`.

Two passes, both without recursion over the graph: the first counts how often
each node and component is reached (shared ones get an ``$id``) and measures
each node's *height* (node levels below it); the second encodes.  Nodes whose
height is a positive multiple of :data:`DEFINITION_DEPTH` are written once in the
document's ``definitions`` list (lowest first) and referred to with ``$ref``, so
a document never nests more than about ``2 * DEFINITION_DEPTH`` levels however
deep the graph is: a chain of 100,000 nodes saves and loads like a flat list.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..core.component import RenderingComponent
from .arrays import COMPACT_MIN_SIZE, encode_base64
from .node import Node
from .registry import _MARKERS, _registry, type_name

__all__ = ["encode", "json_text", "DEFINITION_DEPTH", "ARRAY_FORMS", "FORMAT", "VERSION"]

FORMAT = "omnirender-scene"
VERSION = 1
#: Node levels written nested before a deeper node becomes a definition.
DEFINITION_DEPTH = 32
#: How ``om.save`` writes large arrays (see :mod:`omnirender.scene.arrays`).
ARRAY_FORMS = ("auto", "lists", "npz")


class Writer:
    """Encodes one graph; ``outside`` lists file paths that leave ``base_dir``, ``sidecar`` the npz arrays."""

    def __init__(self, base_dir: str | None, arrays: str = "auto", sidecar_name: str | None = None) -> None:
        if arrays not in ARRAY_FORMS:
            raise ValueError(f"save: arrays must be one of {ARRAY_FORMS}, got {arrays!r}")
        if arrays == "npz" and sidecar_name is None:
            raise ValueError(
                "save: arrays='npz' writes a side-car file next to the scene file; use om.save(scene, path)"
            )
        self.base_dir = base_dir
        self.arrays = arrays
        self.sidecar_name = sidecar_name
        self.sidecar: dict[str, np.ndarray] = {}
        self.outside: list[str] = []
        self.counts: dict[int, int] = {}
        self.heights: dict[int, int] = {}
        self.ids: dict[int, str] = {}
        self.written: set[int] = set()
        self.used_ids: set[str] = set()
        self.keep: list[Any] = []  # keep objects alive so id() stays unique

    # pass 1: how often is each node / component reached, and how high is each node?
    def count(self, root: Node) -> list[Node]:
        """Count references; returns the nodes to write as definitions, lowest first."""
        state: dict[int, bool] = {}  # False: entered (on the current path), True: finished
        stack: list[tuple[Any, bool]] = [(root, False)]
        heights = self.heights
        while stack:
            obj, done = stack.pop()
            key = id(obj)
            if done:
                state[key] = True
                if isinstance(obj, Node):
                    h = -1
                    for item in obj._items:
                        if isinstance(item, Node):
                            h = max(h, heights[id(item)])
                    heights[key] = h + 1
                continue
            self.counts[key] = self.counts.get(key, 0) + 1
            entered = state.get(key)
            if entered is False and isinstance(obj, Node):
                raise ValueError(f"cannot save node {obj.path!r}: the graph has a cycle")
            if entered is not None:
                continue
            state[key] = False
            self.keep.append(obj)
            stack.append((obj, True))
            children = obj._items if isinstance(obj, Node) else _references(obj.parameters())
            for child in reversed(children):
                stack.append((child, False))
        cuts = [
            n
            for n in self.keep
            if isinstance(n, Node) and n is not root and heights[id(n)] and heights[id(n)] % DEFINITION_DEPTH == 0
        ]
        cuts.sort(key=lambda n: heights[id(n)])
        for node in cuts:
            self.ids[id(node)] = self._id_for(node)
        return cuts

    def _id_for(self, obj: Any) -> str:
        base = obj.name if isinstance(obj, Node) else type(obj).__name__.lower()
        candidate = base if isinstance(obj, Node) else f"{base}-1"
        k = 1
        while candidate in self.used_ids:
            k += 1
            candidate = f"{base}-{k}"
        self.used_ids.add(candidate)
        return candidate

    def _shared(self, obj: Any) -> dict[str, Any] | None:
        """``{"$ref": id}`` when already written; else registers an id if shared and returns None."""
        key = id(obj)
        if key in self.written:
            return {"$ref": self.ids[key]}
        self.written.add(key)
        if self.counts.get(key, 1) > 1 and key not in self.ids:
            self.ids[key] = self._id_for(obj)
        return None

    # pass 2: encode
    def node(self, node: Node) -> dict[str, Any]:
        key = id(node)
        ref = self._shared(node)
        if ref is not None:
            return ref
        out: dict[str, Any] = {"node": node.name}
        if key in self.ids:
            out["$id"] = self.ids[key]
        if node.groups:
            out["groups"] = sorted(node.groups)
        out["contents"] = [self.item(item) for item in node._items]
        return out

    def item(self, item: Any) -> dict[str, Any]:
        if isinstance(item, Node):
            return self.node(item)
        return self.component(item)

    def component(self, comp: RenderingComponent) -> dict[str, Any]:
        ref = self._shared(comp)
        if ref is not None:
            return ref
        name = type_name(type(comp))
        out: dict[str, Any] = {"type": name}
        if id(comp) in self.ids:
            out["$id"] = self.ids[id(comp)]
        path_params = _registry.paths.get(name, ())
        for key, value in comp.parameters().items():
            if key in ("type", "$id", "$ref"):
                raise ValueError(f"cannot save {name}: its parameter name {key!r} is reserved in scene files")
            if key in path_params and isinstance(value, (str, os.PathLike)):
                out[key] = self.path(value)
            else:
                out[key] = self.value(value, f"{name}.{key}")
        return out

    def path(self, value: str | os.PathLike[str]) -> str:
        text = os.fspath(value)
        if self.base_dir is None:
            return Path(text).as_posix()
        rel = os.path.relpath(os.path.abspath(text), self.base_dir)
        if rel == ".." or rel.startswith(".." + os.sep) or os.path.isabs(rel):
            self.outside.append(text)
        return Path(rel).as_posix()

    def value(self, value: Any, where: str) -> Any:
        if value is None or isinstance(value, (bool, str)):
            return value
        if isinstance(value, (int, np.integer)) and not isinstance(value, np.bool_):
            return int(value)
        if isinstance(value, np.bool_):
            return bool(value)
        if isinstance(value, (float, np.floating)):
            x = float(value)
            if not math.isfinite(x):
                raise ValueError(f"cannot save {where}: {x} is not a finite number")
            return x
        if isinstance(value, (RenderingComponent, Node)):
            return self.item(value)
        if isinstance(value, np.ndarray):
            return self.array(value, where)
        if isinstance(value, (list, tuple)):
            return [self.value(v, where) for v in value]
        if isinstance(value, dict):
            data = {str(k): self.value(v, where) for k, v in value.items()}
            # plain data (e.g. a Mitsuba plugin dict with a "type" key) must not read back as a component
            return {"$dict": data} if _MARKERS & data.keys() else data
        if isinstance(value, os.PathLike):
            return os.fspath(value)
        if hasattr(value, "array") and callable(value.array):  # om.data sequences
            return self.array(np.asarray(value.array()), where)
        if callable(value):
            raise ValueError(
                f"cannot save {where}: {getattr(value, '__qualname__', value)!r} is Python code, and scene files "
                "hold data only; use data tracks (om.Keyframes, om.Orbit) or add the callable after loading"
            )
        raise ValueError(f"cannot save {where}: values of type {type(value).__name__} have no scene-file form")

    def array(self, arr: np.ndarray, where: str) -> Any:
        if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
            raise ValueError(f"cannot save {where}: the array holds non-finite numbers")
        if arr.dtype.kind not in "biuf":
            raise ValueError(f"cannot save {where}: arrays of dtype {arr.dtype} have no scene-file form")
        if arr.size >= COMPACT_MIN_SIZE and self.arrays != "lists":
            if self.arrays == "npz":
                key = f"array-{len(self.sidecar)}"
                self.sidecar[key] = np.ascontiguousarray(arr)
                return {"$file": self.sidecar_name, "key": key}
            return encode_base64(arr)
        data = arr.tolist()
        if arr.dtype == np.float64:
            return data
        return {"$array": data, "dtype": arr.dtype.name}


def _references(value: Any) -> list[Any]:
    """The components and nodes inside a parameter value (lists, tuples and dicts searched)."""
    found: list[Any] = []
    stack = [value]
    while stack:
        v = stack.pop()
        if isinstance(v, (RenderingComponent, Node)):
            found.append(v)
        elif isinstance(v, (list, tuple)):
            if v and isinstance(v[0], (int, float)):
                continue  # numbers
            stack.extend(reversed(v))
        elif isinstance(v, dict):
            stack.extend(reversed(list(v.values())))
    return found


def encode(scene: Node, writer: Writer) -> dict[str, Any]:
    """The document of ``scene`` (see the module docs)."""
    if not isinstance(scene, Node):
        raise TypeError(f"save: the scene must be an om.Node, got {type(scene).__name__}")
    cuts = writer.count(scene)
    doc: dict[str, Any] = {"format": FORMAT, "version": VERSION}
    if cuts:
        doc["definitions"] = [writer.node(node) for node in cuts]
    doc["root"] = writer.node(scene)
    return doc


def _scalar(value: Any) -> bool:
    return not isinstance(value, (dict, list))


def json_text(value: Any, indent: int = 0) -> str:
    """JSON with short or purely numeric lists on one line (readable vertex arrays)."""
    pad = "  " * (indent + 1)
    end = "  " * indent
    if isinstance(value, dict):
        if not value:
            return "{}"
        if all(_scalar(v) or (isinstance(v, list) and all(_scalar(x) for x in v)) for v in value.values()):
            flat = json.dumps(value, allow_nan=False)
            if len(flat) <= 80:
                return flat
        items = [f"{pad}{json.dumps(k)}: {json_text(v, indent + 1)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + end + "}"
    if isinstance(value, list):
        if not value:
            return "[]"
        if all(not isinstance(v, (dict, list)) for v in value):
            return json.dumps(value, allow_nan=False)
        if all(isinstance(v, list) and all(not isinstance(x, (dict, list)) for x in v) for v in value):
            flat = json.dumps(value, allow_nan=False)
            if len(flat) <= 100:
                return flat
        items = [f"{pad}{json_text(v, indent + 1)}" for v in value]
        return "[\n" + ",\n".join(items) + "\n" + end + "]"
    return json.dumps(value, allow_nan=False)
