"""Dynamic scenes at simulation speed (issue 18): thousands of objects moving every frame.

All figures come from one run, each against a baseline measured in the same
run, interleaved frame by frame so that load changes hit both sides alike:

* 10,000 nodes (``Translation``, ``Color``, a shared ``Box``), all moved every
  frame through their ``Translation`` (the Python cost of setting the offsets
  included), against the steady frame (target: at most 4x);
* one moved node, against the steady frame (at most 1.3x);
* 10,000 instances of an ``om.InstanceSet`` bound to the application's numpy
  array, all moved every frame by writing the array and calling ``touch()``,
  against the steady frame (at most 1.5x) and against hand-written moderngl
  uploading the same array into one instanced draw (at most 1.5x);
* reported: 100,000 instances at 512x512, steady and all moving; a 10,000-object
  scene seen from inside with 90 % of it outside the view, against the same
  scene entirely in view (at most 0.3x: frustum culling).

A frame is render + colour read-back, 256x256, MSAA off, shadows off (the
issue measures the update path; ``bench/shadows.py`` measures shadows).

Run: ``.venv/bin/python bench/dynamic.py`` (``--quick`` for fewer frames).
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import moderngl
import numpy as np

import omnirender as om
from omnirender.attributes.photometry import GLOBAL_AMBIENT, srgb_to_linear
from omnirender.gl import GLEngine

try:
    from omnirender.gl.engine.context import gl_renderer
except ImportError:  # the layout before issue 22 (bench/frame_cost.py measures baselines on older checkouts)
    from omnirender.gl.context import gl_renderer

SIZE = (256, 256)

VS = """
#version 330
in vec3 in_position;
in vec3 in_normal;
in mat4 i_model;
in vec4 i_color;
uniform mat4 u_view;
uniform mat4 u_proj;
out vec3 v_normal;
out vec4 v_color;
void main() {
    v_normal = mat3(u_view) * mat3(i_model) * in_normal;
    v_color = i_color;
    gl_Position = u_proj * u_view * i_model * vec4(in_position, 1.0);
}
"""

#: The picture the engine draws for this scene: OpenGL lighting of one directional light, the global
#: ambient following the colour, no specular (om.Material's default), linear colours encoded to sRGB.
FS_SAME = """
#version 330
in vec3 v_normal;
in vec4 v_color;
uniform vec3 u_light;  // towards the light, eye space
out vec4 f_color;
vec3 to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    vec3 kd = v_color.rgb;
    f_color = vec4(to_srgb(kd * (AMBIENT + max(dot(n, u_light), 0.0))), 1.0);
}
""".replace("AMBIENT", repr(GLOBAL_AMBIENT))

#: The least a hand-written program can do: one Lambert term on the display colour.
FS_MINIMAL = """
#version 330
in vec3 v_normal;
in vec4 v_color;
uniform vec3 u_light;
out vec4 f_color;
void main() {
    f_color = vec4(v_color.rgb * (0.2 + max(dot(normalize(v_normal), u_light), 0.0)), 1.0);
}
"""

LIGHT = (-0.4, -0.6, -1.0)


def grid(n: int, spacing: float = 1.5) -> np.ndarray:
    side = int(np.ceil(n ** (1 / 3)))
    idx = np.arange(n)
    pos = np.stack([idx % side, (idx // side) % side, idx // (side * side)], axis=1).astype(np.float64)
    return (pos - (side - 1) / 2.0) * spacing


def camera_for(n: int) -> om.Camera:
    d = np.ceil(n ** (1 / 3)) * 1.5 * 2.2 + 3
    return om.Camera.look_at((d * 0.6, d * 0.5, d), (0, 0, 0), fov=40, near=0.5, far=d * 3)


def timed(fn) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def node_scene(n: int) -> tuple[om.Node, list[om.Translation]]:
    pos = grid(n)
    scene = om.Node("scene", [camera_for(n), om.DirectionalLight(direction=LIGHT)])
    box = om.Box(size=1.0)
    moves = []
    rng = np.random.default_rng(0)
    for i in range(n):
        t = om.Translation(*pos[i])
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Color(*rng.uniform(0.2, 1.0, 3)), box]))
    return scene, moves


def bench_nodes(n: int, frames: int) -> dict[str, float]:
    scene, moves = node_scene(n)
    offsets = [t.offset for t in moves]
    with GLEngine(size=SIZE, samples=0, shadows=False) as engine:
        engine.render(scene, read_depth=False)
        steady, all_moved, one_moved = [], [], []
        for frame in range(frames):
            steady.append(timed(lambda: engine.render(scene, read_depth=False)))
            dy = 0.01 * (frame + 1)

            def move_all(dy: float = dy) -> None:
                for t, (x, y, z) in zip(moves, offsets, strict=True):
                    t.offset = (x, y + dy, z)
                engine.render(scene, read_depth=False)

            all_moved.append(timed(move_all))
            k = frame % n

            def move_one(dy: float = dy, k: int = k) -> None:
                x, y, z = offsets[k]
                moves[k].offset = (x, y - dy, z)
                engine.render(scene, read_depth=False)

            one_moved.append(timed(move_one))
    return {
        "steady": statistics.median(steady),
        "all": statistics.median(all_moved),
        "one": statistics.median(one_moved),
    }


class HandInstanced:
    """The same boxes drawn by plain moderngl: the array uploaded, one instanced draw, the picture read back.

    ``shading="same"`` draws the engine's picture (checked by the benchmark);
    ``"minimal"`` one Lambert term, the least a hand-written program does.
    """

    def __init__(self, ctx: moderngl.Context, n: int, camera: om.Camera, background: tuple, shading: str) -> None:
        from omnirender.gl.engine.geometry import unit_mesh

        self.ctx = ctx
        self.background = background
        self.fbo = ctx.simple_framebuffer(SIZE, components=4)
        g = unit_mesh("box")
        self.prog = ctx.program(vertex_shader=VS, fragment_shader=FS_SAME if shading == "same" else FS_MINIMAL)
        view = camera.view_matrix()
        self.prog["u_view"].write(view.T.astype("f4").tobytes())
        self.prog["u_proj"].write(camera.projection_matrix(1.0).T.astype("f4").tobytes())
        towards = -(view[:3, :3] @ np.asarray(LIGHT))
        self.prog["u_light"].value = tuple(towards / np.linalg.norm(towards))
        self.instances = ctx.buffer(reserve=n * 20 * 4, dynamic=True)
        self.vao = ctx.vertex_array(
            self.prog,
            [
                (ctx.buffer(g.positions), "3f", "in_position"),
                (ctx.buffer(g.normals), "3f", "in_normal"),
                (self.instances, "16f 4f/i", "i_model", "i_color"),
            ],  # fmt: skip
            ctx.buffer(g.indices),
            4,
        )
        self.n = n

    def frame(self, positions: np.ndarray, colors: np.ndarray) -> np.ndarray:
        data = np.zeros((self.n, 20), np.float32)
        data[:, 0] = data[:, 5] = data[:, 10] = data[:, 15] = 1.0
        data[:, 12:15] = positions
        data[:, 16:20] = colors
        self.instances.write(data.tobytes())
        self.fbo.use()
        self.ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        self.fbo.clear(*self.background, depth=1.0)
        self.vao.render(instances=self.n)
        data = self.fbo.read(components=4, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(SIZE[1], SIZE[0], 4)[::-1]


def bench_instances(n: int, frames: int, size: tuple[int, int] = SIZE) -> dict[str, float]:
    positions = grid(n)
    colors = np.concatenate([np.random.default_rng(1).uniform(0.2, 1.0, (n, 3)), np.ones((n, 1))], axis=1)
    camera = camera_for(n)
    instances = om.InstanceSet(om.Box(size=1.0), positions, colors=colors)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=LIGHT), instances])
    out: dict[str, Any] = {"steady": [], "moving": [], "same": [], "minimal": []}
    with GLEngine(size=size, samples=0, shadows=False) as engine:
        image = engine.render(scene, read_depth=False).array
        hands = {}
        if size == SIZE:
            # a hand-written program uploads linear colours it converted once (the colours do not change)
            linear = np.concatenate([srgb_to_linear(colors[:, :3]), colors[:, 3:]], axis=1)
            background = tuple(image[0, 0, :3] / 255.0) + (1.0,)
            with engine.current():
                for shading in ("same", "minimal"):
                    hands[shading] = HandInstanced(engine.ctx, n, camera, background, shading)
                hand_image = hands["same"].frame(positions, linear)
            out["agreement"] = float(np.abs(hand_image[..., :3].astype(int) - image[..., :3]).max())
        for _ in range(frames):
            out["steady"].append(timed(lambda: engine.render(scene, read_depth=False)))

            def move() -> None:
                positions[:, 1] += 0.01  # the application's own array, written in place
                instances.touch()
                engine.render(scene, read_depth=False)

            out["moving"].append(timed(move))
            for shading, hand in hands.items():
                with engine.current():
                    out[shading].append(timed(lambda hand=hand: hand.frame(positions, linear)))
    return {k: statistics.median(v) if isinstance(v, list) else v for k, v in out.items() if v != []}


def bench_culling(n: int, frames: int) -> dict[str, float]:
    """The node scene from outside (all in view) and from inside, down a corridor between the boxes.

    From inside, about 10 % of the boxes are in view; the same view is also
    timed with culling (and front-to-back sorting) switched off, to show what
    culling itself saves.
    """
    from omnirender.gl.engine import drawer

    d = np.ceil(n ** (1 / 3)) * 1.5 / 2
    inside = om.Camera.look_at((0, 0, -0.3 * d), (0.1, 0.2, d), fov=50, near=0.1, far=d * 4)
    out: dict[str, list[float]] = {"outside": [], "inside": [], "unculled": []}
    visible = {}
    sort_min = drawer.SORT_MIN
    views = {}
    for label in out:  # one scene and engine per view, frames interleaved
        scene, _ = node_scene(n)
        if label != "outside":
            scene.remove(scene.items[0])
            scene.insert(0, inside)
        views[label] = (scene, GLEngine(size=SIZE, samples=0, shadows=False))
    try:
        for frame in range(frames + 1):
            for label, (scene, engine) in views.items():
                drawer.SORT_MIN = 10**12 if label == "unculled" else sort_min
                try:
                    elapsed = timed(lambda engine=engine, scene=scene: engine.render(scene, read_depth=False))
                finally:
                    drawer.SORT_MIN = sort_min
                if frame:  # the first frame compiles
                    out[label].append(elapsed)
                else:
                    visible[label] = sum(p["items"] for p in engine.stats["passes"])
    finally:
        for _, engine in views.values():
            engine.release()
    result = {k: statistics.median(v) for k, v in out.items()}
    result["visible_inside"] = visible["inside"] / n
    return result


def setter_costs() -> str:
    """Microseconds per assignment of Translation.offset, Rotation.angle, Scaling.factors (validation included)."""
    import timeit

    scene = om.Node("scene")
    out = []
    for t, name, value in (
        (om.Translation(0, 0, 0), "offset", (1.0, 2.0, 3.0)),
        (om.Rotation(10, (0, 1, 0)), "angle", 42.0),
        (om.Scaling(1), "factors", (2.0, 0.5, 1.0)),
    ):
        scene.add(om.Node(name, [t]))
        seconds = min(
            timeit.repeat(lambda t=t, name=name, value=value: setattr(t, name, value), number=20000, repeat=5)
        )
        out.append(f"{type(t).__name__}.{name} {seconds / 20000 * 1e6:.1f} us")
    return ", ".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer frames")
    args = parser.parse_args()
    frames = 7 if args.quick else 21
    renderer = gl_renderer()
    print(f"dynamic scenes, {SIZE[0]}x{SIZE[1]}, MSAA and shadows off, median frame = render + read-back ({renderer})")
    print("setting one transform parameter of a node in a graph:", setter_costs())
    r = bench_nodes(10_000, frames)
    print(
        f"10,000 nodes: steady {r['steady'] * 1e3:.1f} ms; all moved {r['all'] * 1e3:.1f} ms = "
        f"{r['all'] / r['steady']:.2f}x (target <= 4); one moved {r['one'] * 1e3:.1f} ms = "
        f"{r['one'] / r['steady']:.2f}x (target <= 1.3)"
    )
    r = bench_instances(10_000, frames)
    print(
        f"10,000 instances: steady {r['steady'] * 1e3:.1f} ms; all moved {r['moving'] * 1e3:.1f} ms = "
        f"{r['moving'] / r['steady']:.2f}x steady (target <= 1.5), {r['moving'] / r['same']:.2f}x hand-written "
        f"moderngl uploading the same array and drawing the same picture ({r['same'] * 1e3:.1f} ms, largest "
        f"channel difference {r['agreement']:.0f}/255; target <= 1.5); {r['moving'] / r['minimal']:.2f}x a "
        f"hand-written program with one Lambert term ({r['minimal'] * 1e3:.1f} ms)"
    )
    r = bench_instances(100_000, max(3, frames // 3), size=(512, 512))
    print(f"100,000 instances at 512x512: steady {r['steady'] * 1e3:.1f} ms, all moved {r['moving'] * 1e3:.1f} ms")
    r = bench_culling(10_000, frames)
    print(
        f"10,000 objects seen from inside ({r['visible_inside']:.0%} drawn): {r['inside'] * 1e3:.1f} ms = "
        f"{r['inside'] / r['outside']:.2f}x the scene fully in view ({r['outside'] * 1e3:.1f} ms; target <= 0.3); "
        f"{r['inside'] / r['unculled']:.2f}x the same inside view without culling ({r['unculled'] * 1e3:.1f} ms)"
    )


if __name__ == "__main__":
    main()
