"""GL-specific attributes: raster state that only the GL engine understands.

They are ordinary mono attributes (each its own category), so other engines
push them passively and ignore them.  Each one is also a declarative
:class:`~omnirender.gl.state.StateKind`: ``capture()`` says what a draw item
records while it is active, ``default`` what it records otherwise, and the
class method ``apply`` sets the GL state for a captured value.  The GL engine
captures the active values into every draw item it compiles and applies them
at draw time, so popping an attribute restores the previous state for
everything that follows, without any GL call at traversal time.  A new state
attribute is one class here: the compiler, the renderer and the shaders pick
it up from its declaration (``ScissorTest`` and ``AlphaTest`` are such late
additions).
"""

from __future__ import annotations

from typing import Any

from ...core.component import MonoAttribute
from .context import set_masks
from .glenum import GL_DEPTH_CLAMP
from .state import GLCalls, StateKind, register_kind

__all__ = [
    "GLState",
    "DepthTest",
    "DepthMask",
    "Blend",
    "CullFace",
    "PolygonOffset",
    "ColorMask",
    "StencilTest",
    "StencilOp",
    "ScissorTest",
    "AlphaTest",
    "DepthClamp",
]

_FUNCS = ("never", "less", "equal", "lequal", "greater", "notequal", "gequal", "always")
_FACTORS = (
    "zero",
    "one",
    "src_color",
    "one_minus_src_color",
    "dst_color",
    "one_minus_dst_color",
    "src_alpha",
    "one_minus_src_alpha",
    "dst_alpha",
    "one_minus_dst_alpha",
)
_EQUATIONS = ("add", "subtract", "reverse_subtract", "min", "max")
_STENCIL_OPS = ("keep", "zero", "replace", "incr", "decr", "invert", "incr_wrap", "decr_wrap")
#: Depth comparisons by name (as om.gl.DepthTest's ``func``) -> moderngl's depth_func strings.
DEPTH_FUNCS = {
    "never": "0",
    "less": "<",
    "equal": "==",
    "lequal": "<=",
    "greater": ">",
    "notequal": "!=",
    "gequal": ">=",
    "always": "1",
}
#: GLSL comparison operators of the depth/alpha functions ("never"/"always" handled apart).
_GLSL_OPS = {"less": "<", "equal": "==", "lequal": "<=", "greater": ">", "notequal": "!=", "gequal": ">="}


def _choice(owner: str, name: str, value: str, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise ValueError(f"{owner}: {name} must be one of {choices}, got {value!r}")
    return value


def _whole(owner: str, name: str, value: Any, lo: int = 0, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int,)) and not hasattr(value, "__index__"):
        raise ValueError(f"{owner}: {name} must be a whole number, got {value!r}")
    value = int(value)
    if value < lo or (hi is not None and value > hi):
        top = "" if hi is None else f" and <= {hi}"
        raise ValueError(f"{owner}: {name} must be >= {lo}{top}, got {value}")
    return value


class GLState(MonoAttribute, StateKind):
    """Base of the GL raster-state attributes: a mono attribute that declares its GL state.

    Subclasses define ``capture()`` (the hashable value a draw item records),
    the class attribute ``default`` and the class method ``apply(gl, value)``;
    optionally ``orders``, ``features``, ``uniforms`` and ``fragment_code``
    (see :class:`~omnirender.gl.state.StateKind`).  Defining the class
    registers it.
    """

    __slots__ = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.name = cls.__name__
        register_kind(cls)

    def capture(self) -> Any:
        """The value draw items record while this attribute is active."""
        raise NotImplementedError(f"{type(self).__name__}.capture is not implemented")

    def parameters(self) -> dict:
        return {name: getattr(self, name) for name in self.__slots__}

    def key(self) -> tuple:
        """The parameters as a hashable tuple."""
        return tuple(getattr(self, name) for name in self.__slots__)


class DepthTest(GLState):
    """Enable (with comparison ``func``) or disable the depth test for the shapes that follow."""

    __slots__ = ("enabled", "func")
    default = "less"

    def __init__(self, enabled: bool = True, func: str = "less") -> None:
        super().__init__()
        self.enabled = bool(enabled)
        self.func = _choice("DepthTest", "func", func, _FUNCS)

    def capture(self) -> str | None:
        return self.func if self.enabled else None

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        ctx = gl.ctx
        if value is None:
            ctx.disable(ctx.DEPTH_TEST)
        else:
            ctx.enable(ctx.DEPTH_TEST)
            ctx.depth_func = DEPTH_FUNCS[value]

    @classmethod
    def orders(cls, value: Any) -> bool:
        return value != "less"


class _Switch:
    """Mixin of GL states that are one on/off flag (the concrete class declares the ``enabled`` slot)."""

    __slots__ = ()

    def __init__(self, enabled: bool = True) -> None:
        super().__init__()  # type: ignore[call-arg]
        self.enabled = bool(enabled)

    def capture(self) -> bool:
        return self.enabled


