"""GLSL sources of the GL engine and the cache of compiled program variants.

One uber-shader per primitive kind (``mesh``, ``points``, ``lines``) is
specialised with ``#define``s, so a variant pays only for what its batch uses:

* geometry and state: vertex colours, texture, flat shading, clip planes, fog,
  point sizes, GL state kinds that live in the shader (``AlphaTest``);
* material: the shading model (``MODEL`` 0 Phong, 1 PBR, 2 unlit), whether
  the batch shares one material (``UNIFORM_MATERIAL``: material uniforms,
  only model matrix and colour per instance) or carries it per instance (then
  only the fields its model reads), highlight only when something is
  highlighted;
* lights: the light loop unrolled for the frame's light types;
* the pass: depth only, flat colour, unlit, user snippets around the vertex
  (``pass_vertex``) and the colour (``pass_fragment``), linear output for
  float targets.

Lighting is linear; the fragment shader writes sRGB unless the target is a
float target.  Every term is guarded against the degenerate set-ups of the
material test matrix (light at the eye, grazing light, roughness 0 and 1,
metallic 0 and 1, shininess 0): no NaN, no negative bases in ``pow``.
"""

from __future__ import annotations

from typing import Any

from .area_glsl import area_code
from .layout import PBR, PHONG, UNLIT
from .shadow_glsl import VOLUME_FRAGMENT, VOLUME_GEOMETRY, shadow_code

__all__ = ["MAX_LIGHTS", "ProgramCache", "instance_fields", "SRGB_GLSL", "register_tessellation"]

MAX_LIGHTS = 32

#: GLSL sRGB encoding and decoding (every program that writes or reads display values).
SRGB_GLSL = """
vec3 to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
vec3 to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c));
}
"""
#: om.Fog's equations (attributes.environment.Fog.factor) at eye distance ``d``, linear colours: one GLSL
#: implementation for the forward shaders and the post-processing chain's om.gl.DepthFog.
FOG_GLSL = """uniform vec4 u_fog;        // start, end, density, mode (0 linear, 1 exp, 2 exp2)
uniform vec3 u_fog_color;
vec3 apply_fog(vec3 c, float d) {
    float f;
    if (u_fog.w < 0.5) f = (u_fog.y - d) / (u_fog.y - u_fog.x);
    else if (u_fog.w < 1.5) f = exp(-u_fog.z * d);
    else f = exp(-(u_fog.z * d) * (u_fog.z * d));
    return mix(u_fog_color, c, clamp(f, 0.0, 1.0));
}
"""
_COMMON = (
    SRGB_GLSL
    + """
vec3 encode_output(vec3 c) {
#ifdef LINEAR_OUTPUT
    return max(c, vec3(0.0));
#else
    return to_srgb(c);
#endif
}
#ifdef FOG
"""
    + FOG_GLSL
    + """#endif
"""
)

