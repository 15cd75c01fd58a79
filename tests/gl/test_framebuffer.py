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
