"""Generated GLSL of the deferred pipeline: the models' stages wrapped per model, and the uber-shaders.

Every model's code is placed between ``#define``s that give its generic names (``GBuffer``,
``LBuffer``, ``material``, the stage functions) the model's prefix (``sm3_...``) and a ``#line``
directive whose source-string number names the model and the stage, so a compile error is traced
back to them (:func:`explain`).  From a layout (:class:`~.layout.BufferLayout`) this module makes

* the geometry pass's surface snippet (``Shader(surface=...)`` of the forward mesh shader): the
  visibility stage of the program's ``MODEL``, then the packed writes of the fixed layer, the model's
  G-buffer channels and its initial light;
* its vertex snippet (``Shader(vertex=...)``) when a model has a geometry stage;
* the lighting programs (one per light kind): read the G-buffer, evaluate the light, switch on the
  pixel's model and run its lighting stage, add the result into the L-buffer;
* the shading program: switch on the model, run its shading stage, apply fog, write colour and depth.

With multisampling, pixels whose samples show one surface are lit and shaded once, at the pixel
centre, as forward shading does; on geometric edges every sample is lit and shaded on its own, in the
same invocation (unrolled loops; the lights go into one target per sample, the shading writes the
mean of the samples' encoded colours, which is what the resolve of forward multisampling gives).
Everything runs once per pixel: per-sample shading (``gl_SampleID``) would cost every pixel the
sample count on a software rasteriser, whatever it shows.
"""

from __future__ import annotations

from ..engine.area_glsl import AREA_SHADOW_CODE, LTC_CORE
from ..engine.diagnostics import errors
from ..engine.shaders import MAX_LIGHTS, SRGB_GLSL
from ..engine.shadow_glsl import MAPS_CORE
from .layout import BufferLayout, Channel
from .models import G_TYPES, L_TYPES, PARAM_TYPES, STAGES, ShadingModel, ShadingModelError

__all__ = [
    "surface_snippet",
    "vertex_snippet",
    "lighting_program",
    "shading_program",
    "depth_program",
    "pixels_program",
    "explain",
    "LIGHT_KINDS",
    "COMMON",
]

#: Light kinds of the lighting programs (the ``LIGHT_KIND`` define).
LIGHT_KINDS = {"directional": 0, "point": 1, "spot": 2, "area": 3}
#: Fog slots of the fixed layer's flags (3 bits; 0 is "no fog").
FOG_SLOTS = 7
_STAGE_IDS = {"geometry": 1, "visibility": 2, "lighting": 3, "shading": 4}
_MACROS = ("GBuffer", "LBuffer", "material", "geometry", "visibility", "lighting", "shading")

#: Octahedral normals in 12 + 12 bits and 8-bit channels (the fixed layer's packing).
PACKING = """
vec2 oct_wrap(vec2 v) { return (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0); }
uint oct_encode(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.z >= 0.0 ? n.xy : oct_wrap(n.xy);
    uvec2 q = uvec2(round(clamp(e * 0.5 + 0.5, 0.0, 1.0) * 4095.0));
    return (q.x << 20) | (q.y << 8);
}
vec3 oct_decode(uint bits) {
    vec2 e = vec2(float((bits >> 20) & 4095u), float((bits >> 8) & 4095u)) / 4095.0 * 2.0 - 1.0;
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = oct_wrap(n.xy);
    return normalize(n);
}
uint unorm8(float v) { return uint(round(clamp(v, 0.0, 1.0) * 255.0)); }
"""
#: What the lighting and shading stages receive.
STRUCTS = """
struct Pixel {
    vec3 P;        // eye-space position
    vec3 N;        // eye-space unit normal
    vec3 V;        // unit vector towards the eye
    vec3 world;    // world-space position
    int material_id;
};
struct Light {
    vec3 L;        // unit vector towards the light (eye space)
    vec3 diffuse;  // the light's diffuse colour times attenuation, spot factor and shadow
    vec3 specular; // the same for its specular colour
    float distance;
};
"""
#: The sRGB curves, the packing and the stages' structs: the head of the lighting and shading programs.
COMMON = SRGB_GLSL + PACKING + STRUCTS


def first_line(model: ShadingModel, stage: str) -> int:
    """The ``#line`` number a model's stage starts at: ``(model + 1) * 10000 + stage * 1000 + 1``.

    The model and stage are in the line number itself (drivers differ in reporting source-string
    numbers); :func:`explain` decodes it.
    """
    return (model.number + 1) * 10000 + _STAGE_IDS[stage] * 1000 + 1


