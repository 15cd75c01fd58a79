"""GLSL of the post-processing effects: full-screen snippets defining ``vec4 effect(vec2 uv)``.

Every effect's snippet starts with :data:`PRELUDE`: the image the effect reads
(``u_input``, linear colour, HDR before the tone mapper), the scene's window
depth (``u_depth``), the frame's projection and its inverse, and helpers to
rebuild eye-space positions and normals from depth (one rule for the forward
and the deferred pipeline).  ``u_resolution`` (the target's size in pixels),
``to_srgb`` and ``to_linear`` come from the full-screen pass itself
(:mod:`..imagespace`).  User effects (``om.gl.CustomEffect``) get the same
prelude.
"""

from __future__ import annotations

import numpy as np

from ..engine.shaders import FOG_GLSL

__all__ = [
    "PRELUDE",
    "COPY",
    "OUTPUT",
    "FXAA",
    "TONE_OPERATORS",
    "tone_map",
    "LOG_LUMINANCE",
    "BLOOM_BRIGHT",
    "BLOOM_DOWN",
    "BLOOM_UP",
    "BLOOM_COMBINE",
    "ssao",
    "BLUR",
    "SSAO_APPLY",
    "FOG",
    "VIGNETTE",
    "SHAFT_MASK",
    "SHAFT_BLUR",
    "SHAFT_ADD",
    "CIRCLE_OF_CONFUSION",
    "DOF_COMPOSITE",
    "depth_of_field",
    "COLOR_GRADING",
]

PRELUDE = """uniform sampler2D u_input;   // the image so far: linear colour (HDR before the tone mapper)
uniform sampler2D u_depth;   // the scene's window depth in [0, 1] (1: background)
uniform mat4 u_proj;         // the frame's projection
uniform mat4 u_inv_proj;     // and its inverse
float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }
float depth_at(vec2 uv) { return texture(u_depth, uv).r; }
bool is_background(vec2 uv) { return depth_at(uv) >= 1.0; }
vec3 view_position_at(vec2 uv, float depth) {
    vec4 p = u_inv_proj * vec4(uv * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    return p.xyz / p.w;
}
vec3 view_position(vec2 uv) { return view_position_at(uv, depth_at(uv)); }
// the eye-space z alone (cheap: a projection's depth and w rows never involve x and y)
float view_z(vec2 uv) {
    float ndc = depth_at(uv) * 2.0 - 1.0;
    return (u_inv_proj[2][2] * ndc + u_inv_proj[3][2]) / (u_inv_proj[2][3] * ndc + u_inv_proj[3][3]);
}
// the unit direction from the eye's view of eye-space point p towards it: the ray through p of a
// perspective projection, the view axis everywhere for an orthographic one (its w row is (0, 0, 0, 1))
vec3 view_ray(vec3 p) { return u_proj[3][3] > 0.5 ? vec3(0.0, 0.0, -1.0) : normalize(p); }
vec2 project(vec3 p) {
    vec4 c = u_proj * vec4(p, 1.0);
    return c.xy / c.w * 0.5 + 0.5;
}
// the eye-space normal from the depth of the neighbours: on each axis the side whose depth continues the
// surface best, so silhouettes do not bend normals towards the background
vec3 view_normal(vec2 uv) {
    vec2 px = 1.0 / u_resolution;
    vec3 p = view_position(uv);
    vec3 l = view_position(uv - vec2(px.x, 0.0)), r = view_position(uv + vec2(px.x, 0.0));
    vec3 d = view_position(uv - vec2(0.0, px.y)), u = view_position(uv + vec2(0.0, px.y));
    vec3 dx = abs(r.z - p.z) < abs(p.z - l.z) ? r - p : p - l;
    vec3 dy = abs(u.z - p.z) < abs(p.z - d.z) ? u - p : p - d;
    vec3 n = normalize(cross(dx, dy));
    return dot(n, view_ray(p)) > 0.0 ? -n : n;  // facing the eye
}
"""

