"""The shadow group: children cast and receive shadows from one light, whatever kind of renderer they are.

:class:`ShadowGroup` needs nothing of its children but their depth buffers:

1. the children are drawn from the light into a shadow map (a depth target; a
   perspective view for point and spot lights, a parallel one for directional
   lights, framing the children's bounds);
2. the children are drawn from the camera into an offscreen target;
3. a full-screen pass back-projects every pixel of that target's depth buffer
   to the world, projects it into the shadow map and darkens it where
   something nearer to the light was drawn (3 x 3 percentage-closer
   filtering), and merges the result over the framebuffer by depth.

So meshes, volumes (their depth is where their opacity reaches 5 %) and light
fields cast shadows on each other like meshes do.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

from ..attributes.lights import DirectionalLight, LightSource
from ..core.camera import look_at_matrix, orthographic_matrix, perspective_matrix
from ..gl import Clear, Target
from ..gl.engine.frame import ProjectionInfo
from .canvas import EYE_DISTANCE, Canvas, fraction, target_name
from .groups import draw_offscreen
from .renderer import Bounds, Renderer, RendererGroup, draw_all

__all__ = ["ShadowGroup", "light_view"]

SHADE = (
    EYE_DISTANCE
    + """
uniform sampler2D u_color;
uniform sampler2D u_depth;
uniform sampler2D u_shadow;
uniform mat4 u_inv_view_proj;    // camera clip -> world
uniform mat4 u_light_view_proj;  // world -> light clip
uniform vec3 u_light;            // near, far, orthographic (1) of the light's projection
uniform vec4 u_light_position;   // world position (w = 1) or direction towards the light (w = 0)
uniform float u_texel;           // world size of a shadow-map texel at distance 1 (perspective) or anywhere
uniform float u_bias;            // in shadow-map texels
uniform float u_darkness;
float light_distance(float d) { return eye_distance(d, u_light); }
vec4 effect(vec2 uv) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 c = texelFetch(u_color, p, 0);
    float d = texelFetch(u_depth, p, 0).r;
    if (d >= 1.0 || c.a <= 0.0) discard;                     // the children drew nothing here
    vec4 h = u_inv_view_proj * vec4(uv * 2.0 - 1.0, d * 2.0 - 1.0, 1.0);
    vec3 world = h.xyz / h.w;
    vec4 lc = u_light_view_proj * vec4(world, 1.0);
    // slope-scaled bias: surfaces seen at a grazing angle from the light need more (the normal from the
    // world positions of neighbouring pixels; off at depth edges, where the bias is capped)
    vec3 normal = cross(dFdx(world), dFdy(world));
    vec3 to_light = u_light_position.w > 0.5 ? u_light_position.xyz - world : u_light_position.xyz;
    float cosine = abs(dot(normalize(normal), normalize(to_light)));
    float slope = length(normal) > 0.0 ? min(sqrt(max(1.0 - cosine * cosine, 0.0)) / max(cosine, 1e-3), 4.0) : 4.0;
    float shadow = 0.0;
    if (lc.w > 0.0) {
        vec3 l = lc.xyz / lc.w * 0.5 + 0.5;
        float here = light_distance(l.z);
        float bias = u_bias * (1.0 + slope) * u_texel * (u_light.z > 0.5 ? 1.0 : here);
        vec2 texel = 1.0 / vec2(textureSize(u_shadow, 0));
        for (int i = -1; i <= 1; ++i) {
            for (int j = -1; j <= 1; ++j) {
                vec2 q = l.xy + vec2(i, j) * texel;
                if (all(greaterThanEqual(q, vec2(0.0))) && all(lessThanEqual(q, vec2(1.0)))) {
                    float nearest = texture(u_shadow, q).r;
                    // a soft step over one more bias: no speckles where two surfaces almost agree (volumes)
                    if (nearest < 1.0) shadow += smoothstep(bias, 2.0 * bias, here - light_distance(nearest)) / 9.0;
                }
            }
        }
    }
    return vec4(c.rgb / c.a * (1.0 - u_darkness * shadow), c.a);
}
float effect_depth(vec2 uv) { return texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r; }
"""
)


def light_position(light: Any, world: np.ndarray) -> tuple[float, float, float, float]:
    """The light's world position (w = 1), or for a directional light the direction towards it (w = 0)."""
    if isinstance(light, DirectionalLight):
        return (*(-light.world_direction(world)), 0.0)
    position = light.world_position(world) if isinstance(light, LightSource) else np.asarray(light, dtype=np.float64)
    return (*(float(v) for v in position), 1.0)