def _structs(layout: BufferLayout, model: ShadingModel) -> str:
    p = model.prefix
    g = [f"    {G_TYPES[k][0]} {name};" for name, k in model.gbuffer.items()] or ["    float unused_;"]
    lb = [f"    {L_TYPES[k][0]} {name};" for name, k in model.lbuffer.items()] or ["    float unused_;"]
    params = [f"    {PARAM_TYPES[k][0]} {name};" for name, (k, _) in model.parameters.items()] or ["    float unused_;"]
    zero_g = [f"    g.{name} = {G_TYPES[k][0]}(0.0);" for name, k in model.gbuffer.items()] or ["    g.unused_ = 0.0;"]
    zero_l = [f"    l.{name} = {L_TYPES[k][0]}(0.0);" for name, k in model.lbuffer.items()] or ["    l.unused_ = 0.0;"]
    fetch = []
    for slot, (name, (kind, _)) in enumerate(model.parameters.items()):
        glsl, size = PARAM_TYPES[kind]
        swizzle = "xyzw"[:size]
        fetch.append(f"    m.{name} = texelFetch(u_materials, ivec2({slot + 1}, id), 0).{swizzle};")
    fetch = fetch or ["    m.unused_ = 0.0;"]
    return "\n".join(
        [
            f"struct {p}G {{", *g, "};",
            f"struct {p}L {{", *lb, "};",
            f"struct {p}P {{", *params, "};",
            f"{p}P {p}material;",
            f"{p}G {p}G_zero() {{ {p}G g;", *zero_g, "    return g; }",
            f"{p}L {p}L_zero() {{ {p}L l;", *zero_l, "    return l; }",
            f"{p}P {p}params(int id) {{ {p}P m;", *fetch, "    return m; }",
        ]
    )  # fmt: skip


def _stage(model: ShadingModel, stage: str) -> str:
    """A model's stage code between the defines that give its generic names the model's prefix."""
    code = model.stages.get(stage)
    if not code:
        return ""
    p = model.prefix
    head = [
        f"#define GBuffer {p}G",
        f"#define LBuffer {p}L",
        f"#define material {p}material",
        *(f"#define {name} {p}{name}" for name in STAGES),
        f"#line {first_line(model, stage)}",
    ]
    tail = [*(f"#undef {name}" for name in _MACROS)]
    return "\n".join([*head, code, *tail, "#line 1"])


def _model_code(layout: BufferLayout, model: ShadingModel, stages: tuple[str, ...]) -> str:
    return "\n".join([_structs(layout, model), *(_stage(model, s) for s in stages)])


# -- the geometry pass -------------------------------------------------------------------------------------
def _outputs(layout: BufferLayout) -> str:
    lines = []
    for location, (name, fmt) in enumerate(layout.layers):
        kind = "uvec2" if fmt == "rg32ui" else ("vec3" if name in layout.light_layers else "vec4")
        lines.append(f"layout(location = {location}) out {kind} gb_{name};")
    return "\n".join(lines)


#: Integer and flag outputs: stored as a byte's [0, 1] value (GLSL to store, GLSL to read back from ``{}``).
_CODED = {
    "uint8": ("(float(min({}, 255u)) / 255.0)", "uint(round({} * 255.0))"),
    "bool": ("({} ? 1.0 : 0.0)", "({} > 0.5)"),
}


def _component(value: str, kind: str, index: int) -> str:
    """GLSL for component ``index`` of an output ``value`` of G-buffer type ``kind``, as stored."""
    glsl, size, _, srgb = G_TYPES[kind]
    if kind in _CODED:
        return _CODED[kind][0].format(value)
    if srgb:
        value = f"to_srgb({value})"
    return value if size == 1 else f"{value}[{index}]"


def _g_writes(layout: BufferLayout, model: ShadingModel) -> list[str]:
    lines = []
    for name, kind in model.gbuffer.items():
        for i, channel in enumerate(layout.channels[model.number][name]):
            layer, comp = channel.location()
            value = _component(f"g.{name}", kind, i)
            if layer == "fixed":
                lines.append(f"    spare[{comp}] = unorm8({value});")
            else:
                lines.append(f"    gb_{layer}[{comp}] = {value};")
    for name, kind in model.lbuffer.items():
        for i, channel in enumerate(layout.light[model.number][name]):
            layer, comp = channel.location()
            value = f"l.{name}" if L_TYPES[kind][1] == 1 else f"l.{name}[{i}]"
            lines.append(f"    gb_{layer}[{comp}] = max({value}, 0.0);")
    return lines


