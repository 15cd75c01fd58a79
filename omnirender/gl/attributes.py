"""GL-specific attributes: raster state that only the GL engine understands.

They are ordinary mono attributes (each its own category), so other engines
push them passively and ignore them.  The GL engine captures the active state
into every draw item it compiles; popping an attribute therefore restores the
previous state for everything that follows, without any GL call at traversal
time.
"""

from __future__ import annotations

from ..core.component import MonoAttribute

__all__ = ["DepthTest", "DepthMask", "Blend", "CullFace", "PolygonOffset", "ColorMask", "StencilTest", "StencilOp"]

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


def _choice(owner: str, name: str, value: str, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise ValueError(f"{owner}: {name} must be one of {choices}, got {value!r}")
    return value


class _GLState(MonoAttribute):
    __slots__ = ()

    def parameters(self) -> dict:
        return {name: getattr(self, name) for name in self.__slots__}

    def key(self) -> tuple:
        """The captured state (hashable)."""
        return tuple(getattr(self, name) for name in self.__slots__)


class DepthTest(_GLState):
    """Enable (with comparison ``func``) or disable the depth test for the shapes that follow."""

    __slots__ = ("enabled", "func")

    def __init__(self, enabled: bool = True, func: str = "less") -> None:
        super().__init__()
        self.enabled = bool(enabled)
        self.func = _choice("DepthTest", "func", func, _FUNCS)


class DepthMask(_GLState):
    """Whether the shapes that follow write the depth buffer."""

    __slots__ = ("enabled",)

    def __init__(self, enabled: bool = True) -> None:
        super().__init__()
        self.enabled = bool(enabled)


class Blend(_GLState):
    """Blending of the shapes that follow: ``src``/``dst`` factors and the ``equation``.

    Shapes under an enabled Blend are drawn in the transparent pass (after the
    opaque shapes, back to front).
    """

    __slots__ = ("enabled", "src", "dst", "equation")

    def __init__(
        self, enabled: bool = True, src: str = "src_alpha", dst: str = "one_minus_src_alpha", equation: str = "add"
    ) -> None:
        super().__init__()
        self.enabled = bool(enabled)
        self.src = _choice("Blend", "src", src, _FACTORS)
        self.dst = _choice("Blend", "dst", dst, _FACTORS)
        self.equation = _choice("Blend", "equation", equation, _EQUATIONS)


class CullFace(_GLState):
    """Cull ``"back"`` or ``"front"`` faces, or ``"none"`` (overrides DrawStyle.cull)."""

    __slots__ = ("mode",)

    def __init__(self, mode: str = "back") -> None:
        super().__init__()
        self.mode = _choice("CullFace", "mode", mode, ("none", "back", "front", "front_and_back"))


class PolygonOffset(_GLState):
    """Depth offset ``factor * slope + units * r`` (glPolygonOffset), e.g. for decals or outlines."""

    __slots__ = ("factor", "units")

    def __init__(self, factor: float = 1.0, units: float = 1.0) -> None:
        super().__init__()
        self.factor = float(factor)
        self.units = float(units)


class ColorMask(_GLState):
    """Which colour channels the shapes that follow write."""

    __slots__ = ("red", "green", "blue", "alpha")

    def __init__(self, red: bool = True, green: bool = True, blue: bool = True, alpha: bool = True) -> None:
        super().__init__()
        self.red, self.green, self.blue, self.alpha = bool(red), bool(green), bool(blue), bool(alpha)


class StencilTest(_GLState):
    """Stencil test ``func(ref & mask, stencil & mask)`` for the shapes that follow (needs a stencil buffer)."""

    __slots__ = ("enabled", "func", "ref", "mask")

    def __init__(self, enabled: bool = True, func: str = "always", ref: int = 0, mask: int = 0xFF) -> None:
        super().__init__()
        self.enabled = bool(enabled)
        self.func = _choice("StencilTest", "func", func, _FUNCS)
        self.ref = int(ref)
        self.mask = int(mask)


class StencilOp(_GLState):
    """What the stencil test does on stencil fail, depth fail and pass; ``write_mask`` selects bits."""

    __slots__ = ("fail", "zfail", "zpass", "write_mask")

    def __init__(self, fail: str = "keep", zfail: str = "keep", zpass: str = "keep", write_mask: int = 0xFF) -> None:
        super().__init__()
        self.fail = _choice("StencilOp", "fail", fail, _STENCIL_OPS)
        self.zfail = _choice("StencilOp", "zfail", zfail, _STENCIL_OPS)
        self.zpass = _choice("StencilOp", "zpass", zpass, _STENCIL_OPS)
        self.write_mask = int(write_mask)
