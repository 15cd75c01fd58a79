"""Image-space building blocks: offscreen targets, the one full-screen triangle, ping-pong chains.

* :class:`RenderTarget`: the GPU side of a :class:`~.passes.Target`
  description: one texture per named colour attachment (8-bit or float), an
  optional depth texture that later passes sample, and their framebuffer.
* :class:`FullScreenPrograms`: programs of :class:`~.passes.FullScreen`
  passes, all drawing the same single triangle that covers the viewport
  (three vertices, no quad seam), compiled once per snippet.
* :class:`PingPong`: two targets used alternately, so a chain of effects
  reads the previous result and writes the next (the idea of three.js's
  ``EffectComposer``).  It holds names only: which target a step writes is a
  function of the step, so one instance serves any number of technique runs.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .passes import FORMATS, FullScreen, Target
from .resources import gpu_call
from .shaders import SRGB_GLSL

__all__ = ["RenderTarget", "FullScreenPrograms", "PingPong", "RESOLVE", "resolve"]

_TRIANGLE = np.array([-1.0, -1.0, 3.0, -1.0, -1.0, 3.0], np.float32)

_VERTEX = """#version 330
in vec2 in_pos;
out vec2 v_uv;
void main() {
    v_uv = in_pos * 0.5 + 0.5;
    gl_Position = vec4(in_pos, 0.0, 1.0);
}
"""

_FRAGMENT_HEAD = (
    """#version 330
