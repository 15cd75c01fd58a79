"""The light-field renderer: unstructured lumigraph rendering with colour and a consistent depth.

Each frame (see :mod:`.blending` for the CPU part):

0. the depth maps of the views most relevant to the pass's view are drawn as
   meshes (broken at depth edges) into a depth target of this view: the
   per-pixel surface, read back for the screen mesh's vertex depths and used
   per fragment below;
1. the screen mesh of the pass's view is drawn once per camera that has
   weight somewhere, into an offscreen float target, additively: every
   fragment projects its world point (on the per-pixel surface where there is
   one, else on the mesh) into the camera's image (projective texturing) and
   adds ``weight x colour``; where the camera's depth map
   agrees with the fragment's depth (within ``tolerance``) the sum also goes
   to a *consistent* accumulator, so wherever some camera really saw the
   surface point only such cameras are used, and elsewhere (depth edges the
   coarse mesh cannot follow) all cameras with weight are;
2. a full-screen pass normalises the sums, multiplies the coverage by the
   fade towards the images' borders (where the light field ends, it fades
   out), and merges colour and the surface's depth over the framebuffer by the depth test, discarding nearly transparent
   pixels so depth is written exactly where colour is.
"""

from __future__ import annotations

import time
import weakref
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...gl import Blend, Clear, CullFace, DepthTest, Target
from ..canvas import Canvas, eye_distance, target_name
from ..renderer import Bounds, Renderer
from .blending import ScreenMesh, eye_of, relevant_views, screen_mesh
from .data import LightField

__all__ = ["LightFieldRenderer"]

_VERTEX = """
in vec3 in_position;
in float in_weight;
uniform mat4 u_view_proj;
out float v_weight;
void main() {
    v_weight = in_weight;
    gl_Position = u_view_proj * vec4(in_position, 1.0);
}
"""

_FRAGMENT = """
#define SURFACE_REACH 1
in float v_weight;
uniform sampler2D u_image;     // the camera's image (premultiplied RGBA, display values)
uniform sampler2D u_depth;     // its depth map (distance along its axis; 0: nothing)
uniform mat4 u_camera;         // world -> camera
uniform vec4 u_intrinsics;     // fx, fy, cx, cy in pixels (origin top left, y down)
uniform vec2 u_image_size;
uniform float u_tolerance;     // relative depth agreement
uniform float u_border;        // width of the fade at the image border (fraction of the image's smaller side)
uniform sampler2D u_surface;   // window depth of the depth maps' surface in this view (1: none)
uniform mat4 u_inv_view_proj;
uniform vec2 u_viewport;
layout(location = 0) out vec4 f_consistent;
layout(location = 1) out vec4 f_all;
layout(location = 2) out vec4 f_weights;
void main() {
    ivec2 here = ivec2(gl_FragCoord.xy);
    float surface = texelFetch(u_surface, here, 0).r;
    for (int i = -SURFACE_REACH; i <= SURFACE_REACH && surface >= 1.0; ++i)   // close cracks at the mesh's edges
        for (int j = -SURFACE_REACH; j <= SURFACE_REACH; ++j)
            surface = min(surface,
                          texelFetch(u_surface, clamp(here + ivec2(i, j), ivec2(0), ivec2(u_viewport) - 1), 0).r);
    if (surface >= 1.0) discard;                  // no depth map saw a surface here
    gl_FragDepth = surface;
    vec4 q = u_inv_view_proj * vec4(gl_FragCoord.xy / u_viewport * 2.0 - 1.0, surface * 2.0 - 1.0, 1.0);
    vec3 world = q.xyz / q.w;
    vec4 p = u_camera * vec4(world, 1.0);
    float z = -p.z;
    if (z <= 0.0 || v_weight <= 0.0) discard;
    vec2 pixel = vec2(u_intrinsics.z + u_intrinsics.x * p.x / z, u_intrinsics.w - u_intrinsics.y * p.y / z);
    if (any(lessThan(pixel, vec2(0.0))) || any(greaterThanEqual(pixel, u_image_size))) discard;
    vec2 uv = vec2(pixel.x / u_image_size.x, 1.0 - pixel.y / u_image_size.y);
    vec4 c = texture(u_image, uv);
    float seen = texture(u_depth, uv).r;
    float agree = (seen > 0.0 && abs(seen - z) < u_tolerance * z) ? 1.0 : 0.0;
    // the light field ends where its images end: fade out towards the image border
    vec2 inside = min(pixel, u_image_size - pixel) / (u_border * min(u_image_size.x, u_image_size.y));
    float edge = smoothstep(0.0, 1.0, clamp(min(inside.x, inside.y), 0.0, 1.0));
    f_consistent = v_weight * agree * c;
    f_all = v_weight * c;
    f_weights = vec4(v_weight * agree, v_weight, v_weight * edge, 0.0);
}
"""

