"""The common machinery of shape declarations: validated parameters and caches.

A shape lists its constructor parameters in ``_params``.  Each is a property
whose setter re-validates the shape as a whole (so ``sphere.radius = -1``
raises and ``mesh.indices = ...`` is checked against the current vertices)
and bumps ``version``.  Derived arrays (normals, triangulations) are cached
until the version changes.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..core import Shape

__all__ = ["DeclaredShape", "parameter"]

_MISSING = object()


def parameter(name: str, doc: str = "") -> property:
    """A public parameter stored in the private slot ``_<name>``; assigning it re-validates the shape."""
    private = "_" + name

    def get(self: DeclaredShape) -> Any:
        return getattr(self, private)

    def set_(self: DeclaredShape, value: Any) -> None:
        # RenderingComponent.__setattr__ bumps the version after this returns.
        self._apply({name: value})

    return property(get, set_, doc=doc)


class DeclaredShape(Shape):
    """Base of the built-in shapes: validated parameters, ``parameters()``, per-version caches.

    Subclasses set ``_params`` (constructor keyword names, in order), declare a
    private slot ``_<name>`` per parameter plus ``parameter(name)`` properties,
    and implement ``_validate(params) -> (params, derived)``: the values to store
    and a dict of derived values (validated arrays) that go into the cache.
    Derived values are recomputed from the parameters when the version moved
    for another reason (``shape.touch()`` after changing an array in place).
    """

    __slots__ = ("_cache", "_cache_version")
    _params: tuple[str, ...] = ()
    # Derived values are recomputed after unpickling (a MeshFile is sent as its path, not its triangles).
    _transient = {"_cache": dict, "_cache_version": lambda: -1}

    def __init__(self, **params: Any) -> None:
        super().__init__()
        object.__setattr__(self, "_cache", {})
        object.__setattr__(self, "_cache_version", -1)
        self._apply(params, initial=True)
        self.touch()

    # -- parameters -----------------------------------------------------
    def parameters(self) -> dict[str, Any]:
        """Constructor keyword parameters: ``type(s)(**s.parameters())`` rebuilds the shape."""
        return {name: getattr(self, "_" + name) for name in self._params}

    def update(self, **params: Any) -> None:
        """Change several parameters at once, validated together (e.g. new vertices and indices)."""
        unknown = set(params) - set(self._params)
        if unknown:
            raise TypeError(f"{type(self).__name__}.update: unknown parameters {sorted(unknown)}")
        self._apply(params)
        self.touch()

    def _apply(self, params: dict[str, Any], initial: bool = False) -> None:
        # Every _apply is followed by exactly one touch(): the cache filled here
        # belongs to the coming version.
        merged = params if initial else {**self.parameters(), **params}
        stored, derived = self._validate(dict(merged))
        for name in self._params:
            object.__setattr__(self, "_" + name, stored[name])
        self._cache.clear()
        self._cache.update(derived)
        object.__setattr__(self, "_cache_version", self.version + 1)

    def _validate(self, params: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        return params, {}

    # -- caches ---------------------------------------------------------
    def _reuse(self, name: str, value: Any, key: str, convert: Callable[[Any], Any]) -> Any:
        """``convert(value)``, or the current derived ``key`` when parameter ``name`` is unchanged.

        Saves re-validating big arrays when another parameter changes (a volume's
        ``iso``, a mesh's ``colors``).
        """
        if value is getattr(self, "_" + name, _MISSING) and self._cache_version == self.version and key in self._cache:
            return self._cache[key]
        return convert(value)

    def _cached(self, key: str, compute: Callable[[], Any] | None = None) -> Any:
        """A cached value of the current version: ``compute()`` or, without it, a derived value."""
        cache = self._cache
        if self._cache_version != self.version:
            cache.clear()
            object.__setattr__(self, "_cache_version", self.version)
        try:
            return cache[key]
        except KeyError:
            pass
        if compute is None:
            _, derived = self._validate(self.parameters())
            cache.update(derived)
            return cache[key]
        value = cache[key] = compute()
        return value
