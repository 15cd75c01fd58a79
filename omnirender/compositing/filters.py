"""Filters: leaves of a renderer tree that change the image already made (colour only, never depth).

A filter copies what is in the framebuffer (``Canvas.copy``: colour, and depth
when it needs it) and draws one full-screen triangle over it.  Put a filter in
a ``DepthGroup(offscreen=True)`` to change only that group's children.

* :class:`LuminanceFilter`: colour to grey (luminance of the linear colour);
* :class:`BufferDebugFilter`: overlays a buffer one cannot see -- ``"depth"``
  (near bright, far dark, stretched over the depths present), ``"alpha"`` or
  ``"stencil"`` (one colour per stencil value);
* :class:`GLSLFilter`: a user's GLSL function of the colour, depth and position.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from ..gl import StencilTest, Target
from .canvas import EYE_DISTANCE, Canvas, eye_distance, fraction, target_name
from .renderer import Filter

__all__ = ["LuminanceFilter", "BufferDebugFilter", "GLSLFilter", "STENCIL_PALETTE"]

log = logging.getLogger(__name__)

_SOURCE = """
uniform sampler2D u_image;
uniform sampler2D u_image_depth;
vec4 source_color() { return texelFetch(u_image, ivec2(gl_FragCoord.xy), 0); }
float source_depth() { return texelFetch(u_image_depth, ivec2(gl_FragCoord.xy), 0).r; }
"""

LUMINANCE = (
    _SOURCE
    + """
uniform vec3 u_weights;
vec4 effect(vec2 uv) {
    vec4 c = source_color();
    return vec4(to_srgb(vec3(dot(to_linear(c.rgb), u_weights))), c.a);
}
"""
)

DEBUG_DEPTH = (
    _SOURCE
    + EYE_DISTANCE
    + """
uniform vec2 u_range;   // linear depth shown white, black
uniform vec3 u_camera;  // near, far, orthographic (1)
uniform float u_opacity;
vec4 effect(vec2 uv) {
    float d = source_depth();
    if (d >= 1.0) discard;                                   // nothing drawn here: no depth to show
    float z = eye_distance(d, u_camera);
    float g = 1.0 - clamp((z - u_range.x) / max(u_range.y - u_range.x, 1e-9), 0.0, 1.0);
    vec4 c = source_color();
    return vec4(mix(c.rgb, vec3(g), u_opacity), c.a);
}
"""
)

DEBUG_ALPHA = (
    _SOURCE
    + """