VERTEX = """
in vec3 in_position;
#ifndef POINTS
in vec3 in_normal;
#endif
#ifdef VCOLOR
in vec4 in_color;
#endif
#ifdef UVS
in vec2 in_texcoord;
out vec2 v_uv0;
#ifdef UV1
in vec2 in_texcoord1;
out vec2 v_uv1;
#endif
#endif
#ifdef NORMAL_MAP
in vec4 in_tangent;
out vec4 v_tangent;
#endif
#ifdef VSIZE
in float in_size;
#endif
#ifdef SINGLE
uniform mat4 i_model;
uniform vec4 i_color;
#else
in mat4 i_model;
in vec4 i_color;
#ifdef INSTANCE_OFFSET
in vec3 i_offset;  // an instance set's world translations in a buffer of their own (replace i_model's)
#endif
#endif
#ifdef INSTANCE_OFFSET
#define I_MODEL mat4(i_model[0], i_model[1], i_model[2], vec4(i_offset, 1.0))
#else
#define I_MODEL i_model
#endif
#ifdef INSTANCE_MATERIAL
in vec4 i_emis;
#ifdef PHONG_FIELDS
in vec4 i_spec;
in vec4 i_amb;
flat out vec4 v_spec;
flat out vec4 v_amb;
#endif
#if MODEL == 1 || defined(PASS_SURFACE)
in vec4 i_pbr;
flat out vec4 v_pbr;
#endif
flat out vec4 v_emis;
#ifdef HIGHLIGHT
in vec4 i_hl;
flat out vec4 v_hl;
#endif
#if defined(POINTS) && !defined(VSIZE)
in vec4 i_point;
#endif
#elif defined(POINTS) && !defined(VSIZE)
uniform vec4 u_point;
#endif
#ifdef PASS_SURFACE
#ifdef INSTANCE_MATERIAL
#define VERTEX_MATERIAL_ID int(i_pbr.z + 0.5)
#else
uniform vec4 u_pbr;
#define VERTEX_MATERIAL_ID int(u_pbr.z + 0.5)
#endif
#endif
uniform mat4 u_view;
uniform mat4 u_proj;
#if NCLIP > 0
uniform vec4 u_clip[NCLIP];
out float gl_ClipDistance[NCLIP];
#endif
out vec3 v_pos;
out vec3 v_normal;
out vec4 v_color;
#ifdef POINTS
uniform vec2 u_viewport;         // half the viewport's size in pixels
uniform vec2 u_viewport_origin;  // its lower-left corner in window pixels
float point_size;              // the diameter in pixels
flat out vec3 v_sprite;          // the point's centre in window pixels and its radius
#endif
flat out float v_mirror;  // -1 under a mirroring model matrix (its triangles' winding is reversed), else 1
PASS_VERTEX_CODE
void main() {
    vec4 world = I_MODEL * vec4(in_position, 1.0);
#ifdef POINTS
    vec3 normal = vec3(0.0, 0.0, 1.0);
    v_mirror = 1.0;
#else
    mat3 m = mat3(i_model);
    mat3 cof = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    vec3 normal = cof * in_normal;
    v_mirror = dot(m[0], cof[0]) < 0.0 ? -1.0 : 1.0;  // the sign of det(m)
    if (v_mirror < 0.0) normal = -normal;
    float nn = dot(normal, normal);
    normal = nn > 0.0 ? normal * inversesqrt(nn) : vec3(0.0, 0.0, 1.0);
#ifdef NORMAL_MAP
    // the tangent follows the surface (model matrix); a mirroring matrix flips the bitangent
    v_tangent = vec4(mat3(u_view) * (m * in_tangent.xyz), dot(m[0], cof[0]) < 0.0 ? -in_tangent.w : in_tangent.w);
#endif
#endif
    PASS_VERTEX_CALLS
    vec4 eye = u_view * world;
#ifdef POINTS
    v_normal = normal;
#ifdef VSIZE
    point_size = in_size;
#elif defined(INSTANCE_MATERIAL)
    point_size = i_point.x;
#else
    point_size = u_point.x;
#endif
    // a square wider than the disc by a pixel on each side: which pixels on the square's border a driver
    // covers does not matter; the fragment shader cuts the disc out
    gl_PointSize = point_size + POINT_MARGIN;
#else
    v_normal = mat3(u_view) * normal;
#endif
    v_pos = eye.xyz;
#if defined(VCOLOR) && MODEL == 1
    v_color = in_color * i_color;  // glTF: vertex colours multiply the base colour
#elif defined(VCOLOR)
    v_color = vec4(in_color.rgb, in_color.a * i_color.a);  // OpenGL's colour material: they replace it
#else
    v_color = i_color;
#endif
#ifdef UVS
    v_uv0 = in_texcoord;
#ifdef UV1
    v_uv1 = in_texcoord1;
#endif
#endif
#ifdef INSTANCE_MATERIAL
    v_emis = i_emis;
#ifdef PHONG_FIELDS
    v_spec = i_spec; v_amb = i_amb;
#endif
#if MODEL == 1 || defined(PASS_SURFACE)
    v_pbr = i_pbr;
#endif
#ifdef HIGHLIGHT
    v_hl = i_hl;
#endif
#endif
#if NCLIP > 0
    for (int k = 0; k < NCLIP; ++k) gl_ClipDistance[k] = dot(u_clip[k], world);
#endif
    gl_Position = u_proj * eye;
#ifdef POINTS
    // the point's centre in window pixels: the fragment shader measures each pixel centre's distance to it
    v_sprite = vec3((gl_Position.xy / gl_Position.w + 1.0) * u_viewport + u_viewport_origin, 0.5 * point_size);
#endif
}
"""

