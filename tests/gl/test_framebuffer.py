"""Framebuffer stack and depth sprites: the compositing helpers keep colour, depth and state."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl


def scene(x: float, color) -> om.Node:
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6)))
    s.add(om.Color(*color))
    s.add(om.Sphere(center=(x, 0, 0), radius=1.0))
    return s


def test_push_draws_offscreen_and_pop_returns():
    from omnirender.gl import GLEngine
    from omnirender.gl.engine.framebuffer import FramebufferStack

    with GLEngine(size=(64, 48)) as e:
        main = e.render(scene(0, (1, 0, 0)))
        stack = FramebufferStack(e)
        target = stack.push()
        off = e.render(scene(0, (0, 1, 0)))
        assert off.pixel(32, 24)[1] > 150
        assert len(stack) == 1
        popped = stack.pop()
        assert popped is target
        assert target.color_array()[24, 32, 1] > 150
        again = e.render(scene(0, (1, 0, 0)))
        assert again.array.tobytes() == main.array.tobytes()
        target.release()
        with pytest.raises(RuntimeError, match="unbalanced"):
            stack.pop()


def test_depth_sprite_restores_colour_and_depth_consistently():
    from omnirender.gl import GLEngine
    from omnirender.gl.engine.framebuffer import DepthSprite

    with GLEngine(size=(64, 48), samples=0) as e:
        first = e.render(scene(-0.5, (1, 0, 0)))
        sprite = DepthSprite(e).save()
        with e.current():
            e.compile(scene(0.5, (0, 0, 1)))
            e.draw()  # a second renderer draws its own image
            sprite.restore()  # merge the first one back by depth
        merged = e.read()
        # where the red sphere is nearer, red wins; where only blue exists, blue stays
        nearer = first.depth < np.where(np.isfinite(merged.depth), merged.depth, np.inf) + 1e-3
        assert merged.pixel(20, 24)[0] > 150
        assert merged.pixel(44, 24)[2] > 150
        # colour-depth consistency: every red pixel carries the red sphere's depth
        red = (merged.array[:, :, 0] > 150) & (merged.array[:, :, 2] < 60)
        assert red.any()
        assert np.allclose(merged.depth[red], first.depth[red], rtol=1e-3)
        assert nearer[24, 20]
        sprite.release()


def test_between_frames_sets_state_through_the_applier_and_leaves_the_defaults():
    """``engine.between_frames()``: states applied inside hold there; afterwards GL is as after a frame (every
    switch and function in force at its default, the engine's framebuffer bound), whatever was applied."""
    from omnirender.gl import Blend, CullFace, DepthTest, GLEngine
    from omnirender.gl.engine.context import RawGL
    from omnirender.gl.engine.glstate import capture_state

    if not RawGL().available:
        pytest.skip("no libGL for glGet: the GL state cannot be read back")
    with GLEngine(size=(32, 24), samples=0) as e:
        e.render(scene(0, (1, 0, 0)))
        with e.current():
            after_frame = capture_state()
            with e.between_frames():
                e.apply_gl_state(Blend(src="one", dst="one"), DepthTest(func="always"), CullFace("front"))
                inside = capture_state()
            after = capture_state()
        assert inside["blend"] and inside["cull_face"] and inside["depth_func"] != after_frame["depth_func"]
        # the factors of a disabled blend and the mode of a disabled cull stay as they were set (after a frame too)
        off = ("blend_src_rgb", "blend_dst_rgb", "blend_src_alpha", "blend_dst_alpha", "cull_face_mode")
        differ = [d for d in after.diff(after_frame) if d[0] not in off]
        assert not differ and not after["blend"] and not after["cull_face"], differ
        assert after["draw_framebuffer"] == e.framebuffer.glo