COPY = """uniform sampler2D u_input;
vec4 effect(vec2 uv) { return texture(u_input, uv); }
"""

#: The end of every chain: linear colour to the frame (sRGB encoded into an 8-bit frame), with the scene's depth.
#: The multisampled scene resolved in the shader: the mean of the samples' linear colours, and the depth of
#: sample 0 (the surface the samples' mean mostly shows is not defined either way; sample 0 is what Mesa's
#: blit keeps).  glBlitFramebuffer would resolve float samples "in an implementation-dependent manner"
#: (OpenGL 4.6, section 18.3.2): NVIDIA's driver kept the edges aliased.
RESOLVE_SAMPLES = """uniform sampler2DMS u_samples;
uniform sampler2DMS u_depths;
uniform int u_count;
vec4 effect(vec2 uv) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 sum = vec4(0.0);
    for (int i = 0; i < u_count; ++i) sum += texelFetch(u_samples, p, i);
    return sum / float(u_count);
}
float effect_depth(vec2 uv) { return texelFetch(u_depths, ivec2(gl_FragCoord.xy), 0).r; }
"""
OUTPUT = """uniform sampler2D u_input;
uniform sampler2D u_depth;
uniform float u_linear;
vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);
    return vec4(u_linear > 0.5 ? max(c.rgb, vec3(0.0)) : to_srgb(c.rgb), clamp(c.a, 0.0, 1.0));
}
float effect_depth(vec2 uv) { return texture(u_depth, uv).r; }
"""

#: Fast approximate anti-aliasing (Lottes): the luma contrast around a pixel finds edges, their direction
#: from the diagonal neighbours, and the pixel is blended along the edge (two taps, or four where that stays
#: within the neighbourhood's luma range).  Luma is perceptual (square root of linear luminance).
FXAA = """uniform float u_threshold;     // relative contrast below which nothing is done
uniform float u_threshold_min;  // absolute contrast below which nothing is done (dark areas)
uniform float u_span;           // longest blend along an edge, in pixels
vec3 tap(vec2 uv) { return texture(u_input, uv).rgb; }
float luma(vec3 c) { return sqrt(max(luminance(c), 0.0)); }
vec4 effect(vec2 uv) {
    vec2 px = 1.0 / u_resolution;
    vec4 centre = texture(u_input, uv);
    float m = luma(centre.rgb);
    float nw = luma(tap(uv + vec2(-px.x, px.y))), ne = luma(tap(uv + px));
    float sw = luma(tap(uv - px)), se = luma(tap(uv + vec2(px.x, -px.y)));
    float lo = min(m, min(min(nw, ne), min(sw, se))), hi = max(m, max(max(nw, ne), max(sw, se)));
    if (hi - lo < max(u_threshold_min, hi * u_threshold)) return centre;
    vec2 dir = vec2(-((nw + ne) - (sw + se)), (nw + sw) - (ne + se));
    float reduce = max((nw + ne + sw + se) * 0.03125, 1.0 / 128.0);
    float scale = 1.0 / (min(abs(dir.x), abs(dir.y)) + reduce);
    dir = clamp(dir * scale, vec2(-u_span), vec2(u_span)) * px;
    vec3 a = 0.5 * (tap(uv + dir * (1.0 / 3.0 - 0.5)) + tap(uv + dir * (2.0 / 3.0 - 0.5)));
    vec3 b = a * 0.5 + 0.25 * (tap(uv - dir * 0.5) + tap(uv + dir * 0.5));
    float lb = luma(b);
    return vec4((lb < lo || lb > hi) ? a : b, centre.a);
}
"""

