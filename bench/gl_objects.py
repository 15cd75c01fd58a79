"""GL engine speed against hand-written moderngl (issue 4).

N unit cubes (N = 100, 1,000, 10,000), each with its own transform and colour,
one directional light, 256x256, multisampling off everywhere.  Three ways:

* omnirender: ``GLEngine.render(scene)`` (compiled draw list, automatic instancing);
* naive moderngl: one draw call per cube (uniforms per cube);
* hand-instanced moderngl: one instanced draw call.

Both hand-written ways cull back faces, as the engine does for closed opaque
shapes.  The summary states the measured naive/instanced ratio: it bounds what
any instancing renderer can gain over one draw call per object.  On llvmpipe
(software GL) a draw call costs only microseconds and the per-pixel work
dominates, so the issue's >= 5x-over-naive target is out of reach even for the
hand-written instanced code there; on a hardware GPU the per-call overhead is
what instancing removes.

A frame is render + read-back of the colour image.  Also: the frame after
changing one cube's transform (incremental recompile), a 1.3-million-
triangle single mesh at 512x512 against hand-written moderngl, and the scene
as users write it: one shared ``om.TriangleSet`` cube under 10,000 nodes,
each with its own transform and its own ``om.Material`` (target: at most
1.5x hand-instanced moderngl in the same run).

Run: ``.venv/bin/python bench/gl_objects.py`` (``--quick`` for fewer frames).
"""

from __future__ import annotations

import argparse
import statistics
import time

import moderngl
import numpy as np

import omnirender as om
from omnirender.gl import GLEngine
from omnirender.gl.engine.context import gl_renderer

VS = """
#version 330
in vec3 in_position;
in vec3 in_normal;
#ifdef INSTANCED
in mat4 i_model;
in vec4 i_color;
#else
uniform mat4 i_model;
uniform vec4 i_color;
#endif
uniform mat4 u_view;
uniform mat4 u_proj;
out vec3 v_normal;
out vec3 v_pos;
out vec4 v_color;
void main() {
    vec4 eye = u_view * i_model * vec4(in_position, 1.0);
    v_pos = eye.xyz;
    v_normal = mat3(u_view) * transpose(inverse(mat3(i_model))) * in_normal;
    v_color = i_color;
    gl_Position = u_proj * eye;
}
"""

FS = """
#version 330
in vec3 v_normal;
in vec3 v_pos;
in vec4 v_color;
uniform vec3 u_light;   // direction towards the light, eye space
out vec4 f_color;
void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    vec3 v = normalize(-v_pos);
    vec3 h = normalize(u_light + v);
    float d = max(dot(n, u_light), 0.0);
    vec3 c = v_color.rgb * (0.04 + d) + vec3(0.2) * pow(max(dot(n, h), 0.0), 32.0) * step(0.0, d);
    c = clamp(c, 0.0, 1.0);
    f_color = vec4(mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c)), v_color.a);
}
"""


