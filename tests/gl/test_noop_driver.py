"""Partial buffer writes are in range, and Mesa's no-op driver survives them (issue 22).

Under ``GALLIUM_NOOP=1`` Mesa 22's no-op driver, run in its threaded
context, corrupts memory when part of a buffer a draw used is rewritten
(``glBufferSubData`` after a draw): a plain moderngl program does it too.
Our writes are checked here to lie inside their buffers; the engine's
context runs the no-op driver unthreaded (``GALLIUM_THREAD=0``, as llvmpipe
runs), and a scene that writes partial ranges after draws (sorted batches,
shadow maps, attributes replaced, nodes added and removed) renders to the end.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SCRIPT = r"""
import numpy as np, omnirender as om
from omnirender.gl import GLEngine

def scene(n):
    s = om.Node("scene", [om.Camera.look_at((20, 16, 30), (0, 0, 0), fov=40)])
    s.add(om.DirectionalLight(direction=(-0.4, -0.6, -1)))
    box = om.Box(size=1.0)
    nodes = [s.add(om.Node(f"b{i}", [om.Translation(i % 10 * 1.5 - 7, i // 10 % 10 * 1.5 - 7, i // 100 * 1.5 - 3),
                                    om.Material(diffuse=(0.5, 0.6, 0.7)), box])) for i in range(n)]
    return s, nodes, box

def run(n, frames):
    s, nodes, box = scene(n)
    moves = [node.items[0] for node in nodes]
    with GLEngine(size=(64, 64), samples=0) as e:
        e.render(s)
        extra = None
        for f in range(frames):
            k = (f * 37 + 1) % n
            moves[k].offset = (0.1 * f, 0.0, 0.0)
            e.render(s)
            node = nodes[(f * 53 + 5) % n]
            node.remove(node.items[0])
            node.insert(0, om.Matrix(np.eye(4)))
            e.render(s)
            node.remove(node.items[1])
            node.insert(1, om.Material(diffuse=(1, 0, 0)))
            e.render(s)
            if extra is not None:
                s.remove(extra)
            extra = s.add(om.Node(f"x{f}", [om.Translation(0, 0.5, 0), box]))
            e.render(s)
"""


def test_partial_buffer_writes_lie_inside_their_buffers(monkeypatch):
    import moderngl

    writes: list[tuple[int, int, int]] = []
    original = moderngl.Buffer.write

    def write(self, data, offset=0):
        writes.append((offset, len(data), self.size))
        return original(self, data, offset=offset)

    monkeypatch.setattr(moderngl.Buffer, "write", write)
    namespace: dict = {}
    exec(SCRIPT, namespace)
    namespace["run"](300, 4)
    assert writes
    assert all(0 <= offset and offset + size <= capacity for offset, size, capacity in writes), writes
    assert any(offset > 0 or size < capacity for offset, size, capacity in writes)  # partial writes happened


#: The driver's failure in plain moderngl: a buffer drawn from, then partly rewritten (crashes threaded).
DRIVER = r"""
import moderngl, numpy as np
from omnirender.gl.engine.context import create_context
ctx = create_context()
prog = ctx.program(vertex_shader="#version 330\nin vec4 a; void main() { gl_Position = a; }",
                   fragment_shader="#version 330\nout vec4 c; void main() { c = vec4(1.0); }")
n, stride = 10000, 80
buffer = ctx.buffer(reserve=n * stride, dynamic=True)
vao = ctx.vertex_array(prog, [(buffer, "4f 64x", "a")])
ctx.simple_framebuffer((64, 64)).use()
for i in range(20):
    buffer.write(np.zeros(n * stride // 4, "f4").tobytes())
    vao.render(moderngl.POINTS, vertices=n)
    buffer.write(b"\1" * 63280, offset=736720)
    vao.render(moderngl.POINTS, vertices=n)
ctx.finish()
"""


@pytest.mark.parametrize("script", ["driver", "engine"])
def test_the_no_op_driver_renders_partial_updates_to_the_end(script):
    env = dict(os.environ, GALLIUM_NOOP="1")
    env.pop("GALLIUM_THREAD", None)  # the engine's context decides
    env.pop("GALLIUM_DRIVER", None)  # the no-op driver, whatever driver the suite runs on (softpipe in CI)
    code = (DRIVER if script == "driver" else SCRIPT + "\nrun(1000, 4)") + "\nprint('done')\n"
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0 and "done" in done.stdout, (done.returncode, done.stderr[-2000:])


def _vendor() -> str:
    """The GL vendor and version of this machine's default driver (Mesa's name both where it is Mesa)."""
    code = "from omnirender.gl.engine.context import create_context\nc = create_context()\n"
    code += "print(c.info['GL_VENDOR'], c.info['GL_VERSION'])"
    env = {k: v for k, v in os.environ.items() if k != "GALLIUM_NOOP"}
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120).stdout


def test_the_engine_asks_for_an_unthreaded_no_op_driver_only_under_gallium_noop():
    env = dict(os.environ, GALLIUM_NOOP="1")
    env.pop("GALLIUM_THREAD", None)
    env.pop("GALLIUM_DRIVER", None)  # the no-op driver, whatever driver the suite runs on (softpipe in CI)
    code = (
        "import os\nfrom omnirender.gl.engine.context import create_context\nc = create_context()\n"
        "print(os.environ.get('GALLIUM_THREAD'), c.info['GL_RENDERER'])"
    )
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    if "NOOP" not in out.stdout and "Mesa" not in _vendor():
        pytest.skip("GALLIUM_NOOP is a variable of Mesa's Gallium drivers; this GL driver ignores it")
    assert out.stdout.split() == ["0", "NOOP"], out.stderr[-2000:]
    env.pop("GALLIUM_NOOP")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.stdout.split()[0] == "None", out.stderr[-2000:]
    assert np.isfinite(1.0) and om  # the module's imports are used
