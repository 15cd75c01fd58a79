"""NURBS surfaces tessellated on the GPU: Bézier patches, tessellation shaders, trimming per fragment.

The painter splits the surface into rational Bézier patches (knot insertion) and submits one draw
item of kind ``"mesh"`` whose geometry is those patches (:class:`PatchGeometry`, drawn as
``GL_PATCHES``): the engine's own mesh shaders then do everything they do for meshes (materials,
textures, clip planes, fog, shadows, the deferred pipeline's G-buffer), with three stages in front
of the fragment shader instead of the vertex shader:

* a vertex stage that passes control points and the instance's row through;
* a tessellation control stage choosing the levels from a screen-space error bound ``ε``: linear
  interpolation of a degree-``d`` Bézier curve by ``n`` segments is within ``d (d - 1) max|Δ² P| /
  (8 n²)`` of it, and on the triangles of an ``nu x nv`` grid a tensor-product patch is within
  ``a / nu² + 2 c / (nu nv) + b / nv²`` (``a``, ``b`` those curve terms, ``c = p q max|twist| / 8``);
  the differences are taken of the control points in clip space and turned into pixels with the
  patch's least ``w`` and pixel extent, which bounds the error under perspective too.  Edge levels
  get half the budget and use only the edge's control points, so neighbouring patches agree (no
  cracks); inner levels ``sqrt(2 (a + c) / ε)``, ``sqrt(2 (b + c) / ε)`` keep the inside under ``ε``.
  GL caps a level at 64: finer bounds than a patch can reach are not met (Tessellation levels 6+ on
  large patches);
* a tessellation evaluation stage evaluating the rational patch, its normal and its ``(u, v)``,
  then running the mesh vertex shader's body on them.

Trimming loops become a uniform array of edges; the fragment shader discards fragments whose
``(u, v)`` the loops do not keep (the winding rule of :mod:`omnirender.geometry.nurbs`).  Surfaces
of degree above 4 in a direction, or with more than :data:`MAX_TRIM_EDGES` trimming edges, are drawn
from their simplifier's mesh.  The error bound is ``0.5 * 2**(3 - level)`` pixels at the active
``om.Tessellation`` level (half a pixel at the default level 3).
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from ...core import SIMPLIFY, ShapePainter, default_for
from ...geometry.nurbs import trim_segments
from ...shapes import NURBSSurface
from ...shapes.simplifiers import tessellation_level
from ..engine.geometry import Geometry
from ..engine.layout import ROW
from ..engine.shaders import register_tessellation
from ..glengine import GLEngine

__all__ = ["NURBSPainter", "PatchGeometry", "tessellation_sources", "error_bound", "MAX_TRIM_EDGES"]

#: Trimming edges a surface may have for the GPU (a uniform array); more: the simplifier's mesh.
MAX_TRIM_EDGES = 256
#: Highest degree per direction for the GPU ((4 + 1)^2 = 25 control points per patch, under GL's 32).
MAX_GPU_DEGREE = 4


def error_bound(level: int) -> float:
    """The screen-space tessellation error in pixels at Tessellation ``level``."""
    return 0.5 * 2.0 ** (3 - int(level))


class PatchGeometry(Geometry):
    """Rational Bézier patches of a NURBS surface: per control point (x w, y w, z w, w) and the patch's domain."""

    __slots__ = ("patch_size", "patch_data", "program_features", "program_uniforms")

    def __init__(self, shape: NURBSSurface, level: int, label: str) -> None:
        patches, domains = shape.bezier_patches()
        k, p1, q1, _ = patches.shape
        homogeneous = patches.reshape(k, p1 * q1, 4)
        data = np.concatenate([homogeneous, np.repeat(domains[:, None, :], p1 * q1, axis=1)], axis=2)
        points = homogeneous[..., :3] / homogeneous[..., 3:]
        params = np.zeros((k * p1 * q1, 2))  # texture coordinates are made per vertex by the evaluation stage
        super().__init__("triangles", points.reshape(-1, 3), texcoords=params, label=label)
        self.mode = "patches"
        self.patch_size = p1 * q1
        self.patch_data = np.ascontiguousarray(data.reshape(-1, 8), np.float32)
        features: list[tuple[str, Any]] = [("NURBS", True), ("NURBS_P", p1 - 1), ("NURBS_Q", q1 - 1),
                                           ("NURBS_ERROR", error_bound(level))]  # fmt: skip
        uniforms: list[tuple[str, Any]] = []
        loops = shape.trim_loops()
        if loops:
            segments, outer = trim_segments(loops)
            features.append(("TRIM", len(segments)))
            uniforms += [("u_trim", tuple(float(x) for x in segments.ravel())), ("u_trim_outer", float(outer))]
        #: program features and uniform values the draw state takes from the geometry
        self.program_features = tuple(features)
        self.program_uniforms = tuple(uniforms)

    def upload(self, ctx: Any) -> dict[str, Any]:
        if self.buffers is None:
            from ..engine.resources import gpu_call

            self.buffers = {"in_position": gpu_call(ctx.buffer, self.patch_data, what=f"patches of {self.label}")}
        return self.buffers

    def content(self, program: Any) -> list[tuple]:
        return [(self.buffers["in_position"], "4f 4f", "in_position", "in_domain")]  # type: ignore[index]


