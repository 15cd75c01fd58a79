"""Write the example scene files: the demo scene (demo.json, demo.yaml) and a tour of the format (features.yaml).

Run ``python examples/scenes/make_demo_scene.py``.  ``demo.json`` and
``demo.yaml`` hold exactly the scene ``omnirender demo`` renders
(``omnirender.demo.demo_scene``), with its mesh file copied next to them
(``meshes/knot.obj``: scene files name files inside their own folder), so
``omnirender render examples/scenes/demo.yaml -e povray`` renders the demo.
``features.yaml`` shows what the format holds: an engine-specific attribute
(``povray.Finish``), a mesh file by relative path, a node shared by two
parents (written once with ``$id``, then as ``$ref``) and a group tag hidden
by the camera's mask (a wireframe debug sphere around the torus, left out of
pictures and of clicks in ``omnirender view``).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import omnirender as om
from omnirender.demo import KNOT_PATH, demo_scene

HERE = Path(__file__).resolve().parent


def demo_file_scene() -> om.Node:
    """The demo scene with its mesh file in ``meshes/`` next to the scene files."""
    scene = demo_scene()
    knot = HERE / "meshes" / KNOT_PATH.name
    for node in scene.walk():
        for item in node.items:
            if isinstance(item, om.MeshFile) and Path(item.path) == KNOT_PATH:
                item.path = str(knot)
    return scene


def features_scene() -> om.Node:
    scene = om.Node("demo")
    # the debug sphere (group "debug") is for interactive views, not for this camera's pictures
    scene.add(om.Camera.look_at(eye=(5, 3.5, 7), center=(0, 0.8, 0), up=(0, 1, 0), fov=35, mask="!debug"))
    scene.add(om.Background((0.85, 0.9, 1.0)))
    scene.add(om.PointLight(position=(5, 6, 5), color=(1, 1, 1), intensity=0.9))
    scene.add(om.PointLight(position=(-5, 4, 2), color=(0.6, 0.7, 1.0), intensity=0.5))
    scene.add(om.AmbientLight(intensity=0.15))

    floor = scene.add(om.Node("floor"))
    floor.add(om.Material(diffuse=(0.8, 0.8, 0.8)))
    floor.add(om.Box(size=(10, 0.1, 10), center=(0, -0.05, 0)))

    body = scene.add(om.Node("body"))
    body.add(om.Translation(0, 1.2, 0))
    body.add(om.Rotation(60, (1, 0, 0)))
    body.add(om.Material(diffuse=(1, 0.4, 0.6), specular=(1, 1, 1), shininess=40))
    body.add(om.povray.Finish(phong=0.8))
    body.add(om.Torus(major_radius=1, minor_radius=0.3))

    wheel = om.Node("wheel")
    wheel.add(om.Rotation(90, (1, 0, 0)))
    wheel.add(om.PBRMaterial(base_color=(0.2, 0.2, 0.25), metallic=0.8, roughness=0.3))
    wheel.add(om.Cylinder(radius=0.4, height=0.2))
    wheels = scene.add(om.Node("wheels"))
    wheels.add(om.Node("left", [om.Translation(-2, 0.4, 1.5), wheel]))
    wheels.add(om.Node("right", [om.Translation(2, 0.4, 1.5), wheel]))

    mesh = scene.add(om.Node("mesh"))
    mesh.add(om.Translation(2, 0, -1.5))
    mesh.add(om.Material(diffuse=(0.3, 0.7, 0.4)))
    mesh.add(om.MeshFile(HERE / "meshes" / "pyramid.obj"))

    debug = scene.add(om.Node("debug", groups=["debug"]))
    debug.add(om.DrawStyle(mode="wireframe"))
    debug.add(om.Sphere(center=(0, 1.2, 0), radius=1.6))
    return scene


if __name__ == "__main__":
    shutil.copyfile(KNOT_PATH, HERE / "meshes" / KNOT_PATH.name)
    demo = demo_file_scene()
    for name in ("demo.json", "demo.yaml"):
        print(om.save(demo, HERE / name))
    print(om.save(features_scene(), HERE / "features.yaml"))
