"""GLSL of the shadow techniques, inserted into the lit fragment shader at ``SHADOW_CODE``.

Kept apart from the material code of :mod:`.shaders`: the light loops call
``SHADOW_ATT(i)`` after computing light ``i``'s attenuation ``att``, and scale
the ambient and emitted terms by ``AMBIENT_ON``.  Without the features below
both are no-ops.

* ``SHADOW_MAPS`` (the number of map faces in the frame's atlas): light ``i``
  is looked up in its face of the shadow-map atlas (``u_lshadow[i]``: first
  face and face count, 0 for a light without shadows, 1 for directional and
  spot lights, 6 for point lights, whose face is the major axis of the
  direction from the light), with normal offset and depth bias measured in
  texels of that face, and percentage-closer filtering chosen at compile
  time by ``SHADOW_PCF`` (0: one comparison, hard shadows; 1: bilinear 2x2;
  2, the default softness: a tent over 3x3 texels, Filament's and three.js's
  PCF; 3: four bilinear taps spread over ``u_shadow_style.x`` texels).  Software
  rasterisers run every side of a branch, so the filter is a define, not a
  uniform.
* ``LIGHT_SELECT``: ``u_light_on[i]`` scales light ``i`` and ``u_ambient_on``
  the ambient and emitted light (the additive passes of shadow volumes).
* ``SPECULAR_OFF``: the Phong model without its specular term (the first
  pass of ``om.gl.PhongHighlight``).
"""

from __future__ import annotations

from typing import Any

__all__ = ["shadow_code", "pcf_mode", "MAX_SHADOW_FACES", "MAPS_CORE"]

#: Faces a frame's atlas holds at most (4 point lights, or 24 directional/spot lights).
MAX_SHADOW_FACES = 24

