"""Line styles of the VRS paper as a GL technique: silhouettes and creases, haloed wire-frame, hidden lines.

``om.gl.SurfaceStyle(style, width=..., color=...)`` put into a node draws the
subgraph after it in one of three non-photorealistic styles:

* ``"silhouette"`` (enhanced silhouettes and creases over shaded surfaces):
  the scope is drawn once into an offscreen target holding its normals and
  depth, then shaded as usual; a full-screen pass finds the pixels within
  ``width / 2`` of a depth jump (silhouettes, outlines against the background
  or other parts) or of a normal turning by more than ``crease_angle``
  degrees (creases) and draws them in ``color``, depth-tested against the
  scene so nearer shapes hide them;
* ``"haloed"`` (the paper's Figure 16b): the triangle edges as lines of
  ``width`` pixels, each cut by a ``halo`` (pixels on both sides) where it
  passes behind another line: a first pass writes the wide halos' depth
  only, a second draws the lines with ``lequal`` a little towards the camera;
* ``"hidden-line"``: only the visible edges: the surfaces fill the depth
  buffer (pushed back by a polygon offset), then the edges are drawn on top.

Lines are in ``color`` (display RGB), or in each shape's own colour with
``color=None`` (``"haloed"`` and ``"hidden-line"``).  They work with any shape
and with instancing (they are pass state, not geometry).  POV-Ray, Mitsuba
and Radiance ignore the technique (the shapes render as usual).
"""

from __future__ import annotations

from typing import Any

from ...attributes._params import check_rgba
from ..engine.attributes import ColorMask, CullFace, DepthMask, DepthTest, PolygonOffset
from ..engine.passes import Clear, FullScreen, Pass, Shader, Target
from ..engine.state import FillMode, LineWidth
from ..engine.technique import GLTechnique

__all__ = ["SurfaceStyle", "STYLES"]

STYLES = ("silhouette", "haloed", "hidden-line")

_NORMALS = "void pass_fragment(inout vec4 color, vec3 P, vec3 N) { color = vec4(normalize(N) * 0.5 + 0.5, 1.0); }"
_PULL = """uniform vec3 u_style_eye;
uniform float u_style_pull;
void pass_vertex(inout vec3 world, inout vec3 normal) { world += (u_style_eye - world) * u_style_pull; }"""

_EDGES = """
uniform sampler2D u_normal;
uniform sampler2D u_depth;
uniform vec4 u_line_color;     // display RGBA
uniform float u_radius;        // pixels
uniform float u_crease;        // cos of the crease angle
uniform vec3 u_camera;         // near, far, orthographic (1) or perspective (0)
float edge_depth = 1.0;
float linear(float d) {
    if (u_camera.z > 0.5) return u_camera.x + d * (u_camera.y - u_camera.x);
    float z = d * 2.0 - 1.0;
    return 2.0 * u_camera.x * u_camera.y / ((u_camera.y + u_camera.x) - z * (u_camera.y - u_camera.x));
}
vec4 effect(vec2 uv) {
    vec2 px = 1.0 / u_resolution;
    float dc = texture(u_depth, uv).r;
    vec3 nc = texture(u_normal, uv).xyz * 2.0 - 1.0;
    bool edge = false;
    float nearest = dc;
    for (int k = 0; k < 8; ++k) {
        float a = 0.785398 * float(k);
        vec2 at = uv + vec2(cos(a), sin(a)) * u_radius * px;
        float dn = texture(u_depth, at).r;
        nearest = min(nearest, dn);
        if ((dc < 1.0) != (dn < 1.0)) { edge = true; continue; }       // outline against the background
        if (dc >= 1.0) continue;
        float lc = linear(dc), ln = linear(dn);
        if (abs(lc - ln) > 0.04 * min(lc, ln) * max(u_radius, 1.0)) edge = true;   // depth jump: silhouette
        vec3 nn = texture(u_normal, at).xyz * 2.0 - 1.0;
        if (dot(nc, nn) < u_crease) edge = true;                          // normal turns: crease
    }
    if (!edge || nearest >= 1.0) discard;
    edge_depth = nearest;
    return u_line_color;
}
float effect_depth(vec2 uv) { return edge_depth; }
"""