_SURFACE_VERTEX = """
in vec3 in_position;
uniform mat4 u_view_proj;
void main() { gl_Position = u_view_proj * vec4(in_position, 1.0); }
"""

_SURFACE_FRAGMENT = """
void main() {}
"""

RESOLVE = """
uniform sampler2D u_consistent;
uniform sampler2D u_all;
uniform sampler2D u_weights;
uniform sampler2D u_depth;
uniform float u_min_alpha;
vec4 effect(vec2 uv) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 w = texelFetch(u_weights, p, 0);
    if (w.y <= 0.0) discard;                                   // no camera sees this pixel
    vec4 sum = w.x > 0.05 * w.y ? texelFetch(u_consistent, p, 0) / w.x : texelFetch(u_all, p, 0) / w.y;
    float alpha = clamp(sum.a, 0.0, 1.0) * clamp(w.z / w.y, 0.0, 1.0);
    if (alpha < u_min_alpha || sum.a <= 0.0) discard;          // colour and depth: both or neither
    return vec4(clamp(sum.rgb / sum.a, 0.0, 1.0), alpha);
}
float effect_depth(vec2 uv) { return texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r; }
"""


class _Textures:
    """The light field's images, depth maps and depth-map meshes on one GL context (uploaded once, meshes lazily)."""

    def __init__(self, engine: Any, lf: LightField) -> None:
        ctx = engine.ctx
        self.ctx = ctx
        self.lf = lf
        self.surfaces: dict[tuple[int, int], tuple[Any, Any, int]] = {}
        self.images = []
        self.depths = []
        for i, view in enumerate(lf.views):
            w, h = view.size
            engine.check_texture_size(f"LightFieldRenderer: view {i} ({w}x{h})", (w, h), engine.max_texture_size)
            image = ctx.texture((w, h), 4, np.ascontiguousarray(view.image[::-1]).tobytes())
            image.filter = (ctx.LINEAR, ctx.LINEAR)
            image.repeat_x = image.repeat_y = False
            depth = np.where(np.isfinite(view.depth), view.depth, 0.0).astype(np.float32)
            dtex = ctx.texture((w, h), 1, np.ascontiguousarray(depth[::-1]).tobytes(), dtype="f4")
            dtex.filter = (ctx.NEAREST, ctx.NEAREST)
            dtex.repeat_x = dtex.repeat_y = False
            self.images.append(image)
            self.depths.append(dtex)

    def surface(self, index: int, step: int) -> tuple[Any, Any, int]:
        """(vertex buffer, index buffer, index count) of view ``index``'s depth map as a mesh."""
        found = self.surfaces.get((index, step))
        if found is None:
            vertices, triangles = self.lf.views[index].surface(step)
            found = (
                self.ctx.buffer(vertices.tobytes()),
                self.ctx.buffer(np.ascontiguousarray(triangles).tobytes() or bytes(12)),
                triangles.size,
            )
            self.surfaces[(index, step)] = found
        return found

    def release(self) -> None:
        for tex in (*self.images, *self.depths):
            tex.release()
        for vbo, ibo, _ in self.surfaces.values():
            vbo.release()
            ibo.release()
        self.images, self.depths, self.surfaces = [], [], {}