#: The atlas look-up for one light's faces (``face_shadow``), with the uniforms it reads: used by the forward
#: light loops through :data:`_MAPS` and by the deferred pipeline's lighting pass (one light per proxy).
MAPS_CORE = """
uniform sampler2D u_shadow_atlas;             // window depth of the faces' casters (raw values)
uniform mat4 u_shadow_mat[SHADOW_MAPS];      // world -> clip space of the face's light camera
uniform vec4 u_shadow_tile[SHADOW_MAPS];     // atlas texel offset (xy) and size (zw); size 0: no map (lit)
uniform vec2 u_shadow_texel[SHADOW_MAPS];    // world size of one texel: x + y * (distance from the light)
uniform vec3 u_shadow_style;                 // softness, depth bias, normal offset (texels)
// texelFetch and our own comparisons: software rasterisers (llvmpipe) compare-and-filter far more slowly
float shadow_at(vec4 tile, vec2 t, float z) {
    ivec2 c = ivec2(clamp(t, tile.xy, tile.xy + tile.zw - 1.0));
    return texelFetch(u_shadow_atlas, c, 0).r < z ? 0.0 : 1.0;
}
float shadow_bilinear(vec4 tile, vec2 t, float z) {  // 2x2 percentage-closer filter, bilinear weights
    vec2 b = t - 0.5;
    vec2 f = fract(b);
    vec2 c = floor(b);
    float s00 = shadow_at(tile, c + 0.5, z), s10 = shadow_at(tile, c + vec2(1.5, 0.5), z);
    float s01 = shadow_at(tile, c + vec2(0.5, 1.5), z), s11 = shadow_at(tile, c + 1.5, z);
    return mix(mix(s00, s10, f.x), mix(s01, s11, f.x), f.y);
}
float shadow_lookup(vec4 tile, vec2 uv, float z) {
    vec2 t = tile.xy + uv * tile.zw;   // texels of the atlas
#if SHADOW_PCF == 0
    return shadow_at(tile, t, z);
#elif SHADOW_PCF == 1
    return shadow_bilinear(tile, t, z);
#elif SHADOW_PCF == 2
    // a tent 3 texels wide (the PCF of Filament and three.js): the 3x3 texels nearest t, each weighted by
    // 1.5 - |distance| per axis; 9 fetches where four bilinear taps take 16
    vec2 c = floor(t) + 0.5;   // the nearest texel centre
    vec2 f = t - c;            // in [-0.5, 0.5)
    vec3 wx = vec3(0.5 + f.x, 1.5 - abs(f.x), 0.5 - f.x);   // 1.5 - |d| for d = f + 1, f, f - 1
    vec3 wy = vec3(0.5 + f.y, 1.5 - abs(f.y), 0.5 - f.y);
    float sum = 0.0;
    for (int j = -1; j <= 1; ++j) {
        for (int i = -1; i <= 1; ++i) {
            sum += wx[1 - i] * wy[1 - j] * shadow_at(tile, c + vec2(float(i), float(j)), z);
        }
    }
    return sum / ((wx.x + wx.y + wx.z) * (wy.x + wy.y + wy.z));
#else
    float h = 0.5 * max(u_shadow_style.x - 1.0, 0.0);  // four filtered taps spread over the softness radius
    return 0.25 * (shadow_bilinear(tile, t + vec2(-h, -h), z) + shadow_bilinear(tile, t + vec2(h, -h), z)
                   + shadow_bilinear(tile, t + vec2(-h, h), z) + shadow_bilinear(tile, t + vec2(h, h), z));
#endif
}
// light with faces [f, f + count) (count 1 or 6) at eye position light_eye; P, N, L in eye space
float face_shadow(int f, int count, vec3 light_eye, vec3 P, vec3 N, vec3 L) {
    vec3 W = (u_eye_to_world * vec4(P, 1.0)).xyz;
    mat3 rot = mat3(u_eye_to_world);
    if (count == 6) {
        vec3 d = W - (u_eye_to_world * vec4(light_eye, 1.0)).xyz;
        vec3 a = abs(d);
        f += a.x >= a.y && a.x >= a.z ? (d.x > 0.0 ? 0 : 1) : (a.y >= a.z ? (d.y > 0.0 ? 2 : 3) : (d.z > 0.0 ? 4 : 5));
    }
    vec4 tile = u_shadow_tile[f];
    if (tile.z <= 0.0) return 1.0;
    vec4 clip = u_shadow_mat[f] * vec4(W, 1.0);
    float texel = u_shadow_texel[f].x + u_shadow_texel[f].y * max(clip.w, 0.0);
    float slope = clamp(1.0 - abs(dot(N, L)), 0.0, 1.0);
    vec3 NW = rot * N, LW = rot * L;
    // normal offset (grows at grazing light) and a depth bias towards the light, both in texels of the face
    W += NW * (u_shadow_style.z * texel * slope) + LW * (u_shadow_style.y * texel);
    clip = u_shadow_mat[f] * vec4(W, 1.0);
    if (clip.w <= 0.0) return 1.0;
    vec3 q = clip.xyz / clip.w * 0.5 + 0.5;
    // outside the face's map no caster can be (faces are cropped to the casters); a cube face's own border
    // keeps a few texels of slack for the offsets, which may carry a point just past it
    float slack = count == 1 ? 0.0 : 4.0 / tile.z;
    if (q.x < -slack || q.x > 1.0 + slack || q.y < -slack || q.y > 1.0 + slack) return 1.0;
    return shadow_lookup(tile, clamp(q.xy, 0.0, 1.0), clamp(q.z, 0.0, 1.0));
}
"""

_MAPS = (
    MAPS_CORE
    + """
uniform vec4 u_lshadow[MAX_LIGHTS];          // first face, face count (0 none, 1, 6)
float light_shadow(int i, vec3 P, vec3 N, vec3 L) {
    int count = int(u_lshadow[i].y);
    if (count == 0 || dot(N, L) <= 0.0) return 1.0;  // facing away: the light adds nothing anyway
    return face_shadow(int(u_lshadow[i].x), count, u_lpos[i].xyz, P, N, L);
}
#define SHADOW_MAP_ATT(i) att *= light_shadow(i, P, N, L);
"""
)