in vec2 v_uv;
uniform vec2 u_resolution;   // the target's size in pixels
layout(location = 0) out vec4 f_color;
"""
    + SRGB_GLSL
)


class RenderTarget:
    """Textures and framebuffer of one offscreen target (made from a :class:`Target` at a pixel size)."""

    def __init__(
        self, ctx: Any, description: Target, size: tuple[int, int], raw: Any = None, shared_depth: Any = None
    ) -> None:
        self.ctx = ctx
        self.description = description
        self.size = size
        self.colors: dict[str, Any] = {}
        samples = description.samples
        what = f"target {description.name!r}"
        for name in description.colors:
            components, dtype, internal, _ = FORMATS[description.format_of(name)]
            options = {"internal_format": internal} if internal is not None else {}
            tex = gpu_call(ctx.texture, size, components, dtype=dtype, samples=samples, what=what, **options)
            if not samples:  # multisampled textures have no sampler state (texelFetch only)
                exact = dtype[0] in "iu"  # integer textures are never filtered
                tex.filter = (ctx.NEAREST, ctx.NEAREST) if exact else (ctx.LINEAR, ctx.LINEAR)
                tex.repeat_x = tex.repeat_y = False
            self.colors[name] = tex
        self.depth = None
        self._release_raw = None
        #: the depth texture of another target this one shares (not released with it), or None
        self.shared_depth = shared_depth
        if description.stencil:
            from .context import depth_stencil_target

            made = depth_stencil_target(ctx, raw, list(self.colors.values()), size) if raw is not None else None
            if made is None:
                raise ValueError(
                    f"target {description.name!r}: this OpenGL driver offers no depth-stencil texture; "
                    "techniques that need one (om.gl.ShadowVolumes) cannot run here"
                )
            self.fbo, self.depth, self._release_raw = made
            return
        if shared_depth is not None:
            self.fbo = ctx.framebuffer(list(self.colors.values()), shared_depth)
            return
        if description.depth:
            self.depth = gpu_call(
                ctx.depth_texture, size, samples=samples, what=f"depth of target {description.name!r}"
            )
            if not samples:
                self.depth.filter = (ctx.NEAREST, ctx.NEAREST)
                self.depth.repeat_x = self.depth.repeat_y = False
                self.depth.compare_func = ""  # sample depth values, not comparisons
        self.fbo = ctx.framebuffer(list(self.colors.values()), self.depth)

    def texture(self, name: str) -> Any:
        """The texture of colour attachment ``name`` (``"depth"``: the depth texture)."""
        if name == "depth":
            return self.depth
        try:
            return self.colors[name]
        except KeyError:
            raise KeyError(
                f"target {self.description.name!r} has no attachment {name!r}; it has {list(self.colors)}"
                + (" and depth" if self.depth is not None else "")
            ) from None

    def color_array(self, name: str | None = None) -> np.ndarray:
        """(H, W, 4) array of a colour attachment, top row first (uint8 or float32 by the target's dtype)."""
        name = name or next(iter(self.colors))
        dtype = self.description.format_of(name)
        if dtype not in ("f1", "f2", "f4") or self.description.samples:
            raise ValueError(f"target {self.description.name!r}: attachment {name!r} ({dtype}) is not an RGBA image")
        w, h = self.size
        data = self.texture(name).read(alignment=1)
        np_dtype = {"f1": np.uint8, "f2": np.float16, "f4": np.float32}[dtype]
        return np.frombuffer(data, np_dtype).reshape(h, w, 4)[::-1].astype(np.uint8 if dtype == "f1" else np.float32)

    def depth_array(self) -> np.ndarray:
        """(H, W) window depth in [0, 1], top row first."""
        if self.depth is None:
            raise ValueError(f"target {self.description.name!r} has no depth texture (Target(..., depth=True))")
        w, h = self.size
        raw = self.depth.read(alignment=1)
        return np.frombuffer(raw, np.float32).reshape(h, w)[::-1].copy()

    def release(self) -> None:
        if self._release_raw is not None:
            self._release_raw()  # the raw framebuffer and depth-stencil texture (the wrappers own nothing)
            self.depth = None
        else:
            self.fbo.release()
        for tex in self.colors.values():
            tex.release()
        if self.depth is not None:
            self.depth.release()
        self.colors.clear()
        self.depth = None


class FullScreenPrograms:
    """The shared full-screen triangle and the programs of full-screen passes, compiled once per snippet."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self._triangle: Any = None
        self._programs: dict[tuple[str, bool, bool], tuple[Any, Any]] = {}

    def get(self, effect: FullScreen, linear_output: bool) -> tuple[Any, Any]:
        """(program, vertex array) for ``effect`` writing a float (linear) or 8-bit target."""
        key = (effect.fragment, effect.depth, linear_output)
        found = self._programs.get(key)
        if found is not None:
            return found
        if self._triangle is None:
            self._triangle = self.ctx.buffer(_TRIANGLE.tobytes())
        main = ["void main() {", "    f_color = effect(v_uv);"]
        if effect.depth:
            main.append("    gl_FragDepth = effect_depth(v_uv);")
        main.append("}")
        source = _FRAGMENT_HEAD + effect.fragment + "\n" + "\n".join(main) + "\n"
        try:
            prog = self.ctx.program(vertex_shader=_VERTEX, fragment_shader=source)
        except Exception as exc:
            raise ValueError(f"{effect.label or 'FullScreen'}: the effect's GLSL failed to compile: {exc}") from None
        vao = self.ctx.vertex_array(prog, [(self._triangle, "2f", "in_pos")])
        self._programs[key] = (prog, vao)
        return prog, vao

    def __len__(self) -> int:
        return len(self._programs)

    def release(self) -> None:
        for prog, vao in self._programs.values():
            vao.release()
            prog.release()
        self._programs.clear()
        if self._triangle is not None:
            self._triangle.release()
            self._triangle = None


#: Composite a float target holding premultiplied linear colour (``u_sum`` divided by ``u_count`` samples)
#: over the frame, with its depth (``u_depth``) tested against the frame's: how offscreen techniques return.
RESOLVE = """uniform sampler2D u_sum;
uniform sampler2D u_depth;
uniform float u_count;
vec4 effect(vec2 uv) {
    vec4 c = texture(u_sum, uv) / u_count;
    if (c.a <= 0.0) discard;
    return vec4(to_srgb(c.rgb / c.a), min(c.a, 1.0));
}
float effect_depth(vec2 uv) { return texture(u_depth, uv).r; }
"""


def resolve(target: str, color: str = "color", depth_target: str | None = None, count: float = 1.0) -> FullScreen:
    """The full-screen pass compositing a float target over the frame (see :data:`RESOLVE`)."""
    return FullScreen(RESOLVE, inputs={"u_sum": (target, color), "u_depth": (depth_target or target, "depth")},
                      uniforms={"u_count": float(count)}, blend=True, depth=True, depth_test=True)  # fmt: skip


class PingPong:
    """Two offscreen targets used alternately by a chain of image-space passes.

    ``write(step)`` is the target step ``step`` draws into and ``read(step)``
    the one it reads (what step ``step - 1`` wrote): step 0 renders the scene,
    step 1 reads it and writes the other target, and so on.
    """

    def __init__(self, name: str, colors: tuple[str, ...] = ("color",), depth: bool = False, dtype: str = "f1") -> None:
        self.name = name
        self.targets = (
            Target(f"{name}.0", colors=colors, depth=depth, dtype=dtype),
            Target(f"{name}.1", colors=colors, depth=depth, dtype=dtype),
        )

    def write(self, step: int) -> Target:
        return self.targets[step % 2]

    def read(self, step: int) -> Target:
        return self.targets[(step + 1) % 2]

    def __repr__(self) -> str:
        return f"PingPong({self.name!r})"
