"""Example 2: data sequences.

A star-shaped polygon whose outline comes from a numpy array (``om.data.Array``,
no copy), one normal for all its vertices (``om.data.Constant``, stored once)
and alternating tip/notch colours (``om.data.Repeat`` of a two-colour
pattern).  The sequences describe the data without building it; painters call
``.array()`` and get vectorised numpy.  Writes 02-data-sequences.png.

    python examples/02_data_sequences.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir

import omnirender as om


def star_polygon(tips: int = 7, outer: float = 1.4, inner: float = 0.6) -> om.Polygon:
    angles = np.pi / 2 + np.arange(2 * tips) * np.pi / tips
    radii = np.where(np.arange(2 * tips) % 2 == 0, outer, inner)
    outline = np.stack([radii * np.cos(angles), radii * np.sin(angles), np.zeros(2 * tips)], axis=1)
    vertices = om.data.Array(outline)  # the array itself, no copy
    normals = om.data.Constant((0.0, 0.0, 1.0), len(vertices))  # one normal, stored once
    pattern = [(1.0, 0.78, 0.1, 1.0), (0.8, 0.1, 0.6, 1.0)]  # tip colour, notch colour
    colors = om.data.Repeat(pattern, times=tips)  # tip, notch, tip, notch, ...
    assert vertices.array() is outline and colors.array().shape == (2 * tips, 4)
    return om.Polygon(vertices, normals=normals, colors=colors)


def main() -> list:
    out = output_dir()
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 0, 6), center=(0, 0, 0), fov=40))
    scene.add(om.Background((0.08, 0.09, 0.12)))
    scene.add(om.DirectionalLight(direction=(0, 0, -1)))
    stars = scene.add(om.Node("stars"))
    for i, tips in enumerate((5, 7, 9)):
        node = stars.add(om.Node(f"star{tips}"))
        node.add(om.Translation((i - 1) * 2.6, 0, 0))
        node.add(om.Rotation(10 * i, (0, 0, 1)))
        node.add(star_polygon(tips, outer=1.2, inner=0.5))
    image = om.render(scene, engine="gl", size=(720, 280))
    path = image.save(out / "02-data-sequences.png")
    print(path)
    return [path]


if __name__ == "__main__":
    main()
