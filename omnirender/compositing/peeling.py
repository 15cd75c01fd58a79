"""Depth peeling: order-independent transparency of several renderers, composited in temporary buffers.

A :class:`DepthPeelGroup` draws its children ``layers`` times into an
offscreen target.  Each time every child draws its *nearest fragments behind
the previous layer* (:meth:`Renderer.draw_layer`: colour unblended, depth
written, fragments at or in front of the previous layer's depth discarded),
so layer k holds, per pixel, the k-th nearest surface of all children
together.  The layers are composited front to back ("under") in a float
target and the result is merged over the framebuffer with the nearest
layer's depth (a depth sprite: integration rules 1 and 2).  Surfaces of
different renderers that interleave in depth -- a translucent ball inside a
translucent box drawn by another renderer -- are blended in their true order,
which neither the depth test of a :class:`DepthGroup` nor a sort of whole
objects gives.

What the framebuffer already holds hides the layers behind it: every layer
target starts with the framebuffer's depth.  In a scene graph the node's
content is drawn first, as it is (it is not peeled), and hides the layers
behind it.  Layers are single-sampled: with the engine's MSAA the silhouettes
of peeled surfaces stay aliased (0.2/255 mean difference from the engine's
sorted, multisampled image in the tests, up to 50/255 on edge pixels).  Only renderers that can draw
layers can be peeled: :class:`SceneRenderer` (meshes, lines and points drawn
by the engine's own shaders), groups of them (:class:`DepthGroup`,
:class:`DepthPeelGroup`); ``check_tree`` reports others.
"""

from __future__ import annotations

import weakref
from collections.abc import Iterable
from typing import Any

from ..gl import Blend, Clear, DepthMask, DepthTest, Pass, Shader, Target
from ..gl.engine.technique import GLTechnique
from ..gl.engine.units import PASS_INPUTS
from .canvas import Canvas, target_name
from .groups import MERGE
from .renderer import Renderer, RendererGroup

__all__ = ["DepthPeelGroup", "PeelLayer", "PEEL_UNIT", "draw_layers"]

#: The texture unit the previous layer's depth is bound to while a scene engine draws a layer (the last of
#: the pass-input units: a peel layer's pass names no inputs of its own, so the engine binds nothing there).
PEEL_UNIT = PASS_INPUTS + 5

#: Fragment snippet of a peeled layer: fragments at or in front of the previous layer's depth are gone.
#: The depth texture holds 24-bit values: the tolerance keeps a layer's own fragments (rounded either way)
#: out of the next layer.
PEEL_FRAGMENT = """
uniform sampler2D u_peel;
void pass_fragment(inout vec4 color, vec3 P, vec3 N) {
    if (gl_FragCoord.z <= texelFetch(u_peel, ivec2(gl_FragCoord.xy), 0).r + 2.0e-7) discard;
}
"""

#: Full-screen GLSL: the framebuffer's depth into a layer target (colour transparent black).
_START = """
uniform sampler2D u_depth;
vec4 effect(vec2 uv) { return vec4(0.0); }
float effect_depth(vec2 uv) { return texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r; }
"""

#: Full-screen GLSL: a layer (unpremultiplied colour) composited under the layers in front of it.
_UNDER = """
uniform sampler2D u_front;
uniform sampler2D u_layer;
uniform float u_first;
vec4 effect(vec2 uv) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 front = u_first > 0.5 ? vec4(0.0) : texelFetch(u_front, p, 0);
    vec4 layer = texelFetch(u_layer, p, 0);
    return front + (1.0 - front.a) * vec4(layer.rgb * layer.a, layer.a);
}
"""


class PeelLayer(GLTechnique):
    """The technique a scene engine draws one peeled layer with (see :meth:`SceneRenderer.draw_layer`).

    One pass over the opaque and transparent items: depth test ``less``,
    depth writes on, colour replaced (no blending), both faces of closed
    transparent shapes; with :attr:`peel` (the previous layer's depth
    texture) fragments at or in front of it are discarded.
    """

    __slots__ = ("peel",)

    def __init__(self) -> None:
        super().__init__(passes=1)
        object.__setattr__(self, "peel", None)

    def prepare_pass(self, engine: Any) -> None:
        state = (DepthTest(True, "less"), DepthMask(True), Blend(True, "one", "zero"))
        shader = None if self.peel is None else Shader(fragment=PEEL_FRAGMENT, uniforms={"u_peel": PEEL_UNIT})
        engine.set_pass(
            Pass("peel layer", items={"opaque", "transparent"}, state=state, shader=shader, custom=self._draw)
        )

    def _draw(self, engine: Any, draw: Any) -> int:
        if self.peel is not None:
            self.peel.use(PEEL_UNIT)
        return draw()


