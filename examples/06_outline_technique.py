"""Example 6: a user-written two-pass technique, put into the scene like an attribute.

Pass 1 draws the back faces of the shapes after it, pushed out along their
normals in a flat colour; pass 2 draws the shapes normally, so an outline
remains around them.  It applies to one subgraph only; POV-Ray ignores it.

    python examples/06_outline_technique.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

from _common import output_dir, side_by_side

import omnirender as om

PUSH_OUT = "uniform float u_width; void pass_vertex(inout vec3 world, inout vec3 normal) { world += normal * u_width; }"


class Outline(om.gl.GLTechnique):
    """Outlines of ``width`` (world units) in ``color`` around the rest of the node."""

    __slots__ = ("color", "width")

    def __init__(self, color=(0.05, 0.05, 0.08), width=0.035):
        super().__init__(passes=2)
        self.color, self.width = color, width

    def prepare_pass(self, engine):
        if engine.current_pass == 0:
            shader = om.gl.Shader(flat_color=self.color, vertex=PUSH_OUT, uniforms={"u_width": self.width})
            engine.set_pass(om.gl.Pass("outline", state=[om.gl.CullFace("front")], shader=shader))
        else:
            engine.set_pass(om.gl.Pass("shapes"))


def build_scene(outline: bool = True) -> om.Node:
    scene = om.Node("scene", [om.Camera.look_at((0, 2.2, 6), (0, 0.6, 0), fov=40), om.PointLight(position=(3, 5, 4)),
                              om.Background((0.82, 0.86, 0.9))])  # fmt: skip
    scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.75)), om.Box(size=(8, 0.1, 5), center=(0, -0.05, 0))]))
    toon = scene.add(om.Node("toon", [Outline()] if outline else []))
    ring = [om.Translation(-1.1, 0.8, 0), om.Rotation(60, (1, 0, 0)), om.Material(diffuse=(1, 0.45, 0.3))]
    toon.add(om.Node("ring", [*ring, om.Torus(major_radius=0.6, minor_radius=0.22)]))
    scene.add(om.Node("ball", [om.Translation(1.2, 0.6, 0), om.Material(diffuse=(0.3, 0.6, 1)), om.Sphere(radius=0.6)]))
    return scene


if __name__ == "__main__":
    out = output_dir()
    gl, pov = (om.render(build_scene(), engine=e, size=(480, 320)) for e in ("gl", "povray"))
    side_by_side([gl, pov]).save(out / "06-outline-technique.png")
    print(f"wrote {out / '06-outline-technique.png'} (left: GL with the outline technique, right: POV-Ray ignoring it)")
