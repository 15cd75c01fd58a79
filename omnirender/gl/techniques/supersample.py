"""Supersampling as a technique: jittered multi-pass accumulation (anti-aliasing beyond MSAA).

``om.gl.Supersample(n)`` put into a node draws the subgraph after it ``n``
times, each time with the projection shifted by a different sub-pixel offset
(a rotated grid), into a float target, and averages the images (a ping-pong
chain of full-screen passes); the average is composited over the frame with
the depth of the last image.  It smooths what multisampling leaves jagged:
thin lines, shadow-map edges, texture and shading aliasing (every sample is
shaded, not only its coverage).  Cost: ``n`` times the subgraph.  Other
engines ignore it (POV-Ray has its own ``antialias``, Mitsuba ``spp``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..engine.imagespace import PingPong, resolve
from ..engine.passes import Clear, FullScreen, Pass, Target
from ..engine.technique import GLTechnique

__all__ = ["Supersample", "jitter"]

_ACCUMULATE = """uniform sampler2D u_frame;
uniform sampler2D u_sum;
uniform float u_first;
vec4 effect(vec2 uv) { return texture(u_frame, uv) + (u_first > 0.5 ? vec4(0.0) : texture(u_sum, uv)); }
"""


def jitter(n: int) -> np.ndarray:
    """``n`` sub-pixel offsets in [-0.5, 0.5)^2: a rotated grid (n = 1: the pixel centre)."""
    if n == 1:
        return np.zeros((1, 2))
    k = int(np.ceil(np.sqrt(n)))
    cells = [((i + 0.5) / k - 0.5, (j + 0.5) / k - 0.5) for j in range(k) for i in range(k)][:n]
    angle = np.arctan(0.5)  # the rotated grid spreads the offsets over both axes
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return (np.asarray(cells) @ rot.T) * 0.9


class Supersample(GLTechnique):
    """Average ``n`` jittered renderings of the subgraph after it (2 <= n <= 64)."""

    __slots__ = ("n",)

    def __init__(self, n: int = 4) -> None:
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 64:
            raise ValueError(f"Supersample: n must be a whole number in [1, 64], got {n!r}")
        super().__init__(passes=2 * n + 1)
        self.n = n

    def prepare_pass(self, engine: Any) -> None:
        index = engine.current_pass
        chain = PingPong("supersample.sum", dtype="f4")
        frame = Target("supersample.frame", dtype="f4")
        if index == 2 * self.n:
            average = resolve(chain.read(self.n).name, depth_target=frame.name, count=self.n)
            engine.set_pass(Pass("resolve", fullscreen=average))
            return
        k, step = divmod(index, 2)
        if step == 0:
            dx, dy = jitter(self.n)[k]
            w, h = engine.target_size
            shift = np.eye(4)
            shift[0, 3], shift[1, 3] = 2.0 * dx / w, 2.0 * dy / h
            camera = (engine.frame_view, shift @ engine.frame_projection)
            engine.set_pass(Pass(f"sample[{k}]", target=frame, clear=Clear(), camera=camera))
        else:
            previous = frame.name if k == 0 else chain.read(k).name  # nothing summed yet: any bound texture
            add = FullScreen(_ACCUMULATE, inputs={"u_frame": (frame.name, "color"), "u_sum": (previous, "color")},
                             uniforms={"u_first": float(k == 0)})  # fmt: skip
            engine.set_pass(Pass(f"accumulate[{k}]", target=chain.write(k), fullscreen=add))
