"""GLSL of the Gaussian-splat painter: the EWA projection, the SH colour rule, the Gaussian footprint.

The spherical-harmonics constants are written from :mod:`omnirender.shapes._sh` (through its public
names in :mod:`omnirender.shapes.splats`)
(the one implementation of the colour rule), so the two cannot drift apart.
Splat data lives in two float textures read with ``texelFetch`` (OpenGL 3.3):
``u_geom`` holds three texels per splat -- (centre, opacity), (Sigma_xx,
Sigma_xy, Sigma_xz, Sigma_yy), (Sigma_yz, Sigma_zz, 0, 0) in the shape's local
space -- and ``u_sh`` one RGB texel per SH coefficient.  The instance attribute
``in_splat`` is the splat's index in back-to-front order (the sort's output).
"""

from __future__ import annotations

from ...shapes.splats import SH_C0, SH_C1, SH_C2, SH_C3

__all__ = ["SPLAT_VERTEX", "SPLAT_FRAGMENT", "SH_GLSL", "FETCH_GLSL"]


def _floats(values: tuple[float, ...]) -> str:
    return ", ".join(repr(float(v)) for v in values)


#: The SH colour rule of ``_sh.sh_colors``: ``max(0.5 + sum_k Y_k(dir) sh_k, 0)``, same constants and signs.
SH_GLSL = f"""
const float SH_C0 = {SH_C0!r};
const float SH_C1 = {SH_C1!r};
const float SH_C2[5] = float[5]({_floats(SH_C2)});
const float SH_C3[7] = float[7]({_floats(SH_C3)});
vec3 sh_coefficient(int base, int k);
vec3 sh_color(int base, int degree, vec3 dir) {{
    vec3 c = SH_C0 * sh_coefficient(base, 0);
    if (degree > 0) {{
        float x = dir.x, y = dir.y, z = dir.z;
        c += -SH_C1 * y * sh_coefficient(base, 1) + SH_C1 * z * sh_coefficient(base, 2)
             - SH_C1 * x * sh_coefficient(base, 3);
        if (degree > 1) {{
            float xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
            c += SH_C2[0] * xy * sh_coefficient(base, 4) + SH_C2[1] * yz * sh_coefficient(base, 5)
                 + SH_C2[2] * (2.0 * zz - xx - yy) * sh_coefficient(base, 6)
                 + SH_C2[3] * xz * sh_coefficient(base, 7) + SH_C2[4] * (xx - yy) * sh_coefficient(base, 8);
            if (degree > 2) {{
                c += SH_C3[0] * y * (3.0 * xx - yy) * sh_coefficient(base, 9)
                     + SH_C3[1] * xy * z * sh_coefficient(base, 10)
                     + SH_C3[2] * y * (4.0 * zz - xx - yy) * sh_coefficient(base, 11)
                     + SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy) * sh_coefficient(base, 12)
                     + SH_C3[4] * x * (4.0 * zz - xx - yy) * sh_coefficient(base, 13)
                     + SH_C3[5] * z * (xx - yy) * sh_coefficient(base, 14)
                     + SH_C3[6] * x * (xx - 3.0 * yy) * sh_coefficient(base, 15);
            }}
        }}
    }}
    return max(c + 0.5, vec3(0.0));
}}
"""

#: Texel ``t`` of a splat-data texture ``u_width`` texels wide (row-major).
FETCH_GLSL = """
uniform int u_width;
vec4 fetch(sampler2D s, int t) {
    return texelFetch(s, ivec2(t % u_width, t / u_width), 0);
}
"""