FRAGMENT = """
in vec3 v_pos;
in vec3 v_normal;
in vec4 v_color;
#ifdef POINTS
flat in vec3 v_sprite;
#endif
flat in float v_mirror;
#ifdef UVS
in vec2 v_uv0;
#ifdef UV1
in vec2 v_uv1;
#define UV_SET1 v_uv1
#else
#define UV_SET1 v_uv0
#endif
// a texture slot's coordinates: its UV set, then its transform (KHR_texture_transform)
#define SLOT_UV(set, m) ((m) * vec3((set) == 1 ? UV_SET1 : v_uv0, 1.0)).xy
#endif
#ifdef NORMAL_MAP
in vec4 v_tangent;
uniform sampler2D u_normal_texture;
uniform mat3 u_uvm_normal;
uniform float u_normal_scale;
#endif
#ifdef MR_TEXTURE
uniform sampler2D u_mr_texture;
uniform mat3 u_uvm_mr;
#endif
#ifdef OCCLUSION_TEXTURE
uniform sampler2D u_occlusion_texture;
uniform mat3 u_uvm_occlusion;
uniform float u_occlusion_strength;
#endif
#ifdef EMISSIVE_TEXTURE
uniform sampler2D u_emissive_texture;
uniform mat3 u_uvm_emissive;
#endif
#ifdef ALPHA_MASK
uniform float u_alpha_cutoff;
#endif
#ifdef LAYERS
LAYER_UNIFORMS
#endif
#ifdef INSTANCE_MATERIAL
flat in vec4 v_emis;
#define M_EMIS v_emis
#ifdef PHONG_FIELDS
flat in vec4 v_spec;
flat in vec4 v_amb;
#define M_SPEC v_spec
#define M_AMB v_amb
#endif
#if MODEL == 1 || defined(PASS_SURFACE)
flat in vec4 v_pbr;
#define M_PBR v_pbr
#endif
#ifdef HIGHLIGHT
flat in vec4 v_hl;
#define M_HL v_hl
#endif
#else
uniform vec4 u_spec;
uniform vec4 u_emis;
uniform vec4 u_amb;
uniform vec4 u_pbr;
uniform vec4 u_hl;
#define M_SPEC u_spec
#define M_EMIS u_emis
#define M_AMB u_amb
#define M_PBR u_pbr
#define M_HL u_hl
#endif
#ifndef NLIGHTS
#define NLIGHTS u_nlights
#endif
uniform int u_nlights;
uniform vec4 u_lpos[MAX_LIGHTS];    // view space; w = 0: direction towards the light, 1: position
uniform vec3 u_ldiff[MAX_LIGHTS];
uniform vec3 u_lspec[MAX_LIGHTS];
uniform vec3 u_latt[MAX_LIGHTS];    // constant, linear, quadratic
uniform vec4 u_lspot[MAX_LIGHTS];   // spot axis (view space), cos(cutoff); w < -1.5: no spot
uniform float u_lexp[MAX_LIGHTS];
uniform vec3 u_ambient;
uniform mat4 u_eye_to_world;        // the pass camera's eye space to world space (shadows, pass snippets)
#ifdef TEXTURE
uniform sampler2D u_texture;
uniform mat3 u_uvm_base;
#endif
#ifdef FLAT_COLOR
uniform vec4 u_flat_color;          // linear
#endif
const float PI = 3.14159265;
#ifdef TRIM
in vec2 v_param;                    // the NURBS surface's (u, v) in the unit square
uniform vec4 u_trim[TRIM];          // its trimming loops' edges (x0, y0, x1, y1)
uniform float u_trim_outer;         // 1: the square's boundary is the outer loop (every loop is a hole)
bool trim_kept(vec2 p) {            // the winding rule of omnirender.geometry.nurbs.trim_winding
    float w = u_trim_outer;
    for (int k = 0; k < TRIM; ++k) {
        vec4 e = u_trim[k];
        float c = (e.z - e.x) * (p.y - e.y) - (p.x - e.x) * (e.w - e.y);
        if (e.y <= p.y && e.w > p.y && c > 0.0) w += 1.0;
        else if (e.y > p.y && e.w <= p.y && c < 0.0) w -= 1.0;
    }
    return w > 0.0;
}
#endif
#ifdef PASS_SURFACE
SURFACE_STRUCT
PASS_SURFACE_CODE
#else
out vec4 f_color;
#endif
STATE_CODE
PASS_FRAGMENT_CODE

float dir_light(int i, out vec3 L) {
    L = u_lpos[i].xyz;
    return 1.0;
}
float point_light(int i, vec3 P, out vec3 L) {
    vec3 d = u_lpos[i].xyz - P;
    float dist = length(d);
    L = dist > 1e-20 ? d / dist : vec3(0.0, 0.0, 1.0);
    return 1.0 / max(u_latt[i].x + u_latt[i].y * dist + u_latt[i].z * dist * dist, 1e-20);
}
float spot_light(int i, vec3 P, out vec3 L) {
    float att = point_light(i, P, L);
    float c = dot(-L, u_lspot[i].xyz);
    return c >= u_lspot[i].w ? att * pow(max(c, 0.0), u_lexp[i]) : 0.0;
}
float any_light(int i, vec3 P, out vec3 L) {
    if (u_lpos[i].w == 0.0) return dir_light(i, L);
    if (u_lspot[i].w > -1.5) return spot_light(i, P, L);
    return point_light(i, P, L);
}
SHADOW_CODE
vec3 half_vector(vec3 L, vec3 V, vec3 N) {
    vec3 h = L + V;
    float hh = dot(h, h);
    return hh > 1e-12 ? h * inversesqrt(hh) : N;  // light exactly opposite the eye: no highlight direction
}
#ifdef PHONG_FIELDS
vec3 phong_light(int i, float att, vec3 L, vec3 N, vec3 V, vec3 kd) {
    float NdL = dot(N, L);
    if (NdL <= 0.0 || att <= 0.0) return vec3(0.0);
    // Phong's lobe (the reflected light against the eye), as POV-Ray's phong: shininess is a Phong exponent,
    // and shininess 0 acts as 1 (POV-Ray's phong_size floor) instead of flooding the surface with specular
    float s = pow(clamp(dot(reflect(-L, N), V), 0.0, 1.0), max(M_SPEC.w, 1.0));
    return att * (kd * NdL * u_ldiff[i] + M_SPEC.rgb * s * u_lspec[i]);
}
#elif MODEL == 1
vec3 pbr_light(int i, float att, vec3 L, vec3 N, vec3 V, vec3 albedo, vec3 F0, float metallic, float a2, float k) {
    float NdL = dot(N, L);
    if (NdL <= 0.0 || att <= 0.0) return vec3(0.0);
    float NdV = max(dot(N, V), 1e-4);
    vec3 H = half_vector(L, V, N);
    float NdH = clamp(dot(N, H), 0.0, 1.0);
    float dd = NdH * NdH * (a2 - 1.0) + 1.0;
    float D = a2 / (PI * max(dd * dd, 1e-12));
    float G = (NdV / (NdV * (1.0 - k) + k)) * (NdL / (NdL * (1.0 - k) + k));
    float fresnel = pow(clamp(1.0 - dot(H, V), 0.0, 1.0), 5.0);  // rounding can push dot(H, V) above 1
    vec3 F = F0 + (1.0 - F0) * fresnel;
    vec3 spec = D * G * F / (4.0 * NdV * NdL);
    vec3 kd = (1.0 - F) * (1.0 - metallic);
    return (kd * albedo + PI * spec) * u_ldiff[i] * NdL * att;
}
#endif

void main() {
    vec3 P = v_pos;
    vec4 base = v_color;
    vec4 surf = vec4(1.0);
#ifdef TEXTURE
    surf = texture(u_texture, SLOT_UV(UVSET_BASE, u_uvm_base));  // sRGB: filtered and returned linear by the GPU
#endif
#ifdef LAYERS
    LAYER_CODE
#endif
    base *= surf;  // the texture (and its layers) multiply the base colour and the alpha
    vec3 texel = surf.rgb;
#ifdef PASS_ALPHA_CUTOFF
    if (base.a < float(PASS_ALPHA_CUTOFF)) discard;
#endif
#ifdef ALPHA_MASK
    if (base.a < u_alpha_cutoff) discard;
    base.a = 1.0;
#elif defined(ALPHA_OPAQUE)
    base.a = 1.0;
#endif
    vec3 emission = M_EMIS.rgb;
#ifdef EMISSIVE_TEXTURE
    emission *= texture(u_emissive_texture, SLOT_UV(UVSET_EMISSIVE, u_uvm_emissive)).rgb;
#endif
    float occlusion = 1.0;
#ifdef OCCLUSION_TEXTURE
    vec2 occlusion_uv = SLOT_UV(UVSET_OCCLUSION, u_uvm_occlusion);
    occlusion = 1.0 + u_occlusion_strength * (texture(u_occlusion_texture, occlusion_uv).r - 1.0);
#endif
    vec3 N;
#ifdef POINTS
    // the pixel centre on the point's unit disc, measured from the projected centre: neither which pixels the
    // driver's square covers nor its gl_PointCoord (llvmpipe's is a pixel off with multisampling) matter
    vec2 c = (gl_FragCoord.xy - v_sprite.xy) / max(v_sprite.z, 1e-6);
    float r2 = dot(c, c);
    if (r2 > 1.0) discard;
    N = vec3(c.x, c.y, sqrt(1.0 - r2));
#elif defined(FLAT)
    N = cross(dFdx(P), dFdy(P));
    N = dot(N, N) > 0.0 ? normalize(N) : vec3(0.0, 0.0, 1.0);
#else
    N = dot(v_normal, v_normal) > 0.0 ? normalize(v_normal) : vec3(0.0, 0.0, 1.0);
    // the side facing the eye: a mirroring model matrix reverses the winding, so its front faces rasterise as back
    if (gl_FrontFacing == (v_mirror < 0.0)) N = -N;
#ifdef NORMAL_MAP
    {   // tangent-space normal map (OpenGL convention: x along u, y along v, z out of the surface)
        vec3 t = v_tangent.xyz - N * dot(N, v_tangent.xyz);
        float tt = dot(t, t);
        if (tt > 1e-20) {
            t *= inversesqrt(tt);
            vec3 b = cross(N, t) * (v_tangent.w < 0.0 ? -1.0 : 1.0);
            vec3 tn = texture(u_normal_texture, SLOT_UV(UVSET_NORMAL, u_uvm_normal)).xyz * 2.0 - 1.0;
            tn.xy *= u_normal_scale;
            vec3 n = t * tn.x + b * tn.y + N * tn.z;
            N = dot(n, n) > 0.0 ? normalize(n) : N;
        }
    }
#endif
#endif
    STATE_MAIN
#ifdef TRIM
    if (!trim_kept(v_param)) discard;
#endif
#ifdef ORTHO
    vec3 V = vec3(0.0, 0.0, 1.0);
#else
    float pp = dot(P, P);
    vec3 V = pp > 0.0 ? -P * inversesqrt(pp) : vec3(0.0, 0.0, 1.0);
#endif
    float metallic = 0.0;
    float rough = 1.0;
#if MODEL == 1
    metallic = clamp(M_PBR.y, 0.0, 1.0);
    rough = clamp(M_PBR.x, 0.04, 1.0);
#ifdef MR_TEXTURE
    vec4 mr = texture(u_mr_texture, SLOT_UV(UVSET_MR, u_uvm_mr));  // glTF: roughness in green, metallic in blue
    metallic = clamp(M_PBR.y * mr.b, 0.0, 1.0);
    rough = clamp(M_PBR.x * mr.g, 0.04, 1.0);
#endif
#endif
#ifdef PASS_SURFACE
    {   // the pass takes over: the resolved surface goes to its snippet (a G-buffer write), not to the lights
        Surface s;
        s.P = P; s.N = N; s.V = V; s.world = (u_eye_to_world * vec4(P, 1.0)).xyz; s.eye = u_eye_to_world[3].xyz;
        s.base = base; s.texel = texel; s.emission = emission; s.occlusion = occlusion;
        s.ambient = u_ambient;
#ifdef PHONG_FIELDS
        s.ambient_reflectance = M_AMB.w > 0.5 ? base.rgb : M_AMB.rgb * texel;
#else
        s.ambient_reflectance = base.rgb;
#endif
        s.metallic = metallic; s.roughness = rough;
        s.material_id = int(M_PBR.z + 0.5);
#ifdef UVS
        s.uv = v_uv0;
#else
        s.uv = vec2(0.0);
#endif
        s.depth = -1.0;
        pass_surface(s);
    }
#elif defined(DEPTH_ONLY)
    f_color = vec4(0.0);
#else
    vec3 color;
#if defined(FLAT_COLOR)
    color = u_flat_color.rgb;
    base.a = u_flat_color.a;
#elif defined(UNLIT) || MODEL == 2
    color = base.rgb;
#elif MODEL == 1
    float a2 = rough * rough * rough * rough;
    vec3 F0 = mix(vec3(0.04), base.rgb, metallic);
    float k = (rough + 1.0) * (rough + 1.0) / 8.0;
    vec3 albedo = base.rgb;
    color = AMBIENT_ON * (emission + occlusion * u_ambient * (base.rgb * (1.0 - metallic) + F0 * metallic));
#ifdef PBR_LIGHTS
    PBR_LIGHTS
#else
    for (int i = 0; i < NLIGHTS; ++i) {
        vec3 L;
        float att = any_light(i, P, L);
        SHADOW_ATT(i)
        color += pbr_light(i, att, L, N, V, albedo, F0, metallic, a2, k);
    }
#endif
#else
    vec3 kd = base.rgb;
    // the texture modulates the ambient term too (GL_MODULATE, POV-Ray's pigment, Mitsuba's albedo)
    color = AMBIENT_ON * (emission + occlusion * (M_AMB.w > 0.5 ? base.rgb : M_AMB.rgb * texel) * u_ambient);
#ifdef PHONG_LIGHTS
    PHONG_LIGHTS
#else
    for (int i = 0; i < NLIGHTS; ++i) {
        vec3 L;
        float att = any_light(i, P, L);
        SHADOW_ATT(i)
        color += phong_light(i, att, L, N, V, kd);
    }
#endif
#endif
#if defined(HIGHLIGHT) && !defined(FLAT_COLOR)
    if (M_HL.w > 0.0) {
        float rim = 1.0 - abs(dot(N, V));
        color = mix(color, M_HL.rgb, 0.35) + M_HL.rgb * rim * rim;
    }
#endif
#if defined(FOG) && !defined(FLAT_COLOR)
    color = apply_fog(color, length(P));
#endif
    vec4 result = vec4(color, base.a);
    PASS_FRAGMENT_CALLS
    f_color = vec4(encode_output(result.rgb), result.a);
#endif
}
"""

