"""GL capabilities renderer trees build on: custom passes, copies of the framebuffer, depth-tested full-screen
passes with pass state, targets of fixed or enclosing size, drawing into another framebuffer with another camera,
GL state snapshots, and volumes whose rays stop at what is already drawn."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

from .test_techniques import OnePass

pytestmark = pytest.mark.gl


@pytest.fixture
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(80, 60), samples=0)
    yield e
    e.release()


def camera() -> om.Camera:
    return om.Camera.look_at(eye=(0, 0, 6), center=(0, 0, 0), fov=40)


def test_a_custom_pass_draws_its_scope_and_nested_passes(engine):
    seen = []

    def custom(e, draw):
        seen.append((e.current_framebuffer is e.framebuffer, e.target_size))
        made = draw()  # the scope, as a plain pass would draw it
        flat = om.gl.Pass("flat", state=[om.gl.DepthTest(func="lequal")], shader=om.gl.Shader(flat_color=(0, 1, 0)))
        made += draw(flat)  # a nested pass, composed with this one
        return 0

    scene = om.Node("scene", [camera(), om.Node("fx", [OnePass(om.gl.Pass("mine", custom=custom)), om.Sphere()])])
    img = engine.render(scene, background=(0, 0, 0))
    assert seen == [(True, (80, 60))]
    assert tuple(img.pixel(40, 30)[:3]) == (0, 255, 0)  # the nested flat pass drew last, over the first
    passes = [(p["name"], p["draw_calls"]) for p in engine.stats["passes"]]
    assert ("opaque/mine", 0) in passes and ("opaque/mine/flat", 0) in passes  # the custom and the nested pass
    assert [p for p in passes if p[1]] == [("opaque/mine/opaque", 1), ("opaque/mine/flat/opaque", 1)]
    assert engine.stats["draw_calls"] == 2


def test_custom_pass_validation(engine):
    with pytest.raises(ValueError, match="custom must be a function"):
        om.gl.Pass("p", custom=42)
    with pytest.raises(ValueError, match="not both"):
        om.gl.Pass(
            "p", custom=lambda e, d: None, fullscreen=om.gl.FullScreen("vec4 effect(vec2 uv) { return vec4(1); }")
        )

    def bad(e, draw):
        draw("not a pass")

    scene = om.Node("scene", [camera(), om.Node("fx", [OnePass(om.gl.Pass("bad", custom=bad)), om.Sphere()])])
    with pytest.raises(TypeError, match="draw\\(\\) takes an om.gl.Pass"):
        engine.render(scene)
    with pytest.raises(RuntimeError, match="no frame is being drawn"):
        engine.copy_framebuffer(om.gl.Target("x"))


def test_copy_framebuffer_and_a_depth_tested_fullscreen_merge(engine):
    """Save colour + depth, draw something else, merge the copy back by depth: a depth sprite in a frame."""
    merge = """
        uniform sampler2D u_color; uniform sampler2D u_depth;
        vec4 effect(vec2 uv) {
            ivec2 p = ivec2(gl_FragCoord.xy);
            if (texelFetch(u_depth, p, 0).r >= 1.0) discard;
            return texelFetch(u_color, p, 0);
        }
        float effect_depth(vec2 uv) { return texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r; }"""
    copies = {}

    def custom(e, draw):
        draw()  # the red sphere, at the front left
        copies["saved"] = e.copy_framebuffer(om.gl.Target("saved")).depth_array()
        e.current_framebuffer.clear(0, 0, 0, 1, depth=1.0)
        draw(om.gl.Pass("blue", camera=om.Camera.look_at((2.0, 0, 6), (2.0, 0, 0), fov=40),
                        shader=om.gl.Shader(flat_color=(0, 0, 1))))  # fmt: skip
        effect = om.gl.FullScreen(merge, inputs={"u_color": ("saved", "color"), "u_depth": ("saved", "depth")},
                                  depth=True, depth_test="less")  # fmt: skip
        draw(om.gl.Pass("merge", items="none", fullscreen=effect))

    sphere = [om.Color(1, 0, 0), om.Sphere(center=(-1.0, 0, 0.5), radius=1.2)]
    scene = om.Node("scene", [camera(), om.Node("fx", [OnePass(om.gl.Pass("sprite", custom=custom)), *sphere])])
    img = engine.render(scene, background=(0, 0, 0))
    red = (img.array[..., 0] > 150) & (img.array[..., 2] < 60)
    blue = (img.array[..., 2] > 150) & (img.array[..., 0] < 60)
    assert red.sum() > 200 and blue.sum() > 200
    # the merged sprite keeps its own depth: where red shows, the depth is the saved one
    window = copies["saved"]
    assert np.all(window[red] < 1.0)
    with pytest.raises(ValueError, match="depth_test must be"):
        om.gl.FullScreen(merge, depth=True, depth_test="sometimes")
    with pytest.raises(ValueError, match="give depth=True"):
        om.gl.FullScreen("vec4 effect(vec2 uv) { return vec4(1); }", depth_test="less")


def test_fullscreen_passes_apply_the_pass_state(engine):
    """A StencilTest in the pass limits the full-screen triangle to the stencilled pixels."""

    def custom(e, draw):
        draw()  # writes stencil 1 where the sphere is (the scope's StencilOp)
        flat = om.gl.FullScreen("vec4 effect(vec2 uv) { return vec4(0.0, 1.0, 0.0, 1.0); }")
        draw(om.gl.Pass("green", items="none", state=[om.gl.StencilTest(func="equal", ref=1)], fullscreen=flat))

    scope = [om.gl.StencilTest(func="always", ref=1), om.gl.StencilOp(zpass="replace"), om.Color(1, 0, 0),
             om.Sphere(radius=1.0)]  # fmt: skip
    scene = om.Node("scene", [camera(), om.Node("fx", [OnePass(om.gl.Pass("stencil", custom=custom)), *scope])])
    img = engine.render(scene, background=(0, 0, 0))
    assert tuple(img.pixel(40, 30)[:3]) == (0, 255, 0)  # inside the sphere: stencil 1, painted green
    assert tuple(img.pixel(3, 3)[:3]) == (0, 0, 0)  # outside: the test failed


def test_targets_of_fixed_and_enclosing_size(engine):
    sizes = {}

    def inner(e, draw):
        sizes["inner"] = e.target_size

    def outer(e, draw):
        sizes["outer"] = e.target_size
        draw(om.gl.Pass("inner", target=om.gl.Target("in", scale=0.5, relative="enclosing"), custom=inner))

    t = om.gl.Target("fixed", size=(64, 64))
    scene = om.Node("scene", [camera(), om.Node("fx", [OnePass(om.gl.Pass("o", target=t, custom=outer)), om.Sphere()])])
    engine.render(scene)
    assert sizes == {"outer": (64, 64), "inner": (32, 32)}
    with pytest.raises(ValueError, match="size must be"):
        om.gl.Target("bad", size=(0, 10))
    with pytest.raises(ValueError, match="relative must be"):
        om.gl.Target("bad", relative="screen")


def test_an_engine_draws_into_another_engines_framebuffer_with_its_camera():
    """The compositing building block: one engine's scene drawn into another's frame, seen by its camera."""
    from omnirender.gl import GLEngine

    top = om.Camera.look_at((0, 6, 0.001), (0, 0, 0), fov=40)
    red = om.Node("red", [om.Color(1, 0, 0), om.Box(size=(3, 0.2, 0.4))])
    with GLEngine(size=(80, 60), samples=0) as host:
        guest = GLEngine(size=(1, 1), samples=0, context=host.ctx)
        drawn = {}

        def custom(e, draw):
            guest.compile(red)
            guest.draw(clear=False, camera=(e.frame_view, e.frame_projection), framebuffer=e.current_framebuffer)

        scene = om.Node("scene", [top, OnePass(om.gl.Pass("guest", custom=custom))])
        img = host.render(scene, background=(0, 0, 0))
        drawn["mask"] = img.mask
        reference = host.render(om.Node("ref", [top, red]), background=(0, 0, 0))
        assert (drawn["mask"] == reference.mask).mean() > 0.995  # same place: the host's camera was used
        assert np.allclose(img.depth[reference.mask], reference.depth[reference.mask], rtol=1e-4)
        guest.release()
    with pytest.raises(TypeError, match="moderngl Framebuffer"):
        GLEngine(size=(8, 8)).draw(framebuffer="screen")


def test_gl_state_snapshots_capture_restore_and_diff(engine):
    from omnirender.gl.engine.glstate import capture_state, preserved_state

    with engine.current():
        before = capture_state()
        with preserved_state():
            engine.ctx.enable(engine.ctx.BLEND)
            engine.ctx.depth_func = ">="
            changed = capture_state()
            names = {name for name, *_ in before.diff(changed)}
            assert {"blend", "depth_func"} <= names
        assert before.diff(capture_state()) == []  # put back
        odd = before.replace(cull_face_mode=0x0404, line_width=2.0)
        odd.restore()
        assert capture_state()["cull_face_mode"] == 0x0404
        before.restore()
        with pytest.raises(KeyError, match="unknown state"):
            before.replace(colour=1)


def test_volume_rays_end_at_what_is_already_drawn(engine):
    """An opaque sphere inside a volume: in front of it the volume blends over the sphere, behind it nothing."""
    data = np.ones((16, 16, 16), np.float32)
    blue = (0.2, 0.4, 1.0, 0.02)
    volume = om.Volume(data, spacing=2.0 / 15, transfer_function=[(0.0, blue), (1.0, blue)])
    inside = om.Node("ball", [om.Color(1, 0.8, 0), om.Sphere(radius=0.4)])
    alone = engine.render(om.Node("s", [camera(), volume]), background=(0, 0, 0))
    both = engine.render(om.Node("s", [camera(), inside, volume]), background=(0, 0, 0))
    ball = engine.render(om.Node("s", [camera(), inside]), background=(0, 0, 0))
    centre = np.asarray(both.pixel(40, 30)[:3], int)
    # the sphere shows through the volume in front of it (not hidden, not drawn over by the whole ray)
    assert centre[0] > 100 and centre[0] < ball.pixel(40, 30)[0]
    # the volume's colour there is less than the whole ray's: its rays stopped at the sphere
    blue_alone, blue_both = alone.pixel(40, 30)[2], both.pixel(40, 30)[2]
    assert blue_both < blue_alone
    assert both.depth[30, 40] <= ball.depth[30, 40] + 1e-4