_SELECT = """
uniform float u_light_on[MAX_LIGHTS];
uniform float u_ambient_on;
#define AMBIENT_ON u_ambient_on
#define LIGHT_SELECT_ATT(i) att *= u_light_on[i];
"""


def pcf_mode(softness: float) -> int:
    """The ``SHADOW_PCF`` define for a softness in texels (0 hard, 1 bilinear, 2 tent, 3 four spread taps)."""
    return 0 if softness <= 0.0 else 1 if softness <= 1.0 else 2 if softness <= 2.0 else 3


def shadow_code(features: dict[str, Any]) -> str:
    """The GLSL for the shadow features of a program variant (``SHADOW_ATT`` and ``AMBIENT_ON`` always)."""
    parts = []
    calls = []
    if features.get("SHADOW_MAPS"):
        if "SHADOW_PCF" not in features:
            parts.append("#define SHADOW_PCF 1")
        parts.append(_MAPS)
        calls.append("SHADOW_MAP_ATT(i)")
    if features.get("LIGHT_SELECT"):
        parts.append(_SELECT)
        calls.append("LIGHT_SELECT_ATT(i)")
    else:
        parts.append("#define AMBIENT_ON 1.0")
    parts.append("#define SHADOW_ATT(i) " + " ".join(calls))
    if features.get("SPECULAR_OFF"):
        parts.append("#undef M_SPEC\n#define M_SPEC vec4(0.0, 0.0, 0.0, 1.0)")
    return "\n".join(parts) + "\n"


#: Geometry shader of the shadow-volume passes (``SHADOW_VOLUME``), fed triangles with their neighbours
#: (``triangles_adjacency``): every triangle of a closed mesh that faces the light gives its near cap (itself)
#: and its far cap (projected to infinity away from the light), and each of its edges whose neighbour faces
#: away (a silhouette edge) a side quad to infinity.  Only silhouettes get sides: the fill stays small.
VOLUME_GEOMETRY = """
layout(triangles_adjacency) in;
layout(triangle_strip, max_vertices = 18) out;
in vec3 v_pos[];
uniform mat4 u_view;
uniform mat4 u_proj;
uniform vec4 u_volume_light;   // world: position (w = 1) or the direction towards the light (w = 0)
vec4 light_eye;
bool faces_light(vec3 a, vec3 b, vec3 c) {
    vec3 towards = light_eye.w > 0.5 ? light_eye.xyz - a : light_eye.xyz;
    return dot(cross(b - a, c - a), towards) > 0.0;
}
vec4 far_point(vec3 p) { return u_proj * vec4(light_eye.w > 0.5 ? p - light_eye.xyz : -light_eye.xyz, 0.0); }
void main() {
    light_eye = u_view * u_volume_light;
    vec3 a = v_pos[0], b = v_pos[2], c = v_pos[4];
    if (!faces_light(a, b, c)) return;
    vec3 p[3] = vec3[3](a, b, c);
    vec3 n[3] = vec3[3](v_pos[1], v_pos[3], v_pos[5]);
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3;
        if (faces_light(p[i], n[i], p[j])) continue;   // the neighbour is lit too: an inner edge
        gl_Position = u_proj * vec4(p[i], 1.0); EmitVertex(); gl_Position = far_point(p[i]); EmitVertex();
        gl_Position = u_proj * vec4(p[j], 1.0); EmitVertex(); gl_Position = far_point(p[j]); EmitVertex();
        EndPrimitive();
    }
    gl_Position = u_proj * vec4(a, 1.0); EmitVertex(); gl_Position = u_proj * vec4(b, 1.0); EmitVertex();
    gl_Position = u_proj * vec4(c, 1.0); EmitVertex();
    EndPrimitive();
    gl_Position = far_point(a); EmitVertex(); gl_Position = far_point(c); EmitVertex(); gl_Position = far_point(b);
    EmitVertex();
    EndPrimitive();
}
"""

VOLUME_FRAGMENT = """
out vec4 f_color;
void main() { f_color = vec4(0.0); }
"""
