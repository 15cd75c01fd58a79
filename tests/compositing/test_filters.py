"""Filters change the image already made: luminance, buffer overlays (depth, alpha, stencil), user GLSL."""

from __future__ import annotations

import numpy as np
import pytest
from pixels import assert_rgb

import omnirender as om

from .scenes import CAMERA, ball, cube

pytestmark = pytest.mark.gl
C = om.compositing
SIZE = (96, 72)
KW = dict(camera=CAMERA, samples=0, background=(0.1, 0.1, 0.1))


def scene_renderers() -> list[C.Renderer]:
    return [C.SceneRenderer(ball()), C.SceneRenderer(cube())]


def test_the_luminance_filter_turns_colour_to_the_grey_of_its_luminance():
    colour = C.DepthGroup(scene_renderers()).render(SIZE, **KW)
    grey = C.DepthGroup([*scene_renderers(), C.LuminanceFilter()]).render(SIZE, **KW)
    rgb = grey.array[..., :3].astype(int)
    assert np.all(rgb[..., 0] == rgb[..., 1]) and np.all(rgb[..., 1] == rgb[..., 2])
    from omnirender.attributes.photometry import linear_to_srgb, srgb_to_linear

    linear = srgb_to_linear(colour.array[..., :3] / 255.0)
    expected = linear_to_srgb(linear @ np.array([0.2126, 0.7152, 0.0722])) * 255
    assert np.abs(rgb[..., 0] - expected).max() <= 1.5
    assert np.array_equal(np.isfinite(grey.depth), np.isfinite(colour.depth))  # depth untouched
    red_only = C.DepthGroup([*scene_renderers(), C.LuminanceFilter(weights=(1, 0, 0))]).render(SIZE, **KW)
    assert red_only.pixel(30, 36)[0] > grey.pixel(30, 36)[0]  # the red ball weighs more by its red alone
    with pytest.raises(ValueError, match="weights"):
        C.LuminanceFilter(weights=(1, 2))


def test_a_filter_in_an_offscreen_group_changes_only_that_groups_children():
    ball_renderer, cube_renderer = scene_renderers()
    tree = C.DepthGroup([cube_renderer, C.DepthGroup([ball_renderer, C.LuminanceFilter()], offscreen=True)])
    img = tree.render(SIZE, **KW)
    cube_only = C.SceneRenderer(cube()).render(SIZE, **KW)
    ball_px = img.pixel(26, 36)[:3]
    assert_rgb(ball_px, (ball_px[1],) * 3)  # the ball is grey
    blue = img.array[cube_only.mask & ~np.isfinite(C.SceneRenderer(ball()).render(SIZE, **KW).depth)]
    assert len(blue) > 100 and np.all(blue[:, 2] > blue[:, 0] + 60)  # the cube stays blue
    assert_rgb(img.pixel(2, 2), (25.5, 25.5, 25.5))  # 0.1 * 255: the background was never filtered


def test_the_depth_overlay_shows_near_bright_and_far_dark():
    slanted = om.Node("floor", [om.Color(0.5, 0.2, 0.2), om.Box(size=(3, 0.05, 8), center=(0, -0.6, -2))])
    img = C.DepthGroup([C.SceneRenderer(slanted), C.BufferDebugFilter("depth", opacity=1.0)]).render(SIZE, **KW)
    column = img.array[:, 48, 0].astype(int)
    rows = np.nonzero(np.isfinite(img.depth[:, 48]))[0]
    assert len(rows) > 10
    values = column[rows]
    assert values[-1] > 200 and values[0] < 40  # the near end (image bottom) white, the far end black
    assert np.all(np.diff(values) >= -1)  # brighter all the way towards the camera
    assert_rgb(img.pixel(48, 2), (25.5, 25.5, 25.5))  # 0.1 * 255: nothing drawn: the image shows through


def test_the_alpha_overlay_shows_coverage():
    img = C.DepthGroup([*scene_renderers(), C.BufferDebugFilter("alpha", opacity=1.0)]).render(
        SIZE, camera=CAMERA, samples=0, background=(0.5, 0.5, 0.5, 0.0)
    )
    assert_rgb(img.pixel(30, 36), (255, 255, 255))  # opaque ball
    assert_rgb(img.pixel(2, 2), (0, 0, 0))  # transparent background


def test_the_stencil_overlay_paints_each_stencil_value():
    write = lambda ref, center: om.Node(  # noqa: E731
        f"s{ref}", [om.gl.StencilTest(ref=ref), om.gl.StencilOp(zpass="replace"), om.Sphere(center=center, radius=0.5)]
    )
    stencil = C.SceneRenderer(om.Node("s", [write(1, (-1.2, 0, 0)), write(3, (1.2, 0, 0)), write(40, (0, 0, 1))]))
    img = C.DepthGroup([stencil, C.BufferDebugFilter("stencil", opacity=1.0)]).render(SIZE, **KW)
    palette = np.round(np.asarray(C.filters.STENCIL_PALETTE) * 255)
    assert np.abs(np.asarray(img.pixel(22, 36)[:3]) - palette[0]).max() <= 1  # value 1
    assert np.abs(np.asarray(img.pixel(74, 36)[:3]) - palette[2]).max() <= 1  # value 3
    assert_rgb(img.pixel(48, 36), (255, 255, 255))  # 40: beyond the palette
    assert_rgb(img.pixel(48, 4), (25.5, 25.5, 25.5))  # 0.1 * 255: 0: nothing painted


def test_a_glsl_filter():
    invert = C.GLSLFilter(
        "uniform float u_amount; vec4 filter_color(vec4 c, float depth, vec2 uv) {"
        " return depth < 1.0 ? vec4(mix(c.rgb, 1.0 - c.rgb, u_amount), c.a) : c; }",
        uniforms={"u_amount": 1.0},
    )
    plain = C.DepthGroup(scene_renderers()).render(SIZE, **KW)
    inverted = C.DepthGroup([*scene_renderers(), invert]).render(SIZE, **KW)
    drawn = np.isfinite(plain.depth)
    assert np.abs((255 - plain.array[drawn][:, :3].astype(int)) - inverted.array[drawn][:, :3]).max() <= 1
    assert np.array_equal(plain.array[~drawn], inverted.array[~drawn])  # the snippet kept the background
    with pytest.raises(ValueError, match="filter_color"):
        C.GLSLFilter("vec4 effect(vec2 uv) { return vec4(1); }")
    with pytest.raises(ValueError, match="failed to compile"):
        C.DepthGroup([C.GLSLFilter("vec4 filter_color(vec4 c, float d, vec2 uv) { return oops; }")]).render((8, 8))
    with pytest.raises(ValueError, match="buffer must be one of"):
        C.BufferDebugFilter("normals")
