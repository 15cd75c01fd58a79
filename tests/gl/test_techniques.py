"""GL techniques run their passes at draw time: nesting, DAG sharing, pass descriptions, targets, image space."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from pixels import assert_rgb

import omnirender as om

pytestmark = pytest.mark.gl

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def load_example(name: str):
    sys.path.insert(0, str(EXAMPLES))
    try:
        spec = importlib.util.spec_from_file_location(name.replace(".py", ""), EXAMPLES / name)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(EXAMPLES))


@pytest.fixture
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(96, 72), samples=0)
    yield e
    e.release()


class Counted(om.Technique):
    """A generic technique that counts its pass-control calls (in a list it shares)."""

    __slots__ = ("log",)

    def __init__(self, passes: int, log: list) -> None:
        super().__init__(passes=passes)
        object.__setattr__(self, "log", log)

    def start(self, engine):
        self.log.append("start")

    def prepare_pass(self, engine):
        self.log.append(("prepare", engine.current_pass))

    def stop(self, engine):
        self.log.append("stop")


def camera() -> om.Camera:
    return om.Camera.look_at(eye=(0, 0, 6), center=(0, 0, 0), fov=40)


def passes_drawing(engine) -> list[tuple[str, int]]:
    return [(p["name"], p["draw_calls"]) for p in engine.stats["passes"] if p["draw_calls"]]


# --- pass control at draw time ---------------------------------------------------------------


def test_pass_control_runs_on_replayed_frames(engine):
    log: list = []
    scene = om.Node("scene", [camera(), om.Node("fx", [Counted(2, log), om.Sphere()])])
    engine.render(scene)
    assert engine.stats["compiled"] is True
    first = list(log)
    log.clear()
    engine.render(scene)
    assert engine.stats["compiled"] is False  # replayed from the compiled scopes
    assert log == first == ["start", ("prepare", 0), ("prepare", 1), "stop"]
    assert passes_drawing(engine)[-2:] == [("opaque/Counted[0]/opaque", 1), ("opaque/Counted[1]/opaque", 1)]


def test_a_technique_declining_passes_draws_only_the_others(engine):
    """VRS pass protocol: prepare_pass returning False skips that pass (drawn nowhere, finish_pass not called),
    on the first frame and on replayed ones."""

    class Skipping(Counted):
        __slots__ = ()

        def prepare_pass(self, engine):
            super().prepare_pass(engine)
            return engine.current_pass in (1, 3)

        def finish_pass(self, engine):
            self.log.append(("finish", engine.current_pass))

    log: list = []
    scene = om.Node("scene", [camera(), om.Node("fx", [Skipping(4, log), om.Sphere()])])
    for _ in range(2):
        log.clear()
        engine.render(scene)
        assert [p for p in passes_drawing(engine) if "Skipping" in p[0]] == [
            ("opaque/Skipping[1]/opaque", 1),
            ("opaque/Skipping[3]/opaque", 1),
        ]
        assert [entry for entry in log if entry[0] == "finish"] == [("finish", 1), ("finish", 3)]
        assert log.count("stop") == 1 and len([e for e in log if e[0] == "prepare"]) == 4


def test_nested_techniques_nest_passes_as_draw_calls():
    from omnirender.gl import GLEngine

    outer_log: list = []
    inner_log: list = []
    inner = om.Node("inner", [Counted(2, inner_log), om.Sphere()])
    scene = om.Node("scene", [camera(), om.Node("outer", [Counted(3, outer_log), inner])])
    with GLEngine(size=(64, 48), samples=0) as e:
        e.render(scene)
        sphere_passes = [(name, calls) for name, calls in passes_drawing(e) if name.count("Counted") == 2]
        assert len(sphere_passes) == 6 and all(calls == 1 for _, calls in sphere_passes)
        assert e.stats["draw_calls"] == 6
        assert outer_log.count("start") == 1 and inner_log.count("start") == 3


def test_a_technique_shared_at_two_levels_of_a_dag_runs_nine_passes(engine):
    t = Counted(3, [])
    inner = om.Node("inner", [t, om.Sphere()])
    scene = om.Node("scene", [camera(), om.Node("outer", [t, inner])])
    engine.render(scene)
    assert engine.stats["draw_calls"] == 9
    engine.render(scene)
    assert engine.stats["draw_calls"] == 9  # also when replayed


def test_an_unsupported_technique_is_ignored_and_its_scope_drawn_once(engine):
    class NotHere(om.Technique):
        __slots__ = ()

        def supported(self, engine):
            return False

    scene = om.Node("scene", [camera(), om.Node("n", [NotHere(passes=4), om.Sphere()])])
    engine.render(scene)
    assert engine.stats["draw_calls"] == 1 and len(engine.scopes) == 1


def test_gl_techniques_are_ignored_by_other_engines():
    ex = load_example("06_outline_technique.py")
    with_outline = om.trace(ex.build_scene(outline=True))
    without = om.trace(ex.build_scene(outline=False))
    shapes = lambda prog: [type(o).__name__ for op, o in prog if op == "eval"]  # noqa: E731
    assert shapes(with_outline) == shapes(without)  # a generic engine evaluates the scope once
    assert not ex.Outline().supported(om.Engine())


def test_the_default_technique_is_replaceable():
    from omnirender.gl import GLEngine

    class OpaqueOnly(om.gl.GLTechnique):
        __slots__ = ()

        def prepare_pass(self, engine):
            engine.set_pass(om.gl.Pass("solid", items="opaque"))

    scene = om.Node("scene", [camera(), om.Color(1, 0, 0), om.Sphere(center=(-1, 0, 0), radius=0.6)])
    scene.add(om.Node("glass", [om.Color(0, 0, 1, a=0.5), om.Sphere(center=(1, 0, 0), radius=0.6)]))
    with GLEngine(size=(96, 72), samples=0, technique=OpaqueOnly()) as e:
        img = e.render(scene, background=(0, 0, 0))
        assert [p["name"] for p in e.stats["passes"]] == ["solid"]
    assert img.pixel(30, 36)[0] > 150 and img.pixel(66, 36)[2] == 0  # the translucent sphere is not drawn
    default = om.render(scene, engine="gl", size=(96, 72), samples=0, background=(0, 0, 0))
    assert default.pixel(66, 36)[2] > 60
    with pytest.raises(TypeError, match="technique must be an om.Technique"):
        GLEngine(size=(8, 8), technique="forward")


# --- the outline example ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def outline_renders():
    ex = load_example("06_outline_technique.py")
    from omnirender.gl import GLEngine

    with GLEngine(size=(240, 160), samples=0) as e:
        plain = e.render(ex.build_scene(outline=False), background=(1, 1, 1))
        outlined = e.render(ex.build_scene(outline=True), background=(1, 1, 1))
        passes = passes_drawing(e)
    return ex, plain, outlined, passes


def test_outline_pixels_appear_only_around_the_scoped_subgraph(outline_renders):
    ex, plain, outlined, _ = outline_renders
    changed = np.abs(plain.array[..., :3].astype(int) - outlined.array[..., :3].astype(int)).max(axis=2) > 40
    assert changed.sum() > 150  # an outline was drawn
    ring = om.render(_only(ex, "ring"), engine="gl", size=(240, 160), samples=0, background=(0, 0, 0)).mask
    ball = om.render(_only(ex, "ball"), engine="gl", size=(240, 160), samples=0, background=(0, 0, 0)).mask
    near_ring = _dilate(ring, 4)
    assert not (changed & ~near_ring).any()  # nothing changes away from the outlined ring
    assert not (changed & _dilate(ball, 4) & ~near_ring).any()  # the ball, outside the technique, has none
    dark = outlined.array[..., :3].max(axis=2) < 60
    assert (dark & changed).sum() > 0.8 * changed.sum()  # the outline is the flat dark colour


def _only(ex, name: str) -> om.Node:
    scene = ex.build_scene(outline=False)
    keep = om.Node("scene", [c for c in scene.items if not isinstance(c, om.Node)])
    for child in scene.children:
        for node in child.walk():
            if node.name == name:
                keep.add(node)
    return keep


def _dilate(mask: np.ndarray, r: int) -> np.ndarray:
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= np.roll(np.roll(mask, dy, axis=0), dx, axis=1)
    return out


def test_outline_draw_calls_per_pass(outline_renders):
    _, _, _, passes = outline_renders
    assert ("opaque/outline/opaque", 1) in passes and ("opaque/shapes/opaque", 1) in passes
    assert dict(passes)["opaque"] == 2  # floor and ball, outside the technique: drawn once


@pytest.mark.povray
def test_outline_scene_renders_in_povray_without_outlines():
    ex = load_example("06_outline_technique.py")
    a = om.render(ex.build_scene(outline=True), engine="povray", size=(120, 80))
    b = om.render(ex.build_scene(outline=False), engine="povray", size=(120, 80))
    assert np.array_equal(a.array, b.array)


# --- pass descriptions ----------------------------------------------------------------------------


class OnePass(om.gl.GLTechnique):
    """A technique with one described pass (made per test)."""

    __slots__ = ("description",)

    def __init__(self, description: om.gl.Pass) -> None:
        super().__init__(passes=1)
        object.__setattr__(self, "description", description)

    def prepare_pass(self, engine):
        engine.set_pass(self.description)


def test_flat_color_unlit_and_depth_only_shading(engine):
    def render(shader):
        t = OnePass(om.gl.Pass("p", shader=shader))
        scene = om.Node("scene", [camera(), om.Node("fx", [t, om.Material(diffuse=(0.2, 0.8, 0.3)), om.Sphere()])])
        return engine.render(scene, background=(0, 0, 0))

    flat = render(om.gl.Shader(flat_color=(1.0, 0.5, 0.0)))
    assert_rgb(flat.pixel(48, 36), (255, 127.5, 0), tolerance=0.5)  # 0.5 * 255: 127 or 128 by the driver's rounding
    assert_rgb(flat.pixel(20, 36), (0, 0, 0))
    unlit = render(om.gl.Shader(unlit=True))
    assert tuple(unlit.pixel(48, 36)[:3]) == pytest.approx((51, 204, 77), abs=1)  # the diffuse colour itself
    assert_rgb(unlit.pixel(40, 30), unlit.pixel(56, 44))  # no shading
    depth = render(om.gl.Shader(depth_only=True))
    assert np.isfinite(depth.depth[36, 48]) and max(depth.pixel(48, 36)[:3]) <= 1


def test_state_overrides_and_fallbacks_apply_to_the_pass(engine):
    sphere = om.Sphere()
    t = OnePass(om.gl.Pass("front", state=[om.gl.CullFace("back")], fallback=[om.gl.ColorMask(red=False)]))
    scene = om.Node("scene", [camera(), om.Node("fx", [t, om.Color(1, 1, 1), sphere])])
    img = engine.render(scene, background=(0, 0, 0))
    r, g, b, _ = img.pixel(48, 36)
    assert r == 0 and g > 150 and b > 150  # red masked where the item set no colour mask


def test_pass_masks_and_predicates_select_items(engine):
    red = om.Node("red", [om.Color(1, 0, 0), om.Sphere(center=(-1.2, 0, 0), radius=0.5)], groups="red")
    blue = om.Node("blue", [om.Color(0, 0, 1), om.Sphere(center=(1.2, 0, 0), radius=0.5)], groups="blue")
    t = OnePass(om.gl.Pass("reds", mask="red"))
    scene = om.Node("scene", [camera(), om.Node("fx", [t, red, blue])])
    img = engine.render(scene, background=(0, 0, 0))
    assert img.pixel(28, 36)[0] > 100 and img.pixel(68, 36)[2] == 0
    picky = OnePass(om.gl.Pass("right", select=lambda item: item.path.endswith("blue")))
    img = engine.render(om.Node("scene", [camera(), om.Node("fx", [picky, red, blue])]), background=(0, 0, 0))
    assert img.pixel(28, 36)[0] == 0 and img.pixel(68, 36)[2] > 100


def test_camera_override_draws_from_another_view(engine):
    top = om.Camera.look_at(eye=(0, 6, 0.001), center=(0, 0, 0), fov=40)
    t = OnePass(om.gl.Pass("top", camera=top))
    box = om.Box(size=(3, 0.2, 0.4))  # wide, flat and shallow: seen from above it is a thin horizontal bar
    scene = om.Node("scene", [camera(), om.Node("fx", [t, box])])
    from_top = engine.render(scene, background=(0, 0, 0)).mask
    reference = engine.render(om.Node("scene", [top, box]), background=(0, 0, 0)).mask
    assert (from_top == reference).mean() > 0.99


def test_offscreen_target_with_two_attachments_and_depth_feeds_a_fullscreen_pass(engine):
    normals = (
        "layout(location = 1) out vec4 f_normal;"
        "void pass_fragment(inout vec4 color, vec3 P, vec3 N) { f_normal = vec4(N * 0.5 + 0.5, 1.0); }"
    )
    show = """
        uniform sampler2D u_normal; uniform sampler2D u_depth; uniform sampler2D u_color;
        vec4 effect(vec2 uv) {
            if (texture(u_depth, uv).r >= 1.0) return vec4(0.0, 0.0, 0.0, 1.0);
            return uv.x < 0.5 ? texture(u_normal, uv) : texture(u_color, uv);
        }"""

    class GBuffer(om.gl.GLTechnique):
        __slots__ = ()

        def __init__(self):
            super().__init__(passes=2)

        def prepare_pass(self, engine):
            if engine.current_pass == 0:
                target = om.gl.Target("g", colors=("color", "normal"), depth=True)
                engine.set_pass(om.gl.Pass("geometry", target=target, clear=om.gl.Clear(),
                                           shader=om.gl.Shader(fragment=normals)))  # fmt: skip
            else:
                inputs = {"u_normal": ("g", "normal"), "u_depth": ("g", "depth"), "u_color": ("g", "color")}
                engine.set_pass(om.gl.Pass("show", fullscreen=om.gl.FullScreen(show, inputs=inputs)))

    scene = om.Node("scene", [camera(), om.Node("fx", [GBuffer(), om.Color(1, 0, 0), om.Sphere(radius=1.5)])])
    img = engine.render(scene, background=(0.5, 0.5, 0.5))
    # left half: the eye-space normal (here = world: the camera looks down -z), as om.pick finds it analytically
    (hit, *_) = om.pick(scene, pixel=(40, 36), size=(96, 72))
    expected = (np.asarray(hit.normal) * 0.5 + 0.5) * 255
    assert np.abs(np.asarray(img.pixel(40, 36)[:3], float) - expected).max() < 8
    c = img.pixel(60, 36)[:3]
    assert c[0] > 150 and c[1] < 40  # right half: the lit red colour
    assert tuple(img.pixel(2, 2)[:3]) == (0, 0, 0)  # where the depth texture says nothing was drawn
    g = engine.target("g")
    assert set(g.colors) == {"color", "normal"} and g.depth_array()[36, 48] < 1.0
    assert [p["name"] for p in engine.stats["passes"] if p["technique"] == "GBuffer"] == [
        "opaque/geometry",
        "opaque/show",
    ]


def test_gpu_objects_are_rebuilt_only_when_the_description_changes(engine):
    class Offscreen(om.gl.GLTechnique):
        __slots__ = ("dtype",)

        def __init__(self, dtype="f1"):
            super().__init__(passes=1)
            self.dtype = dtype

        def prepare_pass(self, engine):
            engine.set_pass(om.gl.Pass("off", target=om.gl.Target("t", dtype=self.dtype), clear=om.gl.Clear()))

    t = Offscreen()
    scene = om.Node("scene", [camera(), om.Node("fx", [t, om.Sphere()])])
    engine.render(scene)
    first = engine.target("t")
    engine.render(scene)
    assert engine.target("t") is first  # same description: the same GPU target, only drawn again
    t.dtype = "f2"
    engine.render(scene)
    assert engine.target("t") is not first and engine.target("t").description.dtype == "f2"
    assert first.colors == {}  # the old one was released


def test_ping_pong_chain_of_effects(engine):
    chain = om.gl.PingPong("post")
    invert = (
        "uniform sampler2D u_image;"
        "vec4 effect(vec2 uv) { vec4 c = texture(u_image, uv); return vec4(1.0 - c.rgb, 1.0); }"
    )
    copy = "uniform sampler2D u_image; vec4 effect(vec2 uv) { return texture(u_image, uv); }"

    class Post(om.gl.GLTechnique):
        __slots__ = ()

        def __init__(self):
            super().__init__(passes=5)  # scene, 3 inversions, copy out

        def prepare_pass(self, engine):
            step = engine.current_pass
            if step == 0:
                engine.set_pass(om.gl.Pass("scene", target=chain.write(0), clear=om.gl.Clear((0, 0, 0, 1))))
            elif step < 4:
                effect = om.gl.FullScreen(invert, inputs={"u_image": (chain.read(step).name, "color")})
                engine.set_pass(om.gl.Pass(f"invert{step}", items="none", target=chain.write(step), fullscreen=effect))
            else:
                effect = om.gl.FullScreen(copy, inputs={"u_image": (chain.read(step).name, "color")})
                engine.set_pass(om.gl.Pass("out", items="none", fullscreen=effect))

    lit = [camera(), om.PointLight(position=(2, 3, 4)), om.Color(0.9, 0.5, 0.2), om.Sphere()]
    plain = engine.render(om.Node("scene", list(lit)), background=(0, 0, 0)).array[..., :3].astype(int)
    post = engine.render(om.Node("scene", [*lit[:2], om.Node("fx", [Post(), *lit[2:]])]), background=(0, 0, 0))
    assert np.abs((255 - plain) - post.array[..., :3].astype(int)).max() <= 2  # odd number of inversions
    names = [p["name"] for p in engine.stats["passes"] if p["technique"] == "Post"]
    assert names == ["opaque/scene", "opaque/invert1", "opaque/invert2", "opaque/invert3", "opaque/out"]


def test_timer_queries_report_gpu_time_per_pass():
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [camera(), om.Node("fx", [Counted(2, []), om.Sphere()])])
    with GLEngine(size=(64, 48), samples=0, timing=True) as e:
        e.render(scene)
        times = [p["gpu_ms"] for p in e.stats["passes"]]
    assert all(isinstance(t, float) and t >= 0.0 for t in times) and sum(times) > 0.0
    with GLEngine(size=(64, 48), samples=0) as e:
        e.render(scene)
        assert all(p["gpu_ms"] is None for p in e.stats["passes"])


# --- bad input ---------------------------------------------------------------------------------------


def test_pass_descriptions_are_validated_with_the_fix():
    with pytest.raises(ValueError, match="items must be"):
        om.gl.Pass("p", items="solid")
    with pytest.raises(ValueError, match="state takes GL state attributes"):
        om.gl.Pass("p", state=[om.Color(1, 0, 0)])
    with pytest.raises(ValueError, match="camera must be"):
        om.gl.Pass("p", camera=np.eye(3))
    with pytest.raises(ValueError, match="pass_vertex"):
        om.gl.Shader(vertex="void main() {}")
    with pytest.raises(ValueError, match="flat_color"):
        om.gl.Shader(flat_color=(2, 0, 0))
    with pytest.raises(ValueError, match="not finite"):
        om.gl.Shader(uniforms={"u_x": float("nan")})
    with pytest.raises(ValueError, match="dtype"):
        om.gl.Target("t", dtype="f8")
    with pytest.raises(ValueError, match="effect"):
        om.gl.FullScreen("void main() {}")
    with pytest.raises(om.MaskError, match="expected a group name"):
        om.gl.Pass("p", mask="red &")


def test_misused_passes_fail_with_clear_messages(engine):
    with pytest.raises(RuntimeError, match="call it from a technique's prepare_pass"):
        engine.set_pass(om.gl.Pass("p"))
    bad = OnePass(
        om.gl.Pass("p", shader=om.gl.Shader(fragment="void pass_fragment(inout vec4 c, vec3 P, vec3 N) { c = nope; }"))
    )
    with pytest.raises(ValueError, match="check the GLSL snippet"):
        engine.render(om.Node("scene", [camera(), om.Node("fx", [bad, om.Sphere()])]))
    missing = OnePass(om.gl.Pass("p", fullscreen=om.gl.FullScreen("vec4 effect(vec2 uv) { return vec4(1.0); }",
                                                                  inputs={"u_x": ("nowhere", "color")})))  # fmt: skip
    with pytest.raises(KeyError, match="no offscreen target 'nowhere'"):
        engine.render(om.Node("scene", [camera(), om.Node("fx", [missing, om.Sphere()])]))
    ok = engine.render(om.Node("scene", [camera(), om.Color(0, 1, 0), om.Sphere()]), background=(0, 0, 0))
    assert ok.pixel(48, 36)[1] > 100  # the engine is still usable afterwards
