"""GL-specific attributes (om.gl), light switch and state restoration when attributes are popped."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(64, 48))
    yield e
    e.release()


def base() -> om.Node:
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 5), fov=40))
    s.add(om.DirectionalLight(direction=(0, 0, -1), casts_shadows=False))  # depth and state tests, not shadows
    return s


def near_red_far_blue(*attrs) -> om.Node:
    s = base()
    a = s.add(om.Node("near"))
    a.add(om.Color(1, 0, 0))
    a.add(om.Box(size=(1, 1, 0.1), center=(0, 0, 1)))
    b = s.add(om.Node("far"))
    for attr in attrs:
        b.add(attr)
    b.add(om.Color(0, 0, 1))
    b.add(om.Box(size=(2, 2, 0.1), center=(0, 0, -1)))
    return s


def centre(img) -> tuple[int, int, int, int]:
    return img.pixel(32, 24)


def test_depth_test_off_draws_over_nearer_shapes(engine):
    assert centre(engine.render(near_red_far_blue()))[0] > 200
    r, g, b, _ = centre(engine.render(near_red_far_blue(om.gl.DepthTest(False))))
    assert b > 200 and r < 30


def test_depth_func_greater_keeps_only_farther_fragments(engine):
    img = engine.render(near_red_far_blue(om.gl.DepthTest(func="always")))
    assert centre(img)[2] > 200


def test_color_mask_limits_channels(engine):
    s = base()
    s.add(om.gl.ColorMask(red=True, green=False, blue=False))
    s.add(om.Color(1, 1, 1))
    s.add(om.Box(size=(2, 2, 0.1)))
    r, g, b, _ = centre(engine.render(s, background=(0, 0, 0)))
    assert r > 200 and g == 0 and b == 0


def test_cull_front_shows_the_inside(engine):
    s = base()
    s.add(om.gl.CullFace("front"))
    s.add(om.Color(1, 1, 1))
    s.add(om.Sphere(radius=1))
    img = engine.render(s)
    # back faces only: the far side of the sphere, about radius further away
    assert img.depth[24, 32] == pytest.approx(6.0, rel=0.02)


def test_depth_mask_off_does_not_write_depth(engine):
    s = base()
    s.add(om.gl.DepthMask(False))
    s.add(om.Color(1, 1, 1))
    s.add(om.Box(size=(2, 2, 0.1)))
    img = engine.render(s)
    assert centre(img)[0] > 200 and np.isinf(img.depth[24, 32])


def test_polygon_offset_puts_a_coplanar_decal_in_front(engine):
    s = base()
    s.add(om.Color(0, 0, 1))
    s.add(om.Rectangle(size=(2, 2)))
    d = s.add(om.Node("decal"))
    d.add(om.gl.PolygonOffset(-1.0, -4.0))
    d.add(om.Color(1, 0, 0))
    d.add(om.Rectangle(size=(1, 1)))
    s.insert(2, om.Rotation(90, (1, 0, 0)))
    r, g, b, _ = centre(engine.render(s))
    assert r > 200 and b < 30


def test_stencil_masks_later_shapes(engine):
    if not engine.has_stencil:
        pytest.skip("no stencil buffer on this driver")
    s = base()
    w = s.add(om.Node("write"))
    w.add(om.gl.ColorMask(False, False, False, False))
    w.add(om.gl.DepthMask(False))
    w.add(om.gl.StencilTest(func="always", ref=1))
    w.add(om.gl.StencilOp(zpass="replace"))
    w.add(om.Box(size=(0.6, 0.6, 0.1)))
    t = s.add(om.Node("test"))
    t.add(om.gl.StencilTest(func="equal", ref=1))
    t.add(om.Color(0, 1, 0))
    t.add(om.Box(size=(3, 3, 0.1), center=(0, 0, -0.5)))
    img = engine.render(s, background=(0, 0, 0))
    assert centre(img)[1] > 200
    assert img.pixel(5, 24)[1] == 0  # outside the stencil shape nothing was drawn
    assert img.pixel(5, 24)[0] == 0


def test_popping_restores_state(engine):
    s = base()
    a = s.add(om.Node("special"))
    a.add(om.gl.DepthTest(False))
    a.add(om.gl.Blend())
    a.add(om.gl.CullFace("front"))
    a.add(om.Sphere())
    s.add(om.Torus())
    s.add(om.Box())
    engine.compile(s)
    special, plain, box = engine.draw_items
    value = lambda item, kind: item.state.value(kind)  # noqa: E731
    assert value(special, om.gl.DepthTest) is None and value(special, om.gl.Blend) is not None
    assert value(special, om.gl.CullFace) == "front"
    assert value(plain, om.gl.DepthTest) == "less" and value(plain, om.gl.Blend) is None
    assert value(plain, om.gl.CullFace) == "back"  # the torus's closed triangle set is culled too
    assert special.transparent and not plain.transparent
    assert value(box, om.gl.CullFace) == "back"  # closed opaque native shapes cull their back faces automatically


def test_gl_attributes_are_ignored_by_other_engines():
    s = near_red_far_blue(om.gl.DepthTest(False), om.gl.StencilTest())
    assert om.trace(s)  # a generic engine pushes them passively


def test_light_switch_turns_lights_off_for_a_subgraph(engine):
    s = base()
    lit = s.add(om.Node("lit"))
    lit.add(om.Color(1, 1, 1))
    lit.add(om.Box(size=(1, 1, 0.1), center=(-1, 0, 0)))
    dark = s.add(om.Node("dark"))
    dark.add(om.LightSwitch(on=False))
    dark.add(om.Color(1, 1, 1))
    dark.add(om.Box(size=(1, 1, 0.1), center=(1, 0, 0)))
    img = engine.render(s)
    left = img.pixel(32 - 12, 24)[0]
    right = img.pixel(32 + 12, 24)[0]
    assert left > 200 and right < left / 2
    assert engine.lights() == []  # nothing stays active after the traversal


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
def test_sixteen_point_lights(engine):
    s = base()
    s.remove(s.components[1])
    for i in range(16):
        a = 2 * np.pi * i / 16
        s.add(om.PointLight(position=(np.cos(a) * 2, np.sin(a) * 2, 2), intensity=0.08))
    s.add(om.Color(1, 1, 1))
    s.add(om.Sphere())
    img = engine.render(s)
    r = img.array[:, :, 0].astype(int)
    assert r[24, 32] > 100
    # symmetric lights give a symmetric image
    assert abs(int(r[24, 20]) - int(r[24, 43])) <= 4  # pixel centres mirror around x = 31.5


# --- declarative GL state: ScissorTest, AlphaTest, and a state defined in one class ---------------------


def test_scissor_test_limits_drawing_to_a_rectangle_from_the_top_left(engine):
    s = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 5)), om.Color(1, 1, 1)])
    cut = s.add(om.Node("cut", [om.gl.ScissorTest((10, 5, 20, 30)), om.Box(size=(4, 4, 0.1))]))
    s.add(om.Node("after", [om.Color(0, 0, 1), om.Sphere(center=(0, -1.5, 1), radius=0.3)]))
    img = engine.render(s, background=(0, 0, 0))
    white = img.array[..., 0] > 200
    ys, xs = np.nonzero(white)
    assert (xs.min(), xs.max(), ys.min(), ys.max()) == (10, 29, 5, 34)  # exactly the box (x, y, w, h)
    assert img.array[..., 2].max() > 150  # the scissor was popped with its node: the sphere after it is whole
    cut.items[0].enabled = False
    assert (engine.render(s, background=(0, 0, 0)).array[..., 0] > 200).sum() > white.sum()
    with pytest.raises(ValueError, match="width must be >= 1"):
        om.gl.ScissorTest((0, 0, 0, 5))
    assert om.trace(s)  # other engines push it passively


def test_alpha_test_cuts_out_texels_and_keeps_depth(engine):
    checker = np.zeros((8, 8, 4), np.uint8)
    checker[..., :3] = 255
    checker[..., 3] = np.where((np.indices((8, 8)).sum(axis=0) % 2) == 0, 255, 0)
    s = om.Node("scene", [om.Camera.look_at(eye=(0, 5, 0.001), fov=40)])
    leaf = s.add(om.Node("leaf", [om.Texture(checker, filter="nearest", mipmap=False), om.Color(1, 1, 1)]))
    leaf.add(om.gl.AlphaTest("greater", 0.5))
    leaf.add(om.Rectangle(size=(2, 2)))
    img = engine.render(s, background=(0, 0, 0))
    leaf.items[2].enabled = False
    solid = engine.render(s, background=(0, 0, 0))
    ys, xs = np.nonzero(img.array[..., 0] > 200)
    inside = (slice(ys.min() + 1, ys.max()), slice(xs.min() + 1, xs.max()))
    holes = img.array[inside][..., 0] < 30
    assert 0.35 < holes.mean() < 0.65  # half the texels are cut out
    # without the test the texture's alpha blends (the one appearance model): the same picture, drawn see-through
    assert np.mean((solid.array[inside][..., 0] < 30) == holes) > 0.97
    depth = img.depth[inside]
    assert np.isinf(depth[holes]).all() and np.isfinite(depth[~holes]).all()  # cut-outs write no depth
    with pytest.raises(ValueError, match="ref must be in"):
        om.gl.AlphaTest(ref=2)


def test_a_gl_state_defined_in_one_class_reaches_capture_apply_and_shader(engine):
    applied: list = []

    class Tint(om.gl.GLState):
        """Scales the surface colour in the shader and records its GL calls: nothing else is edited."""

        __slots__ = ("factor",)
        default = None
        fragment_code = "uniform float u_tint;\n"
        fragment_main = "base.rgb *= u_tint;"

        def __init__(self, factor: float = 0.5) -> None:
            super().__init__()
            self.factor = float(factor)

        def capture(self):
            return self.factor

        @classmethod
        def apply(cls, gl, value):
            applied.append(value)

        @classmethod
        def features(cls, value):
            return () if value is None else (("TINT", True),)

        @classmethod
        def uniforms(cls, value):
            return () if value is None else (("u_tint", value),)

    s = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 5)), om.AmbientLight(intensity=1.0)])
    s.add(om.Node("a", [Tint(0.25), om.Color(0.6, 0.6, 0.6), om.Sphere(center=(-1, 0, 0))]))
    s.add(om.Node("b", [om.Color(0.6, 0.6, 0.6), om.Sphere(center=(1, 0, 0))]))
    img = engine.render(s, background=(0, 0, 0))
    tinted, plain = img.pixel(21, 24)[0], img.pixel(43, 24)[0]
    assert 0 < tinted < plain * 0.75
    assert 0.25 in applied and None in applied  # applied for the tinted sphere, restored for the other