@default_for(GLEngine)
class NURBSPainter(ShapePainter):
    """GPU-tessellated NURBS surface (see the module docstring); its simplifier's mesh where the GPU cannot."""

    __slots__ = ()
    service = "gl.paint"
    target = NURBSSurface

    def exec(self, shape: NURBSSurface, engine: GLEngine) -> None:
        trims = sum(len(loop) for loop in shape.trim_loops())
        if max(shape.degrees) > MAX_GPU_DEGREE or trims > MAX_TRIM_EDGES:
            simplifier = engine.find_handler(SIMPLIFY, NURBSSurface)
            engine.evaluate(simplifier.exec(shape, engine))
            return
        level = tessellation_level(engine)
        geom = engine.geometry_cache.get(shape, level)
        if geom is None:
            label = f"NURBSSurface in {engine.node_path or '/'}"
            geom = engine.geometry_cache.put(shape, PatchGeometry(shape, level, label), level)
        engine.submit(geom, kind="mesh")


_TYPES = {16: "mat4", 4: "vec4", 1: "float"}


def _instance(fields: tuple[str, ...]) -> list[tuple[str, str]]:
    """(GLSL type, attribute name) of the instance fields a variant reads."""
    return [(_TYPES[f.size], f.attribute) for f in ROW.subset(fields).fields]


_BERNSTEIN = """
// Bernstein polynomials of degree D at t, and their derivatives, into the global arrays given by the macro
float bern_t[8], bern_s[8];
float binomial(int n, int k) {
    float c = 1.0;
    for (int i = 1; i <= k; ++i) c = c * float(n - k + i) / float(i);
    return c;
}
float bern(int d, int i, float t) {  // C(d, i) t^i (1 - t)^(d - i); 0 outside 0 <= i <= d
    if (i < 0 || i > d) return 0.0;
    float v = binomial(d, i);
    for (int k = 0; k < i; ++k) v *= t;
    for (int k = 0; k < d - i; ++k) v *= 1.0 - t;
    return v;
}
#define BERNSTEIN(D, t, b, db) for (int i = 0; i <= D; ++i) { \\
    b[i] = bern(D, i, t); db[i] = float(D) * (bern(D - 1, i - 1, t) - bern(D - 1, i, t)); }
"""