#: Tone-mapping operators: linear HDR colour (exposed) -> linear colour in [0, 1], monotonic.
TONE_OPERATORS = {
    "reinhard": "vec3 tone(vec3 x) { return x / (1.0 + x); }",
    # Narkowicz's fit of the ACES filmic reference rendering transform
    "aces": "vec3 tone(vec3 x) { return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0); }",
    # Hable's filmic curve (Uncharted 2), with exposure bias 2 and white point u_white
    "uncharted2": """vec3 hable(vec3 x) {
    const float A = 0.15, B = 0.50, C = 0.10, D = 0.20, E = 0.02, F = 0.30;
    return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
}
vec3 tone(vec3 x) { return clamp(hable(2.0 * x) / hable(vec3(u_white)), 0.0, 1.0); }""",
    # Hejl and Burgess-Dawson's filmic fit: its output is display-encoded, so decode it (the chain encodes last)
    "hejl": """vec3 tone(vec3 x) {
    x = max(vec3(0.0), x - 0.004);
    return to_linear(clamp(x * (6.2 * x + 0.5) / (x * (6.2 * x + 1.7) + 0.06), 0.0, 1.0));
}""",
}


def tone_map(operator: str, automatic: bool) -> str:
    """The tone mapper's snippet: exposure (2^stops, times key / average luminance when automatic), operator."""
    auto = "uniform sampler2D u_average;\nuniform float u_key;\n" if automatic else ""
    scale = "u_scale * u_key / max(texture(u_average, vec2(0.5)).r, 1e-4)" if automatic else "u_scale"
    return f"""uniform float u_scale;   // 2^exposure
uniform float u_white;   // the Uncharted 2 curve's white point
{auto}{TONE_OPERATORS[operator]}
vec4 effect(vec2 uv) {{
    vec4 c = texture(u_input, uv);
    return vec4(tone(max(c.rgb, vec3(0.0)) * {scale}), c.a);
}}
"""


#: The average luminance of the image as exp(mean(log(delta + L))) over a grid of samples, into a 1x1 target.
LOG_LUMINANCE = """const int GRID = 32;
vec4 effect(vec2 uv) {
    float sum = 0.0;
    for (int y = 0; y < GRID; ++y)
        for (int x = 0; x < GRID; ++x)
            sum += log(1e-4 + luminance(max(texture(u_input, (vec2(x, y) + 0.5) / float(GRID)).rgb, 0.0)));
    return vec4(vec3(exp(sum / float(GRID * GRID))), 1.0);
}
"""

#: Bloom: the light above a threshold (soft knee), halved in size; then a mip chain down and up again.
BLOOM_BRIGHT = """uniform float u_threshold;
uniform float u_knee;
vec4 effect(vec2 uv) {
    vec2 px = 1.0 / u_resolution * 0.5;   // the source is twice as large: four taps average 4x4 texels
    vec3 c = 0.25 * (texture(u_input, uv + vec2(-px.x, -px.y)).rgb + texture(u_input, uv + vec2(px.x, -px.y)).rgb
                   + texture(u_input, uv + vec2(-px.x, px.y)).rgb + texture(u_input, uv + vec2(px.x, px.y)).rgb);
    c = max(c, vec3(0.0));
    float l = max(c.r, max(c.g, c.b));
    float soft = clamp(l - u_threshold + u_knee, 0.0, 2.0 * u_knee);
    soft = soft * soft / (4.0 * u_knee + 1e-5);
    float over = max(soft, l - u_threshold) / max(l, 1e-5);
    return vec4(c * over, 1.0);
}
"""

BLOOM_DOWN = """uniform sampler2D u_level;
vec4 effect(vec2 uv) {
    vec2 px = 1.0 / u_resolution * 0.5;
    return 0.25 * (texture(u_level, uv + vec2(-px.x, -px.y)) + texture(u_level, uv + vec2(px.x, -px.y))
                 + texture(u_level, uv + vec2(-px.x, px.y)) + texture(u_level, uv + vec2(px.x, px.y)));
}
"""

