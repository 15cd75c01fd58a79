"""Example 16: a see-through shading model (guacamole's multi-user example) for the deferred pipeline.

Its *visibility* stage runs per fragment before the G-buffer write and discards
the fragments in a cone between the eye and a point of interest, so walls that
stand in the way open up around it: one user sees where another points.  The
lighting is a plain Lambert model.  Other engines and the forward pipeline
show the wall closed.

    python examples/16_see_through.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

from _common import output_dir, side_by_side

import omnirender as om

SEE_THROUGH = om.gl.ShadingModel(
    "see_through",
    parameters={"target": "vec3", "angle": ("float", 10.0)},
    gbuffer={"diffuse": "color"},
    lbuffer={"light": "rgb"},
    visibility="""
void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) {
    vec3 axis = material.target - s.eye;          // from the eye to the point of interest
    vec3 ray = s.world - s.eye;
    float along = dot(ray, axis) / dot(axis, axis);
    if (along > 0.0 && along < 0.97 && dot(normalize(ray), normalize(axis)) > cos(radians(material.angle)))
        discard;                                   // in the cone before the point: see through
    g.diffuse = s.base.rgb;
    l.light = s.emission + s.ambient_reflectance * s.ambient;
}""",
    lighting="""
void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l) {
    l.light += g.diffuse * max(dot(p.N, light.L), 0.0) * light.diffuse;
}""",
    shading="vec3 shading(Pixel p, GBuffer g, LBuffer l) { return l.light; }",
)
TARGET = (0.0, 0.6, -1.5)


def build_scene() -> om.Node:
    scene = om.Node("scene", [om.Camera.look_at((0.5, 1.6, 5), (0, 0.6, -1.5), fov=40),
                              om.PointLight(position=(2, 5, 3)), om.Background((0.82, 0.86, 0.9))])  # fmt: skip
    scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.75)), om.Box(size=(8, 0.1, 8), center=(0, -0.05, 0))]))
    scene.add(om.Node("treasure", [om.Translation(*TARGET), om.Material(diffuse=(1.0, 0.75, 0.1), specular=(1, 1, 1)),
                                   om.Sphere(radius=0.45)]))  # fmt: skip
    walls = scene.add(om.Node("walls", [SEE_THROUGH(target=TARGET, angle=9.0), om.Material(diffuse=(0.55, 0.6, 0.7))]))
    walls.add(om.Box(size=(4, 2.2, 0.2), center=(0, 1.1, 0.5)))
    walls.add(om.Box(size=(0.2, 2.2, 3), center=(-2, 1.1, -1)))
    return scene


if __name__ == "__main__":
    out = output_dir()
    scene = build_scene()
    images = [om.render(scene, engine="gl", size=(480, 320), pipeline=p) for p in ("deferred", "forward")]
    side_by_side(images).save(out / "16-see-through.png")
    print(f"wrote {out / '16-see-through.png'} (left: deferred, the wall opens towards the sphere; right: forward)")
