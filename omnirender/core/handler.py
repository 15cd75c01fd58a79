"""Handlers: algorithm objects identified by a service and a target class.

A handler says *what it does* (``service``, e.g. ``"gl.paint"``) and *to what*
(``target``, a component class).  Engines keep a stack of handlers per
(service, target); the top one is used.  Handler classes may declare themselves
defaults for engine classes with :func:`default_for`, which is how an adapter
package plugs into the system without any edit of the core.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from .component import Attribute, RenderingComponent, Shape

if TYPE_CHECKING:
    from .engine import Engine

__all__ = [
    "Handler",
    "ShapePainter",
    "ShapeSimplifier",
    "AttributePainter",
    "AttributeSimplifier",
    "RayIntersector",
    "default_for",
    "registry",
    "HandlerRegistry",
]

SIMPLIFY = "simplify"


class Handler(RenderingComponent):
    """An algorithm for one service applied to components of one target class."""

    __slots__ = ()
    service: str = ""
    target: type = RenderingComponent

    def exec(self, component: Any, engine: Engine) -> Any:
        """Apply the algorithm to ``component`` in the state of ``engine``."""
        raise NotImplementedError(f"{type(self).__name__}.exec is not implemented")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(service={self.service!r}, target={self.target.__name__})"


class ShapePainter(Handler):
    """Draws (or otherwise consumes) a shape for the handler's service."""

    __slots__ = ()
    target = Shape


class ShapeSimplifier(Handler):
    """Turns a shape into simpler components; works for every engine.

    ``exec`` returns an iterable of components (shapes, attributes, nodes) that
    the engine evaluates in order, scoped like the contents of a node.
    """

    __slots__ = ()
    service = SIMPLIFY
    target = Shape

    def exec(self, shape: Any, engine: Engine) -> Iterable[Any]:  # pragma: no cover - abstract
        raise NotImplementedError(f"{type(self).__name__}.exec is not implemented")


class AttributePainter(Handler):
    """Applies an attribute when it becomes active and undoes it when it goes."""

    __slots__ = ()
    target = Attribute

    def exec(self, attribute: Any, engine: Engine) -> None:
        """Called after the attribute was pushed or added."""

    def unexec(self, attribute: Any, engine: Engine) -> None:
        """Called after the attribute was popped or removed."""


class AttributeSimplifier(Handler):
    """Replaces an attribute by the attributes its ``exec`` pushes or adds.

    The engine records what ``exec`` pushed, added or installed; the default
    ``unexec`` undoes exactly that in reverse order (the paper's billboarding
    example: the billboard pushes a computed rotation and pops it again).
    """

    __slots__ = ()
    service = SIMPLIFY
    target = Attribute

    def exec(self, attribute: Any, engine: Engine) -> None:  # pragma: no cover - abstract
        raise NotImplementedError(f"{type(self).__name__}.exec is not implemented")

    def unexec(self, attribute: Any, engine: Engine, record: list[tuple[str, Any]]) -> None:
        """Undo what ``exec`` did; ``record`` lists its (op, object) calls in order."""
        engine.undo(record)


class RayIntersector(Handler):
    """Intersects a ray with a shape (service ``"ray.intersect"``)."""

    __slots__ = ()
    service = "ray.intersect"
    target = Shape


class HandlerRegistry:
    """Default handlers per engine class, as registered by adapter packages.

    Entries record the module that registered them, can be listed, and can be
    snapshotted and restored (for tests that register temporary handlers).
    """

    def __init__(self) -> None:
        self._entries: dict[type, dict[tuple[str, type], Any]] = {}
        self._origin: dict[tuple[type, str, type], str] = {}
        self.generation = 0
        self._lock = threading.Lock()

    def register(self, handler: Any, engine_classes: Iterable[type], *, override: bool = False) -> None:
        """Make ``handler`` (an instance) a default for each engine class."""
        key = (handler.service, handler.target)
        if not key[0]:
            raise ValueError(f"{type(handler).__name__}: a handler needs a non-empty 'service'")
        if key[1] in (RenderingComponent, Shape, Attribute):
            raise ValueError(
                f"{type(handler).__name__}: set 'target' to the component class it handles "
                f"(it is the generic {key[1].__name__})"
            )
        with self._lock:
            for engine_cls in engine_classes:
                table = self._entries.setdefault(engine_cls, {})
                existing = table.get(key)
                if existing is not None and not override and type(existing) is not type(handler):
                    raise ValueError(
                        f"default handler for service {key[0]!r} and {key[1].__name__} on "
                        f"{engine_cls.__name__} is already {type(existing).__name__} "
                        f"(from {self._origin[(engine_cls, *key)]}); pass override=True to replace it"
                    )
                table[key] = handler
                self._origin[(engine_cls, *key)] = type(handler).__module__
            self.generation += 1

    def unregister(self, handler_cls: type, engine_classes: Iterable[type]) -> None:
        with self._lock:
            for engine_cls in engine_classes:
                table = self._entries.get(engine_cls, {})
                for key, h in list(table.items()):
                    if type(h) is handler_cls:
                        del table[key]
            self.generation += 1

    def lookup(self, engine_cls: type, service: str, target: type) -> Any:
        """The default handler for (service, target) on ``engine_cls`` or its bases."""
        key = (service, target)
        for cls in engine_cls.__mro__:
            table = self._entries.get(cls)
            if table is not None:
                h = table.get(key)
                if h is not None:
                    return h
        return None

    def entries(self) -> list[tuple[str, str, str, str, str]]:
        """(engine, service, target, handler, module) for every registered default."""
        out = []
        for engine_cls, table in self._entries.items():
            for (service, target), h in table.items():
                out.append(
                    (
                        engine_cls.__name__,
                        service,
                        target.__name__,
                        type(h).__name__,
                        self._origin[(engine_cls, service, target)],
                    )
                )
        return sorted(out)

    def snapshot(self) -> Any:
        return ({k: dict(v) for k, v in self._entries.items()}, dict(self._origin))

    def restore(self, state: Any) -> None:
        entries, origin = state
        with self._lock:
            self._entries = {k: dict(v) for k, v in entries.items()}
            self._origin = dict(origin)
            self.generation += 1


registry = HandlerRegistry()


def default_for(*engine_classes: type, override: bool = False):
    """Class decorator: make one instance of the handler class a default handler.

    ``@default_for(Engine)`` makes a simplifier available to every engine;
    ``@default_for(GLEngine)`` makes a painter the GL engine's default.
    """
    if not engine_classes:
        raise TypeError("default_for needs at least one engine class")
    from .engine import Engine

    for cls in engine_classes:
        if not (isinstance(cls, type) and issubclass(cls, Engine)):
            raise TypeError(f"default_for needs engine classes (subclasses of om.Engine), got {cls!r}")

    def decorate(handler_cls: type) -> type:
        registry.register(handler_cls(), engine_classes, override=override)
        return handler_cls

    return decorate
