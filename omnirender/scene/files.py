"""Scene files: a declarative JSON/YAML document mirroring the object model.

A document looks like this (JSON; YAML is the same structure)::

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
  as ``{"$ref": ID}``.
* Values: numbers, strings, booleans, null, lists (numpy arrays become nested
  lists; arrays of a dtype other than float64 are written as
  ``{"$array": [...], "dtype": "uint8"}`` so they come back bit for bit), and
  components.  Data sequences (``om.data``) are written as their arrays.
  Paths of mesh files and texture images are stored relative to the scene
  file's folder and resolved against it on loading.

Loading never executes code: JSON through :mod:`json`, YAML through
``yaml.safe_load``, types only from the registry (or ``omnirender``'s own
subpackages).  Component classes that declare ``scene_file_trusted_only =
True`` (``povray.Raw``, whose text goes verbatim into the renderer's input)
are refused unless the caller vouches for the file with ``trusted=True``: a
scene file from elsewhere cannot smuggle renderer directives.  Dict parameters
whose keys look like entries (``type``, ``node``, ``$ref``...), such as Mitsuba
plugin dicts, are written as ``{"$dict": {...}}`` so they load back as data.
Unknown types and bad parameters raise :class:`SceneFileError` (a ValueError)
with the JSON path of the offending element, e.g.
``root.contents[2].contents[1].radius: must be > 0, got -1.0 (Sphere)``.
Third-party components become loadable with :func:`register_type`.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import json
import math
import os
import re
import threading
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ..core.component import Attribute, MonoAttribute, PolyAttribute, RenderingComponent, Shape
from ..core.handler import (
    AttributePainter,
    AttributeSimplifier,
    Handler,
    RayIntersector,
    ShapePainter,
    ShapeSimplifier,
)
from ..core.light import Light
from ..core.transform import Transform
from ..fileio import atomic_write
from .node import Node

__all__ = [
    "load",
    "save",
    "loads",
    "dumps",
    "register_type",
    "unregister_type",
    "registered_types",
    "type_name",
    "SceneFileError",
    "FORMAT",
    "VERSION",
]

FORMAT = "omnirender-scene"
VERSION = 1
_EXTENSIONS = {".json": "json", ".yaml": "yaml", ".yml": "yaml"}
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")

# Abstract bases that are exported but never placed in a scene.
_ABSTRACT = {
    RenderingComponent,
    Shape,
    Attribute,
    MonoAttribute,
    PolyAttribute,
    Handler,
    ShapePainter,
    ShapeSimplifier,
    AttributePainter,
    AttributeSimplifier,
    RayIntersector,
    Transform,
    Light,
}
_ABSTRACT_NAMES = {"DeclaredShape", "LightSource"}
_BUILTIN_MODULES = ("omnirender.core", "omnirender.shapes", "omnirender.attributes")
# Parameters holding file paths, stored relative to the scene file.
_BUILTIN_PATHS = {"MeshFile": ("path",), "Texture": ("image",)}
# Keys that make a dict read as an entry or special value; dicts holding one are wrapped in {"$dict": ...}.
_MARKERS = frozenset({"type", "node", "$ref", "$id", "$array", "$dict"})


def _build_translation(offset: Any = (0.0, 0.0, 0.0)) -> Any:
    from ..core.transform import Translation

    return Translation(offset)


def _build_scaling(factors: Any = (1.0, 1.0, 1.0)) -> Any:
    from ..core.transform import Scaling

    return Scaling(factors)


# Types whose parameters() keywords differ from their constructor's: build from parameters().
_BUILTIN_BUILDERS: dict[str, Callable[..., Any]] = {"Translation": _build_translation, "Scaling": _build_scaling}


class SceneFileError(ValueError):
    """A malformed scene file: ``path`` is the JSON path of the offending element."""

    def __init__(self, path: str, message: str, source: str | None = None) -> None:
        self.path = path
        self.reason = message
        self.source = source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{path}: {message}" if path else f"{where}{message}")


# -- the type registry ------------------------------------------------------------
class _Registry:
    """Type names <-> classes, with the module that registered each and its path parameters."""

    def __init__(self) -> None:
        self.by_name: dict[str, type] = {}
        self.by_class: dict[type, str] = {}
        self.origin: dict[str, str] = {}
        self.paths: dict[str, tuple[str, ...]] = {}
        self.builders: dict[str, Callable[..., Any]] = {}
        self.builtins_done = False
        self.lock = threading.RLock()

    def ensure_builtins(self) -> None:
        if self.builtins_done:
            return
        with self.lock:
            if self.builtins_done:
                return
            self.builtins_done = True
            for module_name in _BUILTIN_MODULES:
                module = importlib.import_module(module_name)
                for name in getattr(module, "__all__", ()):
                    cls = getattr(module, name, None)
                    if _is_concrete_component(cls) and name not in self.by_name:
                        self.add(name, cls, override=False, paths=_BUILTIN_PATHS.get(name, ()), origin=module_name)
            for name, build in _BUILTIN_BUILDERS.items():
                self.builders.setdefault(name, build)

    def add(
        self,
        name: str,
        cls: type,
        *,
        override: bool,
        paths: Iterable[str],
        origin: str,
        build: Callable[..., Any] | None = None,
    ) -> None:
        existing = self.by_name.get(name)
        if existing is not None and existing is not cls and not override:
            raise ValueError(
                f"register_type: the scene-file type {name!r} is already {existing.__module__}."
                f"{existing.__qualname__} (registered by {self.origin[name]}); pass override=True to replace it"
            )
        if existing is not None and existing is not cls:
            self.by_class.pop(existing, None)
        self.by_name[name] = cls
        self.by_class.setdefault(cls, name)
        self.origin[name] = origin
        self.paths[name] = tuple(paths)
        if build is None:
            self.builders.pop(name, None)
        else:
            self.builders[name] = build


_registry = _Registry()


def _is_concrete_component(cls: Any) -> bool:
    return (
        isinstance(cls, type)
        and issubclass(cls, RenderingComponent)
        and cls not in _ABSTRACT
        and cls.__name__ not in _ABSTRACT_NAMES
        and not cls.__name__.startswith("_")
    )


def register_type(
    name: str,
    cls: type,
    *,
    override: bool = False,
    paths: Iterable[str] = (),
    build: Callable[..., Any] | None = None,
) -> type:
    """Make components of ``cls`` loadable and savable under the type name ``name``.

    Engine-specific types use a qualified name (``"povray.Finish"``).  ``paths``
    names parameters that hold file paths (stored relative to the scene file).
    Components are saved with ``parameters()`` and rebuilt with
    ``cls(**params)``; give ``build`` (a callable taking the ``parameters()``
    keywords) when the constructor's keywords differ.
    Registering a taken name for another class raises ValueError unless
    ``override=True``.  Returns ``cls`` (usable as a decorator's body).
    """
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise ValueError(f"register_type: {name!r} is not a valid type name (dotted identifiers, e.g. 'povray.Finish')")
    if not (isinstance(cls, type) and issubclass(cls, RenderingComponent)):
        raise ValueError(f"register_type: {cls!r} is not a RenderingComponent class")
    _registry.ensure_builtins()
    frame = inspect.currentframe()
    caller = frame.f_back.f_globals.get("__name__", "?") if frame and frame.f_back else "?"
    with _registry.lock:
        _registry.add(name, cls, override=override, paths=paths, origin=caller, build=build)
    return cls


def unregister_type(name: str) -> None:
    """Forget the type name ``name`` (for tests and plug-ins that unload)."""
    with _registry.lock:
        cls = _registry.by_name.pop(name, None)
        if cls is None:
            raise KeyError(f"unregister_type: no scene-file type named {name!r}")
        if _registry.by_class.get(cls) == name:
            del _registry.by_class[cls]
            for other, klass in _registry.by_name.items():
                if klass is cls:
                    _registry.by_class[cls] = other
                    break
        _registry.origin.pop(name, None)
        _registry.paths.pop(name, None)
        _registry.builders.pop(name, None)


def registered_types() -> dict[str, type]:
    """Every registered type name and its class (built-ins included)."""
    _registry.ensure_builtins()
    return dict(_registry.by_name)


def type_name(cls: type) -> str:
    """The scene-file type name of ``cls`` (registered, or ``<subpackage>.<Class>`` for omnirender adapters)."""
    _registry.ensure_builtins()
    name = _registry.by_class.get(cls)
    if name is not None:
        return name
    module = cls.__module__
    parts = module.split(".")
    if len(parts) >= 2 and parts[0] == "omnirender":
        qualified = f"{parts[1]}.{cls.__name__}"
        try:
            if _resolve(qualified, "") is cls:
                return qualified
        except SceneFileError:
            pass
    raise ValueError(
        f"cannot save a {module}.{cls.__qualname__}: its type has no scene-file name; "
        f"call om.register_type('<name>', {cls.__name__}) first"
    )


def _resolve(name: str, where: str) -> type:
    """The class of type name ``name``; qualified names import ``omnirender.<prefix>`` on demand."""
    _registry.ensure_builtins()
    cls = _registry.by_name.get(name)
    if cls is not None:
        return cls
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise SceneFileError(where, f"invalid type name {name!r}")
    if "." in name:
        prefix, _, attr = name.rpartition(".")
        module_name = f"omnirender.{prefix}"
        try:
            spec = importlib.util.find_spec(module_name)
        except (ImportError, ValueError):
            spec = None
        if spec is None:
            raise SceneFileError(
                where, f"unknown type {name!r}: there is no omnirender package {prefix!r} (known: {_known()})"
            )
        try:
            module = importlib.import_module(module_name)
        except Exception as exc:
            raise SceneFileError(where, f"type {name!r} needs {module_name}, which failed to import: {exc}") from None
        cls = _registry.by_name.get(name)  # the adapter may have registered it on import
        if cls is None:
            candidate = getattr(module, attr, None)
            if _is_concrete_component(candidate):
                cls = candidate
                with _registry.lock:
                    _registry.add(name, cls, override=False, paths=(), origin=module_name)
        if cls is not None:
            return cls
        raise SceneFileError(where, f"unknown type {name!r}: {module_name} defines no component {attr!r}")
    raise SceneFileError(where, f"unknown type {name!r} (known: {_known()}; register others with om.register_type)")


def _known() -> str:
    names = sorted(n for n in _registry.by_name if "." not in n)
    return ", ".join(names[:12]) + (", ..." if len(names) > 12 else "")


# -- writing ----------------------------------------------------------------------
class _Writer:
    def __init__(self, base_dir: str | None) -> None:
        self.base_dir = base_dir
        self.counts: dict[int, int] = {}
        self.ids: dict[int, str] = {}
        self.written: set[int] = set()
        self.used_ids: set[str] = set()
        self.keep: list[Any] = []  # keep objects alive so id() stays unique

    # pass 1: how often is each node / component reached?
    def count(self, obj: Any, active: set[int]) -> None:
        key = id(obj)
        self.keep.append(obj)
        seen = key in self.counts
        self.counts[key] = self.counts.get(key, 0) + 1
        if seen:
            return
        if isinstance(obj, Node):
            if key in active:
                raise ValueError(f"cannot save node {obj.path!r}: the graph has a cycle")
            active.add(key)
            for item in obj:
                self.count(item, active)
            active.discard(key)
        elif isinstance(obj, RenderingComponent):
            for value in obj.parameters().values():
                self._count_value(value, active)

    def _count_value(self, value: Any, active: set[int]) -> None:
        if isinstance(value, (RenderingComponent, Node)):
            self.count(value, active)
        elif isinstance(value, (list, tuple)):
            for v in value:
                self._count_value(v, active)
        elif isinstance(value, dict):
            for v in value.values():
                self._count_value(v, active)

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
        if self.counts.get(key, 1) > 1:
            self.ids[key] = self._id_for(obj)
        return None

    # pass 2: encode
    def node(self, node: Node) -> dict[str, Any]:
        ref = self._shared(node)
        if ref is not None:
            return ref
        out: dict[str, Any] = {"node": node.name}
        if id(node) in self.ids:
            out["$id"] = self.ids[id(node)]
        if node.groups:
            out["groups"] = sorted(node.groups)
        out["contents"] = [self.item(item) for item in node]
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
        data = arr.tolist()
        if arr.dtype == np.float64:
            return data
        return {"$array": data, "dtype": arr.dtype.name}


def _document(scene: Node, base_dir: str | None) -> dict[str, Any]:
    if not isinstance(scene, Node):
        raise TypeError(f"save: the scene must be an om.Node, got {type(scene).__name__}")
    writer = _Writer(base_dir)
    writer.count(scene, set())
    return {"format": FORMAT, "version": VERSION, "root": writer.node(scene)}


def dumps(scene: Node, fmt: str = "json", base_dir: str | os.PathLike[str] | None = None) -> str:
    """The scene as JSON or YAML text; paths are made relative to ``base_dir`` when given."""
    fmt = _check_format(fmt)
    doc = _document(scene, None if base_dir is None else os.path.abspath(os.fspath(base_dir)))
    if fmt == "json":
        return _json_text(doc) + "\n"
    yaml = _yaml()
    return yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=120, allow_unicode=True)


def save(scene: Node, path: str | os.PathLike[str]) -> Path:
    """Write ``scene`` to ``path`` (``.json``, ``.yaml`` or ``.yml``) atomically; returns the path."""
    target = Path(path)
    fmt = _format_of(target)
    text = dumps(scene, fmt, base_dir=target.resolve().parent)
    with atomic_write(target, "w") as fh:
        fh.write(text)
    return target


def _json_text(value: Any, indent: int = 0) -> str:
    """JSON with short or purely numeric lists on one line (readable vertex arrays)."""
    pad = "  " * (indent + 1)
    end = "  " * indent
    if isinstance(value, dict):
        if not value:
            return "{}"
        flat = json.dumps(value, allow_nan=False)
        if len(flat) <= 80 and not any(isinstance(v, (dict, list)) and v for v in value.values()):
            return flat
        items = [f"{pad}{json.dumps(k)}: {_json_text(v, indent + 1)}" for k, v in value.items()]
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
        items = [f"{pad}{_json_text(v, indent + 1)}" for v in value]
        return "[\n" + ",\n".join(items) + "\n" + end + "]"
    return json.dumps(value, allow_nan=False)


# -- reading ----------------------------------------------------------------------
class _Reader:
    def __init__(self, base_dir: str | None, source: str | None, trusted: bool = False) -> None:
        self.base_dir = base_dir
        self.source = source
        self.trusted = trusted
        self.objects: dict[str, Any] = {}

    def error(self, where: str, message: str) -> SceneFileError:
        return SceneFileError(where, message, self.source)

    def document(self, doc: Any) -> Node:
        if not isinstance(doc, dict):
            raise self.error("", f"a scene file must hold an object/mapping, got {type(doc).__name__}")
        if doc.get("format") != FORMAT:
            raise self.error("format", f"expected {FORMAT!r}, got {doc.get('format')!r} (is this a scene file?)")
        version = doc.get("version")
        if version != VERSION:
            raise self.error("version", f"unsupported version {version!r} (this omnirender reads version {VERSION})")
        unknown = set(doc) - {"format", "version", "root"}
        if unknown:
            raise self.error(sorted(unknown)[0], "unknown key (expected format, version, root)")
        if "root" not in doc:
            raise self.error("root", "missing (the root node)")
        root = self.entry(doc["root"], "root")
        if not isinstance(root, Node):
            raise self.error("root", 'must be a node ({"node": NAME, "contents": [...]})')
        return root

    def entry(self, data: Any, where: str) -> Any:
        if not isinstance(data, dict):
            raise self.error(where, f"expected a node, component or reference object, got {_describe(data)}")
        if "$ref" in data:
            if len(data) != 1:
                raise self.error(where, "a reference holds only '$ref'")
            return self.ref(data["$ref"], where)
        if "node" in data:
            if "type" in data:
                raise self.error(where, "an entry is either a node ('node') or a component ('type'), not both")
            return self.node(data, where)
        if "type" in data:
            return self.component(data, where)
        raise self.error(where, "expected 'node', 'type' or '$ref'")

    def ref(self, key: Any, where: str) -> Any:
        if not isinstance(key, str) or key not in self.objects:
            known = ", ".join(sorted(self.objects)) or "none"
            raise self.error(f"{where}.$ref", f"unknown id {key!r} (ids defined before this point: {known})")
        return self.objects[key]

    def define(self, data: dict[str, Any], obj: Any, where: str) -> None:
        if "$id" in data:
            key = data["$id"]
            if not isinstance(key, str) or not key:
                raise self.error(f"{where}.$id", f"must be a non-empty string, got {key!r}")
            if key in self.objects:
                raise self.error(f"{where}.$id", f"duplicate id {key!r}")
            self.objects[key] = obj

    def node(self, data: dict[str, Any], where: str) -> Node:
        unknown = set(data) - {"node", "$id", "groups", "contents"}
        if unknown:
            bad = sorted(unknown)[0]
            raise self.error(f"{where}.{bad}", "unknown key in a node (expected node, groups, contents, $id)")
        name = data["node"]
        if not isinstance(name, str):
            raise self.error(f"{where}.node", f"the node name must be a string, got {_describe(name)}")
        groups = data.get("groups", [])
        if not isinstance(groups, list) or not all(isinstance(g, str) for g in groups):
            raise self.error(f"{where}.groups", "must be a list of group names (strings)")
        try:
            node = Node(name, groups=groups)
        except ValueError as exc:
            raise self.error(f"{where}.node", str(exc)) from None
        self.define(data, node, where)
        contents = data.get("contents", [])
        if not isinstance(contents, list):
            raise self.error(f"{where}.contents", f"must be a list, got {_describe(contents)}")
        for i, item in enumerate(contents):
            here = f"{where}.contents[{i}]"
            obj = self.entry(item, here)
            try:
                node.add(obj)
            except (ValueError, TypeError) as exc:
                raise self.error(here, str(exc)) from None
        return node

    def component(self, data: dict[str, Any], where: str) -> RenderingComponent:
        name = data["type"]
        if not isinstance(name, str):
            raise self.error(f"{where}.type", f"must be a type name string, got {_describe(name)}")
        try:
            cls = _resolve(name, f"{where}.type")
        except SceneFileError as exc:
            raise self.error(exc.path, exc.reason) from None
        if getattr(cls, "scene_file_trusted_only", False) and not self.trusted:
            raise self.error(
                f"{where}.type",
                f"{name} is trusted-only: its text goes verbatim into the renderer's input, so a scene file "
                "could use it to inject directives; it is refused by default. If you wrote this file yourself "
                "or trust its author, load it with om.load(path, trusted=True) / om.scene.files.loads(text, "
                "trusted=True)",
            )
        params = {k: v for k, v in data.items() if k not in ("type", "$id")}
        for key in params:
            if not isinstance(key, str):
                raise self.error(
                    where, f"parameter names must be strings, got {key!r} (in YAML, quote keys like 'on', 'yes', 'no')"
                )
        build = _registry.builders.get(name, cls)
        accepted = _accepted_parameters(build)
        if accepted is not None:
            for key in params:
                if key not in accepted:
                    choices = ", ".join(accepted) or "none"
                    raise self.error(f"{where}.{key}", f"{name} has no parameter {key!r} (parameters: {choices})")
        path_params = _registry.paths.get(name, ())
        kwargs: dict[str, Any] = {}
        for key, value in params.items():
            if key in path_params and isinstance(value, str):
                kwargs[key] = self.path(value)
            else:
                kwargs[key] = self.value(value, f"{where}.{key}")
        try:
            obj = build(**kwargs)
        except (ValueError, TypeError, OSError) as exc:
            located = _locate(where, cls, kwargs, exc)
            if located[0] == where and isinstance(exc, OSError):
                given = [k for k in path_params if k in kwargs]
                if len(given) == 1:
                    located = (f"{where}.{given[0]}", located[1])
            raise self.error(*located) from None
        self.define(data, obj, where)
        return obj

    def path(self, text: str) -> str:
        if self.base_dir is None or os.path.isabs(text):
            return text
        return os.path.normpath(os.path.join(self.base_dir, text))

    def value(self, value: Any, where: str) -> Any:
        if isinstance(value, list):
            return [self.value(v, f"{where}[{i}]") for i, v in enumerate(value)]
        if isinstance(value, dict):
            if "$dict" in value:
                if len(value) != 1 or not isinstance(value["$dict"], dict):
                    raise self.error(where, "a '$dict' wrapper holds only '$dict' with an object/mapping")
                return {k: self.value(v, f"{where}.{k}") for k, v in value["$dict"].items()}
            if "$array" in value:
                return self.array(value, where)
            if "type" in value or "node" in value or "$ref" in value:
                return self.entry(value, where)
            return {k: self.value(v, f"{where}.{k}") for k, v in value.items()}
        if isinstance(value, float) and not math.isfinite(value):
            raise self.error(where, f"must be a finite number, got {value}")
        return value

    def array(self, value: dict[str, Any], where: str) -> np.ndarray:
        if set(value) - {"$array", "dtype"}:
            raise self.error(where, "an array holds only '$array' and 'dtype'")
        dtype = value.get("dtype", "float64")
        if not isinstance(dtype, str):
            raise self.error(f"{where}.dtype", "must be a dtype name such as 'uint8' or 'float32'")
        try:
            dt = np.dtype(dtype)
        except TypeError:
            raise self.error(f"{where}.dtype", f"unknown dtype {dtype!r}") from None
        if dt.kind not in "biuf":
            raise self.error(f"{where}.dtype", f"dtype {dtype!r} is not numeric")
        try:
            arr = np.array(value["$array"], dtype=dt)
        except (TypeError, ValueError, OverflowError) as exc:
            raise self.error(f"{where}.$array", f"not a regular array of {dtype}: {exc}") from None
        return arr


def _accepted_parameters(cls: Callable[..., Any]) -> list[str] | None:
    """Keyword names ``cls`` accepts, or None when it takes **kwargs or has no inspectable signature."""
    try:
        sig = inspect.signature(cls)
    except (TypeError, ValueError):
        return None
    names = []
    for p in sig.parameters.values():
        if p.kind is p.VAR_KEYWORD:
            return None
        if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY):
            names.append(p.name)
    return names


def _locate(where: str, cls: type, kwargs: dict[str, Any], exc: BaseException) -> tuple[str, str]:
    """(JSON path, message) for a constructor error: the parameter it names, when it names one."""
    message = str(exc).strip() or type(exc).__name__
    prefix = f"{cls.__name__}: "
    body = message[len(prefix) :] if message.startswith(prefix) else message
    for key in sorted(kwargs, key=len, reverse=True):
        m = re.match(re.escape(key) + r"((?:\[\d+\])*)(?=[ :]|$)", body)
        if m:
            rest = body[m.end() :].lstrip(": ")
            return f"{where}.{key}{m.group(1)}", f"{rest} ({cls.__name__})"
    if isinstance(exc, TypeError):
        return where, f"{cls.__name__}: {message}"
    return where, message if message.startswith(prefix) else f"{cls.__name__}: {message}"


def _describe(value: Any) -> str:
    text = repr(value)
    return f"{type(value).__name__} {text[:40]}{'...' if len(text) > 40 else ''}"


def loads(
    text: str,
    fmt: str = "json",
    base_dir: str | os.PathLike[str] | None = None,
    *,
    source: str | None = None,
    trusted: bool = False,
):
    """Parse scene-file text; relative file paths are resolved against ``base_dir`` (cwd when None).

    ``trusted=True`` allows trusted-only components (``povray.Raw``); pass it
    only for files you wrote yourself.
    """
    fmt = _check_format(fmt)
    where = source or "<scene text>"
    if fmt == "json":
        try:
            doc = json.loads(text, parse_constant=_reject_constant)
        except json.JSONDecodeError as exc:
            raise SceneFileError(
                "", f"invalid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}", where
            ) from None
        except ValueError as exc:
            raise SceneFileError("", f"invalid JSON: {exc}", where) from None
    else:
        yaml = _yaml()
        try:
            doc = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            raise SceneFileError("", f"invalid YAML: {exc}", where) from None
    base = None if base_dir is None else os.path.abspath(os.fspath(base_dir))
    return _Reader(base, source, trusted).document(doc)


def _reject_constant(name: str) -> Any:
    raise ValueError(f"{name} is not allowed (numbers must be finite)")


def load(path: str | os.PathLike[str], *, trusted: bool = False) -> Node:
    """Read a scene file (``.json``, ``.yaml``, ``.yml``) and return its root node.

    ``trusted=True`` allows trusted-only components such as ``povray.Raw``
    (hand-written SDL); without it they are refused with a SceneFileError.
    """
    target = Path(path)
    fmt = _format_of(target)
    try:
        text = target.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"scene file {str(target)!r} does not exist") from None
    except UnicodeDecodeError as exc:
        raise SceneFileError("", f"not a UTF-8 text file ({exc})", str(target)) from None
    return loads(text, fmt, base_dir=target.resolve().parent, source=str(target), trusted=trusted)


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
