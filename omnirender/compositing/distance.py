"""Distance visualisation: a surface coloured by its distance to another renderer's surface.

A :class:`DistanceGroup` has two children: the **surface** (what is seen and
coloured) and the **reference** (what distances are measured to).  Both draw
into temporary buffers of their own; then, per pixel where the surface is
seen, the two depths give the eye-space points of both surfaces on the pixel's
view ray and their distance picks a colour of the colour map (``range`` maps
onto it, clamped).  Where the ray misses the reference the pixel gets
``missing``.  The result is merged over the framebuffer with the surface's
depth, depth-tested (integration rules 1 and 2: outside the surface nothing
changes).  With ``signed=True`` the map spans ``-range[1] .. range[1]``:
negative where the reference lies in front of the surface (it pierces it),
positive behind.

Typical uses are the paper's: how far a tool is from an organ behind it along
the line of sight, the thickness of a shell (surface = its outside drawn with
front faces, reference = the same scene drawn with back faces), the gap
between a planned and a reconstructed surface.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from ..attributes._params import check_rgba
from .canvas import Canvas
from .groups import draw_offscreen
from .renderer import Renderer, RendererGroup

__all__ = ["DistanceGroup", "VIRIDIS", "distance_colors"]

#: The default colour map (display RGB stops, evenly spaced): viridis, dark blue (near) to yellow (far).
VIRIDIS = (
    (0.267, 0.005, 0.329),
    (0.283, 0.141, 0.458),
    (0.254, 0.265, 0.530),
    (0.207, 0.372, 0.553),
    (0.164, 0.471, 0.558),
    (0.128, 0.567, 0.551),
    (0.135, 0.659, 0.518),
    (0.267, 0.749, 0.441),
    (0.478, 0.821, 0.318),
    (0.741, 0.873, 0.150),
    (0.993, 0.906, 0.144),
)
_MAX_STOPS = 16

DISTANCE = """
uniform sampler2D u_surface;
uniform sampler2D u_surface_depth;
uniform sampler2D u_reference_depth;
uniform mat4 u_inverse_projection;
uniform vec3 u_stops[16];
uniform float u_count;       // stops used
uniform vec2 u_range;        // distance at the first and the last stop
uniform float u_signed;      // 1: negative where the reference is in front of the surface
uniform vec4 u_missing;      // where the ray misses the reference
float g_depth;
vec3 eye_point(vec2 uv, float depth) {
    vec4 p = u_inverse_projection * vec4(uv * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    return p.xyz / p.w;
}
vec3 colormap(float t) {
    float x = clamp(t, 0.0, 1.0) * (u_count - 1.0);
    int i = int(min(floor(x), u_count - 2.0));
    return mix(u_stops[i], u_stops[i + 1], x - float(i));
}
vec4 effect(vec2 uv) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 s = texelFetch(u_surface, p, 0);
    float sd = texelFetch(u_surface_depth, p, 0).r;
    if (sd >= 1.0 || s.a <= 0.0) discard;                     // the surface is not seen here
    g_depth = sd;
    float rd = texelFetch(u_reference_depth, p, 0).r;
    if (rd >= 1.0) { if (u_missing.a <= 0.0) discard; return u_missing; }
    float d = distance(eye_point(uv, sd), eye_point(uv, rd));
    if (u_signed > 0.5 && rd < sd) d = -d;
    return vec4(colormap((d - u_range.x) / (u_range.y - u_range.x)), 1.0);
}
float effect_depth(vec2 uv) { return g_depth; }
"""


def distance_colors(distance: Any, range: tuple[float, float], colormap: Sequence[Sequence[float]] = VIRIDIS) -> Any:
    """The colours (display RGB in [0, 1]) a :class:`DistanceGroup` gives ``distance`` (numpy, for tests and
    legends)."""
    stops = np.asarray(colormap, dtype=np.float64)
    t = np.clip((np.asarray(distance, dtype=np.float64) - range[0]) / (range[1] - range[0]), 0.0, 1.0)
    x = t * (len(stops) - 1)
    i = np.minimum(np.floor(x).astype(int), len(stops) - 2)
    f = (x - i)[..., None]
    return stops[i] * (1 - f) + stops[i + 1] * f


class DistanceGroup(RendererGroup):
    """The first child's visible surface coloured by its distance to the second child's (see the module).

    ``range``: the distances (world units) at the two ends of the colour map
    (default ``(0, 1)``; with ``signed=True`` a single number ``r`` gives
    ``(-r, r)``); ``colormap``: 2 to 16 display RGB stops, evenly spaced
    (default :data:`VIRIDIS`); ``missing``: the colour (RGB or RGBA) where the
    ray misses the reference.
    """

    __slots__ = ("range", "colormap", "signed", "missing")

    def __init__(
        self,
        children: Iterable[Renderer] = (),
        range: float | tuple[float, float] = (0.0, 1.0),
        colormap: Sequence[Sequence[float]] = VIRIDIS,
        signed: bool = False,
        missing: Sequence[float] = (0.5, 0.5, 0.5),
    ) -> None:
        super().__init__(children)
        self.signed = bool(signed)
        self.range = _range(range, self.signed)
        self.colormap = _stops(colormap)
        self.missing = check_rgba("DistanceGroup", "missing", missing)

    def composite(self, canvas: Canvas, children: tuple[Renderer, ...]) -> None:
        if len(children) != 2:
            raise ValueError(
                f"DistanceGroup: needs two children, the surface to colour and the reference to measure to; got "
                f"{len(children)}"
            )
        surface = draw_offscreen(canvas, self, children[:1], "surface")
        reference = draw_offscreen(canvas, self, children[1:], "reference")
        stops = np.zeros((_MAX_STOPS, 3))
        stops[: len(self.colormap)] = self.colormap
        inputs = {
            "u_surface": (surface, "color"),
            "u_surface_depth": (surface, "depth"),
            "u_reference_depth": (reference, "depth"),
        }
        uniforms = {
            "u_inverse_projection": np.linalg.inv(canvas.projection).T.ravel(),
            "u_stops": stops.ravel(),
            "u_count": float(len(self.colormap)),
            "u_range": self.range,
            "u_signed": 1.0 if self.signed else 0.0,
            "u_missing": self.missing,
        }
        canvas.fullscreen("distance", DISTANCE, inputs, uniforms, blend=True, depth=True, depth_test="less")


def _range(value: Any, signed: bool) -> tuple[float, float]:
    try:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            lo, hi = (-float(value), float(value)) if signed else (0.0, float(value))
        else:
            lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        lo = hi = float("nan")
    if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
        raise ValueError(f"DistanceGroup: range must be (near, far) with far > near (or one number > 0), got {value!r}")
    return lo, hi


def _stops(colormap: Any) -> tuple[tuple[float, float, float], ...]:
    try:
        stops = np.asarray(colormap, dtype=np.float64)
    except (TypeError, ValueError):
        stops = np.zeros((0,))
    if (
        stops.ndim != 2
        or stops.shape[1] != 3
        or not 2 <= len(stops) <= _MAX_STOPS
        or not np.all((stops >= 0) & (stops <= 1))
    ):
        raise ValueError(
            f"DistanceGroup: colormap must be 2 to {_MAX_STOPS} RGB colours in [0, 1], got {colormap!r:.80}"
        )
    return tuple(tuple(float(v) for v in row) for row in stops)