class SurfaceStyle(GLTechnique):
    """A line style for the subgraph after it: ``"silhouette"``, ``"haloed"`` or ``"hidden-line"``."""

    __slots__ = ("style", "width", "color", "halo", "crease_angle")

    def __init__(
        self,
        style: str = "silhouette",
        width: float = 2.0,
        color: Any = (0.0, 0.0, 0.0),
        halo: float = 3.0,
        crease_angle: float = 50.0,
    ) -> None:
        if style not in STYLES:
            raise ValueError(f"SurfaceStyle: style must be one of {STYLES}, got {style!r}")
        passes = 3 if style == "silhouette" else 2
        super().__init__(passes=passes)
        for name, value, low in (("width", width, 0.5), ("halo", halo, 0.0), ("crease_angle", crease_angle, 0.0)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= 180.0:
                raise ValueError(f"SurfaceStyle: {name} must be a number in [{low}, 180], got {value!r}")
        if color is None and style == "silhouette":
            raise ValueError("SurfaceStyle: the silhouette style needs a line color")
        self.style = style
        self.width = float(width)
        self.color = None if color is None else check_rgba("SurfaceStyle", "color", color)
        self.halo = float(halo)
        self.crease_angle = float(crease_angle)

    def _lines(self) -> Shader:
        return Shader(unlit=True) if self.color is None else Shader(flat_color=self.color)

    def prepare_pass(self, engine: Any) -> None:
        index = engine.current_pass
        getattr(self, "_" + self.style.replace("-", "_"))(engine, index)

    # -- the three styles ------------------------------------------------------------
    def _silhouette(self, engine: Any, index: int) -> None:
        target = Target("surface-style", colors=("normal",), dtype="f2")
        if index == 0:
            engine.set_pass(Pass("normals", target=target, clear=Clear(color=(0.5, 0.5, 1.0, 0.0), depth=1.0),
                                 shader=Shader(unlit=True, fragment=_NORMALS)))  # fmt: skip
        elif index == 1:
            engine.set_pass(Pass("shaded"))
        else:
            camera = engine.frame_camera
            edges = FullScreen(
                _EDGES,
                inputs={"u_normal": ("surface-style", "normal"), "u_depth": ("surface-style", "depth")},
                uniforms={
                    "u_line_color": self.color,
                    "u_radius": max(self.width / 2.0, 0.5),
                    "u_crease": _cos(self.crease_angle),
                    "u_camera": (camera.near, camera.far, 1.0 if camera.is_orthographic else 0.0),
                },
                blend=True,
                depth=True,
                depth_test=True,
            )
            engine.set_pass(Pass("edges", fullscreen=edges))

    def _haloed(self, engine: Any, index: int) -> None:
        wire = [(FillMode, True), CullFace("none")]
        if index == 0:
            engine.set_pass(Pass("halos", items="opaque", shader=Shader(depth_only=True), state=(
                *wire, (LineWidth, self.width + 2.0 * self.halo), ColorMask(False, False, False, False))))  # fmt: skip
        else:
            eye = engine.frame_eye
            shader = self._lines()
            pull = Shader(vertex=_PULL, uniforms={"u_style_eye": tuple(eye), "u_style_pull": 0.1})
            engine.set_pass(Pass("lines", items="opaque", shader=_merge(shader, pull), state=(
                *wire, (LineWidth, self.width), DepthTest(True, "lequal"))))  # fmt: skip

    def _hidden_line(self, engine: Any, index: int) -> None:
        if index == 0:
            engine.set_pass(Pass("fill", items="opaque", shader=Shader(depth_only=True), state=(
                ColorMask(False, False, False, False), DepthMask(True), PolygonOffset(1.0, 1.0))))  # fmt: skip
        else:
            engine.set_pass(Pass("edges", items="opaque", shader=self._lines(), state=(
                (FillMode, True), (LineWidth, self.width), CullFace("none"), DepthTest(True, "lequal"))))  # fmt: skip


def _merge(a: Shader, b: Shader) -> Shader:
    return Shader(
        flat_color=a.flat_color,
        unlit=a.unlit,
        vertex=b.vertex,
        uniforms=dict((*a.uniforms, *b.uniforms)),
    )


def _cos(degrees: float) -> float:
    import math

    return math.cos(math.radians(degrees))