uniform float u_opacity;
vec4 effect(vec2 uv) {
    vec4 c = source_color();
    return vec4(mix(c.rgb, vec3(c.a), u_opacity), c.a);
}
"""
)

FLAT = """
uniform vec4 u_flat;
vec4 effect(vec2 uv) { return u_flat; }
"""

#: sRGB colours of stencil values 1..15 in the stencil overlay; larger values show white, 0 nothing.
STENCIL_PALETTE = tuple(
    tuple(float(c) for c in rgb)
    for rgb in (
        (0.90, 0.10, 0.10), (0.10, 0.70, 0.10), (0.15, 0.35, 0.95), (0.95, 0.85, 0.10), (0.85, 0.20, 0.85),
        (0.10, 0.85, 0.85), (0.95, 0.55, 0.10), (0.55, 0.25, 0.05), (0.55, 0.75, 0.25), (0.45, 0.10, 0.60),
        (0.95, 0.60, 0.70), (0.20, 0.45, 0.45), (0.60, 0.60, 0.95), (0.40, 0.40, 0.40), (0.75, 0.75, 0.55),
    )
)  # fmt: skip


def _source(canvas: Canvas, owner: Any, depth: bool = False) -> dict[str, tuple[str, str]]:
    """Copy the framebuffer (colour, and depth if asked) for ``owner``; the inputs naming the copy."""
    name = target_name(owner, "image")
    canvas.copy(Target(name, depth=depth, relative="enclosing"))
    inputs = {"u_image": (name, "color")}
    if depth:
        inputs["u_image_depth"] = (name, "depth")
    return inputs


class LuminanceFilter(Filter):
    """Colour to grey: the luminance of the linear colour (``weights``: Rec. 709 by default)."""

    __slots__ = ("weights",)

    def __init__(self, weights: tuple[float, float, float] = (0.2126, 0.7152, 0.0722)) -> None:
        super().__init__()
        w = np.asarray(weights, dtype=np.float64)
        if w.shape != (3,) or not np.all(np.isfinite(w)) or np.any(w < 0):
            raise ValueError(f"LuminanceFilter: weights must be 3 numbers >= 0, got {weights!r}")
        self.weights = tuple(float(v) for v in w)

    def draw(self, canvas: Canvas) -> None:
        with canvas.preserved():
            canvas.fullscreen("luminance", LUMINANCE, _source(canvas, self), {"u_weights": self.weights})


class BufferDebugFilter(Filter):
    """Overlays an invisible buffer on the image: ``buffer="depth"``, ``"alpha"`` or ``"stencil"``.

    ``opacity`` mixes the overlay with the image.  Depth shows near as white
    and far as black over the range of depths drawn (read back once per frame:
    a debugging aid, not for speed); stencil paints values 1..15 in
    :data:`STENCIL_PALETTE` and larger ones white (only where the framebuffer
    has a stencil buffer: the frame's, not a group's offscreen target).
    """

    __slots__ = ("buffer", "opacity")
    BUFFERS = ("depth", "alpha", "stencil")

    def __init__(self, buffer: str = "depth", opacity: float = 0.85) -> None:
        super().__init__()
        if buffer not in self.BUFFERS:
            raise ValueError(f"BufferDebugFilter: buffer must be one of {self.BUFFERS}, got {buffer!r}")
        self.buffer = buffer
        self.opacity = fraction("BufferDebugFilter", "opacity", opacity)

    def draw(self, canvas: Canvas) -> None:
        with canvas.preserved():
            if self.buffer == "alpha":
                canvas.fullscreen("debug-alpha", DEBUG_ALPHA, _source(canvas, self), {"u_opacity": self.opacity})
            elif self.buffer == "depth":
                self._depth(canvas)
            else:
                self._stencil(canvas)

    def _depth(self, canvas: Canvas) -> None:
        inputs = _source(canvas, self, depth=True)
        window = canvas.target(inputs["u_image"][0]).depth_array()
        z = eye_distance(window[window < 1.0], canvas.projection)
        if z.size == 0:
            return
        uniforms = {"u_range": (float(z.min()), float(z.max())), "u_camera": canvas.camera_uniform,
                    "u_opacity": self.opacity}  # fmt: skip
        canvas.fullscreen("debug-depth", DEBUG_DEPTH, inputs, uniforms)

    def _stencil(self, canvas: Canvas) -> None:
        from ..gl.engine.glstate import stencil_bits

        if stencil_bits() == 0:
            log.warning("BufferDebugFilter: the framebuffer being drawn has no stencil buffer; nothing to show")
            return
        for value, rgb in enumerate(STENCIL_PALETTE, start=1):
            test = StencilTest(func="equal", ref=value)
            canvas.fullscreen(f"debug-stencil-{value}", FLAT, (), {"u_flat": (*rgb, self.opacity)}, blend=True,
                              state=[test])  # fmt: skip
        beyond = StencilTest(func="less", ref=len(STENCIL_PALETTE))  # 15 < stencil
        canvas.fullscreen("debug-stencil-more", FLAT, (), {"u_flat": (1.0, 1.0, 1.0, self.opacity)}, blend=True,
                          state=[beyond])  # fmt: skip


class GLSLFilter(Filter):
    """A user's filter: GLSL defining ``vec4 filter_color(vec4 color, float depth, vec2 uv)``.

    ``color`` is the pixel's (display values, alpha), ``depth`` its window
    depth (1: nothing drawn), ``uv`` its position in [0, 1]; the function
    returns the new colour.  ``uniforms`` gives values of uniforms it declares.
    """

    __slots__ = ("glsl", "uniforms")

    def __init__(self, glsl: str, uniforms: Any = None) -> None:
        super().__init__()
        if not isinstance(glsl, str) or "filter_color" not in glsl:
            raise ValueError(
                f"GLSLFilter: glsl must define vec4 filter_color(vec4 color, float depth, vec2 uv), got {glsl!r:.60}"
            )
        self.glsl = glsl
        self.uniforms = dict(uniforms or {})

    def draw(self, canvas: Canvas) -> None:
        fragment = (
            _SOURCE
            + self.glsl
            + "\nvec4 effect(vec2 uv) { return filter_color(source_color(), source_depth(), uv); }\n"
        )
        with canvas.preserved():
            canvas.fullscreen("glsl-filter", fragment, _source(canvas, self, depth=True), self.uniforms)