def surface_snippet(layout: BufferLayout) -> str:
    """``Shader(surface=...)`` code of the geometry pass: the visibility stage and the G-buffer writes."""
    parts = [
        PACKING,  # the forward shader it goes into has the sRGB curves
        "uniform sampler2D u_materials;",
        f"uniform vec4 u_fogs[{FOG_SLOTS}];",
        f"uniform vec3 u_fog_colors[{FOG_SLOTS}];",
        _outputs(layout),
    ]
    branches = []
    for model in layout.models:
        p = model.prefix
        body = [
            f"#{'elif' if branches else 'if'} MODEL == {model.number}",
            _model_code(layout, model, ("visibility",)),
            "void model_surface(inout Surface s) {",
            f"    {p}material = {p}params(s.material_id);",
            f"    {p}G g = {p}G_zero();",
            f"    {p}L l = {p}L_zero();",
        ]
        if "visibility" in model.stages:
            body.append(f"    {p}visibility(s, g, l);")
        body += _g_writes(layout, model)
        if model.depth:
            body.append("    gl_FragDepth = s.depth >= 0.0 ? clamp(s.depth, 0.0, 1.0) : gl_FragCoord.z;")
        body.append("}")
        branches.append("\n".join(body))
    branches += ["#else", "void model_surface(inout Surface s) { discard; }  // not a model of this layout", "#endif"]
    parts += ["uint spare[3];", *branches]
    zeros = {name: "vec3(0.0)" for name in layout.light_layers} | {"fixed": "uvec2(0u)"}
    zero = [f"    gb_{name} = {zeros.get(name, 'vec4(0.0)')};" for name, _ in layout.layers]
    parts.append(
        "\n".join(
            [
                "void pass_surface(Surface s) {",
                *zero,
                "    spare = uint[3](0u, 0u, 0u);",
                "    model_surface(s);",
                "    uint flags = 0u;",
                "#ifdef SHADOW_MAPS",
                "    flags |= 1u;  // receives shadows",
                "#endif",
                "#ifdef FOG",
                f"    for (int k = 0; k < {FOG_SLOTS}; ++k)",
                "        if (u_fogs[k] == u_fog && u_fog_colors[k] == u_fog_color) {",
                "            flags |= uint(k + 1) << 1;",
                "            break;",
                "        }",
                "#endif",
                "    uint id = uint(clamp(s.material_id, 0, 4095));",
                "    uint word = (id << 20) | (flags << 16) | (spare[1] << 8) | spare[2];",
                "    gb_fixed = uvec2(oct_encode(s.N) | spare[0], word);",
                "}",
            ]
        )
    )
    return "\n".join(parts)


def vertex_snippet(layout: BufferLayout) -> str:
    """``Shader(vertex=...)`` code running the geometry stage of the program's model ('' when no model has one)."""
    models = [m for m in layout.models if "geometry" in m.stages]
    if not models:
        return ""
    parts = ["uniform sampler2D u_materials;"]
    calls = []
    for model in models:
        p = model.prefix
        parts += [f"#if MODEL == {model.number}", _model_code(layout, model, ("geometry",)), "#endif"]
        calls += [
            f"#if MODEL == {model.number}",
            f"    {p}material = {p}params(VERTEX_MATERIAL_ID);",
            f"    {p}geometry(world, normal);",
            "#endif",
        ]
    parts += ["void pass_vertex(inout vec3 world, inout vec3 normal) {", *calls, "}"]
    return "\n".join(parts)


# -- reading the G-buffer (lighting and shading passes) ----------------------------------------------------
def _header(samples: int, defines: dict[str, object]) -> str:
    lines = ["#version 330"]
    for name, value in sorted(defines.items()):
        lines.append(f"#define {name}" if value is True else f"#define {name} {value}")
    lines.append(f"#define MAX_LIGHTS {MAX_LIGHTS}")
    lines.append(f"#define SAMPLES {max(samples, 1)}")
    if samples > 1:
        lines.append("#define MULTI")
    return "\n".join(lines) + "\n"


def _gbuffer_samplers(layout: BufferLayout, samples: int, ambient: bool) -> list[str]:
    """Sampler uniforms of the G-buffer layers (the light layers' ambient part with ``ambient``) and globals."""
    ms = "MS" if samples > 1 else ""
    lines = [f"uniform usampler2D{ms} u_fixed;", f"uniform sampler2D{ms} u_depth;", "uniform sampler2D u_materials;"]
    lines.append("uvec2 px_fixed;")
    for name, _fmt in layout.layers[1:]:
        if name not in layout.light_layers or ambient:
            lines += [f"uniform sampler2D{ms} u_{name};", f"vec4 px_{name};"]
    if samples > 1:
        lines += [
            "uniform sampler2D u_pixels;              // x: depth at the pixel centre (1: nothing), y: 1 on edges",
            f"uniform vec2 u_offsets[{samples}];       // sample position - pixel centre",
        ]
    return lines


