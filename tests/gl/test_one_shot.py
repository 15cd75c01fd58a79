"""One-shot renders: one hidden context per thread, GPU resources freed after each call, nothing left behind."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import omnirender as om
from omnirender import gl

pytestmark = pytest.mark.gl


def _scene() -> om.Node:
    return om.Node("s", [om.Camera.look_at(eye=(0, 0, 4)), om.PointLight(position=(2, 2, 4)), om.Sphere()])


def test_one_shot_renders_share_one_context_per_thread_and_agree_with_an_engine():
    first = om.render(_scene(), engine="gl", size=(48, 36))
    ctx = gl.one_shot_context()
    second = om.render(_scene(), engine="gl", size=(48, 36))
    assert gl.one_shot_context() is ctx
    assert np.array_equal(first.array, second.array)
    with gl.GLEngine(size=(48, 36)) as engine:  # its own context, as before
        assert np.array_equal(engine.render(_scene()).array, first.array)
    other: list = []
    thread = threading.Thread(target=lambda: other.append(gl.one_shot_context()))
    thread.start()
    thread.join()
    assert other[0] is not ctx  # a context is current in one thread at a time


def test_the_raw_depth_stencil_renderbuffer_is_deleted_with_its_engine():
    ctx = gl.one_shot_context()
    ctx.mglo.__enter__()
    engine = gl.GLEngine(size=(32, 24), context=ctx)
    rbo = engine._stencil_rbo
    assert rbo is not None and engine.raw.available
    is_renderbuffer = engine.raw.glIsRenderbuffer  # GLboolean: declared c_ubyte (see test_raw_gl.py)
    assert is_renderbuffer(rbo) == 1
    engine.size = (40, 30)  # new framebuffers: the old renderbuffer goes
    current = engine._stencil_rbo
    # A deleted name is free at once (OpenGL 4.6, 5.1.2), and a driver may hand it out again to the new
    # renderbuffer (NVIDIA does): the same name for the new one proves the old one was deleted, as does a dead name.
    assert current == rbo or is_renderbuffer(rbo) == 0, "the old depth-stencil renderbuffer is still alive"
    assert is_renderbuffer(current) == 1
    engine.release()
    assert is_renderbuffer(current) == 0


def test_a_size_no_engine_accepts_costs_no_context(monkeypatch):
    monkeypatch.setattr(gl, "one_shot_context", lambda: pytest.fail("a context was made"))
    with pytest.raises(ValueError, match="268,435,456"):
        om.render(_scene(), engine="gl", size=(20000, 20000), samples=4)
