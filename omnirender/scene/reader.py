"""Reading scene files: the document of :mod:`omnirender.scene.files` back to a graph.

The reader checks everything a file says before it builds anything with it:
keys, type names (only registered ones, or omnirender's own subpackages),
parameter names, nesting depth, duplicate keys, JSON's types only, integers in
range, trusted-only types, and the *path policy*: file paths (mesh files,
texture images, side-car arrays) must name files inside the scene file's folder
unless the caller trusts the file.  Every error names the JSON path of the
offending element.  Nodes are built bottom-up (a node is complete before its
parent adds it), so loading stays linear however deep the graph.
"""

from __future__ import annotations

import inspect
import math
import os
import re
from collections.abc import Callable
from typing import Any

import numpy as np

from ..core.component import RenderingComponent
from ..core.paths import PathPolicy, RemoteReferenceError, UntrustedReferenceError
from ..options import did_you_mean
from .arrays import COMPACT_MIN_SIZE, SideCar, decode_base64, numeric_list
from .node import Node
from .parse import LIMITS, DuplicateKeys, ParseLimits, nesting_message
from .registry import SceneFileError, UntrustedContentError, _registry, _resolve
from .writer import FORMAT, VERSION

__all__ = ["Reader"]

#: Integers a scene file may hold (larger ones are refused: no engine parameter needs them).
MAX_INTEGER = 2**63 - 1