def _fetch(layout: BufferLayout, samples: int, ambient: bool, direct: bool) -> str:
    """``fetch(c, s)``: the G-buffer values of sample ``s`` of pixel ``c`` into the ``px_`` globals; with ``direct``
    the light layers add the lights of the lighting pass (their per-sample targets ``u_<layer>_s<k>``)."""
    lines = ["void fetch(ivec2 c, int s) {", "    px_fixed = texelFetch(u_fixed, c, s).xy;"]
    for name, _fmt in layout.layers[1:]:
        if name not in layout.light_layers or ambient:
            lines.append(f"    px_{name} = texelFetch(u_{name}, c, s);")
    if direct and samples > 1:
        for name in layout.light_layers:
            for k in range(samples):
                lines.append(
                    f"    {'else ' if k else ''}if (s == {k}) px_{name}.rgb += texelFetch(u_{name}_s{k}, c, 0).rgb;"
                )
    lines.append("}")
    return "\n".join(lines)


def _channel_value(channel: Channel) -> str:
    layer, comp = channel.location()
    if layer == "fixed":
        shift = (0, 8, 0)[comp]
        word = "x" if comp == 0 else "y"
        return f"float((px_fixed.{word} >> {shift}u) & 255u) / 255.0"
    return f"px_{layer}[{comp}]"


def _g_reads(layout: BufferLayout, model: ShadingModel) -> str:
    p = model.prefix
    lines = [f"{p}G {p}G_read() {{", f"    {p}G g = {p}G_zero();"]
    for name, kind in model.gbuffer.items():
        glsl, size, _, srgb = G_TYPES[kind]
        values = [_channel_value(c) for c in layout.channels[model.number][name]]
        value = values[0] if size == 1 else f"{glsl}({', '.join(values)})"
        if kind in _CODED:
            value = _CODED[kind][1].format(value)
        lines.append(f"    g.{name} = {f'to_linear({value})' if srgb else value};")
    lines += ["    return g;", "}"]
    return "\n".join(lines)


def _l_reads(layout: BufferLayout, model: ShadingModel) -> str:
    p = model.prefix
    lines = [f"{p}L {p}L_read() {{", f"    {p}L l = {p}L_zero();"]
    for name, kind in model.lbuffer.items():
        glsl, size = L_TYPES[kind]
        values = [_channel_value(c) for c in layout.light[model.number][name]]
        value = values[0] if size == 1 else glsl + "(" + ", ".join(values) + ")"
        lines.append(f"    l.{name} = {value};")
    lines += ["    return l;", "}"]
    return "\n".join(lines)


_SURFACE_AT = """
uniform mat4 u_inv_proj;       // clip space -> eye space of the frame's camera
uniform mat4 u_eye_to_world;
uniform vec2 u_size;           // the target's size in pixels
// the surface seen by sample s of the pixel at window position xy (the pixel centre or the sample's), depth z
Pixel surface_at(vec2 xy, float z, int s, out int model, out uint id, out uint flags) {
    fetch(ivec2(xy), s);
    vec4 q = u_inv_proj * vec4(xy / u_size * 2.0 - 1.0, z * 2.0 - 1.0, 1.0);
    vec3 P = q.xyz / q.w;
    id = px_fixed.y >> 20;
    flags = (px_fixed.y >> 16) & 15u;
#ifdef ORTHO
    vec3 V = vec3(0.0, 0.0, 1.0);
#else
    vec3 V = -normalize(P);
#endif
    model = int(texelFetch(u_materials, ivec2(0, int(id)), 0).x);
    return Pixel(P, oct_decode(px_fixed.x), V, (u_eye_to_world * vec4(P, 1.0)).xyz, int(id));
}
"""