LINE_VERTEX = """
in vec3 in_position;
#ifdef VCOLOR
in vec4 in_color;
#endif
in mat4 i_model;
in vec4 i_color;
#ifdef INSTANCE_OFFSET
in vec3 i_offset;  // an instance set's world translations in a buffer of their own (replace i_model's)
#define I_MODEL mat4(i_model[0], i_model[1], i_model[2], vec4(i_offset, 1.0))
#else
#define I_MODEL i_model
#endif
#ifdef HIGHLIGHT
in vec4 i_hl;
#endif
uniform mat4 u_view;
uniform mat4 u_proj;
out vec3 g_pos;
out vec4 g_color;
out vec4 g_world;
void main() {
    vec4 world = I_MODEL * vec4(in_position, 1.0);
    vec4 eye = u_view * world;
    g_pos = eye.xyz;
    g_world = world;
#ifdef VCOLOR
    g_color = vec4(in_color.rgb, in_color.a * i_color.a);
#else
    g_color = i_color;
#endif
#ifdef HIGHLIGHT
    if (i_hl.w > 0.0) g_color.rgb = mix(g_color.rgb, i_hl.rgb, 0.6);
#endif
    gl_Position = u_proj * eye;
}
"""

LINE_GEOMETRY = """
layout(lines) in;
layout(triangle_strip, max_vertices = 4) out;
in vec3 g_pos[];
in vec4 g_color[];
in vec4 g_world[];
#if NCLIP > 0
uniform vec4 u_clip[NCLIP];
out float gl_ClipDistance[NCLIP];
#endif
uniform vec2 u_viewport;
uniform float u_line_width;
out vec3 v_pos;
out vec4 v_color;
void emit(vec4 p, vec3 pos, vec4 color, vec4 world, vec2 offset) {
    gl_Position = vec4(p.xy + offset * p.w, p.zw);
    v_pos = pos;
    v_color = color;
#if NCLIP > 0
    for (int k = 0; k < NCLIP; ++k) gl_ClipDistance[k] = dot(u_clip[k], world);
#endif
    EmitVertex();
}
void main() {
    vec4 a = gl_in[0].gl_Position;
    vec4 b = gl_in[1].gl_Position;
    vec3 pa = g_pos[0], pb = g_pos[1];
    vec4 ca = g_color[0], cb = g_color[1];
    vec4 wa = g_world[0], wb = g_world[1];
    // clip the segment against the near plane (z >= -w) before projecting: an endpoint behind the camera
    // would otherwise project to a mirrored position
    float da = a.z + a.w;
    float db = b.z + b.w;
    if (da < 0.0 && db < 0.0) return;
    if (da < 0.0) {
        float t = da / (da - db);
        a = mix(a, b, t); pa = mix(pa, pb, t); ca = mix(ca, cb, t); wa = mix(wa, wb, t);
    } else if (db < 0.0) {
        float t = db / (db - da);
        b = mix(b, a, t); pb = mix(pb, pa, t); cb = mix(cb, ca, t); wb = mix(wb, wa, t);
    }
    if (a.w <= 0.0 || b.w <= 0.0) return;
    vec2 sa = a.xy / a.w * u_viewport;
    vec2 sb = b.xy / b.w * u_viewport;
    vec2 d = sb - sa;
    float len = length(d);
    vec2 dir = len > 1e-6 ? d / len : vec2(1.0, 0.0);
    vec2 n = vec2(-dir.y, dir.x) * (0.5 * u_line_width) / u_viewport;
    emit(a, pa, ca, wa, n);
    emit(a, pa, ca, wa, -n);
    emit(b, pb, cb, wb, n);
    emit(b, pb, cb, wb, -n);
    EndPrimitive();
}
"""