def cube_data(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(n, 4, 4) model matrices on a grid with random rotations, (n, 4) colours."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(n ** (1 / 3)))
    idx = np.arange(n)
    pos = np.stack([idx % side, (idx // side) % side, idx // (side * side)], axis=1).astype(np.float64)
    pos = (pos - (side - 1) / 2.0) * 1.6
    mats = np.zeros((n, 4, 4))
    for i in range(n):
        a = rng.normal(size=3)
        a /= np.linalg.norm(a)
        m = om.Rotation(float(rng.uniform(0, 360)), tuple(a)).matrix.copy()
        m[:3, 3] = pos[i]
        mats[i] = m
    colors = np.concatenate([rng.uniform(0.2, 1.0, size=(n, 3)), np.ones((n, 1))], axis=1)
    return mats, colors


def camera_for(n: int) -> om.Camera:
    side = int(np.ceil(n ** (1 / 3)))
    d = side * 1.6 * 2.2 + 3
    return om.Camera.look_at((d * 0.6, d * 0.5, d), (0, 0, 0), fov=40, near=0.5, far=d * 3)


def user_scene(mats: np.ndarray, colors: np.ndarray, camera: om.Camera) -> om.Node:
    """The way the README teaches it: one shared TriangleSet cube, each node its own Matrix and Material."""
    from omnirender.geometry import tessellate

    box = tessellate.box((1.0, 1.0, 1.0))
    cube = om.TriangleSet(box.vertices, box.indices.reshape(-1, 3), normals=box.normals)
    scene = om.Node("scene")
    scene.add(camera)
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    for i in range(len(mats)):
        scene.add(om.Node(f"cube{i}", [om.Matrix(mats[i]), om.Material(diffuse=tuple(colors[i, :3])), cube]))
    return scene


def omni_scene(mats: np.ndarray, colors: np.ndarray, camera: om.Camera) -> tuple[om.Node, list[om.Matrix]]:
    scene = om.Node("scene")
    scene.add(camera)
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    transforms = []
    for i in range(len(mats)):
        node = scene.add(om.Node(f"cube{i}"))
        transforms.append(node.add(om.Matrix(mats[i])))
        node.add(om.Color(*colors[i, :3]))
        node.add(om.Box())
    return scene, transforms


def median_time(fn, frames: int) -> float:
    times = []
    for _ in range(frames):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


class HandWritten:
    """The same cubes drawn by plain moderngl in the engine's context (naive and instanced)."""

    def __init__(self, ctx: moderngl.Context, size: tuple[int, int], mats, colors, camera: om.Camera) -> None:
        self.ctx = ctx
        self.size = size
        self.fbo = ctx.simple_framebuffer(size, components=4)
        from omnirender.gl.engine.geometry import unit_mesh

        g = unit_mesh("box")
        self.vbo = ctx.buffer(g.positions)
        self.nbo = ctx.buffer(g.normals)
        self.ibo = ctx.buffer(g.indices)
        self.naive_prog = ctx.program(vertex_shader=VS, fragment_shader=FS)
        inst_vs = VS.replace("#version 330", "#version 330\n#define INSTANCED")
        self.inst_prog = ctx.program(vertex_shader=inst_vs, fragment_shader=FS)
        view = camera.view_matrix()
        proj = camera.projection_matrix(size[0] / size[1])
        light = view[:3, :3] @ -np.array([-0.4, -0.6, -1.0])
        light /= np.linalg.norm(light)
        for prog in (self.naive_prog, self.inst_prog):
            prog["u_view"].write(view.T.astype("f4").tobytes())
            prog["u_proj"].write(proj.T.astype("f4").tobytes())
            prog["u_light"].value = tuple(light)
        self.naive_vao = ctx.vertex_array(
            self.naive_prog, [(self.vbo, "3f", "in_position"), (self.nbo, "3f", "in_normal")], self.ibo, 4
        )
        inst = np.concatenate([mats.transpose(0, 2, 1).reshape(-1, 16), colors], axis=1).astype("f4")
        self.ibuf = ctx.buffer(inst)
        self.inst_vao = ctx.vertex_array(
            self.inst_prog,
            [
                (self.vbo, "3f", "in_position"),
                (self.nbo, "3f", "in_normal"),
                (self.ibuf, "16f 4f/i", "i_model", "i_color"),
            ],
            self.ibo,
            4,
        )
        self.models = [m.T.astype("f4").tobytes() for m in mats]
        self.colors = [tuple(float(x) for x in c) for c in colors]
        self.n = len(mats)

    def _begin(self) -> None:
        self.fbo.use()
        # back-face culling, as the engine does for closed opaque shapes: a fair comparison on both sides
        self.ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        self.ctx.cull_face = "back"
        self.fbo.clear(0.16, 0.16, 0.17, 1.0)

    def _read(self) -> np.ndarray:
        return np.frombuffer(self.fbo.read(components=4), np.uint8)

    def naive(self) -> np.ndarray:
        self._begin()
        model = self.naive_prog["i_model"]
        color = self.naive_prog["i_color"]
        vao = self.naive_vao
        for m, c in zip(self.models, self.colors, strict=True):
            model.write(m)
            color.value = c
            vao.render()
        return self._read()

    def instanced(self) -> np.ndarray:
        self._begin()
        self.inst_vao.render(instances=self.n)
        return self._read()


def bench_cubes(n: int, frames: int) -> dict[str, float]:
    mats, colors = cube_data(n)
    camera = camera_for(n)
    scene, transforms = omni_scene(mats, colors, camera)
    engine = GLEngine(size=(256, 256), samples=0)
    t = time.perf_counter()
    engine.render(scene, read_depth=False)
    first = time.perf_counter() - t
    with engine.current():
        hand = HandWritten(engine.ctx, (256, 256), mats, colors, camera)
        hand.instanced()
        hand.naive()
    # interleave the three ways frame by frame so that load changes on a shared machine hit all alike
    omni_t, inst_t, naive_t = [], [], []
    for frame in range(frames):
        omni_t.append(median_time(lambda: engine.render(scene, read_depth=False), 1))
        with engine.current():
            inst_t.append(median_time(hand.instanced, 1))
            if n < 10000 or frame % 3 == 0:
                naive_t.append(median_time(hand.naive, 1))
    instanced = statistics.median(inst_t)
    naive = statistics.median(naive_t)
    rng = np.random.default_rng(5)
    changed = []
    for _ in range(max(5, frames // 2)):
        k = int(rng.integers(n))
        m = mats[k].copy()
        m[:3, 3] += rng.normal(size=3) * 0.1
        node = scene.child(f"cube{k}")
        t = time.perf_counter()
        node.remove(transforms[k])
        transforms[k] = node.insert(0, om.Matrix(m))
        engine.render(scene, read_depth=False)
        changed.append(time.perf_counter() - t)
        # only that cube's item patched: a transform replaced by a transform is a dirty bit (one row rewritten
        # in place); were it a subtree splice, its old item removed and its new one added (two rows)
        assert (engine.stats["compiled"], engine.stats["incremental"]) in {("dirty", 1), ("subtrees", 2)}, engine.stats
        # a steady frame right after, for the ratio under the same load
        omni_t.append(median_time(lambda: engine.render(scene, read_depth=False), 1))
    one_changed = statistics.median(changed)
    steady = statistics.median(omni_t)
    # the scene as users write it, interleaved with the hand-instanced draw again
    users = user_scene(mats, colors, camera)
    engine.render(users, read_depth=False)
    user_t, inst2_t = [], []
    for _ in range(frames):
        user_t.append(median_time(lambda: engine.render(users, read_depth=False), 1))
        with engine.current():
            inst2_t.append(median_time(hand.instanced, 1))
    engine.release()
    return {
        "n": n,
        "first": first,
        "omni": steady,
        "one_changed": one_changed,
        "naive": naive,
        "instanced": instanced,
        "user": statistics.median(user_t),
        "user_instanced": statistics.median(inst2_t),
    }


def bench_mesh(frames: int) -> dict[str, float]:
    k = 806  # 2 * 805^2 = 1,296,050 triangles
    x, z = np.meshgrid(np.linspace(-2, 2, k), np.linspace(-2, 2, k))
    y = 0.3 * np.sin(3 * x) * np.cos(3 * z)
    verts = np.stack([x, y, z], axis=-1).reshape(-1, 3).astype(np.float32)
    i, j = np.meshgrid(np.arange(k - 1), np.arange(k - 1), indexing="ij")
    a = (i * k + j).ravel()
    tris = np.concatenate(
        [np.stack([a, a + k, a + 1], axis=1), np.stack([a + 1, a + k, a + k + 1], axis=1)], axis=0
    ).astype(np.uint32)
    mesh = om.TriangleSet(verts, tris)
    normals = mesh.normal_array()
    camera = om.Camera.look_at((0, 4, 5), (0, 0, 0), fov=40)
    scene = om.Node("scene")
    scene.add(camera)
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    scene.add(om.Color(0.8, 0.6, 0.3))
    scene.add(mesh)
    # the same picture as the hand-written program: no shadows (the default scene self-shadows the surface)
    plain = om.Node("plain", [om.gl.ShadowMaps(enabled=False), *scene.components])
    engine = GLEngine(size=(512, 512), samples=0)
    plain_engine = GLEngine(size=(512, 512), samples=0)
    engine.render(scene, read_depth=False)
    plain_engine.render(plain, read_depth=False)
    with engine.current():
        ctx = engine.ctx
        fbo = ctx.simple_framebuffer((512, 512), components=4)
        prog = ctx.program(vertex_shader=VS, fragment_shader=FS)
        view = camera.view_matrix()
        proj = camera.projection_matrix(1.0)
        light = view[:3, :3] @ -np.array([-0.4, -0.6, -1.0])
        prog["u_view"].write(view.T.astype("f4").tobytes())
        prog["u_proj"].write(proj.T.astype("f4").tobytes())
        prog["u_light"].value = tuple(light / np.linalg.norm(light))
        prog["i_model"].write(np.eye(4, dtype="f4").tobytes())
        prog["i_color"].value = (0.8, 0.6, 0.3, 1.0)
        vao = ctx.vertex_array(
            prog,
            [(ctx.buffer(verts), "3f", "in_position"), (ctx.buffer(normals), "3f", "in_normal")],
            ctx.buffer(tris),
            4,
        )

        def hand() -> np.ndarray:
            fbo.use()
            ctx.enable(moderngl.DEPTH_TEST)
            fbo.clear(0.16, 0.16, 0.17, 1.0)
            vao.render()
            return np.frombuffer(fbo.read(components=4), np.uint8)

        hand()
        omni_t, plain_t, hand_t = [], [], []
        for _ in range(frames):
            omni_t.append(median_time(lambda: engine.render(scene, read_depth=False), 1))
            plain_t.append(median_time(lambda: plain_engine.render(plain, read_depth=False), 1))
            with engine.current():
                hand_t.append(median_time(hand, 1))
        omni = statistics.median(omni_t)
        unshadowed = statistics.median(plain_t)
        handwritten = statistics.median(hand_t)
    engine.release()
    plain_engine.release()
    return {"triangles": len(tris), "omni": omni, "plain": unshadowed, "hand": handwritten}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer frames")
    parser.add_argument("--sizes", type=int, nargs="*", default=[100, 1000, 10000])
    args = parser.parse_args()
    frames = 9 if args.quick else 25
    print("GL engine vs hand-written moderngl (256x256, MSAA off, median frame = render + colour read-back)")
    print(
        f"{'N':>6} {'omni ms':>9} {'1 changed':>10} {'naive ms':>9} {'instanced':>10} "
        f"{'omni/inst':>10} {'naive/omni':>11} {'changed/steady':>15} {'first frame':>12} {'users/inst':>11}"
    )
    results = []
    for n in args.sizes:
        r = bench_cubes(n, frames)
        results.append(r)
        print(
            f"{n:>6} {r['omni'] * 1e3:>9.2f} {r['one_changed'] * 1e3:>10.2f} {r['naive'] * 1e3:>9.2f} "
            f"{r['instanced'] * 1e3:>10.2f} {r['omni'] / r['instanced']:>10.2f} {r['naive'] / r['omni']:>11.1f} "
            f"{r['one_changed'] / r['omni']:>15.2f} {r['first'] * 1e3:>10.0f}ms "
            f"{r['user'] / r['user_instanced']:>11.2f}"
        )
    m = bench_mesh(max(5, frames // 2))
    print(
        f"single mesh of {m['triangles']:,} triangles at 512x512: omni {m['omni'] * 1e3:.1f} ms, "
        f"hand-written {m['hand'] * 1e3:.1f} ms, ratio {m['omni'] / m['hand']:.2f}; "
        f"the same picture (om.gl.ShadowMaps(enabled=False)): {m['plain'] * 1e3:.1f} ms, ratio "
        f"{m['plain'] / m['hand']:.2f}"
    )
    print(
        "targets at N=10,000: omni/inst <= 1.25, naive/omni >= 5, changed/steady <= 2, users/inst <= 1.5 "
        "(users: a shared om.TriangleSet, an om.Material per cube); mesh ratio <= 1.1 (the same picture)"
    )
    renderer = gl_renderer()
    ratios = ", ".join(f"N={r['n']}: {r['naive'] / r['instanced']:.1f}x" for r in results)
    print(f"measured naive/instanced (hand-written, both culling back faces) on {renderer}: {ratios}")
    print(
        "naive/omni >= 5 needs naive/instanced >= 5 at least: where one draw call costs microseconds (llvmpipe,"
        " software GL) and shading dominates, no instancing can reach it; omni/inst is the figure that shows"
        " the engine's own overhead"
    )


if __name__ == "__main__":
    main()
