"""Declarative GL state: what each state kind captures into a draw item and how it is applied.

Every GL raster-state kind (the GL attributes of :mod:`.attributes`, plus the
fill mode and line width the engine derives from ``om.DrawStyle``) is a
:class:`StateKind`: a ``default`` value (nothing active), ``apply(gl, value)``
(the GL calls that establish a value; applying the default restores it),
``orders(value)`` (whether the value makes drawing order matter, so batches
are never merged across it) and, for states the shader implements, program
``features(value)``, ``uniforms(value)``, ``fragment_code`` and
``fragment_main``.

Kinds register themselves when their class is defined; a draw item captures
one value per registered kind (its *raster* tuple, in registration order), and
the renderer applies a tuple by comparing it with the values applied last.
Adding a state therefore touches one module: the attribute's own.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

__all__ = [
    "StateKind",
    "GLCalls",
    "kinds",
    "register_kind",
    "RasterApplier",
    "FillMode",
    "LineWidth",
    "ShadowingState",
    "MirrorState",
    "casts_shadows",
    "not_mirror",
]


class StateKind:
    """The protocol of a GL state kind (GL attribute classes implement it as class methods)."""

    #: Name shown in reports and errors.
    name: str = "state"
    #: The captured value when nothing of this kind is active.
    default: Hashable = None
    #: Position in raster tuples (set by :func:`register_kind`).
    index: int = -1
    #: GLSL at global scope of the mesh/point fragment shader while the kind has features (functions, uniforms).
    fragment_code: str = ""
    #: GLSL run in the fragment shader's ``main`` once the surface colour ``base`` (vec4, linear, texture
    #: applied) is known and before lighting; it may ``discard``.
    fragment_main: str = ""

    @classmethod
    def source(cls) -> type | None:
        """A generic attribute class whose active instance the kind captures (``from_attribute`` makes the
        value); None for GL attributes and the kinds derived from DrawStyle."""
        return None

    @classmethod
    def from_attribute(cls, attribute: Any) -> Hashable:
        """The value captured while ``attribute`` (an instance of ``source``) is active."""
        return cls.default

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        """Make ``value`` the current GL state."""

    @classmethod
    def orders(cls, value: Any) -> bool:
        """Whether items with ``value`` must keep their drawing order (not merged across in batches)."""
        return False

    @classmethod
    def features(cls, value: Any) -> tuple[tuple[str, Any], ...]:
        """Shader ``#define``s the value needs (default: none)."""
        return ()

    @classmethod
    def uniforms(cls, value: Any) -> tuple[tuple[str, Any], ...]:
        """Uniform values the value needs (default: none)."""
        return ()


_KINDS: list[type[StateKind]] = []


def register_kind(kind: type[StateKind]) -> type[StateKind]:
    """Give ``kind`` the next raster position (once)."""
    if kind.__dict__.get("index", -1) < 0 or kind not in _KINDS:
        kind.index = len(_KINDS)
        _KINDS.append(kind)
    return kind


def kinds() -> tuple[type[StateKind], ...]:
    """The registered state kinds in raster order."""
    return tuple(_KINDS)


class GLCalls:
    """What ``apply`` functions reach: the moderngl context, the raw GL entry points, the bound framebuffer."""

    __slots__ = ("ctx", "raw", "framebuffer", "size")

    def __init__(self, ctx: Any, raw: Any, framebuffer: Any, size: tuple[int, int]) -> None:
        self.ctx = ctx
        self.raw = raw
        self.framebuffer = framebuffer
        self.size = size


@register_kind
class FillMode(StateKind):
    """Polygons filled or as wireframe (from ``om.DrawStyle(mode="wireframe")``)."""

    name = "fill mode"
    default = False  # wireframe off

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        gl.ctx.wireframe = bool(value)


@register_kind
class LineWidth(StateKind):
    """Wireframe line width in pixels (from ``om.DrawStyle.line_width``)."""

    name = "line width"
    default = 1.0

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        gl.ctx.line_width = float(value)


@register_kind
class ShadowingState(StateKind):
    """``om.Shadowing``: (casts, receives) shadows; shadow techniques select casters and receivers by it."""

    name = "shadowing"
    default = (True, True)

    @classmethod
    def source(cls) -> type:
        from ...attributes import Shadowing

        return Shadowing

    @classmethod
    def from_attribute(cls, attribute: Any) -> Hashable:
        return (bool(attribute.cast), bool(attribute.receive))


@register_kind
class MirrorState(StateKind):
    """``om.Mirror``: (reflectance, plane normal, plane offset) in the shape's coordinates, or None."""

    name = "mirror"
    default = None

    @classmethod
    def source(cls) -> type:
        from ...attributes import Mirror

        return Mirror

    @classmethod
    def from_attribute(cls, attribute: Any) -> Hashable:
        normal, offset = attribute.plane
        return (float(attribute.reflectance), tuple(normal), float(offset)) if attribute.reflectance > 0 else None


def casts_shadows(item: Any) -> bool:
    """Pass predicate: the item is opaque geometry that casts shadows (``om.Shadowing(cast=...)``)."""
    return item.state.kind == "mesh" and item.state.raster[ShadowingState.index][0]


def not_mirror(item: Any) -> bool:
    """Pass predicate: the item is not a mirror (what a mirror's reflection shows)."""
    return item.state.raster[MirrorState.index] is None


class RasterApplier:
    """Applies raster tuples, issuing GL calls only for the kinds whose value changed."""

    __slots__ = ("current", "gl")

    def __init__(self, gl: GLCalls) -> None:
        self.gl = gl
        self.current: list[Any] | None = None

    def apply(self, raster: tuple[Any, ...]) -> None:
        current = self.current
        all_kinds = _KINDS
        if current is None:
            self.current = list(raster)
            for kind, value in zip(all_kinds, raster, strict=False):  # kinds defined after a compile: left as they are
                kind.apply(self.gl, value)
            return
        for i, value in enumerate(raster):
            if current[i] != value:
                all_kinds[i].apply(self.gl, value)
                current[i] = value

    def forget(self) -> None:
        """The GL state was changed behind our back (a drawer, a full-screen pass): apply everything next time."""
        self.current = None

    def restore_defaults(self) -> None:
        """State preservation: every kind back to its default."""
        self.apply(defaults())
        self.current = None


def defaults() -> tuple[Any, ...]:
    """The raster tuple with every kind at its default (made again only when a kind was registered since)."""
    global _DEFAULTS
    if len(_DEFAULTS) != len(_KINDS):
        _DEFAULTS = tuple(kind.default for kind in _KINDS)
    return _DEFAULTS


_DEFAULTS: tuple[Any, ...] = ()