SPLAT_VERTEX = (
    """
uniform sampler2D u_geom;
uniform sampler2D u_sh;
uniform int u_degree;
uniform int u_sh_count;        // SH texels per splat ((degree + 1)^2)
uniform mat4 u_mv;             // model-view
uniform mat4 u_proj;
uniform vec4 u_viewport;       // the viewport: origin and size in window pixels (a stereo eye's half, ...)
uniform vec4 u_eye;            // eye in local space (w = 1) or the viewing direction there (w = 0: orthographic)
uniform float u_near;
in vec2 in_corner;             // the quad's corners, (+-1, +-1)
in uint in_splat;              // which splat (back-to-front order)
flat out vec3 v_color;         // display RGB
flat out float v_opacity;
flat out vec3 v_conic;         // inverse 2D covariance (a, b, c) in pixels
flat out vec2 v_mean;          // window coordinates of the centre
"""
    + FETCH_GLSL
    + """
vec3 sh_coefficient(int base, int k) { return fetch(u_sh, base + k).rgb; }
"""
    + SH_GLSL
    + """
void main() {
    int i = int(in_splat);
    vec4 g0 = fetch(u_geom, 3 * i);
    vec4 g1 = fetch(u_geom, 3 * i + 1);
    vec4 g2 = fetch(u_geom, 3 * i + 2);
    vec4 t = u_mv * vec4(g0.xyz, 1.0);
    vec4 clip = u_proj * t;
    vec3 ndc = clip.xyz / clip.w;
    float depth = -t.z;
    bool ortho = u_eye.w < 0.5;
    // the paper's in_frustum: nearer than the near plane, or 1.3x outside the frustum sideways (or beyond far)
    bool culled = depth <= u_near || abs(ndc.x) > 1.3 || abs(ndc.y) > 1.3 || ndc.z > 1.0;
    // EWA: Sigma' = J W Sigma W^T J^T (+ 0.3 px^2 on the diagonal, the paper's low-pass filter)
    mat3 cov = mat3(g1.x, g1.y, g1.z, g1.y, g1.w, g2.x, g1.z, g2.x, g2.y);
    mat3 w = mat3(u_mv);
    mat3 cv = w * cov * transpose(w);
    float fx = u_proj[0][0] * u_viewport.z * 0.5;
    float fy = u_proj[1][1] * u_viewport.w * 0.5;
    vec3 j0 = vec3(fx, 0.0, 0.0);
    vec3 j1 = vec3(0.0, fy, 0.0);
    if (!ortho) {
        float d = max(depth, 1e-12);
        // x/z and y/z clamped to 1.3 times the frustum's half-extent around its axis (off-axis frusta too)
        float cx = -u_proj[2][0] / u_proj[0][0];
        float cy = -u_proj[2][1] / u_proj[1][1];
        float limx = 1.3 / u_proj[0][0];
        float limy = 1.3 / u_proj[1][1];
        float tx = (clamp(t.x / d - cx, -limx, limx) + cx) * d;
        float ty = (clamp(t.y / d - cy, -limy, limy) + cy) * d;
        j0 = vec3(fx / d, 0.0, fx * tx / (d * d));
        j1 = vec3(0.0, fy / d, fy * ty / (d * d));
    }
    vec3 c0 = cv * j0;
    vec3 c1 = cv * j1;
    float a = dot(j0, c0) + 0.3;
    float b = dot(j0, c1);
    float c = dot(j1, c1) + 0.3;
    float det = a * c - b * b;
    culled = culled || !(det > 0.0);
    float mid = 0.5 * (a + c);
    float lambda = mid + sqrt(max(0.1, mid * mid - det));
    float radius = ceil(3.0 * sqrt(lambda));
    v_conic = vec3(c, -b, a) / det;
    v_mean = u_viewport.xy + (ndc.xy + 1.0) * 0.5 * u_viewport.zw;
    v_opacity = g0.w;
    vec3 dir = ortho ? normalize(u_eye.xyz) : g0.xyz - u_eye.xyz;
    float len = length(dir);
    dir = len > 0.0 ? dir / len : vec3(0.0, 0.0, 1.0);
    v_color = sh_color(i * u_sh_count, u_degree, dir);
    vec2 px = v_mean + in_corner * radius;
    vec2 xy = (px - u_viewport.xy) / u_viewport.zw * 2.0 - 1.0;
    gl_Position = culled ? vec4(2.0, 2.0, 2.0, 1.0) : vec4(xy, ndc.z, 1.0);
}
"""
)

SPLAT_FRAGMENT = """
flat in vec3 v_color;
flat in float v_opacity;
flat in vec3 v_conic;
flat in vec2 v_mean;
out vec4 f_color;
void main() {
    vec2 d = gl_FragCoord.xy - v_mean;
    float power = -0.5 * (v_conic.x * d.x * d.x + v_conic.z * d.y * d.y) - v_conic.y * d.x * d.y;
    if (power > 0.0) discard;
    float alpha = min(0.99, v_opacity * exp(power));
    if (alpha < 1.0 / 255.0) discard;
#ifdef DEPTH_ONLY
    // a depth-only pass (the forward technique's "transparent depth"): the depth of splats at least this opaque
#ifdef PASS_ALPHA_CUTOFF
    if (alpha < float(PASS_ALPHA_CUTOFF)) discard;
#endif
    f_color = vec4(0.0);
    return;
#endif
#ifdef LINEAR_OUTPUT
    vec3 c = to_linear(v_color);  // a display value: linear targets get it decoded and blend in linear light
#else
    vec3 c = v_color;  // display targets blend display values, as the trainer did (not clamped: only the sum is)
#endif
    f_color = vec4(c * alpha, alpha);  // premultiplied
}
"""
