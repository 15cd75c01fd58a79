"""Scenes and the fresh-engine reference shared by the change-tracker tests (moves, replacements, splices).

Each such test changes a scene an engine has drawn and compares the next picture with a fresh engine's picture
of the same scene: the change path must draw exactly what a full compile draws.
"""

from __future__ import annotations

import numpy as np

import omnirender as om

SIZE = (80, 64)


def fresh(scene: om.Node, shadows: bool = False) -> np.ndarray:
    """A fresh engine's picture of ``scene`` (at :data:`SIZE`, MSAA off)."""
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=shadows) as e:
        return e.render(scene).array


def nested_scene() -> tuple[om.Node, list[om.Node], list[om.Node]]:
    """Four groups (a Translation, then a Rotation) of five leaves each (a Translation, a Material, a box or a
    sphere, the sphere placed by a shape-local matrix); returns the scene, the groups and the leaves."""
    scene = om.Node("scene", [om.Camera.look_at((9, 7, 14), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    groups = [
        scene.add(om.Node(f"g{g}", [om.Translation(2.5 * g - 3.5, 0.0, 0.0), om.Rotation(10.0 * g, (0, 1, 0))]))
        for g in range(4)
    ]
    leaves = []
    for g, group in enumerate(groups):
        for i in range(5):
            shape = om.Box(size=(0.6, 0.4, 0.5)) if (g + i) % 2 else om.Sphere(radius=0.35)
            leaves.append(
                group.add(
                    om.Node(
                        f"l{g}_{i}",
                        [om.Translation(0.0, i - 2.0, 0.0), om.Material(diffuse=(0.2 * i, 0.5, 0.3 * g)), shape],
                    )
                )
            )
    return scene, groups, leaves


def box_grid(
    count: int,
    columns: int,
    box_size: float,
    eye: tuple[float, float, float],
    fov: float = 40.0,
    light: tuple[float, float, float] = (-0.4, -0.6, -1.0),
) -> tuple[om.Node, list[om.Node]]:
    """``count`` nodes of a Translation, a default Material and one shared box, ``columns`` to a row of a grid
    centred on the origin (unit spacing, z = 0), seen from ``eye``; returns the scene and the nodes."""
    scene = om.Node("scene", [om.Camera.look_at(eye, (0, 0, 0), fov=fov), om.DirectionalLight(direction=light)])
    box = om.Box(size=box_size)
    rows = -(-count // columns)
    nodes = []
    for i in range(count):
        place = om.Translation(i % columns - (columns - 1) / 2, i // columns - (rows - 1) / 2, 0.0)
        nodes.append(scene.add(om.Node(f"b{i}", [place, om.Material(), box])))
    return scene, nodes
