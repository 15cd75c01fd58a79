"""Offscreen targets for compositing: a framebuffer stack and depth sprites (DESIGN.md's integration rules).

* :class:`FramebufferStack`: ``push()`` redirects an engine's drawing into a new
  offscreen colour + depth target, ``pop()`` returns to the previous one and
  hands back the target (its textures can be composited).  A renderer that
  needs a known buffer state works in a pushed target and merges afterwards
  (rule 1, preservation of results).
* :class:`DepthSprite`: ``save()`` copies the current framebuffer's colour and
  depth into textures; ``restore()`` writes them back with a full-screen pass
  that sets ``gl_FragDepth`` per pixel, so colour and depth stay consistent
  (rule 2).  Both restore the GL state they change (rule 4) and never touch
  the stencil buffer (rule 3).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .attributes import DepthTest

__all__ = ["OffscreenTarget", "FramebufferStack", "DepthSprite"]

_VS = """
in vec2 in_pos;
out vec2 v_uv;
void main() {
    v_uv = in_pos * 0.5 + 0.5;
    gl_Position = vec4(in_pos, 0.0, 1.0);
}
"""

_FS = """
in vec2 v_uv;
uniform sampler2D u_color;
uniform sampler2D u_depth;
out vec4 f_color;
void main() {
    float d = texture(u_depth, v_uv).r;
    if (d >= 1.0) discard;       // keep what is behind where the sprite saw nothing
    gl_FragDepth = d;
    f_color = texture(u_color, v_uv);
}
"""


class OffscreenTarget:
    """A single-sample colour texture + depth texture framebuffer."""

    def __init__(self, ctx: Any, size: tuple[int, int], current: Any) -> None:
        self.ctx = ctx
        self.current = current
        self.size = size
        self.color = ctx.texture(size, 4)
        self.depth = ctx.depth_texture(size)
        self.color.filter = self.depth.filter = (ctx.NEAREST, ctx.NEAREST)
        self.depth.compare_func = ""  # sample depth values, not comparisons
        self.fbo = ctx.framebuffer(self.color, self.depth)

    def color_array(self) -> np.ndarray:
        """(H, W, 4) uint8, top row first."""
        w, h = self.size
        with self.current():
            data = self.fbo.read(components=4, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(h, w, 4)[::-1].copy()

    def depth_array(self) -> np.ndarray:
        """(H, W) window depth in [0, 1], top row first."""
        w, h = self.size
        with self.current():
            raw = self.fbo.read(components=1, attachment=-1, dtype="f4", alignment=1)
        return np.frombuffer(raw, np.float32).reshape(h, w)[::-1].copy()

    def release(self) -> None:
        with self.current():
            self.fbo.release()
            self.color.release()
            self.depth.release()


class FramebufferStack:
    """Push offscreen targets onto a GL engine; the engine draws into the top one."""

    def __init__(self, engine: Any) -> None:
        self.engine = engine

    def push(self, size: tuple[int, int] | None = None, clear: bool = True) -> OffscreenTarget:
        """A new target the engine draws into until :meth:`pop` (cleared to transparent black)."""
        e = self.engine
        with e.current():
            target = OffscreenTarget(e.ctx, size or e.size, e.current)
            if clear:  # (moderngl binds the framebuffer it clears for the clear, and the bound one again after)
                target.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        e.push_target(target)
        return target

    def pop(self) -> OffscreenTarget:
        """Return to the previous target; the popped one is handed back (release it when done)."""
        e = self.engine
        target = e.pop_target()
        with e.current(), e.between_frames():
            pass  # the engine's own framebuffer bound again (the popped one may be released), GL at its defaults
        return target

    def __len__(self) -> int:
        return self.engine.pushed_targets


class DepthSprite:
    """Colour and depth of a framebuffer saved into textures and drawn back later."""

    def __init__(self, engine: Any) -> None:
        self.engine = engine
        self.target: OffscreenTarget | None = None

    def save(self) -> DepthSprite:
        """Copy the engine's current framebuffer (resolved) into the sprite."""
        e = self.engine
        with e.current():
            if self.target is None or self.target.size != e.size:
                if self.target is not None:
                    self.target.release()
                self.target = OffscreenTarget(e.ctx, e.size, e.current)
            e.ctx.copy_framebuffer(self.target.fbo, e.framebuffer)
        return self

    def restore(self) -> None:
        """Draw the saved colour and depth into the engine's current framebuffer (depth-tested)."""
        if self.target is None:
            raise RuntimeError("DepthSprite.restore: save() was not called")
        e = self.engine
        ctx = e.ctx
        with e.current():
            if not e.programs.registered("sprite"):
                e.programs.register("sprite", _VS, _FS)
            prog = e.programs.get("sprite")
            quad = ctx.buffer(np.array([-1, -1, 3, -1, -1, 3], np.float32).tobytes())
            vao = ctx.vertex_array(prog, [(quad, "2f", "in_pos")])
            with e.between_frames():  # every state at its default (no blend, no culling, all masks written)
                e.apply_gl_state(DepthTest(func="lequal"))
                self.target.color.use(0)
                self.target.depth.use(1)
                prog["u_color"].value = 0
                prog["u_depth"].value = 1
                vao.render()
            vao.release()
            quad.release()

    def release(self) -> None:
        if self.target is not None:
            with self.engine.current():
                self.target.release()
            self.target = None
