"""NURBS surfaces tessellated on the GPU: Bézier patches, tessellation shaders, trimming per fragment.

The painter splits the surface into rational Bézier patches (knot insertion) and submits one draw
item of kind ``"mesh"`` whose geometry is those patches (:class:`PatchGeometry`, drawn as
``GL_PATCHES``): the engine's own mesh shaders then do everything they do for meshes (materials,
textures, clip planes, fog, shadows, the deferred pipeline's G-buffer), with three stages in front
of the fragment shader instead of the vertex shader:

* a vertex stage that passes control points and the instance's row through;
* a tessellation control stage choosing the levels from a screen-space error bound: a degree-``d``
  Bézier curve is within ``d (d - 1) max|Δ² P| / (8 n²)`` of its ``n``-segment polyline (the second
  differences of its control points projected to pixels), so ``n = ceil(sqrt(d (d - 1) max|Δ² P| /
  (8 ε)))``; edge levels use only the edge's control points, so neighbouring patches agree (no
  cracks);
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

from ..core import SIMPLIFY, ShapePainter, default_for
from ..geometry.nurbs import trim_segments
from ..shapes import NURBSSurface
from ..shapes.simplifiers import tessellation_level
from .engine import GLEngine
from .geometry import Geometry
from .layout import ROW

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
            from .resources import gpu_call

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
        "vec2 pixel[NCTRL];",
        "// segments so that a degree-d curve through control points k0, k0 + step, ... deviates < NURBS_ERROR px",
        "float level(int k0, int step, int d) {",
        "    if (d < 2) return 1.0;",
        "    float m = 0.0;",
        "    for (int i = 0; i + 2 <= d; ++i)",
        "        m = max(m, length(pixel[k0 + (i + 2) * step] - 2.0 * pixel[k0 + (i + 1) * step]",
        "                          + pixel[k0 + i * step]));",
        "    return clamp(ceil(sqrt(float(d * (d - 1)) * m / (8.0 * float(NURBS_ERROR)))), 1.0, 64.0);",
        "}",
        "void main() {",
        "    te_point[gl_InvocationID] = tc_point[gl_InvocationID];",
        "    te_domain[gl_InvocationID] = tc_domain[gl_InvocationID];",
        "    if (gl_InvocationID != 0) return;",
        *(f"    te_{a} = tc_{a}[0];" for _, a in attrs),
        "    mat4 mvp = u_proj * u_view * TC_MODEL;",
        "    bool behind = false;",
        "    for (int k = 0; k < NCTRL; ++k) {",
        "        vec4 c = mvp * vec4(tc_point[k].xyz / tc_point[k].w, 1.0);",
        "        if (c.w <= 1e-6) behind = true;",
        "        pixel[k] = c.xy / max(c.w, 1e-6) * u_viewport;",
        "    }",
        "    // control point (i, j) is k = i * (Q + 1) + j: i along u, j along v",
        "    float u0 = level(0, NURBS_Q + 1, NURBS_P);                 // the edge v = 0 (a curve in u)",
        "    float u1 = level(NURBS_Q, NURBS_Q + 1, NURBS_P);           // v = 1",
        "    float v0 = level(0, 1, NURBS_Q);                           // u = 0 (a curve in v)",
        "    float v1 = level(NURBS_P * (NURBS_Q + 1), 1, NURBS_Q);     // u = 1",
        "    float iu = max(u0, u1), iv = max(v0, v1);",
        "    for (int j = 1; j < NURBS_Q; ++j) iu = max(iu, level(j, NURBS_Q + 1, NURBS_P));",
        "    for (int i = 1; i < NURBS_P; ++i) iv = max(iv, level(i * (NURBS_Q + 1), 1, NURBS_Q));",
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