LINE_FRAGMENT = """
in vec3 v_pos;
in vec4 v_color;
#ifdef FLAT_COLOR
uniform vec4 u_flat_color;
#endif
out vec4 f_color;
PASS_FRAGMENT_CODE
void main() {
#ifdef DEPTH_ONLY
    f_color = vec4(0.0);
#else
#ifdef FLAT_COLOR
    vec3 color = u_flat_color.rgb;
    float alpha = u_flat_color.a;
#else
    vec3 color = v_color.rgb;
    float alpha = v_color.a;
#endif
#if defined(FOG) && !defined(FLAT_COLOR)
    color = apply_fog(color, length(v_pos));
#endif
    vec4 result = vec4(color, alpha);
    vec3 P = v_pos;
    vec3 N = vec3(0.0, 0.0, 1.0);
    PASS_FRAGMENT_CALLS
    f_color = vec4(encode_output(result.rgb), result.a);
#endif
}
"""


def instance_fields(kind: str, features: dict[str, Any]) -> tuple[str, ...]:
    """The row fields a program variant reads per instance (the batch buffer's layout)."""
    if "SINGLE" in features:
        return ()
    if kind == "lines":
        return ("model", "color", "highlight") if "HIGHLIGHT" in features else ("model", "color")
    if "INSTANCE_MATERIAL" not in features:
        return ("model", "color")
    fields = ["model", "color", "emission"]
    model = features.get("MODEL", PHONG)
    if model not in (PBR, UNLIT):
        fields += ["specular", "ambient"]
    if model == PBR or "PASS_SURFACE" in features:
        fields.append("pbr")  # PBR's roughness and metallic; the material id of a surface pass
    if "HIGHLIGHT" in features:
        fields.append("highlight")
    if kind == "points" and "VSIZE" not in features:
        fields.append("point")
    return tuple(fields)