class DepthMask(_Switch, GLState):
    """Whether the shapes that follow write the depth buffer."""

    __slots__ = ("enabled",)
    default = True
    framebuffer_state = True  # moderngl sets it per framebuffer on use() and clear()

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        set_masks(gl.ctx, gl.raw, gl.framebuffer, depth=bool(value))

    @classmethod
    def orders(cls, value: Any) -> bool:
        return not value


class Blend(GLState):
    """Blending of the shapes that follow: ``src``/``dst`` factors and the ``equation``.

    Shapes under an enabled Blend are drawn in the transparent pass (after the
    opaque shapes, back to front).
    """

    __slots__ = ("enabled", "src", "dst", "equation")
    default = None

    def __init__(
        self, enabled: bool = True, src: str = "src_alpha", dst: str = "one_minus_src_alpha", equation: str = "add"
    ) -> None:
        super().__init__()
        self.enabled = bool(enabled)
        self.src = _choice("Blend", "src", src, _FACTORS)
        self.dst = _choice("Blend", "dst", dst, _FACTORS)
        self.equation = _choice("Blend", "equation", equation, _EQUATIONS)

    def capture(self) -> tuple[str, str, str] | None:
        return (self.src, self.dst, self.equation) if self.enabled else None

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        ctx = gl.ctx
        if value is None:
            ctx.disable(ctx.BLEND)
            return
        ctx.enable(ctx.BLEND)
        src, dst, eq = value
        if src == "src_alpha" and dst == "one_minus_src_alpha":
            # "over": the alpha channel accumulates coverage (a + (1 - a) dst), so a transparent
            # background keeps the right opacity
            ctx.blend_func = (ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA, ctx.ONE, ctx.ONE_MINUS_SRC_ALPHA)
        else:
            ctx.blend_func = (getattr(ctx, src.upper()), getattr(ctx, dst.upper()))
        ctx.blend_equation = {
            "add": ctx.FUNC_ADD,
            "subtract": ctx.FUNC_SUBTRACT,
            "reverse_subtract": ctx.FUNC_REVERSE_SUBTRACT,
            "min": ctx.MIN,
            "max": ctx.MAX,
        }[eq]


class CullFace(GLState):
    """Cull ``"back"`` or ``"front"`` faces, or ``"none"`` (overrides DrawStyle.cull)."""

    __slots__ = ("mode",)
    default = "none"

    def __init__(self, mode: str = "back") -> None:
        super().__init__()
        self.mode = _choice("CullFace", "mode", mode, ("none", "back", "front", "front_and_back"))

    def capture(self) -> str:
        return self.mode

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        ctx = gl.ctx
        if value == "none":
            ctx.disable(ctx.CULL_FACE)
        else:
            ctx.enable(ctx.CULL_FACE)
            ctx.cull_face = value


class PolygonOffset(GLState):
    """Depth offset ``factor * slope + units * r`` (glPolygonOffset), e.g. for decals or outlines."""

    __slots__ = ("factor", "units")
    default = None

    def __init__(self, factor: float = 1.0, units: float = 1.0) -> None:
        super().__init__()
        self.factor = float(factor)
        self.units = float(units)

    def capture(self) -> tuple[float, float]:
        return (self.factor, self.units)

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        gl.ctx.polygon_offset = value or (0.0, 0.0)


class ColorMask(GLState):
    """Which colour channels the shapes that follow write."""

    __slots__ = ("red", "green", "blue", "alpha")
    default = (True, True, True, True)
    framebuffer_state = True  # moderngl sets it per framebuffer on use() and clear()

    def __init__(self, red: bool = True, green: bool = True, blue: bool = True, alpha: bool = True) -> None:
        super().__init__()
        self.red, self.green, self.blue, self.alpha = bool(red), bool(green), bool(blue), bool(alpha)

    def capture(self) -> tuple[bool, bool, bool, bool]:
        return (self.red, self.green, self.blue, self.alpha)

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        set_masks(gl.ctx, gl.raw, gl.framebuffer, color=value)

    @classmethod
    def orders(cls, value: Any) -> bool:
        return value != (True, True, True, True)


class StencilTest(GLState):
    """Stencil test ``func(ref & mask, stencil & mask)`` for the shapes that follow (needs a stencil buffer)."""

    __slots__ = ("enabled", "func", "ref", "mask")
    default = None

    def __init__(self, enabled: bool = True, func: str = "always", ref: int = 0, mask: int = 0xFF) -> None:
        super().__init__()
        self.enabled = bool(enabled)
        self.func = _choice("StencilTest", "func", func, _FUNCS)
        self.ref = int(ref)
        self.mask = int(mask)

    def capture(self) -> tuple[str, int, int] | None:
        return (self.func, self.ref, self.mask) if self.enabled else None

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        gl.raw.stencil_test(gl.ctx, value)

    @classmethod
    def orders(cls, value: Any) -> bool:
        return value is not None


