"""Example 15: a toon (cel) shading model for the deferred pipeline, written as users write models.

A shading model is GLSL in four stages with typed outputs.  This one keeps the
diffuse colour in the G-buffer, adds each light in a few flat bands and a hard
highlight in its *lighting* stage, and outlines the silhouettes with a dark rim
in its *shading* stage.  The shapes keep their ordinary om.Material, so the
forward pipeline and POV-Ray show them as plain Phong surfaces.

    python examples/15_toon_model.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

from _common import output_dir, side_by_side

import omnirender as om

TOON = om.gl.ShadingModel(
    "toon",
    parameters={"bands": ("float", 3.0), "rim": ("color", (0.05, 0.05, 0.08))},
    gbuffer={"diffuse": "color"},
    lbuffer={"light": "rgb"},
    visibility="""
void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) {
    g.diffuse = s.base.rgb;
    l.light = s.base.rgb * s.ambient;            // flat ambient
}""",
    lighting="""
void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l) {
    float d = max(dot(p.N, light.L), 0.0);
    float band = ceil(d * material.bands) / material.bands;          // a few flat tones
    float spot = step(0.96, dot(reflect(-light.L, p.N), p.V));       // a hard highlight
    l.light += g.diffuse * band * light.diffuse + 0.6 * spot * light.specular;
}""",
    shading="""
vec3 shading(Pixel p, GBuffer g, LBuffer l) {
    float edge = smoothstep(0.25, 0.35, dot(p.N, p.V));              // dark rim where the surface turns away
    return mix(material.rim, l.light, edge);
}""",
)


def build_scene() -> om.Node:
    scene = om.Node("scene", [om.Camera.look_at((0, 2.2, 6), (0, 0.6, 0), fov=40), om.PointLight(position=(3, 5, 4)),
                              om.Background((0.82, 0.86, 0.9))])  # fmt: skip
    scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.75)), om.Box(size=(8, 0.1, 5), center=(0, -0.05, 0))]))
    toon = scene.add(om.Node("toon", [TOON(bands=3)]))
    ring = [om.Translation(-1.1, 0.8, 0), om.Rotation(60, (1, 0, 0)), om.Material(diffuse=(1, 0.45, 0.3))]
    toon.add(om.Node("ring", [*ring, om.Torus(major_radius=0.6, minor_radius=0.22)]))
    toon.add(om.Node("ball", [om.Translation(1.2, 0.6, 0), om.Material(diffuse=(0.3, 0.6, 1)), om.Sphere(radius=0.6)]))
    return scene


if __name__ == "__main__":
    out = output_dir()
    scene = build_scene()
    images = [om.render(scene, engine="gl", size=(480, 320), pipeline=p) for p in ("deferred", "forward")]
    side_by_side(images).save(out / "15-toon-model.png")
    print(f"wrote {out / '15-toon-model.png'} (left: deferred with the toon model, right: forward, plain Phong)")
