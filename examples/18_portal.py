"""Example 18: chained pipelines: a portal into another scene, a security-camera screen and a glass ball.

``om.gl.RenderTexture(scene, camera, size)`` is a texture whose image is a
scene seen through a camera (guacamole's chained pipelines).  The wall's
portal shows a garden, a different scene; the monitor shows the room itself
from a camera in the corner, monitor included: that pipeline reads its own
previous frame, so the screen within the screen lags one frame per level.
The glass ball refracts the room in screen space (``om.gl.Refraction``): it
reads a pipeline of the room seen by the frame's camera without the ball
(the camera's group mask).  The GL engine draws the pipelines before each
frame, in dependency order.

    python examples/18_portal.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir

import omnirender as om


def screen(width: float, height: float) -> om.TriangleSet:
    """A rectangle in the xy plane facing +z, with texture coordinates over it."""
    w, h = width / 2, height / 2
    vertices = np.array([[-w, -h, 0], [w, -h, 0], [w, h, 0], [-w, h, 0]], float)
    return om.TriangleSet(vertices, [[0, 1, 2], [0, 2, 3]], normals=[[0, 0, 1]] * 4,
                          texcoords=[[0, 0], [1, 0], [1, 1], [0, 1]])  # fmt: skip


def garden() -> om.Node:
    scene = om.Node("garden", [om.Background((0.45, 0.65, 0.95)), om.DirectionalLight(direction=(-0.4, -1, -0.6))])
    scene.add(om.Node("lawn", [om.Material(diffuse=(0.25, 0.6, 0.2)), om.Box(size=(30, 0.1, 30))]))
    for i, (x, z, color) in enumerate(
        [(-1.2, -1, (1, 0.3, 0.2)), (0.3, -2, (1, 0.85, 0.2)), (1.5, -0.5, (0.7, 0.3, 1))]
    ):
        tree = scene.add(om.Node(f"tree{i}", [om.Translation(x, 0, z)]))
        tree.add(om.Node("trunk", [om.Material(diffuse=(0.45, 0.3, 0.15)), om.Translation(0, 0.4, 0),
                                   om.Cylinder(radius=0.08, height=0.8)]))  # fmt: skip
        tree.add(om.Node("crown", [om.Material(diffuse=color, specular=(0.3, 0.3, 0.3)), om.Translation(0, 1.1, 0),
                                   om.Sphere(radius=0.45)]))  # fmt: skip
    return scene


SIZE = (640, 420)
EYE, CENTER, FOV = (1.2, 1.7, 5.2), (0, 1.2, 0), 45


def build_scene() -> tuple[om.Node, om.gl.RenderTexture, om.gl.RenderTexture]:
    room = om.Node("room", [om.Camera.look_at(EYE, CENTER, fov=FOV),
                            om.PointLight(position=(1, 3.2, 3)), om.Background((0.1, 0.1, 0.12))])  # fmt: skip
    room.add(om.Node("floor", [om.Material(diffuse=(0.6, 0.55, 0.5)), om.Box(size=(8, 0.1, 8), center=(0, -0.05, 0))]))
    room.add(om.Node("wall", [om.Material(diffuse=(0.8, 0.78, 0.72)), om.Box(size=(8, 3, 0.2), center=(0, 1.5, -0.1))]))
    view = om.gl.RenderTexture(garden(), om.Camera.look_at((0, 1.2, 4), (0, 0.9, 0), fov=50), (480, 300),
                               name="garden view")  # fmt: skip
    portal = room.add(om.Node("portal", [om.Translation(-0.9, 1.4, 0.01)]))
    portal.add(om.Node("frame", [om.Material(diffuse=(0.3, 0.2, 0.1)), om.Box(size=(2.5, 1.7, 0.04))]))
    portal.add(om.Node("glass", [om.Translation(0, 0, 0.03), om.Material(ambient=(1, 1, 1), diffuse=(0.3, 0.3, 0.3)),
                                 view, screen(2.3, 1.5)]))  # fmt: skip
    room.add(om.Node("statue", [om.Translation(-0.3, 0.45, 1.6), om.Material(diffuse=(0.9, 0.2, 0.2),
             specular=(1, 1, 1), shininess=60), om.Torus(major_radius=0.35, minor_radius=0.12)]))  # fmt: skip
    security = om.gl.RenderTexture(room, om.Camera.look_at((-3.2, 2.8, 3.5), (0.3, 0.9, 0.3), fov=60), (320, 240),
                                   name="security camera")  # fmt: skip
    monitor = room.add(om.Node("monitor", [om.Translation(1.9, 1.0, 1.0), om.Rotation(axis=(0, 1, 0), angle=-30)]))
    monitor.add(om.Node("case", [om.Material(diffuse=(0.15, 0.15, 0.15)), om.Box(size=(1.3, 1.0, 0.12))]))
    monitor.add(om.Node("stand", [om.Material(diffuse=(0.15, 0.15, 0.15)), om.Translation(0, -0.75, 0),
                                  om.Box(size=(0.1, 0.5, 0.1))]))  # fmt: skip
    glow = om.Material(ambient=(1, 1, 1), diffuse=(0.3, 0.3, 0.3))
    monitor.add(om.Node("picture", [om.Translation(0, 0, 0.065), glow, security, screen(1.2, 0.9)]))
    behind = om.gl.RenderTexture(room, om.Camera.look_at(EYE, CENTER, fov=FOV, mask="!glass"), SIZE,
                                 name="behind the glass")  # fmt: skip
    ball = room.add(om.Node("glass ball", [om.Translation(0.55, 0.38, 0.9)], groups=["glass"]))
    ball.add(om.gl.Refraction(behind, strength=0.12, tint=(0.85, 0.95, 1.0)))
    ball.add(om.Material(diffuse=(0.2, 0.2, 0.2), specular=(1, 1, 1), shininess=80))
    ball.add(om.Sphere(radius=0.38))
    return room, view, security


if __name__ == "__main__":
    out = output_dir()
    scene, view, security = build_scene()
    with om.gl.GLEngine(size=SIZE) as engine:
        for _ in range(3):  # the monitor shows the room's last frame: three frames fill three levels
            image = engine.render(scene)
        order = [p["name"] for p in engine.stats["pipelines"]]
    image.save(out / "18-portal.png")
    print(f"wrote {out / '18-portal.png'} (pipelines {order}, drawn before each frame)")