def light_view(light: Any, world: np.ndarray, bounds: Bounds) -> tuple[np.ndarray, np.ndarray, float]:
    """(view, projection, world size of a texel per unit of resolution) of the light looking at ``bounds``.

    Directional lights look along their direction with a parallel projection
    enclosing the bounding sphere; point and spot lights (and plain positions)
    look from their position at its centre with the narrowest cone containing it.
    """
    lo, hi = (np.asarray(b, dtype=np.float64) for b in bounds)
    center = (lo + hi) / 2.0
    radius = max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-6)
    if isinstance(light, DirectionalLight):
        direction = light.world_direction(world)
        eye = center - direction * 3.0 * radius
        view = look_at_matrix(eye, center, _up(direction))
        height = 2.05 * radius
        return view, orthographic_matrix(height, 1.0, 1.9 * radius, 4.1 * radius), height
    position = light.world_position(world) if isinstance(light, LightSource) else np.asarray(light, dtype=np.float64)
    offset = center - position
    distance = float(np.linalg.norm(offset))
    if distance <= radius * 1.05:  # the light is among its casters: see as much of them as a cone can
        fov, near = 150.0, max(1e-3 * radius, 1e-6)
        if distance < 1e-9:
            offset = np.array([0.0, -1.0, 0.0])
    else:
        fov = 2.0 * math.degrees(math.asin(radius / distance)) * 1.05
        near = max(distance - radius, 1e-3 * distance) * 0.95
    far = (distance + radius) * 1.05
    view = look_at_matrix(position, position + offset, _up(offset))
    return view, perspective_matrix(fov, 1.0, near, far), 2.0 * math.tan(math.radians(fov) / 2.0)


def _up(direction: np.ndarray) -> np.ndarray:
    d = np.abs(np.asarray(direction, dtype=np.float64))
    return np.array([0.0, 1.0, 0.0]) if d[1] < 0.9 * np.linalg.norm(d) else np.array([1.0, 0.0, 0.0])


class ShadowGroup(RendererGroup):
    """Children lit by ``light`` cast shadows on each other: shadowed pixels are darkened by ``darkness``.

    ``light`` is an ``om.PointLight``, ``om.SpotLight``, ``om.DirectionalLight``
    or a position; a light placed in the scene graph the group draws in is
    taken where it sits.  ``resolution`` is the shadow map's larger side in
    pixels (a square map), ``bias`` the depth tolerance in shadow-map texels (against shadow
    acne), ``enabled=False`` draws the children unshadowed (for comparisons).
    """

    __slots__ = ("light", "darkness", "resolution", "bias", "enabled")

    def __init__(
        self,
        light: Any,
        children: Iterable[Renderer] = (),
        darkness: float = 0.6,
        resolution: int = 2048,
        bias: float = 1.5,
        enabled: bool = True,
    ) -> None:
        super().__init__(children)
        if not isinstance(light, LightSource):
            try:
                position = np.asarray(light, dtype=np.float64)
            except (TypeError, ValueError):
                position = np.zeros(0)
            if position.shape != (3,) or not np.all(np.isfinite(position)):
                raise TypeError(
                    f"ShadowGroup: light must be an om.PointLight, SpotLight, DirectionalLight or a position (x, y, z)"
                    f", got {light!r:.60}"
                )
            light = tuple(float(v) for v in position)
        if (
            isinstance(resolution, bool)
            or not isinstance(resolution, (int, np.integer))
            or not 16 <= resolution <= 8192
        ):
            raise ValueError(
                f"ShadowGroup: resolution must be a whole number of pixels in [16, 8192], got {resolution!r}"
            )
        if not 0.0 <= float(bias) <= 100.0:
            raise ValueError(f"ShadowGroup: bias must be in [0, 100] shadow-map texels, got {bias!r}")
        self.light = light
        self.darkness = fraction("ShadowGroup", "darkness", darkness)
        self.resolution = int(resolution)
        self.bias = float(bias)
        self.enabled = bool(enabled)

    def _light_world(self, canvas: Canvas) -> np.ndarray:
        """The light's world matrix: where the scene graph being drawn places it, else the identity."""
        for light, matrix in getattr(canvas.engine, "scene_lights", None) or ():
            if light is self.light:
                return np.asarray(matrix, dtype=np.float64)
        return np.eye(4)

    def composite(self, canvas: Canvas, children: tuple[Renderer, ...]) -> None:
        box = None
        if self.enabled:
            for child in children:
                found = child.frame_bounds(canvas)
                if found is not None:
                    box = found if box is None else (np.minimum(box[0], found[0]), np.maximum(box[1], found[1]))
        if box is None:  # off, or nothing known to cast: the children as a plain depth group
            draw_all(canvas, children)
            return
        light_world = self._light_world(canvas)
        view, proj, texel = light_view(self.light, light_world, box)
        side = min(self.resolution, int(canvas.engine.max_texture_size))
        shadow = Target(target_name(self, "shadow-map"), colors=(), depth=True, size=(side, side))
        canvas.into("shadow-map", lambda inner: draw_all(inner, children), target=shadow,
                    clear=Clear(color=None, depth=1.0), camera=(view, proj))  # fmt: skip
        drawn = draw_offscreen(canvas, self, children)
        info = ProjectionInfo.of(proj)
        uniforms = {
            "u_inv_view_proj": _mat(np.linalg.inv(canvas.view_projection)),
            "u_light_view_proj": _mat(proj @ view),
            "u_light": (info.near, info.far, 1.0 if info.is_orthographic else 0.0),
            "u_light_position": light_position(self.light, light_world),
            "u_texel": texel / side,
            "u_bias": self.bias,
            "u_darkness": self.darkness,
        }
        inputs = {"u_color": (drawn, "color"), "u_depth": (drawn, "depth"), "u_shadow": (shadow.name, "depth")}
        canvas.fullscreen("shade", SHADE, inputs, uniforms, blend=True, depth=True, depth_test="less")


def _mat(m: np.ndarray) -> tuple[float, ...]:
    """A 4x4 matrix as a GLSL mat4 uniform value (column-major)."""
    return tuple(float(v) for v in np.asarray(m, dtype=np.float64).T.ravel())
