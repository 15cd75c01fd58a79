"""Example 5: picking — which shape is under a pixel, and where is it in the graph?

``om.pick`` shoots the ray through a pixel of the scene's camera and reports
every crossing nearest first, each with the shape the scene holds, its node
path, the distance, world point and normal.  Here a scripted list of "clicks"
stands in for the mouse (``omnirender view`` does the same on a real click).
The viewer then highlights the hit shape.  Writes 05-picking.png with the
clicked pixels marked.

    python examples/05_picking.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir

import omnirender as om
from omnirender.viewer.picking import pick_in_viewer

SIZE = (480, 320)


def build_scene() -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 3, 8), center=(0, 0.6, 0), fov=40))
    scene.add(om.PointLight(position=(4, 6, 6)))
    table = scene.add(om.Node("table"))
    table.add(om.Material(diffuse=(0.6, 0.5, 0.4)))
    table.add(om.Box(size=(7, 0.2, 4), center=(0, -0.1, 0)))
    toys = scene.add(om.Node("toys"))
    for name, x, shape, color in (
        ("ball", -2.2, om.Sphere(radius=0.7), (0.9, 0.2, 0.2)),
        ("ring", 0.0, om.Torus(major_radius=0.7, minor_radius=0.25), (0.2, 0.7, 0.3)),
        ("cone", 2.2, om.Cone(radius=0.6, height=1.5), (0.2, 0.4, 0.9)),
    ):
        node = toys.add(om.Node(name))
        node.add(om.Translation(x, 0.75, 0))
        if name == "ring":
            node.add(om.Rotation(70, (1, 0, 0)))
        node.add(om.Material(diffuse=color))
        node.add(shape)
    return scene


def mark(image: om.Image, x: int, y: int, color=(255, 255, 255, 255)) -> None:
    a = image.array
    a[max(0, y - 8) : y + 9, x] = color
    a[y, max(0, x - 8) : x + 9] = color


def main() -> list:
    out = output_dir()
    scene = build_scene()
    clicks = [(90, 150), (205, 150), (240, 160), (370, 150), (20, 20)]
    for x, y in clicks:
        hits = om.pick(scene, pixel=(x, y), size=SIZE)
        if hits:
            h = hits[0]
            print(f"pixel ({x:3d}, {y:3d}) -> {h.path:18s} {type(h.shape).__name__:8s} "
                  f"at distance {h.distance:.2f}, point {np.round(h.point, 2)}")  # fmt: skip
        else:
            print(f"pixel ({x:3d}, {y:3d}) -> nothing (background)")

    viewer = om.Viewer(size=SIZE)  # highlight the last shape hit, as the window does on a click
    viewer.add_renderable(scene)
    camera, world = scene.preevaluate()[1]
    viewer.set_camera(camera, world)
    viewer.clear_lights()  # the scene brings its own light
    viewer.set_picked(pick_in_viewer(viewer, scene, *clicks[1]))
    image = viewer.rerender()
    for x, y in clicks:
        mark(image, x, y)
    path = image.save(out / "05-picking.png")
    viewer.close()
    print(path)
    return [path]


if __name__ == "__main__":
    main()