def _light_code(types: str) -> list[str]:
    """Unrolled light loops for a known list of light types (d: directional, p: point, s: spot, a: area)."""
    calls = {"d": "dir_light({i}, L)", "p": "point_light({i}, P, L)", "s": "spot_light({i}, P, L)"}
    phong, pbr = ["{ vec3 L; float att;"], ["{ vec3 L; float att;"]
    slot = 0
    for i, t in enumerate(types):
        if t == "a":  # an area light (area_glsl.py): its own shading and soft shadows, slot-th of its kind
            att = f"att = 1.0; AREA_SHADOW_ATT({i}, {slot})"
            phong.append(f"{att} color += att * area_phong({i}, {slot}, P, N, V, kd);")
            pbr.append(f"{att} color += att * area_pbr({i}, {slot}, P, N, V, albedo, F0, metallic, rough);")
            slot += 1
            continue
        att = "att = " + calls[t].format(i=i) + f"; SHADOW_ATT({i})"
        phong.append(f"{att} color += phong_light({i}, att, L, N, V, kd);")
        pbr.append(f"{att} color += pbr_light({i}, att, L, N, V, albedo, F0, metallic, a2, k);")
    phong.append("}")
    pbr.append("}")
    return [
        f"#define NLIGHTS {max(len(types), 1)}",
        "#define PHONG_LIGHTS " + " ".join(phong),
        "#define PBR_LIGHTS " + " ".join(pbr),
    ] + (["#define AREA_LIGHTS"] if slot else [])