def _per_sample(samples: int, body: str, centre: str, background: str) -> list[str]:
    """``main``'s dispatch: one evaluation at the centre of a pixel showing one surface (``centre``, with ``xy`` and
    ``z``), else ``body`` once per sample that shows a surface (unrolled: outputs cannot be indexed)."""
    lines = ["    ivec2 c = ivec2(gl_FragCoord.xy);"]
    if samples <= 1:
        return lines + [
            "    float z = texelFetch(u_depth, c, 0).r;",
            f"    if (z >= 1.0) {background};",
            "    vec2 xy = gl_FragCoord.xy;",
            "    int s = 0;",
            centre,
        ]
    lines += [
        "    vec2 px = texelFetch(u_pixels, c, 0).xy;",
        "    if (px.y < 0.5) {  // one surface covers the pixel: evaluated once, at the centre (as forward shading)",
        f"        if (px.x >= 1.0) {background};",
        "        float z = px.x;",
        "        vec2 xy = gl_FragCoord.xy;",
        "        int s = 0;",
        centre,
        "    } else {  // an edge: every sample on its own",
    ]
    for k in range(samples):
        lines += [
            "        {",
            f"            int s = {k};",
            f"            float z = texelFetch(u_depth, c, {k}).r;",
            f"            vec2 xy = gl_FragCoord.xy + u_offsets[{k}];",
            "            if (z < 1.0) {",
            body.replace("{k}", str(k)),
            "            }",
            "        }",
        ]
    lines.append("    }")
    return lines


_FULLSCREEN_VERTEX = "in vec3 in_position;\nvoid main() { gl_Position = vec4(in_position.xy, 0.0, 1.0); }\n"


def depth_program(samples: int) -> tuple[str, str]:
    """The G-buffer's depth into the frame: sample ``u_sample`` per draw (drawn once per sample under a mask)."""
    head = _header(samples, {})
    ms = "MS" if samples > 1 else ""
    fragment = (
        head
        + f"""
uniform sampler2D{ms} u_depth;
uniform int u_sample;
void main() {{
    float z = texelFetch(u_depth, ivec2(gl_FragCoord.xy), u_sample).r;
    if (z >= 1.0) discard;
    gl_FragDepth = z;
}}
"""
    )
    return head + _FULLSCREEN_VERTEX, fragment


def pixels_program(samples: int) -> tuple[str, str]:
    """Per pixel of a multisampled G-buffer: the depth at its centre and whether its samples show one surface.

    One surface: one material and flags, the samples' depths on one plane, normals within 8 degrees and the
    fixed layer's colour bytes within 2 levels (two triangles of a smooth mesh meeting in the pixel are one
    surface: forward shading gives them nearly the same colour at the pixel centre).  Such pixels are lit and
    shaded once at the centre, with the centre's depth from the plane; edges once per sample.
    """
    head = _header(samples, {})
    fragment = (
        head
        + PACKING
        + """
uniform usampler2DMS u_fixed;
uniform sampler2DMS u_depth;
uniform vec3 u_fit[SAMPLES];       // least-squares plane through the samples' depths: (centre, d/dx, d/dy)
uniform vec2 u_offsets[SAMPLES];   // sample position - pixel centre
out vec2 f_pixel;
void main() {
    ivec2 c = ivec2(gl_FragCoord.xy);
    uvec2 first = texelFetch(u_fixed, c, 0).xy;
    vec3 n0 = oct_decode(first.x);
    float zs[SAMPLES];
    vec3 plane = vec3(0.0);
    bool edge = false;
    for (int k = 0; k < SAMPLES; ++k) {
        zs[k] = texelFetch(u_depth, c, k).r;
        plane += u_fit[k] * zs[k];
        uvec2 f = texelFetch(u_fixed, c, k).xy;
        if ((f.y >> 16) != (first.y >> 16) || dot(oct_decode(f.x), n0) < 0.99) edge = true;
        ivec3 bytes = abs(ivec3(uvec3(f.x & 255u, (f.y >> 8) & 255u, f.y & 255u))
                          - ivec3(uvec3(first.x & 255u, (first.y >> 8) & 255u, first.y & 255u)));
        if (max(bytes.x, max(bytes.y, bytes.z)) > 2) edge = true;
    }
    bool nothing = true;
    for (int k = 0; k < SAMPLES; ++k) {
        if (zs[k] < 1.0) nothing = false;
        if (abs(zs[k] - (plane.x + dot(plane.yz, u_offsets[k]))) > 1e-6) edge = true;
    }
    f_pixel = nothing ? vec2(1.0, 0.0) : (edge ? vec2(zs[0], 1.0) : vec2(plane.x, 0.0));
    float nearest = zs[0];
    for (int k = 1; k < SAMPLES; ++k) nearest = min(nearest, zs[k]);
    gl_FragDepth = nearest;  // what the lights' proxies are culled against (the nearest sample: conservative)
}
"""
    )
    return head + _FULLSCREEN_VERTEX, fragment


