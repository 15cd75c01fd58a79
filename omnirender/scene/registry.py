"""The scene-file type registry: type names <-> component classes, and the scene-file errors.

Built-in types use their class name (``Sphere``, ``Material``); engine-specific
ones a qualified name (``povray.Finish``), resolved by importing
``omnirender.<prefix>`` only when a file uses it.  Third-party components
become loadable with :func:`register_type`.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import re
import threading
from collections.abc import Callable, Iterable
from typing import Any

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
from ..core.paths import UntrustedReferenceError
from ..core.transform import Transform

__all__ = [
    "register_type",
    "unregister_type",
    "registered_types",
    "type_name",
    "SceneFileError",
    "UntrustedContentError",
]

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
_MARKERS = frozenset({"type", "node", "$ref", "$id", "$array", "$base64", "$file", "$dict"})


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
        shown = shorten_path(path)
        super().__init__(f"{where}{shown}: {message}" if path else f"{where}{message}")


def shorten_path(path: str, limit: int = 160) -> str:
    """A JSON path short enough for a message: its start and end around "..." when it is very long."""
    if len(path) <= limit:
        return path
    return f"{path[: limit // 2]}...{path[-limit // 2 :]}"


#: How a caller vouches for a scene file, in the Python API and on the command line.
TRUST_FIX = (
    "if you wrote this file yourself or trust its author, load it with om.load(path, trusted=True) "
    "(or allow the folders it names with om.load(path, allowed_roots=[folder]))"
)
TRUST_FIX_CLI = "if you wrote this file yourself or trust its author, run the command again with --trusted"


class UntrustedContentError(SceneFileError, UntrustedReferenceError):
    """Content a scene file may hold only when its loader trusts it (raw renderer text, files outside its folder).

    An :class:`~omnirender.core.paths.UntrustedReferenceError` like every
    refusal of the path policy, so one ``except`` catches them all.

    The message ends with the Python fix (``trusted=True``); :attr:`cli_message`
    says the same for the command line (``--trusted``).
    """

    def __init__(self, path: str, message: str, source: str | None = None) -> None:
        self.path = path
        self.source = source
        where = f"{source}: " if source else ""
        text = f"{message}; {TRUST_FIX}"
        ValueError.__init__(self, f"{where}{shorten_path(path)}: {text}" if path else f"{where}{text}")
        self.reason = message
        self.referrer = source or "<scene text>"
        self.reference = path
        where = f"{source}: " if source else ""
        shown = shorten_path(path)
        self.cli_message = (
            f"{where}{shown}: {message}; {TRUST_FIX_CLI}" if path else f"{where}{message}; {TRUST_FIX_CLI}"
        )


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
        from ..options import did_you_mean

        known = [n for n in dir(module) if not n.startswith("_") and _is_concrete_component(getattr(module, n))]
        raise SceneFileError(
            where, f"unknown type {name!r}: {module_name} defines no component {attr!r}{did_you_mean(attr, known)}"
        )
    from ..options import did_you_mean

    hint = did_you_mean(name, [n for n in _registry.by_name if "." not in n])
    raise SceneFileError(
        where,
        f"unknown type {name!r}{hint.replace(';', ' -', 1)} (known: {_known()}; register others with om.register_type)",
    )


def _known() -> str:
    names = sorted(n for n in _registry.by_name if "." not in n)
    return ", ".join(names[:12]) + (", ..." if len(names) > 12 else "")