_SNIPPETS = ("PASS_VERTEX", "PASS_FRAGMENT", "PASS_SURFACE")

#: The resolved surface a ``Shader(surface=...)`` snippet receives (eye space; colours linear).
SURFACE_STRUCT = """struct Surface {
    vec3 P;                    // eye-space position
    vec3 N;                    // eye-space unit normal (facing the eye on two-sided surfaces; normal map applied)
    vec3 V;                    // unit vector towards the eye
    vec3 world;                // world-space position
    vec3 eye;                  // world-space position of the eye (of the pass's camera)
    vec4 base;                 // base colour and alpha (texture and vertex colours applied)
    vec3 texel;                // the texture's colour (1 without a texture)
    vec3 emission;
    float occlusion;           // PBR occlusion texture (1 without)
    vec3 ambient;              // the ambient light: global ambient plus the lights' ambient terms
    vec3 ambient_reflectance;  // Phong's ambient colour (or the base colour it follows)
    float metallic;
    float roughness;
    int material_id;           // the row of the deferred material table
    vec2 uv;
    float depth;               // window depth to write instead of the fragment's (-1: keep)
};"""


#: Pixels a point's square is drawn wider than its disc (one on each side; see VERTEX's gl_PointSize).
POINT_MARGIN = 2.0


def _header(defines: dict[str, Any]) -> str:
    lines = ["#version 330"]
    types = defines.pop("LIGHTS", None)
    if types is not None:
        lines += _light_code(types)
    for name in _SNIPPETS:
        if defines.pop(name, None) is not None and name == "PASS_SURFACE":
            lines.append("#define PASS_SURFACE")
    for name, value in sorted(defines.items()):
        lines.append(f"#define {name} {value}" if value is not True else f"#define {name}")
    lines.append(f"#define MAX_LIGHTS {MAX_LIGHTS}")
    lines.append(f"#define POINT_MARGIN {POINT_MARGIN:.1f}")
    if "NCLIP" not in defines:
        lines.append("#define NCLIP 0")
    if "MODEL" not in defines:
        lines.append(f"#define MODEL {PHONG}")
    if defines.get("MODEL", PHONG) not in (PBR, UNLIT):
        # Phong's material fields: the Phong model's, and a custom shading model's (the forward pipeline shades
        # custom models with the Phong model of their appearance; the deferred pipeline runs their stages)
        lines.append("#define PHONG_FIELDS")
    return "\n".join(lines) + "\n"


#: The blend modes of texture layers, as the LAYER_BLEND<i> defines number them.
LAYER_BLENDS = {"over": 0, "multiply": 1, "add": 2}


def _layer_glsl(count: int) -> tuple[str, str]:
    """Uniform declarations and unrolled blending code of ``count`` texture layers (samplers need constant indices)."""
    uniforms, code = [], []
    for i in range(count):
        uniforms.append(f"uniform sampler2D u_layer{i};\nuniform mat3 u_uvm_layer{i};")
        uniforms.append(f"uniform float u_layer_opacity{i};")
        code.append(
            f"{{ vec4 l = texture(u_layer{i}, SLOT_UV(UVSET_LAYER{i}, u_uvm_layer{i}));\n"
            f"#if LAYER_BLEND{i} == 0\n surf.rgb = mix(surf.rgb, l.rgb, l.a * u_layer_opacity{i});\n"
            f"#elif LAYER_BLEND{i} == 1\n surf.rgb *= mix(vec3(1.0), l.rgb, u_layer_opacity{i});\n"
            f"#else\n surf.rgb += l.rgb * l.a * u_layer_opacity{i};\n#endif\n}}"
        )
    return "\n".join(uniforms), "\n".join(code)


