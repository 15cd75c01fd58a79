"""The four integration rules: every built-in renderer, group and filter follows them; broken renderers are caught."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

from .scenes import CAMERA, LIGHT, ball, cube, fog_volume

pytestmark = pytest.mark.gl
C = om.compositing


def built_ins() -> dict[str, C.Renderer]:
    a, b = C.SceneRenderer(om.Node("a", [CAMERA, *ball().items])), C.SceneRenderer(cube())
    volume = C.VolumeRenderer(fog_volume(), om.Translation(0.3, 0.2, 0.5))
    glass = C.SceneRenderer(ball(center=(0.2, 0.1, 0.4), radius=0.8, opacity=0.35))
    return {
        "SceneRenderer": a,
        "VolumeRenderer": volume,
        "DepthGroup": C.DepthGroup([a, b, volume]),
        "DepthGroup(offscreen)": C.DepthGroup([a, volume], offscreen=True),
        "OcclusionGroup(visible)": C.OcclusionGroup([b]),
        "OcclusionGroup(semi-transparent)": C.OcclusionGroup([b, volume], mode="semi-transparent", opacity=0.4),
        "ShadowGroup": C.ShadowGroup(LIGHT, [a, b, volume], resolution=512),
        "LuminanceFilter": C.LuminanceFilter(),
        "BufferDebugFilter(depth)": C.BufferDebugFilter("depth"),
        "BufferDebugFilter(alpha)": C.BufferDebugFilter("alpha"),
        "BufferDebugFilter(stencil)": C.BufferDebugFilter("stencil"),
        "GLSLFilter": C.GLSLFilter("vec4 filter_color(vec4 c, float d, vec2 uv) { return vec4(1.0 - c.rgb, c.a); }"),
        "filter in an offscreen group": C.DepthGroup([a, C.LuminanceFilter()], offscreen=True),
        "DepthPeelGroup": C.DepthPeelGroup([glass, C.DepthGroup([b])], layers=4),
        "DistanceGroup": C.DistanceGroup([b, glass], range=2.0),
        "DistanceGroup(signed)": C.DistanceGroup([glass, a], range=1.0, signed=True, missing=(0, 0, 0, 0)),
    }


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
@pytest.mark.parametrize("name", list(built_ins()))
def test_every_built_in_renderer_follows_the_four_rules(name):
    renderer = built_ins()[name]
    report = C.check_rules(renderer, camera=CAMERA)
    assert report.ok, str(report)
    assert "follows the four integration rules" in str(report)


def test_the_light_field_renderer_follows_the_four_rules(small_light_field):
    report = C.check_rules(C.LightFieldRenderer(small_light_field))
    assert report.ok, str(report)
    tree = C.ShadowGroup(LIGHT, [C.SceneRenderer(cube()), C.LightFieldRenderer(small_light_field)], resolution=256)
    assert C.check_rules(tree).ok


# --- renderers that break one rule each ---------------------------------------------------------------
class Clearing(C.SceneRenderer):
    """Clears the framebuffer before drawing: what others drew is gone (rule 1)."""

    def draw(self, canvas):
        canvas.framebuffer.clear(0, 0, 0, 0, depth=1.0)
        super().draw(canvas)


class Leaky(C.SceneRenderer):
    """Draws its scene without putting the GL state back (rule 4)."""

    def draw(self, canvas):
        engine = self.engine(canvas.engine)
        engine.compile(self.scene)
        engine.draw(clear=False, camera=(canvas.view, canvas.projection), framebuffer=canvas.framebuffer)


class Tint(C.Renderer):
    """Blends a colour over every pixel without depth: colour without a surface (rule 2)."""

    def draw(self, canvas):
        with canvas.preserved():
            canvas.fullscreen("tint", "vec4 effect(vec2 uv) { return vec4(1.0, 0.0, 0.0, 0.5); }", blend=True)


def broken() -> dict[int, list[C.Renderer]]:
    sphere = [CAMERA, om.Sphere(radius=1.0)]
    return {
        1: [Clearing(ball())],
        2: [C.SceneRenderer(om.Node("depth only", [om.gl.ColorMask(False, False, False, False), *sphere])), Tint()],
        3: [C.SceneRenderer(om.Node("stencil", [om.gl.StencilTest(ref=1), om.gl.StencilOp(zpass="replace"), *sphere]))],
        4: [Leaky(ball())],
    }


@pytest.mark.parametrize("rule", [1, 2, 3, 4])
def test_a_broken_renderer_fails_its_rule_with_a_clear_report(rule):
    for renderer in broken()[rule]:
        report = C.check_rules(renderer, camera=CAMERA)
        assert report.rules == {rule}, str(report)
        (violation,) = report.violations
        text = str(report)
        assert f"rule {rule} ({C.rules.RULES[rule]}) violated" in text
        if rule == 4:
            names = {name for name, *_ in violation.states}
            assert {"blend", "depth_func"} <= names  # found: blending one/zero and lequal; left: the engine's own
            assert "GL state not restored" in text and "depth_func" in text
        else:
            assert violation.pixels is not None and len(violation.pixels) > 10
            assert "pixels in x" in text and "colour (" in text and "depth" in text


def test_violations_name_the_pixels_involved():
    """The stencil writer changes the stencil exactly where its sphere covers the pattern."""
    renderer = broken()[3][0]
    report = C.check_rules(renderer, camera=CAMERA, size=(64, 48))
    (violation,) = report.violations
    mask = np.zeros((48, 64), bool)
    mask[violation.pixels[:, 1], violation.pixels[:, 0]] = True
    alone = om.render(om.Node("s", [CAMERA, om.Sphere(radius=1.0)]), size=(64, 48), samples=0).mask
    assert (mask & ~alone).sum() == 0 and mask.sum() > 0.8 * alone.sum()


def test_check_rules_refuses_what_is_not_a_renderer():
    with pytest.raises(TypeError, match="must be an om.compositing.Renderer"):
        C.check_rules(om.Sphere())
