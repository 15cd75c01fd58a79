"""Volume: GPU ray casting through a 3D texture with the transfer function as a lookup texture.

The painter records a draw item whose geometry is the volume's bounding box
(the unit cube scaled to the box the voxel centres span).  The drawer draws
its back faces (so a camera inside the box still gets fragments); the fragment
shader marches the ray front to back through the 3D texture, from where it
enters the box or crosses the near plane (whichever is later) to the back
face, maps samples through the transfer function (opacity corrected for the
step length), composites, and writes ``gl_FragDepth`` at the first sample
where the accumulated opacity crosses 5% (interpolated within the step, so the
depth is smooth) -- so depth changes exactly where colour does (compositing
rule 2).  Rays that stay nearly transparent are discarded.
Rays end at the depth already drawn (a copy of the framebuffer's depth taken
before the volumes are drawn), so opaque shapes inside a volume hide what lies
behind them and are seen through what lies in front.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...attributes.photometry import srgb_to_linear
from ...core.handler import ShapePainter, default_for
from ...shapes import Volume
from ..engine.attributes import Blend, CullFace, DepthClamp, DepthMask, DepthTest
from ..engine.geometry import Geometry, unit_mesh
from ..engine.layout import ROW
from ..engine.passes import Target
from ..glengine import GLEngine

__all__ = ["VolumePainter", "VolumeGeometry"]

#: Where the depth drawn before the volumes is copied (a frame target: made once, kept while volumes are drawn).
_DRAWN_DEPTH = Target("gl.volume.drawn-depth", colors=(), depth=True)

_VS = """
in vec3 in_position;
uniform mat4 u_model;
uniform mat4 u_view;
uniform mat4 u_proj;
out vec3 v_local;
void main() {
    v_local = in_position;
    gl_Position = u_proj * u_view * u_model * vec4(in_position, 1.0);
}
"""

_FS = """
in vec3 v_local;
uniform sampler3D u_volume;
uniform sampler2D u_tf;
uniform vec2 u_range;          // transfer function value range
uniform vec3 u_dims;           // voxels along x, y, z
uniform vec4 u_eye;            // eye in local coordinates (w = 1) or viewing direction (w = 0, orthographic)
uniform mat4 u_mvp;
uniform mat4 u_inv_mvp;
uniform float u_steps;
uniform sampler2D u_scene_depth;  // depth drawn before the volumes (window depth, 1 = nothing)
uniform vec2 u_viewport;
out vec4 f_color;

vec2 box(vec3 ro, vec3 rd) {
    vec3 inv = 1.0 / rd;
    vec3 t0 = (vec3(-0.5) - ro) * inv;
    vec3 t1 = (vec3(0.5) - ro) * inv;
    vec3 lo = min(t0, t1);
    vec3 hi = max(t0, t1);
    return vec2(max(max(lo.x, lo.y), lo.z), min(min(hi.x, hi.y), hi.z));
}