def _snippets(source: str, features: dict[str, Any], code: tuple[Any, ...]) -> str:
    """Insert the pass snippets (renamed per occurrence) and the state kinds' GLSL at their hooks."""
    vertex = features.get("PASS_VERTEX", ())
    fragment = features.get("PASS_FRAGMENT", ())
    v_code = "\n".join(s.replace("pass_vertex", f"pass_vertex_{i}") for i, s in enumerate(vertex))
    v_calls = " ".join(f"pass_vertex_{i}(world.xyz, normal);" for i in range(len(vertex)))
    f_code = "\n".join(s.replace("pass_fragment", f"pass_fragment_{i}") for i, s in enumerate(fragment))
    f_calls = " ".join(f"pass_fragment_{i}(result, P, N);" for i in range(len(fragment)))
    state_code = "\n".join(kind.fragment_code for kind in code)
    if "SHADOW_CODE" in source:
        source = source.replace("SHADOW_CODE", shadow_code(features) + area_code(features))
    state_main = "\n    ".join(kind.fragment_main for kind in code if kind.fragment_main)
    layer_uniforms, layer_code = _layer_glsl(int(features.get("LAYERS", 0)))
    return (
        source.replace("LAYER_UNIFORMS", layer_uniforms)
        .replace("LAYER_CODE", layer_code)
        .replace("PASS_VERTEX_CODE", v_code)
        .replace("PASS_VERTEX_CALLS", v_calls)
        .replace("PASS_FRAGMENT_CODE", f_code)
        .replace("PASS_FRAGMENT_CALLS", f_calls)
        .replace("SURFACE_STRUCT", SURFACE_STRUCT)
        .replace("PASS_SURFACE_CODE", features.get("PASS_SURFACE", ""))
        .replace("STATE_CODE", state_code)
        .replace("STATE_MAIN", state_main)
    )


#: builds (vertex, tessellation control, tessellation evaluation) bodies for GPU-tessellated mesh programs;
#: set by the painter that draws patches (``gl/painters/nurbs.py``), which the engine never imports
_tessellation: Any = None


def register_tessellation(sources: Any) -> None:
    """Set the builder of the tessellation stages of ``NURBS`` mesh programs: ``sources(vertex, fields)``
    returns the (vertex, tessellation control, tessellation evaluation) bodies."""
    global _tessellation
    _tessellation = sources


class ProgramCache:
    """Compiled programs by (kind, features, state code); compiled on first use, kept for the engine's life."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self._programs: dict[tuple, Any] = {}
        self._custom: dict[str, tuple[str, str | None, str]] = {}
        #: the FramePlan (:mod:`.plan`) that wrote the programs' uniforms last, or None when other code may have
        #: written them since (cleared by every frame that is not a replay and by every :meth:`get`)
        self.owner: Any = None

    def register(self, kind: str, vertex: str, fragment: str, geometry: str | None = None) -> None:
        """Add a program kind (text, volume and full-screen passes use it)."""
        self._custom[kind] = (vertex, geometry, fragment)

    def registered(self, kind: str) -> bool:
        """Whether a custom program kind was registered."""
        return kind in self._custom

    def __len__(self) -> int:
        return len(self._programs)

    def get(self, kind: str, features: tuple[tuple[str, Any], ...] = (), code: tuple[Any, ...] = ()) -> Any:
        self.owner = None  # the caller may write the program's uniforms
        key = (kind, features, code)
        prog = self._programs.get(key)
        if prog is not None:
            return prog
        defines = dict(features)
        if kind == "points":
            defines["POINTS"] = True
        head = _header(dict(defines))
        stages: dict[str, str] = {}
        if kind == "mesh" and "NURBS" in defines:  # GPU-tessellated NURBS patches (gl/painters/nurbs.py)
            head = head.replace("#version 330", "#version 400", 1)
            head += f"#define NCTRL {(defines['NURBS_P'] + 1) * (defines['NURBS_Q'] + 1)}\n"
            vs, tcs, tes = _tessellation(VERTEX, instance_fields(kind, defines))
            stages = {"tess_control_shader": head + tcs, "tess_evaluation_shader": head + _snippets(tes, defines, code)}
            gs, fs = None, FRAGMENT
        elif kind == "mesh" and "SHADOW_VOLUME" in defines:
            vs, gs, fs = VERTEX, VOLUME_GEOMETRY, VOLUME_FRAGMENT
        elif kind in ("mesh", "points"):
            vs, gs, fs = VERTEX, None, FRAGMENT
        elif kind == "lines":
            vs, gs, fs = LINE_VERTEX, LINE_GEOMETRY, LINE_FRAGMENT
        else:
            vs, gs, fs = self._custom[kind]
        vs, fs = _snippets(vs, defines, code), _snippets(fs, defines, code)
        try:
            prog = self.ctx.program(
                vertex_shader=head + vs,
                geometry_shader=None if gs is None else head + gs,
                fragment_shader=head + _COMMON + fs,
                **stages,
            )
        except Exception as exc:
            snippets = any(name in defines for name in _SNIPPETS) or kind not in ("mesh", "points", "lines")
            hint = "; check the GLSL snippet of the pass or effect" if snippets else ""
            raise ValueError(f"GLEngine: a {kind} shader failed to compile{hint}: {exc}") from None
        self._programs[key] = prog
        return prog

    def release(self) -> None:
        for prog in self._programs.values():
            prog.release()
        self._programs.clear()
