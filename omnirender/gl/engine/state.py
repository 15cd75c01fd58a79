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

from .glenum import GL_CLIP_DISTANCE0, GL_SAMPLE_MASK

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
    #: Whether binding a framebuffer or a moderngl clear sets this state to the framebuffer's own value
    #: (moderngl keeps colour and depth masks and the scissor per framebuffer): the applier issues it again.
    framebuffer_state: bool = False
    #: ... and the framebuffer's own value may be any (not only the default): issued again in every case.
    always_reassert: bool = False
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
    """The GL state of a frame: applies raster tuples, issuing GL calls only for the kinds whose value changed,
    and owns the few states that are not kinds (the bound framebuffer and viewport, the front face, the
    enabled clip distances).

    Engine code changes GL state only through it, so what it tracks is what GL holds.  Code outside the
    engine that may change any state (a custom pass, a drawer of its own kind) is followed by
    :meth:`forget`: the next :meth:`apply` then sets every kind.
    """

    __slots__ = ("current", "gl", "clip_count", "face", "samples")

    def __init__(self, gl: GLCalls) -> None:
        self.gl = gl
        self.current: list[Any] | None = None
        #: how many clip distances are enabled (GL_CLIP_DISTANCE0 ...)
        self.clip_count = 0
        #: the front face winding ("ccw" or "cw")
        self.face = "ccw"
        #: the one sample a multisampled draw writes (GL_SAMPLE_MASK), or None: every sample
        self.samples: int | None = None

    def apply(self, raster: tuple[Any, ...]) -> None:
        current = self.current
        all_kinds = _KINDS
        if current is None:
            self.current = list(raster)
            gl = self.gl
            n = len(raster)
            for i, apply in _issuing():  # kinds that issue GL calls (the others live in shaders or passes)
                if i < n:  # kinds defined after a compile: left as they are
                    apply(gl, raster[i])
            return
        for i, value in enumerate(raster):
            if current[i] != value:
                all_kinds[i].apply(self.gl, value)
                current[i] = value

    def override(self, values: dict[int, Any]) -> None:
        """Change the kinds at the raster positions in ``values`` (the others stay as they are)."""
        raster = list(self.current if self.current is not None else defaults())
        for index, value in values.items():
            raster[index] = value
        self.apply(tuple(raster))

    def value(self, kind: type[StateKind]) -> Any:
        """The value of ``kind`` GL holds now (its default when nothing was applied yet)."""
        return (self.current if self.current is not None else defaults())[kind.index]

    def reassert(self) -> None:
        """Issue again the kinds a framebuffer bind or a moderngl clear resets to the framebuffer's own values
        (colour and depth masks, scissor): GL holds the tracked values again.  moderngl keeps a framebuffer's
        masks at their defaults while they are set with raw calls, so only masks away from the default are
        issued (all of them without raw GL); the scissor a framebuffer keeps may be any, so it always is."""
        current = self.current
        if current is None:
            return
        exact = not self.gl.raw.available
        for kind in _KINDS:
            if kind.framebuffer_state and kind.index < len(current):
                value = current[kind.index]
                if exact or kind.always_reassert or value != kind.default:
                    kind.apply(self.gl, value)

    def bind(self, framebuffer: Any, size: tuple[int, int], viewport: tuple[int, int, int, int] | None = None) -> None:
        """Draw into ``framebuffer`` of ``size`` (the whole of it, or the pixel rectangle ``viewport``)."""
        framebuffer.use()
        self.gl.framebuffer = framebuffer
        self.gl.size = tuple(size)
        self.gl.ctx.viewport = viewport if viewport is not None else (0, 0, *size)
        self.reassert()

    def viewport(self, box: tuple[int, int, int, int]) -> None:
        """Draw into the pixel rectangle ``box`` (x, y from the bottom-left) of the bound framebuffer."""
        self.gl.ctx.viewport = box

    def front_face(self, winding: str) -> None:
        """Which winding faces the camera: ``"ccw"`` (GL's default) or ``"cw"`` (mirrored cameras)."""
        if winding != self.face:
            self.gl.ctx.front_face = winding
            self.face = winding

    def clip_planes(self, count: int) -> None:
        """Enable clip distances 0 .. ``count`` - 1 and disable the others (up to 6)."""
        if count == self.clip_count:
            return
        ctx = self.gl.ctx
        for i in range(6):
            if i < count:
                ctx.enable_direct(GL_CLIP_DISTANCE0 + i)
            else:
                ctx.disable_direct(GL_CLIP_DISTANCE0 + i)
        self.clip_count = count

    def clear(
        self,
        framebuffer: Any,
        color: tuple[float, ...],
        depth: float,
        write_depth: bool,
        viewport: tuple[int, int, int, int] | None = None,
    ) -> None:
        """Clear ``framebuffer`` with moderngl (colour ``color`` where the colour mask writes, depth ``depth``
        when ``write_depth``; only the pixel rectangle ``viewport``, GL's bottom-left origin, when given), then
        issue the tracked masks again.  moderngl applies the framebuffer's own depth mask when it clears: it is
        set for the clear and back to its default after."""
        framebuffer.depth_mask = write_depth
        framebuffer.clear(*color, depth=depth, viewport=viewport)
        framebuffer.depth_mask = True
        self.reassert()

    def begin(self, framebuffer: Any, size: tuple[int, int]) -> None:
        """A frame starts: ``framebuffer`` bound, every kind at its default (what a clear needs: every channel
        written, no scissor), point sizes taken from the programs."""
        self.bind(framebuffer, size)
        self.apply(defaults())
        ctx = self.gl.ctx
        ctx.enable(ctx.PROGRAM_POINT_SIZE)

    def sample_mask(self, sample: int | None) -> None:
        """Let draws write only sample ``sample`` of a multisampled target (None: every sample)."""
        if sample == self.samples:
            return
        ctx = self.gl.ctx
        if sample is None:
            ctx.disable_direct(GL_SAMPLE_MASK)
        else:
            ctx.enable_direct(GL_SAMPLE_MASK)
            self.gl.raw.glSampleMaski(0, 1 << sample)
        self.samples = sample

    def forget(self) -> None:
        """Code outside the engine may have changed any GL state (a custom pass, a drawer of its own kind):
        apply every state next time."""
        self.current = None
        self.clip_count = -1
        self.face = ""
        self.samples = -1

    def restore_defaults(self) -> None:
        """State preservation: every state back to its default (what a plain moderngl user expects)."""
        self.apply(defaults())
        self.clip_planes(0)
        self.front_face("ccw")
        self.sample_mask(None)


def defaults() -> tuple[Any, ...]:
    """The raster tuple with every kind at its default (made again only when a kind was registered since)."""
    global _DEFAULTS
    if len(_DEFAULTS) != len(_KINDS):
        _DEFAULTS = tuple(kind.default for kind in _KINDS)
    return _DEFAULTS


_DEFAULTS: tuple[Any, ...] = ()


def _issuing() -> tuple[tuple[int, Any], ...]:
    """(raster index, apply) of the kinds whose ``apply`` issues GL calls (not the base class's no-op)."""
    global _ISSUING
    if _ISSUING[0] != len(_KINDS):
        noop = StateKind.__dict__["apply"].__func__
        _ISSUING = (
            len(_KINDS),
            tuple((k.index, k.apply) for k in _KINDS if getattr(k.apply, "__func__", None) is not noop),
        )
    return _ISSUING[1]


_ISSUING: tuple[int, tuple[tuple[int, Any], ...]] = (-1, ())
