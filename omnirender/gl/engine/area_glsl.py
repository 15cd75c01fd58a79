"""Rectangle and disc lights in GLSL: linearly transformed cosines and soft shadows from the light's shape.

Shading (Heitz, Dupuy, Hill and Neubelt 2016, "Real-Time Polygonal-Light
Shading with Linearly Transformed Cosines", as three.js's ``RectAreaLight``
does): the light's polygon (a rectangle's 4 corners, a disc's 8-gon of the
same area) is taken into the frame of the lit point's normal and view,
transformed by the inverse LTC matrix of the material's roughness, and
integrated over the sphere edge by edge; the horizon clipping is the vector
form factor's sphere approximation.  The diffuse term is the identity LTC:
the polygon's form factor, so a diffuse surface shows ``kd * L * F``, the rule
of :mod:`omnirender.attributes.photometry` every engine follows.  The specular
term is the GGX lobe of the material's roughness (Phong shininess through
``phong_roughness``, as Mitsuba's), with the fitted tables of
``omnirender/assets/ltc.npz`` (three.js's, MIT).

Soft shadows (``AREA_SHADOW_ATT``, with shadow maps): the light's map faces are
drawn from its centre, like a point light's; a lit point searches the map for
blockers between it and the light's shape (16 taps half way to the light),
takes their mean distance from the light, and averages 36 bilinear
comparisons at the points where the segments from the lit point to a 6 x 6
grid over the light's shape (a concentric disc grid for a disc) cross the
blockers' distance, each weighted by the form factor's kernel
``cos(receiver) cos(light) / r^2`` of its point of the light (the share of
irradiance it stands for: the offline engines integrate the same).  Each
tap compares with the depth of the receiver's plane
along its ray from the light (a receiver-plane bias: a wide kernel on a
surface the light grazes does not shadow the surface itself).  The kernel is the light's shape scaled by
``(receiver - blocker) / receiver``: the penumbra is as wide as the light's
(PCSS, Fernando 2005, with the light's shape instead of a square).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "MAX_AREA_LIGHTS",
    "POLY_VERTS",
    "AREA_CODE",
    "AREA_SHADOW_CODE",
    "LTC_CORE",
    "LTC_UNIT",
    "area_code",
    "AreaUniforms",
    "bind_ltc",
    "ltc_tables",
]

#: Area lights a forward program shades (more are dropped with a warning; the deferred pipeline has no limit).
MAX_AREA_LIGHTS = 4
#: Vertices per light polygon (a rectangle uses 4, a disc all of them).
POLY_VERTS = 8
#: The texture unit of the LTC tables (after the 16 of :mod:`.units`; every GL 3.3 driver we target has 32).
LTC_UNIT = 16

#: The LTC integral over a polygon (shared by the forward and the deferred pipelines).
LTC_CORE = """
vec3 ltc_edge(vec3 v1, vec3 v2) {           // three.js's LTC_EdgeVectorFormFactor
    float x = dot(v1, v2);
    float y = abs(x);
    float a = 0.8543985 + (0.4965155 + 0.0145206 * y) * y;
    float b = 3.4175940 + (4.1616724 + y) * y;
    float v = a / b;
    float theta_sintheta = x > 0.0 ? v : 0.5 * inversesqrt(max(1.0 - x * x, 1e-7)) - v;
    return cross(v1, v2) * theta_sintheta;
}
// the integral of the LTC ``minv`` over the polygon q[0..n) (counter-clockwise from its lit side) seen from P
// (normal N, view V); ``dir`` gets the vector form factor's direction (eye space): where the light comes from
float ltc_polygon(vec3 q[8], int n, bool two_sided, vec3 N, vec3 V, vec3 P, mat3 minv, out vec3 dir) {
    dir = N;
    vec3 ln = cross(q[1] - q[0], q[2] - q[0]);
    bool behind = dot(ln, P - q[0]) < 0.0;
    if (behind && !two_sided) return 0.0;
    vec3 T1 = V - N * dot(V, N);
    T1 = dot(T1, T1) > 1e-12 ? normalize(T1) : (abs(N.x) < 0.9 ? normalize(cross(N, vec3(1.0, 0.0, 0.0)))
                                                                : normalize(cross(N, vec3(0.0, 1.0, 0.0))));
    vec3 T2 = -cross(N, T1);  // three.js's (left-handed) frame: a polygon counter-clockwise from its lit side
    mat3 frame = transpose(mat3(T1, T2, N));
    mat3 m = minv * frame;
    vec3 first = normalize(m * (q[0] - P));
    vec3 prev = first;
    vec3 f = vec3(0.0);
    for (int j = 1; j < 8; ++j) {
        if (j >= n) break;
        vec3 cur = normalize(m * (q[j] - P));
        f += ltc_edge(prev, cur);
        prev = cur;
    }
    f += ltc_edge(prev, first);
    if (behind) f = -f;  // a two-sided light seen from its back: the same polygon, wound the other way
    float l = length(f);
    if (l > 1e-12) dir = normalize(transpose(frame) * f);
    return max((l * l + f.z) / (l + 1.0), 0.0);  // horizon clipping: the sphere approximation
}
// the polygon of a rectangle (4 corners) or disc (8-gon of the disc's area) around C with half axes HU, HV
int area_polygon(vec3 C, vec3 HU, vec3 HV, bool disc, out vec3 q[8]) {
    if (!disc) {
        q[0] = C - HU - HV; q[1] = C + HU - HV; q[2] = C + HU + HV; q[3] = C - HU + HV;
        q[4] = q[5] = q[6] = q[7] = C;
        return 4;
    }
    for (int j = 0; j < 8; ++j) {
        float t = float(j) * 0.78539816;
        q[j] = C + 1.0539 * (cos(t) * HU + sin(t) * HV);  // sqrt(2 pi / (8 sin(pi / 4))): the disc's area
    }
    return 8;
}
"""

AREA_CODE = """
uniform vec4 u_lpoly[MAX_AREA_LIGHTS * 8];  // view-space polygon; [k*8].w vertex count, [k*8+1].w two-sided
uniform sampler2D u_ltc;                    // LTC tables: rows 0-63 the inverse matrices, 64-127 norm and Fresnel
float ltc_integral(int k, vec3 N, vec3 V, vec3 P, mat3 minv) {
    vec3 q[8];
    for (int j = 0; j < 8; ++j) q[j] = u_lpoly[k * 8 + j].xyz;
    vec3 dir;
    return ltc_polygon(q, int(u_lpoly[k * 8].w), u_lpoly[k * 8 + 1].w > 0.5, N, V, P, minv, dir);
}
vec4 ltc_table(float roughness, vec3 N, vec3 V, float half_) {
    vec2 uv = vec2(roughness, sqrt(1.0 - clamp(dot(N, V), 0.0, 1.0))) * (63.0 / 64.0) + 0.5 / 64.0;
    return texture(u_ltc, vec2(uv.x, 0.5 * uv.y + half_));
}
mat3 ltc_matrix(vec4 t1) { return mat3(vec3(t1.x, 0.0, t1.y), vec3(0.0, 1.0, 0.0), vec3(t1.z, 0.0, t1.w)); }
#ifdef PHONG_FIELDS
// light i (area slot k): Lambert's form factor times kd, and the GGX lobe of the shininess's roughness
vec3 area_phong(int i, int k, vec3 P, vec3 N, vec3 V, vec3 kd) {
    float F = ltc_integral(k, N, V, P, mat3(1.0));
    vec3 color = kd * F * u_ldiff[i];
    if (any(greaterThan(M_SPEC.rgb, vec3(0.0)))) {
        float alpha = clamp(sqrt(2.0 / (4.0 * max(M_SPEC.w, 1.0) + 2.0)), 0.01, 1.0);
        vec4 t1 = ltc_table(sqrt(alpha), N, V, 0.0);
        vec4 t2 = ltc_table(sqrt(alpha), N, V, 0.5);
        color += M_SPEC.rgb * t2.x * ltc_integral(k, N, V, P, ltc_matrix(t1)) * u_lspec[i];
    }
    return color;
}
#elif MODEL == 1
vec3 area_pbr(int i, int k, vec3 P, vec3 N, vec3 V, vec3 albedo, vec3 F0, float metallic, float rough) {
    vec4 t1 = ltc_table(rough, N, V, 0.0);
    vec4 t2 = ltc_table(rough, N, V, 0.5);
    vec3 fresnel = F0 * t2.x + (1.0 - F0) * t2.y;
    float D = ltc_integral(k, N, V, P, mat3(1.0));
    float S = ltc_integral(k, N, V, P, ltc_matrix(t1));
    return (albedo * (1.0 - metallic) * D + fresnel * S) * u_ldiff[i];
}
#endif
"""

#: Soft shadows of area lights (needs the shadow maps' ``MAPS_CORE`` and ``u_lshadow``).
AREA_SHADOW_CODE = """
vec2 area_sample(vec2 s, bool disc) {       // a point of [-1, 1]^2 on the light's shape (Shirley's disc map)
    if (!disc || (s.x == 0.0 && s.y == 0.0)) return s;
    float r, phi;
    if (abs(s.x) > abs(s.y)) { r = s.x; phi = 0.78539816 * s.y / s.x; }
    else { r = s.y; phi = 1.57079633 - 0.78539816 * s.x / s.y; }
    return r * vec2(cos(phi), sin(phi));
}
// where the ray from the light's centre C through X meets the receiver's plane (W, NW), in the face's clip space:
// each tap compares with the receiver's own depth there (a receiver-plane depth bias: no acne under wide kernels)
bool receiver_plane(mat4 M, vec3 C, vec3 X, vec3 W, vec3 NW, out vec4 clip) {
    float denom = dot(X - C, NW);
    if (denom >= -1e-9) return false;
    clip = M * vec4(C + (X - C) * (dot(W - C, NW) / denom), 1.0);
    return clip.w > 0.0;
}
// soft shadow of an area light (world centre C, half axes HU, HV) with map faces [f, f + count)
float area_shadow_faces(int f, int count, vec3 C, vec3 HU, vec3 HV, bool disc, vec3 P, vec3 N) {
    if (count == 0) return 1.0;
    vec3 W = (u_eye_to_world * vec4(P, 1.0)).xyz;
    vec3 NW = mat3(u_eye_to_world) * N;
    if (count == 6) {
        vec3 d = W - C;
        vec3 a = abs(d);
        f += a.x >= a.y && a.x >= a.z ? (d.x > 0.0 ? 0 : 1) : (a.y >= a.z ? (d.y > 0.0 ? 2 : 3) : (d.z > 0.0 ? 4 : 5));
    }
    vec4 tile = u_shadow_tile[f];
    if (tile.z <= 0.0) return 1.0;
    mat4 M = u_shadow_mat[f];
    vec4 clip = M * vec4(W, 1.0);
    float texel = u_shadow_texel[f].x + u_shadow_texel[f].y * max(clip.w, 0.0);
    vec3 LW = normalize(C - W);
    float slope = clamp(1.0 - abs(dot(NW, LW)), 0.0, 1.0);
    W += NW * (u_shadow_style.z * texel * slope) + LW * (u_shadow_style.y * texel);
    clip = M * vec4(W, 1.0);
    if (clip.w <= 0.0) return 1.0;
    float zr = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
    // clip.z = -A clip.w + B along any ray of the face: window depth back to distance along the face's axis
    vec4 c2 = M * vec4(W + LW, 1.0);
    float A = -(clip.z - c2.z) / (clip.w - c2.w);
    float B = clip.z + A * clip.w;
    float sum = 0.0, found = 0.0;
    for (int b = 0; b < 4; ++b) {
        for (int a = 0; a < 4; ++a) {
            vec2 s = area_sample((vec2(float(a), float(b)) + 0.5) * 0.5 - 1.0, disc);
            vec4 cx;
            if (!receiver_plane(M, C, mix(W, C + s.x * HU + s.y * HV, 0.5), W, NW, cx)) continue;
            vec2 uv = cx.xy / cx.w * 0.5 + 0.5;
            if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) continue;
            ivec2 t = ivec2(clamp(tile.xy + uv * tile.zw, tile.xy, tile.xy + tile.zw - 1.0));
            float zb = texelFetch(u_shadow_atlas, t, 0).r;
            if (zb < cx.z / cx.w * 0.5 + 0.5) { sum += zb; found += 1.0; }
        }
    }
    if (found == 0.0) return 1.0;
    float wb = B / ((sum / found) * 2.0 - 1.0 + A);
    float frac = clamp((clip.w - wb) / clip.w, 0.0, 1.0);  // where the blockers cross the segments to the light
    // each tap weighted by the form factor's kernel cos(receiver) cos(light) / r^2 of its point of the light
    // (the share of irradiance it stands for, as the offline engines integrate it)
    vec3 NL = normalize(cross(HU, HV));
    float lit = 0.0, total = 0.0;
    for (int b = 0; b < 6; ++b) {
        for (int a = 0; a < 6; ++a) {
            vec2 s = area_sample((vec2(float(a), float(b)) + 0.5) / 3.0 - 1.0, disc);
            vec3 X = C + s.x * HU + s.y * HV;
            vec3 v = X - W;
            float r2 = max(dot(v, v), 1e-12);
            float k = max(dot(NW, v), 0.0) * abs(dot(NL, v)) / (r2 * r2);
            total += k;
            vec4 cx;
            if (!receiver_plane(M, C, mix(W, X, frac), W, NW, cx)) { lit += k; continue; }
            vec2 uv = cx.xy / cx.w * 0.5 + 0.5;
            if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) { lit += k; continue; }
            lit += k * shadow_bilinear(tile, tile.xy + uv * tile.zw, clamp(cx.z / cx.w * 0.5 + 0.5, 0.0, 1.0));
        }
    }
    return total > 0.0 ? lit / total : 1.0;
}
"""

#: The forward light loops' look-up: light i's faces, area slot k's frame.
AREA_SHADOW_FORWARD = """
uniform vec4 u_larea[MAX_AREA_LIGHTS * 3];  // world: centre (w: 1 for a disc), half axes u and v
float area_shadow(int i, int k, vec3 P, vec3 N) {
    return area_shadow_faces(int(u_lshadow[i].x), int(u_lshadow[i].y), u_larea[k * 3].xyz, u_larea[k * 3 + 1].xyz,
                             u_larea[k * 3 + 2].xyz, u_larea[k * 3].w > 0.5, P, N);
}
#define AREA_SHADOW_MAP_ATT(i, k) att *= area_shadow(i, k, P, N);
"""


def area_code(features: dict[str, Any]) -> str:
    """The GLSL of a program variant whose lights include area lights ("" otherwise); defines ``AREA_SHADOW_ATT``."""
    if "a" not in str(features.get("LIGHTS", "")):
        return ""
    parts = [f"#define MAX_AREA_LIGHTS {MAX_AREA_LIGHTS}", LTC_CORE, AREA_CODE]
    calls = []
    if features.get("SHADOW_MAPS"):
        parts += [AREA_SHADOW_CODE, AREA_SHADOW_FORWARD]
        calls.append("AREA_SHADOW_MAP_ATT(i, k)")
    if features.get("LIGHT_SELECT"):
        calls.append("att *= u_light_on[i];")
    parts.append("#define AREA_SHADOW_ATT(i, k) " + " ".join(calls))
    return "\n".join(parts) + "\n"


class AreaUniforms:
    """``u_lpoly`` (view-space polygons) and ``u_larea`` (world-space frames) of up to ``MAX_AREA_LIGHTS`` lights."""

    __slots__ = ("poly", "world", "count")

    def __init__(self) -> None:
        self.poly = np.zeros((MAX_AREA_LIGHTS * POLY_VERTS, 4), np.float32)
        self.world = np.zeros((MAX_AREA_LIGHTS * 3, 4), np.float32)
        self.count = 0

    def full(self) -> bool:
        return self.count == MAX_AREA_LIGHTS

    def add(self, light: Any, matrix: np.ndarray, view: np.ndarray) -> None:
        """Add ``light`` (an ``AreaLight`` under world ``matrix``) for the eye of ``view``."""
        from ...attributes import DiscLight

        k = self.count
        disc = isinstance(light, DiscLight)
        pts = light.world_polygon(matrix, POLY_VERTS)
        eye = pts @ view[:3, :3].T + view[:3, 3]
        base = k * POLY_VERTS
        self.poly[base : base + len(eye), :3] = eye
        self.poly[base, 3] = len(eye)
        self.poly[base + 1, 3] = 1.0 if light.two_sided else 0.0
        centre, hu, hv, normal = light.world_frame(matrix)
        if float(np.dot(np.cross(hu, hv), normal)) < 0.0:
            hu = -hu  # HU x HV on the lit side (the shape is symmetric)
        self.world[3 * k, :3], self.world[3 * k, 3] = centre, 1.0 if disc else 0.0
        self.world[3 * k + 1, :3], self.world[3 * k + 2, :3] = hu, hv
        self.count += 1


_TABLES: np.ndarray | None = None
_TEXTURES: dict[int, Any] = {}


def ltc_tables() -> np.ndarray:
    """The LTC tables as one (128, 64, 4) float32 array: the inverse matrices above, norm and Fresnel below."""
    global _TABLES
    if _TABLES is None:
        path = Path(__file__).resolve().parents[2] / "assets" / "ltc.npz"
        with np.load(path) as data:
            _TABLES = np.ascontiguousarray(np.concatenate([data["ltc_1"], data["ltc_2"]], axis=0), np.float32)
    return _TABLES


def bind_ltc(program: Any) -> None:
    """Bind the LTC tables (one texture per context, unit ``LTC_UNIT``) for ``program`` if it reads them."""
    u = program.get("u_ltc", None)
    if u is None:
        return
    ctx = program.ctx
    texture = _TEXTURES.get(id(ctx))
    if texture is None or texture.ctx is not ctx:
        table = ltc_tables()
        texture = ctx.texture((64, 128), 4, table.tobytes(), dtype="f4")
        texture.repeat_x = texture.repeat_y = False
        _TEXTURES[id(ctx)] = texture
    texture.use(LTC_UNIT)
    u.value = LTC_UNIT