def lighting_program(layout: BufferLayout, kind: str, fullscreen: bool, samples: int,
                     defines: dict[str, object]) -> tuple[str, str]:  # fmt: skip
    """(vertex, fragment) source of the lighting pass for lights of ``kind`` drawn as proxies or full screen.

    No ``discard``: fragments that add nothing write zero, so a software rasteriser tests depth before shading.
    With multisampling the outputs are one target per light layer and sample (``lb_<layer>_s<k>``).
    """
    defines = {**defines, "LIGHT_KIND": LIGHT_KINDS[kind]}
    if fullscreen:
        defines["FULLSCREEN"] = True
    head = _header(samples, defines)
    vertex = (
        head
        + """
in vec3 in_position;
in mat4 i_proxy;    // unit proxy -> eye space
in vec4 i_lpos;     // eye space: position (w 1) or direction towards the light (w 0)
in vec4 i_ldiff;    // diffuse colour, reach
in vec4 i_lspec;    // specular colour
in vec4 i_latt;     // constant, linear, quadratic attenuation
in vec4 i_lspot;    // spot axis (eye space), cos(cutoff)
in vec4 i_lextra;   // spot exponent, first shadow face, shadow face count
in vec4 i_larea_u;  // an area light's half axis u (eye space), 1 for a disc
in vec4 i_larea_v;  // its half axis v (eye space), 1 when two-sided
uniform mat4 u_proj;
flat out vec4 v_lpos; flat out vec4 v_ldiff; flat out vec4 v_lspec; flat out vec4 v_latt;
flat out vec4 v_lspot; flat out vec4 v_lextra; flat out vec4 v_larea_u; flat out vec4 v_larea_v;
void main() {
#ifdef FULLSCREEN
    gl_Position = vec4(in_position.xy, 0.0, 1.0);
#else
    gl_Position = u_proj * (i_proxy * vec4(in_position, 1.0));
#endif
    v_lpos = i_lpos; v_ldiff = i_ldiff; v_lspec = i_lspec; v_latt = i_latt; v_lspot = i_lspot; v_lextra = i_lextra;
    v_larea_u = i_larea_u; v_larea_v = i_larea_v;
}
"""
    )
    layers = layout.light_layers
    if samples > 1:
        outputs = [f"{name}_s{k}" for name in layers for k in range(samples)]
    else:
        outputs = list(layers)
    decl = [f"layout(location = {k}) out vec3 lb_{name};" for k, name in enumerate(outputs)]
    args = ", ".join(f"inout vec3 o_{name}" for name in layers)
    models = [m for m in layout.models if "lighting" in m.stages]
    branches = []
    for model in models:
        p, n = model.prefix, model.number
        writes = []
        for name, kind_l in model.lbuffer.items():
            for i, channel in enumerate(layout.light[n][name]):
                layer, comp = channel.location()
                value = f"l.{name}" if L_TYPES[kind_l][1] == 1 else f"l.{name}[{i}]"
                writes.append(f"        o_{layer}[{comp}] = {value};")
        branches.append(
            "\n".join(
                [
                    f"    {'else ' if branches else ''}if (model == {n}) {{",
                    f"        {p}material = {p}params(int(id));",
                    f"        {p}G g = {p}G_read();",
                    f"        {p}L l = {p}L_zero();",
                    f"        {p}lighting(p, g, light, l);",
                    *writes,
                    "    }",
                ]
            )
        )
    shadows, shadow_call = "", ""
    if "SHADOW_MAPS" in defines:
        shadows = MAPS_CORE
        shadow_call = """
    if ((flags & 1u) != 0u && v_lextra.z > 0.5 && dot(p.N, light.L) > 0.0)
        att *= face_shadow(int(v_lextra.y), int(v_lextra.z), v_lpos.xyz, p.P, p.N, light.L);"""
        if kind == "area":  # soft shadows from the light's shape (gl/engine/area_glsl.py), in world space
            shadows += AREA_SHADOW_CODE
            shadow_call = """
    if ((flags & 1u) != 0u && v_lextra.z > 0.5 && att > 0.0) {
        mat3 rot = mat3(u_eye_to_world);
        att *= area_shadow_faces(int(v_lextra.y), int(v_lextra.z), (u_eye_to_world * vec4(v_lpos.xyz, 1.0)).xyz,
                                 rot * v_larea_u.xyz, rot * v_larea_v.xyz, v_larea_u.w > 0.5, p.P, p.N);
    }"""
    light_at = "\n".join(
        [
            f"void light_at({', '.join(['vec2 xy', 'float z', 'int s'] + ([args] if args else []))}) {{",
            "    int model; uint id; uint flags;",
            "    Pixel p = surface_at(xy, z, s, model, id, flags);",
            "    Light light;",
            "    float att = 1.0;",
            "#if LIGHT_KIND == 0",
            "    light.L = v_lpos.xyz;",
            "    light.distance = 0.0;",
            "#elif LIGHT_KIND == 3",
            "    // an area light: its form factor F (linearly transformed cosines, gl/engine/area_glsl.py), given to",
            "    // the model as a light from the form factor's direction L of strength F / (N.L), so that a",
            "    // Lambertian model's N.L * diffuse is L_e * F",
            "    vec3 q[8];",
            "    int nq = area_polygon(v_lpos.xyz, v_larea_u.xyz, v_larea_v.xyz, v_larea_u.w > 0.5, q);",
            "    float F = ltc_polygon(q, nq, v_larea_v.w > 0.5, p.N, p.V, p.P, mat3(1.0), light.L);",
            "    if (F <= 0.0) return;",
            "    light.distance = length(v_lpos.xyz - p.P);",
            "    att = F / max(dot(p.N, light.L), 1e-4);",
            "#else",
            "    vec3 d = v_lpos.xyz - p.P;",
            "    float dist = length(d);",
            "    if (dist > v_ldiff.w) return;  // beyond the light's reach: culled against the G-buffer depth",
            "    light.L = dist > 1e-20 ? d / dist : vec3(0.0, 0.0, 1.0);",
            "    light.distance = dist;",
            "    att = 1.0 / max(v_latt.x + v_latt.y * dist + v_latt.z * dist * dist, 1e-20);",
            "#if LIGHT_KIND == 2",
            "    float cs = dot(-light.L, v_lspot.xyz);",
            "    if (cs < v_lspot.w) return;  // outside the cone",
            "    att *= pow(max(cs, 0.0), v_lextra.x);",
            "#endif",
            "#endif",
            shadow_call,
            "    light.diffuse = v_ldiff.rgb * att;",
            "    light.specular = v_lspec.rgb * att;",
            *branches,
            "}",
        ]
    )
    call = ", ".join(f"o_{name}" for name in layers)
    zero = " ".join(f"vec3 o_{name} = vec3(0.0);" for name in layers)
    once = "\n".join(
        [f"    {{ {zero}", f"    light_at({', '.join(['xy', 'z', 's'] + ([call] if call else []))});"]
        + [f"    lb_{out} = o_{out.rsplit('_s', 1)[0] if samples > 1 else out};" for out in outputs]
        + ["    }"]
    )
    each = "\n".join(
        [
            f"                {zero}",
            f"                light_at({', '.join(['xy', 'z', 's'] + ([call] if call else []))});",
        ]
        + [f"                lb_{name}_s{{k}} = o_{name};" for name in layers]
    )
    fragment = head + "\n".join(
        [
            COMMON,
            *_gbuffer_samplers(layout, samples, ambient=False),
            "flat in vec4 v_lpos; flat in vec4 v_ldiff; flat in vec4 v_lspec; flat in vec4 v_latt;",
            "flat in vec4 v_lspot; flat in vec4 v_lextra; flat in vec4 v_larea_u; flat in vec4 v_larea_v;",
            LTC_CORE if kind == "area" else "",
            *decl,
            _fetch(layout, samples, ambient=False, direct=False),
            _SURFACE_AT,
            shadows,
            *(_model_code(layout, m, ("lighting",)) + "\n" + _g_reads(layout, m) for m in models),
            light_at,
            "void main() {",
            *(f"    lb_{name} = vec3(0.0);" for name in outputs),
            *_per_sample(samples, each, once, "return"),
            "}",
        ]
    )
    return vertex, fragment