class Reader:
    """Builds the graph of one document; see the module docs."""

    def __init__(
        self,
        base_dir: str | None,
        source: str | None,
        trusted: bool = False,
        limits: ParseLimits = LIMITS,
        allowed_roots: tuple[str, ...] = (),
    ) -> None:
        self.base_dir = base_dir
        self.source = source
        self.trusted = trusted
        self.policy = PathPolicy.of(trusted, allowed_roots)
        self.limits = limits
        self.objects: dict[str, Any] = {}
        self.sidecar = SideCar()

    def error(self, where: str, message: str) -> SceneFileError:
        return SceneFileError(where, message, self.source)

    def untrusted(self, where: str, message: str) -> UntrustedContentError:
        return UntrustedContentError(where, message, self.source)

    def _mapping(self, data: Any, where: str) -> None:
        if isinstance(data, DuplicateKeys):
            key = data.duplicates[0]
            raise self.error(
                f"{where}.{key}" if where else key, f"duplicate key {key!r}; an object names each key once"
            )

    def document(self, doc: Any) -> Node:
        try:
            return self._document(doc)
        finally:
            self.sidecar.close()

    def _document(self, doc: Any) -> Node:
        if not isinstance(doc, dict):
            got = "nothing (the file is empty)" if doc is None else f"a {type(doc).__name__}"
            raise self.error("", f"a scene file must hold an object/mapping, got {got}")
        self._mapping(doc, "")
        if doc.get("format") != FORMAT:
            raise self.error("format", f"expected {FORMAT!r}, got {doc.get('format')!r} (is this a scene file?)")
        version = doc.get("version")
        if version != VERSION:
            raise self.error("version", f"unsupported version {version!r} (this omnirender reads version {VERSION})")
        unknown = set(doc) - {"format", "version", "definitions", "root"}
        if unknown:
            raise self.error(
                str(sorted(map(str, unknown))[0]), "unknown key (expected format, version, definitions, root)"
            )
        if "root" not in doc:
            raise self.error("root", "missing (the root node)")
        definitions = doc.get("definitions", [])
        if not isinstance(definitions, list):
            raise self.error("definitions", f"must be a list of entries with $id, got {_describe(definitions)}")
        for i, item in enumerate(definitions):
            where = f"definitions[{i}]"
            if not isinstance(item, dict) or "$id" not in item:
                raise self.error(where, "a definition is a node or component with an '$id' (referred to with $ref)")
            self.entry(item, where, 2)
        root = self.entry(doc["root"], "root", 1)
        if not isinstance(root, Node):
            raise self.error("root", 'must be a node ({"node": NAME, "contents": [...]})')
        return root

    def _depth(self, where: str, depth: int) -> None:
        if depth > self.limits.max_depth:
            raise self.error(where, nesting_message(self.limits.max_depth))

    def entry(self, data: Any, where: str, depth: int) -> Any:
        if not isinstance(data, dict):
            raise self.error(where, f"expected a node, component or reference object, got {_describe(data)}")
        self._depth(where, depth)
        self._mapping(data, where)
        if "$ref" in data:
            if len(data) != 1:
                raise self.error(where, "a reference holds only '$ref'")
            return self.ref(data["$ref"], where)
        if "node" in data:
            if "type" in data:
                raise self.error(where, "an entry is either a node ('node') or a component ('type'), not both")
            return self.node(data, where, depth)
        if "type" in data:
            return self.component(data, where, depth)
        raise self.error(where, "expected 'node', 'type' or '$ref'")

    def ref(self, key: Any, where: str) -> Any:
        if not isinstance(key, str) or key not in self.objects:
            known = sorted(self.objects)
            shown = ", ".join(known[:20]) + (", ..." if len(known) > 20 else "") if known else "none"
            raise self.error(f"{where}.$ref", f"unknown id {_short(key)} (ids defined before this point: {shown})")
        return self.objects[key]

    def define(self, data: dict[str, Any], obj: Any, where: str) -> None:
        if "$id" in data:
            key = data["$id"]
            if not isinstance(key, str) or not key or not key.isprintable():
                raise self.error(
                    f"{where}.$id", f"must be a non-empty string of printable characters, got {_short(key)}"
                )
            if key in self.objects:
                raise self.error(f"{where}.$id", f"duplicate id {key!r}")
            self.objects[key] = obj

    def node(self, data: dict[str, Any], where: str, depth: int) -> Node:
        unknown = set(data) - {"node", "$id", "groups", "contents"}
        if unknown:
            bad = sorted(map(str, unknown))[0]
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
            obj = self.entry(item, here, depth + 2)
            try:
                node.add(obj)
            except (ValueError, TypeError) as exc:
                raise self.error(here, str(exc)) from None
        return node

    def component(self, data: dict[str, Any], where: str, depth: int) -> RenderingComponent:
        name = data["type"]
        if not isinstance(name, str):
            raise self.error(f"{where}.type", f"must be a type name string, got {_describe(name)}")
        try:
            cls = _resolve(name, f"{where}.type")
        except SceneFileError as exc:
            raise self.error(exc.path, exc.reason) from None
        if getattr(cls, "scene_file_trusted_only", False) and not self.trusted:
            raise self.untrusted(
                f"{where}.type",
                f"{name} is trusted-only: its text goes verbatim into the renderer's input, so a scene file "
                "could use it to inject directives; it is refused by default",
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
                    hint = did_you_mean(key, accepted).replace("; ", " - ", 1)
                    raise self.error(f"{where}.{key}", f"{name} has no parameter {key!r}{hint} (parameters: {choices})")
        path_params = _registry.paths.get(name, ())
        kwargs: dict[str, Any] = {}
        for key, value in params.items():
            if key in path_params and isinstance(value, str):
                kwargs[key] = self.path(value, f"{where}.{key}")
            else:
                kwargs[key] = self.value(value, f"{where}.{key}", depth + 1)
        try:
            obj = build(**kwargs)
        except (ValueError, TypeError, OSError, OverflowError) as exc:
            located = _locate(where, cls, kwargs, exc)
            if located[0] == where and isinstance(exc, OSError):
                given = [k for k in path_params if k in kwargs]
                if len(given) == 1:
                    located = (f"{where}.{given[0]}", located[1])
            raise self.error(*located) from None
        use_policy = getattr(obj, "use_path_policy", None)
        if use_policy is not None:  # a mesh file reads its own references under the scene's policy
            base = self.base_dir if self.base_dir is not None else os.getcwd()
            use_policy(PathPolicy.of(self.trusted, (base, *self.policy.allowed_roots)))
        self.define(data, obj, where)
        return obj

    # -- the path policy -------------------------------------------------------------
    def path(self, text: str, where: str) -> str:
        """``text`` resolved against the scene's folder by the path policy (:mod:`omnirender.core.paths`)."""
        if "\x00" in text:
            raise self.error(where, "a file path cannot hold a NUL character")
        base = self.base_dir if self.base_dir is not None else os.getcwd()
        referrer = os.path.join(base, os.path.basename(self.source or "<scene text>"))
        try:
            full = os.fspath(self.policy.resolve(text, referrer, "the path"))
        except RemoteReferenceError as exc:
            raise self.error(where, exc.reason) from None
        except UntrustedReferenceError as exc:
            raise self.untrusted(where, exc.reason) from None
        return text if self.base_dir is None else full

    # -- values ------------------------------------------------------------------------
    def value(self, value: Any, where: str, depth: int) -> Any:
        if isinstance(value, list):
            self._depth(where, depth)
            if value:
                arr = numeric_list(value)
                if arr is not None:
                    return self._numbers(arr, value, where, depth)
            return [self.value(v, f"{where}[{i}]", depth + 1) for i, v in enumerate(value)]
        if isinstance(value, dict):
            self._depth(where, depth)
            self._mapping(value, where)
            if "$dict" in value:
                if len(value) != 1 or not isinstance(value["$dict"], dict):
                    raise self.error(where, "a '$dict' wrapper holds only '$dict' with an object/mapping")
                self._mapping(value["$dict"], f"{where}.$dict")
                return {
                    self._key(k, where): self.value(v, f"{where}.{k}", depth + 2) for k, v in value["$dict"].items()
                }
            if "$array" in value:
                return self.array(value, where)
            if "$base64" in value:
                try:
                    return decode_base64(value)
                except ValueError as exc:
                    raise self.error(where, str(exc)) from None
            if "$file" in value:
                return self.file_array(value, where)
            if "type" in value or "node" in value or "$ref" in value:
                return self.entry(value, where, depth)
            return {self._key(k, where): self.value(v, f"{where}.{k}", depth + 1) for k, v in value.items()}
        if isinstance(value, bool) or value is None or isinstance(value, str):
            return value
        if isinstance(value, int):
            if abs(value) > MAX_INTEGER:
                raise self.error(where, f"the integer {_short(value)} is out of range (at most 2**63 - 1 in magnitude)")
            return value
        if isinstance(value, float):
            if not math.isfinite(value):
                raise self.error(where, f"must be a finite number, got {value}")
            return value
        raise self.error(where, f"values of type {type(value).__name__} are not allowed in scene files")

    def _key(self, key: Any, where: str) -> str:
        if not isinstance(key, str):
            raise self.error(where, f"object keys must be strings, got {key!r} (in YAML, quote keys like 'on', 'yes')")
        return key

    def _numbers(self, arr: np.ndarray, value: list[Any], where: str, depth: int) -> Any:
        """A regular numeric list: checked at once; large ones handed on as arrays."""
        if depth + arr.ndim - 1 > self.limits.max_depth:
            raise self.error(where, nesting_message(self.limits.max_depth))
        if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
            bad = "".join(f"[{i}]" for i in np.argwhere(~np.isfinite(arr))[0])
            raise self.error(f"{where}{bad}", "must be a finite number")
        return arr if arr.size >= COMPACT_MIN_SIZE else value

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
        except (TypeError, ValueError, OverflowError):
            raise self.error(
                f"{where}.$array",
                f"not a regular array of {dtype}: rows of different lengths, values that are not numbers, or "
                f"numbers out of the range of {dtype}",
            ) from None
        if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
            raise self.error(f"{where}.$array", "must hold finite numbers")
        return arr

    def file_array(self, value: dict[str, Any], where: str) -> np.ndarray:
        if set(value) - {"$file", "key"}:
            raise self.error(where, "a side-car array holds only '$file' and 'key'")
        name = value["$file"]
        if not isinstance(name, str) or not name:
            raise self.error(f"{where}.$file", f"must be a file name (.npy or .npz), got {_short(name)}")
        path = self.path(name, f"{where}.$file")
        try:
            return self.sidecar.load(path, value.get("key"))
        except OSError as exc:
            raise self.error(f"{where}.$file", f"cannot read {name!r}: {exc.strerror or exc}") from None
        except ValueError as exc:
            raise self.error(where, str(exc)) from None
        except Exception as exc:  # numpy's readers raise many types for corrupt files
            raise self.error(
                f"{where}.$file", f"{name!r} is not a readable NumPy file ({type(exc).__name__})"
            ) from None


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


_ACCEPTED: dict[Any, list[str] | None] = {}


def _accepted_parameters(cls: Callable[..., Any]) -> list[str] | None:
    """Keyword names ``cls`` accepts, or None when it takes **kwargs or has no inspectable signature."""
    try:
        return _ACCEPTED[cls]
    except (KeyError, TypeError):
        pass
    found = _signature_names(cls)
    try:
        _ACCEPTED[cls] = found
    except TypeError:  # pragma: no cover - unhashable builders
        pass
    return found


def _signature_names(cls: Callable[..., Any]) -> list[str] | None:
    try:
        sig = inspect.signature(cls)
    except (TypeError, ValueError):
        return None
    names = []
    excluded = getattr(cls, "scene_file_excluded", ())  # loader options the scene's own policy sets
    for p in sig.parameters.values():
        if p.kind is p.VAR_KEYWORD:
            return None
        if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and p.name not in excluded:
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