#: The next smaller level, upsampled with a 3x3 tent, added to this level.
BLOOM_UP = """uniform sampler2D u_level;
uniform sampler2D u_smaller;
vec4 effect(vec2 uv) {
    vec2 px = 1.0 / u_resolution;
    vec4 s = 4.0 * texture(u_smaller, uv);
    s += 2.0 * (texture(u_smaller, uv + vec2(px.x, 0.0)) + texture(u_smaller, uv - vec2(px.x, 0.0))
              + texture(u_smaller, uv + vec2(0.0, px.y)) + texture(u_smaller, uv - vec2(0.0, px.y)));
    s += texture(u_smaller, uv + px) + texture(u_smaller, uv - px)
       + texture(u_smaller, uv + vec2(px.x, -px.y)) + texture(u_smaller, uv + vec2(-px.x, px.y));
    return texture(u_level, uv) + s / 16.0;
}
"""

BLOOM_COMBINE = """uniform sampler2D u_bloom;
uniform float u_intensity;
uniform float u_levels;
vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);
    return vec4(c.rgb + u_intensity * texture(u_bloom, uv).rgb / u_levels, c.a);
}
"""


def _kernel(samples: int) -> np.ndarray:
    """Hemisphere sample offsets (z up, length < 1, denser near the centre), fixed for a sample count."""
    rng = np.random.default_rng(12)
    out = []
    while len(out) < samples:
        v = rng.uniform(-1.0, 1.0, 3)
        v[2] = abs(v[2])
        n = np.linalg.norm(v)
        if 0.1 < n <= 1.0 and v[2] > 0.15 * n:  # inside the hemisphere, not grazing the surface
            v /= n
            scale = len(out) / samples
            out.append(v * (0.1 + 0.9 * scale * scale))
    return np.array(out)


def ssao(samples: int) -> str:
    """Screen-space ambient occlusion with ``samples`` hemisphere samples: 1 unoccluded, 0 fully occluded.

    Each sample is a point in the hemisphere around the surface's normal (rotated per pixel by a 4x4 pattern
    that the blur averages away); it is occluded when the scene's surface at its pixel is in front of it by
    more than ``u_bias``, counted only when that surface is within ``u_radius`` (no halos from far objects).
    """
    kernel = ",\n    ".join(f"vec3({x:.6f}, {y:.6f}, {z:.6f})" for x, y, z in _kernel(samples))
    return f"""uniform float u_radius;
uniform float u_bias;
const int SAMPLES = {samples};
const vec3 KERNEL[SAMPLES] = vec3[](
    {kernel});
vec4 effect(vec2 uv) {{
    if (is_background(uv)) return vec4(1.0);
    vec3 p = view_position(uv);
    vec3 n = view_normal(uv);
    ivec2 cell = ivec2(gl_FragCoord.xy) % 4;  // the 4 x 4 pattern the blur averages away
    float angle = 6.2831853 * float(cell.x * 4 + cell.y) / 16.0;
    vec3 r = vec3(cos(angle), sin(angle), 0.0);
    vec3 t = r - n * dot(r, n);
    t = length(t) < 1e-3 ? normalize(cross(n, vec3(1.0, 0.0, 0.0))) : normalize(t);
    mat3 tbn = mat3(t, cross(n, t), n);
    float occluded = 0.0;
    for (int k = 0; k < SAMPLES; ++k) {{
        vec3 s = p + tbn * KERNEL[k] * u_radius;
        vec2 at = project(s);
        if (any(lessThan(at, vec2(0.0))) || any(greaterThan(at, vec2(1.0)))) continue;
        float z = view_z(at);
        float near = smoothstep(0.0, 1.0, u_radius / max(abs(p.z - z), 1e-5));
        occluded += (z >= s.z + u_bias ? 1.0 : 0.0) * near;
    }}
    return vec4(vec3(1.0 - occluded / float(SAMPLES)), 1.0);
}}
"""