def shading_program(layout: BufferLayout, samples: int, defines: dict[str, object]) -> tuple[str, str]:
    """(vertex, fragment) source of the shading pass (full screen): the colour of every drawn pixel.

    Edge pixels of a multisampled G-buffer get the mean of their samples' encoded colours, written to the
    samples the G-buffer's surfaces won (``STENCIL_MARKED``) or blended over the others; with ``FRAG_DEPTH``
    the G-buffer depth is written too (tested equal against the frame's: where the surface is seen).
    """
    head = _header(samples, defines)
    branches = []
    for model in layout.models:
        p, n = model.prefix, model.number
        branches.append(
            "\n".join(
                [
                    f"    {'else ' if branches else ''}if (model == {n}) {{",
                    f"        {p}material = {p}params(int(id));",
                    f"        color = {p}shading(p, {p}G_read(), {p}L_read());",
                    "    }",
                ]
            )
        )
    direct = [f"uniform sampler2D u_{name}_s{k};" for name in layout.light_layers for k in range(samples)]
    centre = "\n".join(
        [
            "    f_color = vec4(encode(shade_at(xy, z, s)), 1.0);",
            "#ifdef FRAG_DEPTH",
            "    gl_FragDepth = z;",
            "#endif",
        ]
    )
    each = "                sum += encode(shade_at(xy, z, s));\n                n += 1.0;"
    main = ["void main() {"]
    if samples > 1:
        main += ["    vec3 sum = vec3(0.0);", "    float n = 0.0;"]
    main += _per_sample(samples, each, centre, "discard")
    if samples > 1:
        main += [
            "    if (px.y > 0.5) {",
            "        if (n == 0.0) discard;",
            "#ifdef STENCIL_MARKED",
            "        f_color = vec4(sum / n, 1.0);  // the samples the surfaces won: their mean (the resolve's)",
            "#else",
            "        f_color = vec4(sum / float(SAMPLES), n / float(SAMPLES));  // blended over the others",
            "#endif",
            "    }",
        ]
    main.append("}")
    fragment = head + "\n".join(
        [
            COMMON,
            *_gbuffer_samplers(layout, samples, ambient=True),
            *(direct if samples > 1 else []),
            _fetch(layout, samples, ambient=True, direct=True),
            _SURFACE_AT,
            f"uniform vec4 u_fogs[{FOG_SLOTS}];       // start, end, density, mode (0 linear, 1 exp, 2 exp2)",
            f"uniform vec3 u_fog_colors[{FOG_SLOTS}];",
            "out vec4 f_color;",
            *(
                _model_code(layout, m, ("shading",)) + "\n" + _g_reads(layout, m) + "\n" + _l_reads(layout, m)
                for m in layout.models
            ),
            "vec3 apply_fog(vec3 c, float dist, int slot) {  // the forward shader's fog",
            "    vec4 fog = u_fogs[slot];",
            "    float f;",
            "    if (fog.w < 0.5) f = (fog.y - dist) / (fog.y - fog.x);",
            "    else if (fog.w < 1.5) f = exp(-fog.z * dist);",
            "    else f = exp(-(fog.z * dist) * (fog.z * dist));",
            "    return mix(u_fog_colors[slot], c, clamp(f, 0.0, 1.0));",
            "}",
            "vec3 encode(vec3 c) {",
            "#ifdef LINEAR_OUTPUT",
            "    return max(c, vec3(0.0));",
            "#else",
            "    return to_srgb(c);",
            "#endif",
            "}",
            "vec3 shade_at(vec2 xy, float z, int s) {",
            "    int model; uint id; uint flags;",
            "    Pixel p = surface_at(xy, z, s, model, id, flags);",
            "    vec3 color = vec3(0.0);",
            *branches,
            "    uint slot = flags >> 1;",
            "    if (slot > 0u) color = apply_fog(color, length(p.P), int(slot) - 1);",
            "    return color;",
            "}",
            *main,
        ]
    )
    return head + _FULLSCREEN_VERTEX, fragment


def explain(error: str, models: tuple[ShadingModel, ...], where: str) -> ShadingModelError | None:
    """A :class:`ShadingModelError` naming model, stage and line for a driver error in a model's code, or None.

    The driver's log is read by :func:`~omnirender.gl.engine.diagnostics.parse` (Mesa, NVIDIA, AMD, Intel
    formats); the line number it reports encodes the model and the stage (:func:`first_line`).
    """
    by_number = {m.number: m for m in models}
    for diagnostic in errors(str(error)):
        if diagnostic.line is None:
            continue
        number, rest = divmod(diagnostic.line, 10000)
        stage_id, row = divmod(rest, 1000)
        model = by_number.get(number - 1)
        stage = next((s for s, k in _STAGE_IDS.items() if k == stage_id), None)
        if model is None or stage is None or stage not in model.stages:
            continue
        text = model.stages[stage].splitlines()
        code = text[row - 1].strip() if 0 < row <= len(text) else ""
        return ShadingModelError(
            f"shading model {model.name!r}, {stage} stage, line {row}: {diagnostic.message}"
            + (f"\n    {code}" if code else "")
            + f"\n(compiling the deferred pipeline's {where}; the stage must define {STAGES[stage]})"
        )
    return None