def tessellation_sources(vertex: str, fields: tuple[str, ...]) -> tuple[str, str, str]:
    """(vertex, tessellation control, tessellation evaluation) bodies for the mesh shader ``vertex``."""
    attrs = _instance(fields)
    vs = ["in vec4 in_position;", "in vec4 in_domain;", "out vec4 tc_point;", "out vec4 tc_domain;"]
    vs += [f"in {t} {a};\nout {t} tc_{a};" for t, a in attrs]
    vs += ["void main() {", "    tc_point = in_position;", "    tc_domain = in_domain;"]
    vs += [f"    tc_{a} = {a};" for _, a in attrs] + ["}"]
    tcs = [
        "layout(vertices = NCTRL) out;",
        "in vec4 tc_point[];",
        "in vec4 tc_domain[];",
        "out vec4 te_point[];",
        "out vec4 te_domain[];",
        *(f"in {t} tc_{a}[];\npatch out {t} te_{a};" for t, a in attrs),
        "uniform mat4 u_view;",
        "uniform mat4 u_proj;",
        "uniform vec2 u_viewport;  // half the target's size in pixels",
        "#ifdef SINGLE",
        "uniform mat4 i_model;",
        "#define TC_MODEL i_model",
        "#else",
        "#define TC_MODEL tc_i_model[0]",
        "#endif",
        "// Screen-space error of linear interpolation, bounded in clip space (exact under perspective): a clip",
        "// point c's pixel is s = c.xy / c.w * viewport; an error e of c moves it by (e.xy viewport - s e.w) / c.w,",
        "// which is the same with s measured from any centre: |e.xy viewport - centre e.w| + r |e.w| over w_min",
        "// (r: how far the control points' pixels reach from the centre, w_min: their least w).  The errors come",
        "// from second differences of the control points (d (d - 1) / 8 max|second difference| / n^2).",
        "vec4 clip[NCTRL];",
        "vec2 pixel_of(int k) { return clip[k].xy / clip[k].w * u_viewport; }",
        "// (max |e.xy viewport - centre e.w|, max |e.w|) over the differences e seen so far",
        "vec2 widest(vec2 m, vec4 e, vec2 centre) {",
        "    return max(m, vec2(length(e.xy * u_viewport - centre * e.w), abs(e.w)));",
        "}",
        "// the curve term of the degree-d curve through control points k0, k0 + step, ...: its n-segment",
        "// polyline is within curve_term / n^2 pixels of it",
        "float curve_term(int k0, int step, int d) {",
        "    if (d < 2) return 0.0;",
        "    vec2 centre = vec2(0.0), m = vec2(0.0);",
        "    for (int i = 0; i <= d; ++i) centre += pixel_of(k0 + i * step) / float(d + 1);",
        "    float r = 0.0, wmin = 1e30;",
        "    for (int i = 0; i <= d; ++i) {",
        "        r = max(r, length(pixel_of(k0 + i * step) - centre));",
        "        wmin = min(wmin, clip[k0 + i * step].w);",
        "    }",
        "    for (int i = 0; i + 2 <= d; ++i)",
        "        m = widest(m, clip[k0 + (i + 2) * step] - 2.0 * clip[k0 + (i + 1) * step] + clip[k0 + i * step],",
        "                   centre);",
        "    return float(d * (d - 1)) * (m.x + r * m.y) / (8.0 * wmin);",
        "}",
        "float segments(float term) { return clamp(ceil(sqrt(term / float(NURBS_ERROR))), 1.0, 64.0); }",
        "void main() {",
        "    te_point[gl_InvocationID] = tc_point[gl_InvocationID];",
        "    te_domain[gl_InvocationID] = tc_domain[gl_InvocationID];",
        "    if (gl_InvocationID != 0) return;",
        *(f"    te_{a} = tc_{a}[0];" for _, a in attrs),
        "    mat4 mvp = u_proj * u_view * TC_MODEL;",
        "    bool behind = false;",
        "    vec2 centre = vec2(0.0);",
        "    for (int k = 0; k < NCTRL; ++k) {",
        "        clip[k] = mvp * vec4(tc_point[k].xyz / tc_point[k].w, 1.0);",
        "        if (clip[k].w <= 1e-6) behind = true;",
        "        clip[k].w = max(clip[k].w, 1e-6);",
        "        centre += pixel_of(k) / float(NCTRL);",
        "    }",
        "    float r = 0.0, wmin = 1e30;",
        "    for (int k = 0; k < NCTRL; ++k) {",
        "        r = max(r, length(pixel_of(k) - centre));",
        "        wmin = min(wmin, clip[k].w);",
        "    }",
        "    // control point (i, j) is k = i * (Q + 1) + j: i along u, j along v.  Edges are curves: half the",
        "    // budget (the other half is for the triangles next to them); only the edge's own control points, so",
        "    // neighbouring patches agree (no cracks)",
        "    float u0 = segments(2.0 * curve_term(0, NURBS_Q + 1, NURBS_P));              // v = 0 (a curve in u)",
        "    float u1 = segments(2.0 * curve_term(NURBS_Q, NURBS_Q + 1, NURBS_P));        // v = 1",
        "    float v0 = segments(2.0 * curve_term(0, 1, NURBS_Q));                        // u = 0 (a curve in v)",
        "    float v1 = segments(2.0 * curve_term(NURBS_P * (NURBS_Q + 1), 1, NURBS_Q));  // u = 1",
        "    // inside: linear interpolation on the triangles of an nu x nv grid is within",
        "    // a / nu^2 + 2 c / (nu nv) + b / nv^2 (a, b: the u and v curve terms, c = p q max|twist| / 8);",
        "    // nu = sqrt(2 (a + c) / e), nv = sqrt(2 (b + c) / e) keep that under e",
        "    float a = 0.0, b = 0.0;",
        "    vec2 twist = vec2(0.0);",
        "    for (int j = 0; j <= NURBS_Q; ++j) a = max(a, curve_term(j, NURBS_Q + 1, NURBS_P));",
        "    for (int i = 0; i <= NURBS_P; ++i) b = max(b, curve_term(i * (NURBS_Q + 1), 1, NURBS_Q));",
        "    for (int i = 0; i < NURBS_P; ++i)",
        "        for (int j = 0; j < NURBS_Q; ++j) {",
        "            int k = i * (NURBS_Q + 1) + j;",
        "            vec4 e = clip[k + NURBS_Q + 2] - clip[k + NURBS_Q + 1] - clip[k + 1] + clip[k];",
        "            twist = widest(twist, e, centre);",
        "        }",
        "    float c = float(NURBS_P * NURBS_Q) * (twist.x + r * twist.y) / (8.0 * wmin);",
        "    float iu = max(max(u0, u1), segments(2.0 * (a + c)));",
        "    float iv = max(max(v0, v1), segments(2.0 * (b + c)));",
        "    if (behind) { u0 = u1 = v0 = v1 = iu = iv = 64.0; }  // part of it behind the eye: the finest",
        "    gl_TessLevelOuter[0] = v0;",
        "    gl_TessLevelOuter[1] = u0;",
        "    gl_TessLevelOuter[2] = v1;",
        "    gl_TessLevelOuter[3] = u1;",
        "    gl_TessLevelInner[0] = iu;",
        "    gl_TessLevelInner[1] = iv;",
        "}",
    ]
    body = re.sub(r"^in ", "", vertex, flags=re.M).replace("void main()", "void vertex_main()")
    tes = [
        "layout(quads, equal_spacing, ccw) in;",
        "in vec4 te_point[];",
        "in vec4 te_domain[];",
        *(f"patch in {t} te_{a};" for t, a in attrs),
        "#ifdef TRIM",
        "out vec2 v_param;",
        "#endif",
        body,
        _BERNSTEIN,
        "float bu[8], dbu[8], bv[8], dbv[8];",
        "void patch_point(float s, float t, out vec3 X, out vec3 N) {",
        "    BERNSTEIN(NURBS_P, s, bu, dbu)",
        "    BERNSTEIN(NURBS_Q, t, bv, dbv)",
        "    vec4 S = vec4(0.0), Su = vec4(0.0), Sv = vec4(0.0);",
        "    for (int i = 0; i <= NURBS_P; ++i)",
        "        for (int j = 0; j <= NURBS_Q; ++j) {",
        "            vec4 c = te_point[i * (NURBS_Q + 1) + j];",
        "            S += bu[i] * bv[j] * c; Su += dbu[i] * bv[j] * c; Sv += bu[i] * dbv[j] * c;",
        "        }",
        "    X = S.xyz / S.w;",
        "    N = cross((Su.xyz - X * Su.w) / S.w, (Sv.xyz - X * Sv.w) / S.w);",
        "}",
        "void main() {",
        "    float s = gl_TessCoord.x, t = gl_TessCoord.y;",
        "    vec3 X, N;",
        "    patch_point(s, t, X, N);",
        "    if (dot(N, N) < 1e-24) {  // a pole: the normal a little way into the patch",
        "        vec3 Y;",
        "        patch_point(mix(s, 0.5, 1e-3), mix(t, 0.5, 1e-3), Y, N);",
        "    }",
        "    in_position = X;",
        "    in_normal = N;",
        "    vec4 d = te_domain[0];",
        "    vec2 uv = vec2(mix(d.x, d.y, s), mix(d.z, d.w, t));",
        "#ifdef UVS",
        "    in_texcoord = uv;",
        "#endif",
        "#ifdef TRIM",
        "    v_param = uv;",
        "#endif",
        *(f"    {a} = te_{a};" for _, a in attrs),
        "    vertex_main();",
        "}",
    ]
    return "\n".join(vs) + "\n", "\n".join(tcs) + "\n", "\n".join(tes) + "\n"


register_tessellation(tessellation_sources)  # the engine builds NURBS mesh programs with it