#: A 4x4 box blur of ``u_source``'s texels (removes the SSAO rotation pattern), only over pixels of similar
#: depth; written at the frame's size, it also brings a smaller occlusion buffer back to the frame's pixels.
BLUR = """uniform sampler2D u_source;
vec4 effect(vec2 uv) {
    vec2 px = 1.0 / vec2(textureSize(u_source, 0));
    float z = view_z(uv);
    vec4 sum = vec4(0.0);
    float weight = 0.0;
    for (int y = -2; y < 2; ++y)
        for (int x = -2; x < 2; ++x) {
            vec2 at = uv + (vec2(x, y) + 0.5) * px;
            float w = abs(view_z(at) - z) < 0.05 * abs(z) + 1e-3 ? 1.0 : 0.0;
            sum += w * texture(u_source, at);
            weight += w;
        }
    return weight > 0.0 ? sum / weight : texture(u_source, uv);
}
"""

SSAO_APPLY = """uniform sampler2D u_occlusion;
uniform float u_intensity;
vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);
    float ao = texture(u_occlusion, uv).r;
    return vec4(c.rgb * mix(1.0, ao, u_intensity), c.a);
}
"""

#: om.Fog's equations at each pixel's eye distance, rebuilt from depth (the background stays unfogged, as with
#: om.Fog, which fogs surfaces).
FOG = (
    FOG_GLSL
    + """vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);
    if (is_background(uv)) return c;
    return vec4(apply_fog(c.rgb, length(view_position(uv))), c.a);
}
"""
)

#: Darkens towards the corners: 1 - amount * smoothstep(start, 1, r), r the distance from the centre over the
#: distance of a corner (the corners lose exactly ``amount``).
VIGNETTE = """uniform float u_amount;
uniform float u_start;
vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);
    vec2 d = (uv - 0.5) * u_resolution;
    float r = length(d) / length(0.5 * u_resolution);
    return vec4(c.rgb * (1.0 - u_amount * smoothstep(u_start, 1.0, r)), c.a);
}
"""

#: Volumetric light shafts (radial blur towards each light's image, GPU Gems 3 ch. 13), in three passes at half
#: size: a mask per light (one channel each) of the pixels where nothing nearer than the light is seen
#: (depth occlusion) within ``u_size`` of its image; the mask blurred along the segment from each pixel to
#: the light with a decay per sample, times the light's colour; that light added to the image.
SHAFT_LIGHTS = """const int MAX_LIGHTS = 4;
uniform vec4 u_lights[MAX_LIGHTS];        // light image uv, its window depth, 1 if in front of the eye
uniform int u_count;
"""

SHAFT_MASK = (
    SHAFT_LIGHTS
    + """uniform float u_size;
uniform vec2 u_aspect;   // width / height of the frame, 1
vec4 effect(vec2 uv) {
    vec4 mask = vec4(0.0);
    float depth = depth_at(uv);
    for (int k = 0; k < MAX_LIGHTS; ++k) {
        if (k >= u_count || u_lights[k].w < 0.5 || depth < u_lights[k].z) continue;
        mask[k] = 1.0 - smoothstep(0.0, u_size, length((uv - u_lights[k].xy) * u_aspect));
    }
    return mask;
}
"""
)

SHAFT_BLUR = (
    SHAFT_LIGHTS
    + """uniform sampler2D u_mask;
uniform vec4 u_light_colors[MAX_LIGHTS];  // linear colour times intensity
uniform int u_samples;
uniform float u_decay;
vec4 effect(vec2 uv) {
    vec3 added = vec3(0.0);
    for (int k = 0; k < MAX_LIGHTS; ++k) {
        if (k >= u_count || u_lights[k].w < 0.5) continue;
        vec2 stride = (u_lights[k].xy - uv) / float(u_samples);
        float sum = 0.0, decay = 1.0;
        vec2 at = uv;
        for (int i = 0; i < u_samples; ++i) {
            at += stride;
            bool inside = all(greaterThanEqual(at, vec2(0.0))) && all(lessThanEqual(at, vec2(1.0)));
            sum += (inside ? texture(u_mask, at)[k] : 0.0) * decay;
            decay *= u_decay;
        }
        added += u_light_colors[k].rgb * sum / float(u_samples);
    }
    return vec4(added, 1.0);
}
"""
)