class StencilOp(GLState):
    """What the stencil test does on stencil fail, depth fail and pass; ``write_mask`` selects bits."""

    __slots__ = ("fail", "zfail", "zpass", "write_mask")
    default = ("keep", "keep", "keep", 0xFF)

    def __init__(self, fail: str = "keep", zfail: str = "keep", zpass: str = "keep", write_mask: int = 0xFF) -> None:
        super().__init__()
        self.fail = _choice("StencilOp", "fail", fail, _STENCIL_OPS)
        self.zfail = _choice("StencilOp", "zfail", zfail, _STENCIL_OPS)
        self.zpass = _choice("StencilOp", "zpass", zpass, _STENCIL_OPS)
        self.write_mask = int(write_mask)

    def capture(self) -> tuple[str, str, str, int]:
        return (self.fail, self.zfail, self.zpass, self.write_mask)

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        gl.raw.stencil_op(*value)

    @classmethod
    def orders(cls, value: Any) -> bool:
        return value != cls.default


class ScissorTest(GLState):
    """Draw the shapes that follow only inside a pixel rectangle (glScissor).

    ``box = (x, y, width, height)`` in pixels of the rendered image, measured
    from its top-left corner like ``om.Image`` and picking (OpenGL counts from
    the bottom; the engine converts).  ``ScissorTest(enabled=False)`` turns a
    scissor above it off.  Other engines ignore it.
    """

    __slots__ = ("enabled", "box")
    default = None
    framebuffer_state = True  # moderngl sets it per framebuffer on use() and clear()
    always_reassert = True  # a framebuffer keeps the scissor last set while it was bound

    def __init__(self, box: tuple[int, int, int, int] = (0, 0, 1, 1), enabled: bool = True) -> None:
        super().__init__()
        try:
            values = tuple(box)
        except TypeError:
            raise ValueError(f"ScissorTest: box must be (x, y, width, height) in pixels, got {box!r}") from None
        if len(values) != 4:
            raise ValueError(f"ScissorTest: box must be (x, y, width, height) in pixels, got {box!r}")
        x, y = (_whole("ScissorTest", n, v) for n, v in zip(("x", "y"), values[:2], strict=True))
        w, h = (_whole("ScissorTest", n, v, lo=1) for n, v in zip(("width", "height"), values[2:], strict=True))
        self.enabled = bool(enabled)
        self.box = (x, y, w, h)

    def capture(self) -> tuple[int, int, int, int] | None:
        return self.box if self.enabled else None

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        if value is None:
            gl.ctx.scissor = None
            return
        x, y, w, h = value
        gl.ctx.scissor = (x, gl.size[1] - y - h, w, h)  # GL's origin is the bottom-left corner


class AlphaTest(GLState):
    """Discard the fragments of the shapes that follow whose alpha fails ``func`` against ``ref``.

    The fixed-function alpha test of OpenGL 1 (``glAlphaFunc``), done in the
    fragment shader: ``AlphaTest("greater", 0.5)`` keeps fragments with alpha
    above one half (cut-out leaves, labels), and they write depth like opaque
    ones.  The alpha tested is the shape's colour alpha times its texture's.
    Other engines ignore it.
    """

    __slots__ = ("enabled", "func", "ref")
    default = None
    fragment_code = "uniform float u_alpha_ref;\nbool alpha_passes(float a) { return ALPHA_TEST; }\n"
    fragment_main = "if (!alpha_passes(base.a)) discard;"

    def __init__(self, func: str = "greater", ref: float = 0.5, enabled: bool = True) -> None:
        super().__init__()
        self.func = _choice("AlphaTest", "func", func, _FUNCS)
        ref = float(ref)
        if not 0.0 <= ref <= 1.0:
            raise ValueError(f"AlphaTest: ref must be in [0, 1], got {ref}")
        self.ref = ref
        self.enabled = bool(enabled)

    def capture(self) -> tuple[str, float] | None:
        return (self.func, self.ref) if self.enabled else None

    @classmethod
    def features(cls, value: Any) -> tuple[tuple[str, Any], ...]:
        if value is None:
            return ()
        func = value[0]
        test = "false" if func == "never" else "true" if func == "always" else f"a {_GLSL_OPS[func]} u_alpha_ref"
        return (("ALPHA_TEST", test),)

    @classmethod
    def uniforms(cls, value: Any) -> tuple[tuple[str, Any], ...]:
        return () if value is None else (("u_alpha_ref", float(value[1])),)


class DepthClamp(_Switch, GLState):
    """Clamp depth to the far plane instead of clipping (GL_DEPTH_CLAMP): shadow volumes reach infinity."""

    __slots__ = ("enabled",)
    default = False

    @classmethod
    def apply(cls, gl: GLCalls, value: Any) -> None:
        if value:
            gl.ctx.enable_direct(GL_DEPTH_CLAMP)
        else:
            gl.ctx.disable_direct(GL_DEPTH_CLAMP)
