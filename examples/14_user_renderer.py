"""Example 14: a renderer written by a user in under 40 lines, composited with meshes by depth.

``RayTracedSphere`` draws an exact sphere without triangles: one full-screen
pass intersects every pixel's ray with the sphere, shades the hit and writes
its depth, so the sphere cuts through the meshes of a ``SceneRenderer``
exactly where it should.  ``check_rules`` confirms it follows the four
integration rules; a shadow group makes it cast and receive shadows.
Writes 14-user-renderer.png (left: depth group, right: shadow group).

    python examples/14_user_renderer.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om

C = om.compositing


# --- the renderer: under 40 lines ------------------------------------------------------------------
class RayTracedSphere(C.Renderer):
    """An analytic sphere at ``center`` with ``radius`` and an sRGB ``color``, lit from ``light``."""

    __slots__ = ("center", "radius", "color", "light")

    def __init__(self, center=(0, 0, 0), radius=1.0, color=(0.9, 0.3, 0.2), light=(3, 5, 4)):
        super().__init__()
        self.center, self.radius, self.color, self.light = center, radius, color, light

    GLSL = """
    uniform mat4 u_inverse; uniform mat4 u_view_proj; uniform vec4 u_sphere; uniform vec3 u_color, u_light;
    float g_depth;
    vec4 effect(vec2 uv) {
        vec4 a = u_inverse * vec4(uv * 2.0 - 1.0, -1.0, 1.0), b = u_inverse * vec4(uv * 2.0 - 1.0, 1.0, 1.0);
        vec3 o = a.xyz / a.w, d = normalize(b.xyz / b.w - o), oc = o - u_sphere.xyz;
        float half_b = dot(oc, d), disc = half_b * half_b - dot(oc, oc) + u_sphere.w * u_sphere.w;
        if (disc < 0.0 || -half_b - sqrt(disc) < 0.0) discard;           // no hit in front: nothing drawn
        vec3 p = o + d * (-half_b - sqrt(disc)), n = normalize(p - u_sphere.xyz);
        vec4 clip = u_view_proj * vec4(p, 1.0);
        g_depth = clip.z / clip.w * 0.5 + 0.5;
        float light = 0.2 + 0.8 * max(dot(n, normalize(u_light - p)), 0.0);
        return vec4(to_srgb(to_linear(u_color) * light), 1.0);
    }
    float effect_depth(vec2 uv) { return g_depth; }"""

    def draw(self, canvas):
        uniforms = {"u_inverse": np.linalg.inv(canvas.view_projection).T.ravel(), "u_color": self.color,
                    "u_view_proj": canvas.view_projection.T.ravel(), "u_sphere": (*self.center, self.radius),
                    "u_light": self.light}  # fmt: skip
        with canvas.preserved():  # rule 4: the pass changes GL state
            canvas.fullscreen("ray-traced sphere", self.GLSL, (), uniforms, depth=True, depth_test="less")

    def bounds(self):
        return np.subtract(self.center, self.radius), np.add(self.center, self.radius)


LIGHT = om.PointLight(position=(3, 5, 4))


def meshes() -> om.Node:
    scene = om.Node("meshes", [om.Camera.look_at((0, 2.2, 5.5), (0, 0.4, 0), fov=40), LIGHT])
    scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.75)), om.Box(size=(6, 0.1, 4), center=(0, -0.05, 0))]))
    scene.add(
        om.Node("slab", [om.Material(diffuse=(0.3, 0.55, 0.9)), om.Box(size=(2.4, 1.2, 0.15), center=(0, 0.6, 0))])
    )
    return scene


def trees() -> list[C.Renderer]:
    sphere = RayTracedSphere(center=(0.3, 0.75, 0.0), radius=0.6, light=LIGHT.position)
    return [
        C.DepthGroup([C.SceneRenderer(meshes()), sphere]),
        C.ShadowGroup(LIGHT, [C.SceneRenderer(meshes()), sphere]),
    ]


if __name__ == "__main__":
    out = output_dir()
    print(C.check_rules(trees()[0].children[1]))
    side_by_side([tree.render((400, 300), background=(0.55, 0.6, 0.7)) for tree in trees()]).save(
        out / "14-user-renderer.png"
    )
    print(f"wrote {out / '14-user-renderer.png'}")
