"""Renderer groups combining their children by depth: :class:`DepthGroup` and :class:`OcclusionGroup`.

A group that needs its children's image on its own renders them into an
offscreen target (a nested pass with ``om.gl.Target``, cleared to
transparent black: the children's colour is then premultiplied by their
coverage) and merges it back into the framebuffer with a full-screen pass
that writes colour and depth together -- a depth sprite.  :func:`merge_by_depth`
is that merge; it discards pixels the children left empty, so nothing outside
their footprint changes (integration rules 1 and 2).
"""

from __future__ import annotations

from collections.abc import Iterable

from ..gl import Clear, Target
from .canvas import Canvas, fraction, target_name
from .renderer import Renderer, RendererGroup, draw_all

__all__ = ["DepthGroup", "OcclusionGroup", "merge_by_depth", "draw_offscreen", "MERGE"]

#: Full-screen GLSL: an offscreen image (premultiplied colour + depth) merged "over" the framebuffer by depth.
MERGE = """
uniform sampler2D u_color;
uniform sampler2D u_depth;
vec4 effect(vec2 uv) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 c = texelFetch(u_color, p, 0);
    if (texelFetch(u_depth, p, 0).r >= 1.0 || c.a <= 0.0) discard;  // the children drew nothing here
    return vec4(c.rgb / c.a, c.a);
}
float effect_depth(vec2 uv) { return texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r; }
"""

#: Full-screen GLSL of the occlusion group: B (the children) over A (what was there), hidden parts of B revealed.
OCCLUSION = """
uniform sampler2D u_a_color;
uniform sampler2D u_a_depth;
uniform sampler2D u_b_color;
uniform sampler2D u_b_depth;
uniform float u_opacity;   // how much of B shows where A hides it (1: fully)
float g_depth;
vec4 effect(vec2 uv) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 b = texelFetch(u_b_color, p, 0);
    float bd = texelFetch(u_b_depth, p, 0).r;
    if (bd >= 1.0 || b.a <= 0.0) discard;                      // B is empty here: A stays
    vec4 a = texelFetch(u_a_color, p, 0);
    float ad = texelFetch(u_a_depth, p, 0).r;
    vec4 over = vec4(b.rgb + (1.0 - b.a) * a.rgb, b.a + (1.0 - b.a) * a.a);
    if (bd < ad) { g_depth = bd; return over; }                 // B in front: the depth test's answer
    g_depth = u_opacity >= 1.0 ? bd : ad;                       // B hidden: shown fully (B's depth) or through A
    return mix(a, over, u_opacity);
}
float effect_depth(vec2 uv) { return g_depth; }
"""


def draw_offscreen(canvas: Canvas, owner: object, children: Iterable[Renderer], role: str = "children") -> str:
    """Draw ``children`` into a cleared offscreen target of ``owner``; returns the target's name."""
    target = Target(target_name(owner, role), relative="enclosing")
    items = tuple(children)
    canvas.into(role, lambda inner: draw_all(inner, items), target=target, clear=Clear())
    return target.name


def merge_by_depth(canvas: Canvas, target: str, name: str = "merge") -> None:
    """Merge offscreen target ``target`` (premultiplied colour + depth) over the framebuffer, depth-tested."""
    inputs = {"u_color": (target, "color"), "u_depth": (target, "depth")}
    canvas.fullscreen(name, MERGE, inputs, blend=True, depth=True, depth_test="less")


class DepthGroup(RendererGroup):
    """Children combined by the depth test, in order.

    By default they draw straight into the current framebuffer.  With
    ``offscreen=True`` they draw into a target of their own which is then
    merged by depth: filters among the children then change only the
    children's image.
    """

    __slots__ = ("offscreen",)

    def __init__(self, children: Iterable[Renderer] = (), offscreen: bool = False) -> None:
        super().__init__(children)
        self.offscreen = bool(offscreen)

    def composite(self, canvas: Canvas, children: tuple[Renderer, ...]) -> None:
        if not self.offscreen:
            draw_all(canvas, children)
            return
        merge_by_depth(canvas, draw_offscreen(canvas, self, children))

    def draws_layers(self) -> bool:
        return all(child.draws_layers() for child in self.children)

    def draw_layer(self, canvas: Canvas, peel: str | None) -> None:
        """In a ``DepthPeelGroup`` the children's layers are drawn together (offscreen or not)."""
        for child in self.children:
            child.draw_layer(canvas, peel)


class OcclusionGroup(RendererGroup):
    """Shows what its children draw (image B) even where what is already there (image A) hides it.

    Both images keep their depth buffers.  Where B is in front it is merged by
    depth as usual; where A hides B, ``mode="visible"`` shows B fully (B's
    depth is kept there) and ``mode="semi-transparent"`` shows B through A with
    ``opacity`` (A's depth is kept).  The seed's example: vessels inside a
    liver volume, seen through it.
    """

    __slots__ = ("mode", "opacity")
    MODES = ("visible", "semi-transparent")

    def __init__(self, children: Iterable[Renderer] = (), mode: str = "visible", opacity: float = 0.5) -> None:
        super().__init__(children)
        if mode not in self.MODES:
            raise ValueError(f"OcclusionGroup: mode must be one of {self.MODES}, got {mode!r}")
        self.mode = mode
        self.opacity = fraction("OcclusionGroup", "opacity", opacity)

    def composite(self, canvas: Canvas, children: tuple[Renderer, ...]) -> None:
        a = target_name(self, "A")
        canvas.copy(Target(a))
        b = draw_offscreen(canvas, self, children, "B")
        inputs = {"u_a_color": (a, "color"), "u_a_depth": (a, "depth"), "u_b_color": (b, "color"),
                  "u_b_depth": (b, "depth")}  # fmt: skip
        opacity = 1.0 if self.mode == "visible" else self.opacity
        canvas.fullscreen("occlusion", OCCLUSION, inputs, {"u_opacity": opacity}, depth=True)