def draw_layers(canvas: Canvas, children: Iterable[Renderer], peel: str | None) -> None:
    """Draw the peeled layer of each of ``children`` into ``canvas`` (``peel``: the previous layer's target)."""
    for child in children:
        child.draw_layer(canvas, peel)


class DepthPeelGroup(RendererGroup):
    """Children's transparent surfaces blended in depth order, whichever child draws them (see the module).

    ``layers`` is the most layers peeled (surfaces behind the last are
    dropped: a ray through two overlapping closed translucent shapes meets
    four); peeling stops at the first layer in which no fragment is left (an
    occlusion query counts them), so ``stats["layers"]`` is the number drawn
    in the last frame.  The result is merged over the framebuffer "over" what
    it holds, with the depth of the nearest layer.
    """

    __slots__ = ("layers", "stats", "_queries")
    _transient = {"stats": dict, "_queries": weakref.WeakKeyDictionary}

    def __init__(self, children: Iterable[Renderer] = (), layers: int = 8) -> None:
        super().__init__(children)
        if isinstance(layers, bool) or not isinstance(layers, int) or not 1 <= layers <= 64:
            raise ValueError(f"DepthPeelGroup: layers must be a whole number in 1..64, got {layers!r}")
        self.layers = layers
        object.__setattr__(self, "stats", {})
        object.__setattr__(self, "_queries", weakref.WeakKeyDictionary())

    def _query(self, canvas: Canvas) -> Any:
        """A samples-passed query on the canvas's context (one per engine, reused every layer)."""
        found = self._queries.get(canvas.engine)
        if found is None:
            found = self._queries[canvas.engine] = canvas.ctx.query(samples=True)
        return found

    def composite(self, canvas: Canvas, children: tuple[Renderer, ...]) -> None:
        for i, child in enumerate(children):
            if not child.draws_layers():
                raise TypeError(
                    f"DepthPeelGroup: child {i} ({type(child).__name__}) cannot draw depth-peeled layers; draw it "
                    "outside the group (e.g. DepthGroup([DepthPeelGroup([...]), it])) or wrap its scene in a "
                    "SceneRenderer"
                )
        host = target_name(self, "host")
        canvas.copy(Target(host))
        first = target_name(self, "layer0")
        front = ""
        query = self._query(canvas)
        drawn = 0
        for k in range(self.layers):
            layer = first if k == 0 else target_name(self, f"layer{1 + k % 2}")
            peel = None if k == 0 else (first if k == 1 else target_name(self, f"layer{1 + (k - 1) % 2}"))

            def draw(inner: Canvas, peel: str | None = peel) -> None:
                inner.fullscreen("peel start", _START, {"u_depth": (host, "depth")}, depth=True)
                with query:  # the fragments the children leave in this layer
                    draw_layers(inner, children, peel)

            canvas.into(f"peel layer {k}", draw, target=Target(layer, relative="enclosing"), clear=Clear())
            drawn = k + 1
            if k > 0 and query.samples == 0:  # nothing left behind the previous layer: done
                break
            acc = target_name(self, f"under{k % 2}")
            inputs = {"u_layer": (layer, "color"), "u_front": (front or layer, "color")}

            def under(inner: Canvas, inputs: dict = inputs, k: int = k) -> None:
                inner.fullscreen("peel under", _UNDER, inputs, {"u_first": 1.0 if k == 0 else 0.0})

            canvas.into(f"peel composite {k}", under, target=Target(acc, depth=False, dtype="f2", relative="enclosing"))
            front = acc
        self.stats["layers"] = drawn
        inputs = {"u_color": (front, "color"), "u_depth": (first, "depth")}
        canvas.fullscreen("peel merge", MERGE, inputs, blend=True, depth=True, depth_test="less")

    def draw_in_graph(self, canvas: Canvas) -> None:
        """In a scene graph: the node's content as it is, then the children peeled over it."""
        canvas.scope()
        self.draw(canvas)

    def draws_layers(self) -> bool:
        return all(child.draws_layers() for child in self.children)

    def draw_layer(self, canvas: Canvas, peel: str | None) -> None:
        """Nested in another peel group: the children's layers join the enclosing group's."""
        draw_layers(canvas, self.children, peel)