SHAFT_ADD = """uniform sampler2D u_shafts;
uniform float u_intensity;
vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);
    return vec4(c.rgb + u_intensity * texture(u_shafts, uv).rgb, c.a);
}
"""


def _spiral(samples: int) -> np.ndarray:
    """Points of a golden-angle spiral filling the unit disc evenly."""
    k = np.arange(samples) + 0.5
    r = np.sqrt(k / samples)
    a = k * np.pi * (3.0 - np.sqrt(5.0))
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


#: The circle of confusion's radius in pixels: linear in the eye distance's distance from the focus.
CIRCLE_OF_CONFUSION = """uniform float u_focus;      // distance in focus
uniform float u_range;      // distance from the focus at which the blur is largest
uniform float u_max;        // the largest circle of confusion's radius, pixels
vec4 effect(vec2 uv) {
    float d = is_background(uv) ? 1e9 : length(view_position(uv));
    return vec4(u_max * clamp(abs(d - u_focus) / u_range, 0.0, 1.0), 0.0, 0.0, 1.0);
}
"""


def depth_of_field(samples: int) -> str:
    """Depth of field: a disc of ``samples`` taps scaled by the circle of confusion of the pixel, each tap
    counted where its own circle reaches the pixel (sharp surfaces do not bleed into blurred ones)."""
    taps = ",\n    ".join(f"vec2({x:.6f}, {y:.6f})" for x, y in _spiral(samples))
    return f"""uniform sampler2D u_coc;   // circles of confusion (CIRCLE_OF_CONFUSION)
const int TAPS = {samples};
const vec2 DISC[TAPS] = vec2[](
    {taps});
vec4 effect(vec2 uv) {{
    vec4 centre = texture(u_input, uv);
    float radius = texture(u_coc, uv).r;
    if (radius < 0.5) return centre;
    vec2 px = 1.0 / vec2(textureSize(u_input, 0));   // offsets in the frame's pixels, whatever size this is drawn at
    vec3 sum = centre.rgb;
    float weight = 1.0;
    for (int k = 0; k < TAPS; ++k) {{
        vec2 offset = DISC[k] * radius;
        vec2 at = uv + offset * px;
        float w = smoothstep(length(offset) - 1.0, length(offset) + 1.0, texture(u_coc, at).r);
        sum += w * texture(u_input, at).rgb;
        weight += w;
    }}
    return vec4(sum / weight, centre.a);
}}
"""


#: The sharp image where the circle of confusion is under a pixel, the (smaller) blurred one elsewhere.
DOF_COMPOSITE = """uniform sampler2D u_coc;
uniform sampler2D u_blurred;
vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);
    return vec4(mix(c.rgb, texture(u_blurred, uv).rgb, smoothstep(0.5, 1.5, texture(u_coc, uv).r)), c.a);
}
"""


#: A 3D colour table stored as a strip of N slices of N x N (x = r + N b, y = g): the display-encoded colour
#: looked up with trilinear interpolation (bilinear in the slices, linear between them), decoded again.
COLOR_GRADING = """uniform sampler2D u_table;
uniform float u_size;   // N
uniform float u_amount;
vec3 lookup(vec3 c) {
    float n = u_size;
    float b = c.b * (n - 1.0);
    float b0 = floor(b), b1 = min(b0 + 1.0, n - 1.0);
    vec2 rg = (c.rg * (n - 1.0) + 0.5) / vec2(n * n, n);
    vec3 lo = texture(u_table, rg + vec2(b0 / n, 0.0)).rgb;
    vec3 hi = texture(u_table, rg + vec2(b1 / n, 0.0)).rgb;
    return mix(lo, hi, b - b0);
}
vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);
    vec3 display = to_srgb(c.rgb);
    return vec4(to_linear(mix(display, lookup(display), u_amount)), c.a);
}
"""
