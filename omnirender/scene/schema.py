"""A JSON Schema of scene files, generated from the registered component types.

``om.scene.files.json_schema()`` (or ``omnirender schema``) describes the
document (``format``, ``version``, ``definitions``, ``root``), nodes,
references, the array forms and, for every registered type (built-ins and
the types of omnirender's engine packages that import here), its parameters
with their descriptions: editors validate and complete scene files with it.
Parameter *types* are inferred from the constructors' defaults (a tuple
default means an array, a float a number...), so a parameter without a
default accepts any value: the loader's own checks stay the authority.
"""

from __future__ import annotations

import importlib
import inspect
from typing import Any

from .registry import _is_concrete_component, _registry, registered_types
from .writer import FORMAT, VERSION

__all__ = ["json_schema", "ADAPTER_PACKAGES"]

#: omnirender packages whose component types the schema lists (each imported if it can be).
ADAPTER_PACKAGES = ("gl", "povray", "mitsuba", "radiance", "animation")

_NUMBER = {"type": "number"}
_NAME_PATTERN = r"^[^/\u0000-\u001f\u007f]+$"


def _types() -> dict[str, type]:
    """Every loadable type name: the registry plus the concrete components of the adapter packages."""
    found = dict(registered_types())
    for prefix in ADAPTER_PACKAGES:
        try:
            module = importlib.import_module(f"omnirender.{prefix}")
        except Exception:  # an adapter that cannot be imported here has no types to describe
            continue
        for name in getattr(module, "__all__", ()):
            cls = getattr(module, name, None)
            qualified = f"{prefix}.{name}"
            if _is_concrete_component(cls) and qualified not in found and cls not in found.values():
                found[qualified] = cls
    return dict(sorted(found.items()))


def _value_schema(default: Any) -> dict[str, Any]:
    if default is inspect.Parameter.empty or default is None:
        return {}
    if isinstance(default, bool):
        return {"type": "boolean"}
    if isinstance(default, (int, float)):
        return dict(_NUMBER)
    if isinstance(default, str):
        return {"type": "string"}
    if isinstance(default, (tuple, list)):
        return {"anyOf": [{"type": "array"}, {"$ref": "#/$defs/array"}]}
    if isinstance(default, dict):
        return {"type": "object"}
    return {}


def _description(cls: type, name: str) -> str | None:
    attr = inspect.getattr_static(cls, name, None)
    doc = getattr(attr, "doc", None) or (getattr(attr, "__doc__", None) if isinstance(attr, property) else None)
    return doc.strip() if isinstance(doc, str) and doc.strip() else None


def _type_schema(name: str, cls: type) -> dict[str, Any]:
    build = _registry.builders.get(name, cls)
    properties: dict[str, Any] = {"type": {"const": name}, "$id": {"type": "string", "minLength": 1}}
    required = ["type"]
    open_ended = False
    try:
        signature = inspect.signature(build)
    except (TypeError, ValueError):
        signature = None
        open_ended = True
    if signature is not None:
        for p in signature.parameters.values():
            if p.kind is p.VAR_KEYWORD:
                open_ended = True
                continue
            if p.kind not in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY):
                continue
            if p.name in getattr(cls, "scene_file_excluded", ()):
                continue  # a loader option the scene file's own policy sets (MeshFile's trusted)
            schema = _value_schema(p.default)
            if name in _registry.paths and p.name in _registry.paths[name]:
                schema = {"type": "string", "description": "a file inside the scene file's folder (or trusted)"}
            text = _description(cls, p.name)
            if text and "description" not in schema:
                schema["description"] = text
            properties[p.name] = schema
            if p.default is inspect.Parameter.empty:
                required.append(p.name)
    doc = inspect.getdoc(cls) or ""
    out: dict[str, Any] = {
        "type": "object",
        "description": doc.split("\n\n")[0].replace("\n", " "),
        "properties": properties,
        "required": required,
        "additionalProperties": open_ended,
    }
    if getattr(cls, "scene_file_trusted_only", False):
        out["description"] += " (trusted-only: loaded only with trusted=True / --trusted)"
    return out


def json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of scene files; see the module docs."""
    types = _types()
    defs: dict[str, Any] = {
        "node": {
            "type": "object",
            "description": "A scene-graph node: a name, group tags and an ordered list of components and nodes.",
            "properties": {
                "node": {"type": "string", "minLength": 1, "pattern": _NAME_PATTERN},
                "$id": {"type": "string", "minLength": 1},
                "groups": {"type": "array", "items": {"type": "string", "pattern": r"^[^ !&|()\u0000-\u001f]+$"}},
                "contents": {"type": "array", "items": {"$ref": "#/$defs/entry"}},
            },
            "required": ["node"],
            "additionalProperties": False,
        },
        "reference": {
            "type": "object",
            "description": "The object written earlier with this $id (shared nodes and components).",
            "properties": {"$ref": {"type": "string"}},
            "required": ["$ref"],
            "additionalProperties": False,
        },
        "array": {
            "description": "An array in a compact form (small arrays may also be plain nested lists).",
            "anyOf": [
                {
                    "type": "object",
                    "properties": {"$array": {"type": "array"}, "dtype": {"type": "string"}},
                    "required": ["$array"],
                    "additionalProperties": False,
                },
                {
                    "type": "object",
                    "properties": {
                        "$base64": {"type": "string"},
                        "dtype": {"type": "string"},
                        "shape": {"type": "array", "items": {"type": "integer", "minimum": 0}},
                    },
                    "required": ["$base64", "dtype", "shape"],
                    "additionalProperties": False,
                },
                {
                    "type": "object",
                    "properties": {"$file": {"type": "string"}, "key": {"type": "string"}},
                    "required": ["$file"],
                    "additionalProperties": False,
                },
            ],
        },
        "component": {
            "type": "object",
            "description": "A shape, attribute, handler or technique: its type name and constructor parameters.",
            "properties": {"type": {"enum": list(types)}},
            "required": ["type"],
            "allOf": [{"if": {"properties": {"type": {"const": n}}}, "then": {"$ref": f"#/$defs/{n}"}} for n in types],
        },
        "entry": {"anyOf": [{"$ref": "#/$defs/node"}, {"$ref": "#/$defs/reference"}, {"$ref": "#/$defs/component"}]},
    }
    for name, cls in types.items():
        defs[name] = _type_schema(name, cls)
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://omnirender.invalid/scene-file.schema.json",
        "title": "omnirender scene file",
        "description": "See docs/scene-files.md. Generated by omnirender.scene.files.json_schema().",
        "type": "object",
        "properties": {
            "format": {"const": FORMAT},
            "version": {"const": VERSION},
            "definitions": {
                "type": "array",
                "description": "Entries with $id, defined before the root and referred to with $ref (deep graphs).",
                "items": {"allOf": [{"$ref": "#/$defs/entry"}, {"required": ["$id"]}]},
            },
            "root": {"$ref": "#/$defs/node"},
        },
        "required": ["format", "version", "root"],
        "additionalProperties": False,
        "$defs": defs,
    }