class LightFieldRenderer(Renderer):
    """Draws a :class:`~.data.LightField` from any view by unstructured lumigraph rendering.

    Several light fields of one scene (a list) are drawn as one
    (:meth:`LightField.combine`): moving between the regions they captured,
    the view passes smoothly from one field to the other.

    ``cell`` is the screen mesh's spacing in pixels, ``k`` the number of
    cameras blended per vertex (the ``k``-th best sets the threshold, so
    ``k - 1`` contribute), ``geometry_views`` how many depth maps give the
    surface (drawn as meshes of every ``depth_step``-th sample), ``tolerance``
    the relative depth difference within which a camera's depth map agrees
    with a fragment, ``border`` the width of the fade at the images' borders (a
    fraction of their smaller side), ``min_alpha`` the coverage below
    which nothing (neither colour nor depth) is written.  ``stats`` holds the
    last frame's mesh size and CPU time.
    """

    __slots__ = ("light_field", "cell", "k", "geometry_views", "depth_step", "tolerance", "border", "min_alpha",
                 "_gpu", "stats")  # fmt: skip
    _transient = {"_gpu": weakref.WeakKeyDictionary, "stats": dict}

    def __init__(
        self,
        light_field: LightField | Sequence[LightField],
        cell: int = 8,
        k: int = 4,
        geometry_views: int = 4,
        depth_step: int = 2,
        tolerance: float = 0.02,
        border: float = 0.05,
        min_alpha: float = 0.1,
    ) -> None:
        super().__init__()
        if isinstance(light_field, (list, tuple)):
            light_field = LightField.combine(*light_field)
        if not isinstance(light_field, LightField):
            raise TypeError(
                f"LightFieldRenderer: light_field must be an om.compositing.LightField, got {light_field!r:.60}"
            )
        checked = (("cell", cell, 2), ("k", k, 1), ("geometry_views", geometry_views, 1), ("depth_step", depth_step, 1))
        for name, value, lo in checked:
            if isinstance(value, bool) or not isinstance(value, int) or value < lo:
                raise ValueError(f"LightFieldRenderer: {name} must be a whole number >= {lo}, got {value!r}")
        if not 0.0 < float(tolerance) < 1.0:
            raise ValueError(f"LightFieldRenderer: tolerance must be in (0, 1), got {tolerance!r}")
        if not 0.0 < float(border) <= 0.5:
            raise ValueError(f"LightFieldRenderer: border must be in (0, 0.5], got {border!r}")
        if not 0.0 <= float(min_alpha) < 1.0:
            raise ValueError(f"LightFieldRenderer: min_alpha must be in [0, 1), got {min_alpha!r}")
        self.light_field = light_field
        self.cell = cell
        self.k = k
        self.geometry_views = geometry_views
        self.depth_step = depth_step
        self.tolerance = float(tolerance)
        self.border = float(border)
        self.min_alpha = float(min_alpha)
        object.__setattr__(self, "_gpu", weakref.WeakKeyDictionary())
        object.__setattr__(self, "stats", {})

    def bounds(self) -> Bounds | None:
        return self.light_field.bounds

    def _textures(self, engine: Any) -> _Textures:
        found = self._gpu.get(engine)
        if found is None or found[0] is not self.light_field:
            if found is not None:
                found[1].release()
            found = self._gpu[engine] = (self.light_field, _Textures(engine, self.light_field))
        return found[1]

    def draw(self, canvas: Canvas) -> None:
        t0 = time.perf_counter()
        lf = self.light_field
        eye, toward_viewer, ortho = eye_of(canvas.view, canvas.projection)
        views = relevant_views(lf, eye, toward_viewer, ortho, self.geometry_views)
        surface = target_name(self, "surface")
        accumulation = target_name(self, "accumulation")
        with canvas.preserved():
            depth_target = Target(surface, colors=(), depth=True, relative="enclosing")
            canvas.into("surface", lambda inner: self._surface(inner, views), target=depth_target,
                        clear=Clear(color=None))  # fmt: skip
            window = canvas.target(surface).depth_array()
            t1 = time.perf_counter()
            mesh = screen_mesh(lf, canvas.view, canvas.projection, canvas.size, eye_distance(window, canvas.projection),
                               self.cell, self.k)  # fmt: skip
            t2 = time.perf_counter()
            self.stats.update(vertices=len(mesh.positions), triangles=len(mesh.triangles), mesh_ms=(t2 - t1) * 1e3)
            if len(mesh.triangles):
                target = Target(accumulation, colors=("consistent", "all", "weights"), depth=True, dtype="f4",
                                relative="enclosing")  # fmt: skip
                canvas.into("lumigraph", lambda inner: self._accumulate(inner, mesh, surface), target=target,
                            clear=Clear())  # fmt: skip
                inputs = {"u_consistent": (accumulation, "consistent"), "u_all": (accumulation, "all"),
                          "u_weights": (accumulation, "weights"), "u_depth": (accumulation, "depth")}  # fmt: skip
                canvas.fullscreen("resolve", RESOLVE, inputs, {"u_min_alpha": self.min_alpha}, blend=True, depth=True,
                                  depth_test="less")  # fmt: skip
        self.stats["frame_ms"] = (time.perf_counter() - t0) * 1e3

    def _surface(self, canvas: Canvas, views: np.ndarray) -> None:
        """Draw the depth maps of ``views`` as meshes into the (depth-only) target being drawn."""
        ctx = canvas.ctx
        textures = self._textures(canvas.engine)
        prog = canvas.program("compositing.lumigraph-surface", _SURFACE_VERTEX, _SURFACE_FRAGMENT)
        canvas.engine.apply_gl_state(DepthTest(), Blend(False), CullFace("none"))  # through the engine's applier
        prog["u_view_proj"].write(canvas.view_projection.T.astype(np.float32).tobytes())
        calls = 0
        for i in views:
            vbo, ibo, count = textures.surface(int(i), self.depth_step)
            if not count:
                continue
            vao = ctx.vertex_array(prog, [(vbo, "3f", "in_position")], ibo, 4)
            vao.render(ctx.TRIANGLES, vertices=count)
            vao.release()
            calls += 1
        canvas.count(calls)

    def _accumulate(self, canvas: Canvas, mesh: ScreenMesh, surface: str) -> None:
        ctx = canvas.ctx
        textures = self._textures(canvas.engine)
        prog = canvas.program("compositing.lumigraph", _VERTEX, _FRAGMENT)
        v = len(mesh.positions)
        positions = ctx.buffer(np.ascontiguousarray(mesh.positions, np.float32).tobytes())
        weight = ctx.buffer(reserve=v * 4)
        index = ctx.buffer(reserve=max(4, mesh.triangles.nbytes))
        vao = ctx.vertex_array(prog, [(positions, "3f", "in_position"), (weight, "1f", "in_weight")], index, 4)
        try:
            # additive, and every camera's pass writes the same mesh depth (through the engine's applier)
            canvas.engine.apply_gl_state(Blend(src="one", dst="one"), DepthTest(func="always"), CullFace("none"))
            prog["u_view_proj"].write(canvas.view_projection.T.astype(np.float32).tobytes())
            prog["u_inv_view_proj"].write(np.linalg.inv(canvas.view_projection).T.astype(np.float32).tobytes())
            prog["u_viewport"].value = tuple(float(v) for v in canvas.size)
            prog["u_tolerance"].value = self.tolerance
            prog["u_border"].value = self.border
            canvas.target(surface).depth.use(2)
            prog["u_surface"].value = 2
            calls = 0
            for i, lf_view in enumerate(self.light_field.views):
                w_i = mesh.weights[i]
                if not (w_i > 0).any():
                    continue
                tris = mesh.triangles[(w_i[mesh.triangles] > 0).any(axis=1)]
                weight.write(np.ascontiguousarray(w_i, np.float32).tobytes())
                index.write(np.ascontiguousarray(tris, np.uint32).tobytes())
                textures.images[i].use(0)
                textures.depths[i].use(1)
                prog["u_image"].value = 0
                prog["u_depth"].value = 1
                prog["u_camera"].write(lf_view.view.T.astype(np.float32).tobytes())
                prog["u_intrinsics"].value = lf_view.intrinsics
                prog["u_image_size"].value = tuple(float(s) for s in lf_view.size)
                vao.render(ctx.TRIANGLES, vertices=tris.size)
                calls += 1
            canvas.count(calls, len(mesh.triangles))
        finally:
            vao.release()
            for buf in (positions, weight, index):
                buf.release()

    def release(self) -> None:
        for _, textures in list(self._gpu.values()):
            textures.release()
        self._gpu.clear()