void main() {
    vec3 rd = u_eye.w > 0.5 ? normalize(v_local - u_eye.xyz) : normalize(u_eye.xyz);
    vec3 ro = v_local - rd * 4.0;
    vec2 t = box(ro, rd);
    // the drawn (back) face ends the ray; it starts where the ray enters the box or crosses the near plane,
    // whichever is later, so a camera inside the box still sees the volume in front of it.  The near plane
    // is linear in local coordinates: clip.z + clip.w = dot(row 2 + row 3 of u_mvp, p) >= 0.
    vec4 near = vec4(u_mvp[0][2] + u_mvp[0][3], u_mvp[1][2] + u_mvp[1][3],
                     u_mvp[2][2] + u_mvp[2][3], u_mvp[3][2] + u_mvp[3][3]);
    float a0 = dot(near, vec4(ro, 1.0));
    float b0 = dot(near.xyz, rd);
    if (abs(b0) > 1e-12) {
        float tn = -a0 / b0;
        if (b0 > 0.0) t.x = max(t.x, tn); else t.y = min(t.y, tn);
    } else if (a0 < 0.0) {
        discard;
    }
    // end the ray where it meets what is already drawn
    float drawn = texelFetch(u_scene_depth, ivec2(gl_FragCoord.xy), 0).r;
    if (drawn < 1.0) {
        vec4 q = u_inv_mvp * vec4(gl_FragCoord.xy / u_viewport * 2.0 - 1.0, drawn * 2.0 - 1.0, 1.0);
        t.y = min(t.y, dot(q.xyz / q.w - ro, rd));
    }
    if (t.y <= t.x) discard;
    float len = t.y - t.x;
    float dt = 1.7320508 / u_steps;
    int n = int(ceil(len / dt));
    vec3 color = vec3(0.0);
    float alpha = 0.0;
    float depth = -1.0;
    for (int i = 0; i < n && i < 2048; ++i) {
        vec3 p = ro + rd * (t.x + (float(i) + 0.5) * dt);
        vec3 tc = (p + 0.5) * (u_dims - 1.0) / u_dims + 0.5 / u_dims;
        float s = texture(u_volume, tc).r;
        float x = clamp((s - u_range.x) / max(u_range.y - u_range.x, 1e-20), 0.0, 1.0);
        vec4 c = texture(u_tf, vec2(x, 0.5));
        float a = 1.0 - pow(max(1.0 - c.a, 0.0), dt * max(max(u_dims.x, u_dims.y), u_dims.z));
        color += (1.0 - alpha) * a * c.rgb;
        float before = alpha;
        alpha += (1.0 - alpha) * a;
        if (depth < 0.0 && alpha > 0.05) {
            // where within this step's stretch the opacity crossed 5 %: a smooth depth, not one in steps
            float f = clamp((0.05 - before) / max(alpha - before, 1e-6), 0.0, 1.0);
            vec4 clip = u_mvp * vec4(p + rd * (f - 0.5) * dt, 1.0);
            depth = clip.z / clip.w * 0.5 + 0.5;
        }
        if (alpha > 0.99) break;
    }
    if (depth < 0.0) discard;
    gl_FragDepth = clamp(depth, 0.0, 1.0);
    f_color = vec4(to_srgb(color / max(alpha, 1e-6)), alpha);
}
"""


class VolumeGeometry(Geometry):
    """The bounding box of a volume plus its data and transfer-function table (uploaded lazily)."""

    __slots__ = ("data", "table", "range", "textures")

    def __init__(self, volume: Volume, label: str) -> None:
        box = unit_mesh("box")
        super().__init__("triangles", box.positions, box.normals, indices=box.indices, label=label)
        self.data = volume.data_array()
        tf = volume.transfer_function
        table = tf.table(256).astype(np.float32)
        rgb = table[:, :3]  # transfer-function colours are display (sRGB) values: linear for compositing
        table[:, :3] = srgb_to_linear(rgb)
        self.table = table
        self.range = tf.range
        self.textures: tuple[Any, Any] | None = None

    def release(self) -> None:
        super().release()
        if self.textures is not None:
            for t in self.textures:
                t.release()
            self.textures = None


@default_for(GLEngine)
class VolumePainter(ShapePainter):
    """Ray-cast volume rendering (drawn with the transparent items, writing a consistent depth)."""

    __slots__ = ()
    service = "gl.paint"
    target = Volume

    def exec(self, shape: Volume, engine: GLEngine) -> None:
        geom = engine.geometry_cache.get(shape)
        if geom is None:
            d, h, w = shape.data_array().shape
            engine.check_texture_size(f"Volume (data {w}x{h}x{d})", (w, h, d), engine.max_texture_size_3d)
            geom = VolumeGeometry(shape, f"Volume in {engine.node_path or '/'}")
            engine.geometry_cache.put(shape, geom)
        lo, hi = shape.bounds()
        local = np.diag([*(hi - lo), 1.0])
        local[:3, 3] = (lo + hi) / 2.0
        engine.submit(geom, local, kind="volume", transparent=True)


#: back faces (they exist also when the camera is inside the box), blended over, not clipped by the far plane
_STATE = (DepthTest(True, "less"), Blend(), CullFace("front"), DepthClamp(True), DepthMask(True))


def draw_volumes(engine: GLEngine, items: list, state: Any) -> int:
    """The drawer for ``"volume"`` items."""
    ctx = engine.ctx
    if not engine.programs.registered("volume"):
        engine.programs.register("volume", _VS, _FS)
    prog = engine.programs.get("volume")
    drawn = engine.copy_framebuffer(_DRAWN_DEPTH)
    # back faces: they exist also when the camera is inside the box (front faces are then behind the near
    # plane); depth clamping keeps back faces beyond the far plane from being clipped away
    engine.apply_gl_state(*_STATE)
    view, proj = engine.frame_view, engine.frame_projection
    calls = 0
    for item in items:
        geom: VolumeGeometry = item.geometry
        engine.upload(geom)
        if geom.textures is None:
            d, h, w = geom.data.shape
            vol = ctx.texture3d((w, h, d), 1, np.ascontiguousarray(geom.data, np.float32).tobytes(), dtype="f4")
            vol.repeat_x = vol.repeat_y = vol.repeat_z = False
            tf = ctx.texture((256, 1), 4, geom.table.tobytes(), dtype="f4")
            tf.repeat_x = tf.repeat_y = False
            geom.textures = (vol, tf)
        vol, tf = geom.textures
        model = item.row[ROW.slice("model")].reshape(4, 4).T.astype(np.float64)
        inv = np.linalg.inv(view @ model)
        if engine.frame_orthographic:
            eye = inv @ np.array([0.0, 0.0, -1.0, 0.0])
            eye[3] = 0.0
        else:
            eye = inv @ np.array([0.0, 0.0, 0.0, 1.0])
            eye = eye / eye[3]
        mvp = proj @ view @ model
        prog["u_model"].write(model.T.astype(np.float32).tobytes())
        prog["u_view"].write(view.T.astype(np.float32).tobytes())
        prog["u_proj"].write(proj.T.astype(np.float32).tobytes())
        prog["u_mvp"].write(mvp.T.astype(np.float32).tobytes())
        prog["u_inv_mvp"].write(np.linalg.inv(mvp).T.astype(np.float32).tobytes())
        prog["u_viewport"].value = tuple(float(v) for v in engine.target_size)
        prog["u_eye"].value = tuple(float(x) for x in eye)
        d, h, w = geom.data.shape
        prog["u_dims"].value = (float(w), float(h), float(d))
        prog["u_range"].value = tuple(float(x) for x in geom.range)
        prog["u_steps"].value = float(min(2 * max(w, h, d), 1024))
        vol.use(0)
        tf.use(1)
        drawn.depth.use(2)
        prog["u_volume"].value = 0
        prog["u_tf"].value = 1
        prog["u_scene_depth"].value = 2
        vao = ctx.vertex_array(prog, [(geom.buffers["in_position"], "3f", "in_position")], geom.buffers["index"], 4)
        vao.render(ctx.TRIANGLES)
        vao.release()
        calls += 1
    return calls


GLEngine.register_drawer("volume", draw_volumes)
