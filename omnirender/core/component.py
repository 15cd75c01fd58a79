"""Rendering components: the parameters a scene is made of.

A component holds parameters only, never an algorithm (algorithms are
:class:`~omnirender.core.handler.Handler` objects).  Components carry a
``version`` counter that is bumped whenever a public parameter is assigned, and
the bump is forwarded to every node that owns the component so that engines can
recompile only what changed.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "RenderingComponent",
    "Shape",
    "Attribute",
    "MonoAttribute",
    "PolyAttribute",
    "category_of",
]


class RenderingComponent:
    """Base of everything a node can hold: shapes, attributes, handlers, techniques."""

    __slots__ = ("_version", "_owners", "__weakref__")

    #: Render hints for viewers and techniques (``"transparent"``, ``"2d"``).
    hints: frozenset[str] = frozenset()
    #: Declarative pre-evaluation (see :mod:`.declarations`): ``"all"`` placements are collected
    #: (lights), only the ``"first"`` (camera, background), or None: the component is not declarative.
    declared: str | None = None

    def __init__(self) -> None:
        object.__setattr__(self, "_version", 0)
        object.__setattr__(self, "_owners", None)

    def __setattr__(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)
        if name[0] != "_":
            try:
                self.touch()
            except AttributeError:
                raise TypeError(
                    f"{type(self).__name__}.__init__ must call super().__init__() before setting {name!r}"
                ) from None

    @property
    def version(self) -> int:
        """Counter bumped on every change of a public parameter."""
        return self._version

    def touch(self) -> None:
        """Mark the component as changed: bump its version and its owners' versions."""
        object.__setattr__(self, "_version", self._version + 1)
        owners = self._owners
        if owners:
            for node in owners:
                node.touch()

    def _attach(self, owner: Any) -> None:
        owners = self._owners
        if owners is None:
            object.__setattr__(self, "_owners", [owner])
        else:
            owners.append(owner)

    def _detach(self, owner: Any) -> None:
        owners = self._owners
        if owners:
            for i, o in enumerate(owners):
                if o is owner:
                    del owners[i]
                    break

    def parameters(self) -> dict[str, Any]:
        """The public parameters as a dict (used by scene files, traces and repr)."""
        out: dict[str, Any] = {}
        for cls in type(self).__mro__:
            for name in getattr(cls, "__slots__", ()):
                if not name.startswith("_") and name not in out and hasattr(self, name):
                    out[name] = getattr(self, name)
        return out

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={_short(v)}" for k, v in self.parameters().items())
        return f"{type(self).__name__}({params})"


def _short(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return text.replace("\n", " ")


class Shape(RenderingComponent):
    """Something perceived as an entity of the target medium (sphere, mesh, text).

    Engines evaluate shapes through handlers looked up by the shape's class:
    a painter for the technique's service, else a simplifier that turns the shape
    into simpler components, else the same for the parent class.
    """

    __slots__ = ()


class Attribute(RenderingComponent):
    """A modifier of shape evaluation (colour, material, transform, light...).

    ``category`` is the key of the context stack or set the attribute lives in.
    It defaults to the attribute's own class; a class that sets
    ``shares_category = True`` in its body makes itself the category of all its
    subclasses (all lights share ``Light``, all transforms share ``Transform``);
    a class may also name another category explicitly (``category = Transform``).
    """

    __slots__ = ()
    category: type = None  # type: ignore[assignment]
    shares_category = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "category" in cls.__dict__:  # set explicitly in the class body
            return
        for base in cls.__mro__:
            if base.__dict__.get("shares_category", False):
                cls.category = base
                return
        cls.category = cls


class MonoAttribute(Attribute):
    """Attribute kept on a per-category stack; only the top one is active."""

    __slots__ = ()


class PolyAttribute(Attribute):
    """Attribute kept in a per-category set; any number are active at once."""

    __slots__ = ()


Attribute.category = Attribute
MonoAttribute.category = MonoAttribute
PolyAttribute.category = PolyAttribute


def category_of(attribute: Attribute) -> type:
    """The category key of ``attribute`` (its class unless a base shares one)."""
    return attribute.category
