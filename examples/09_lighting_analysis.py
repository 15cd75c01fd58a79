"""Example 6: lighting simulation with Radiance — a picture and an illuminance map from one scene graph.

A courtyard: a floor between two walls, under a uniform overcast sky, with a
lamp (a point light with physical inverse-square falloff).  The same graph is
rendered as a picture with ``rpict`` and, as an analysis engine, gives the
illuminance in lux on a grid of floor points with ``rtrace`` (the paper's
point that engines need not make images).  Writes 09-lighting-analysis.png: the
picture next to the illuminance map in false colour, with the lux values of
the colour scale printed.  The picture is exposed for the sky (``exposure=``);
its ``.hdr`` keeps the radiance in W/sr/m².

    python examples/09_lighting_analysis.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om

SIZE = (320, 240)
GRID = 48  # floor points per side of the map


def build_scene() -> om.Node:
    scene = om.Node("courtyard")
    scene.add(om.Camera.look_at(eye=(6, 7, 9), center=(0, 0, 0), fov=40))
    scene.add(om.radiance.Sky(intensity=10))  # overcast: 10 W/sr/m² from every direction above
    scene.add(om.radiance.Options(ab=1))  # the sky lights through one interreflection
    lamp = om.PointLight(position=(1.5, 2.5, 1), color=(1, 0.9, 0.7), intensity=60, constant=0, quadratic=1)
    scene.add(lamp)  # 60 pi W/sr
    scene.add(om.Node("floor", [om.Color(0.7, 0.7, 0.7), om.Box(size=(8, 0.1, 8), center=(0, -0.05, 0))]))
    walls = scene.add(om.Node("walls", [om.Color(0.8, 0.75, 0.7)]))
    walls.add(om.Box(size=(0.3, 4, 8), center=(-4, 2, 0)))
    walls.add(om.Box(size=(8, 4, 0.3), center=(0, 2, -4)))
    return scene


def false_colour(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """Blue (low) - green - yellow - red (high) for an (H, W) array: (H, W, 4) uint8."""
    t = np.clip((values - low) / (high - low), 0.0, 1.0)[..., None]
    stops = np.array([[0.1, 0.2, 0.8], [0.1, 0.8, 0.4], [0.95, 0.9, 0.2], [0.9, 0.2, 0.1]])
    x = t * (len(stops) - 1)
    i = np.minimum(x.astype(int), len(stops) - 2)[..., 0]
    rgb = stops[i] + (x - i[..., None]) * (stops[i + 1] - stops[i])
    return np.concatenate([np.round(rgb * 255), np.full(values.shape + (1,), 255)], axis=-1).astype(np.uint8)


def main() -> None:
    out = output_dir()
    scene = build_scene()
    # physical units: expose the picture for the sky (1 / its radiance), the .hdr keeps W/sr/m²
    picture = om.render(scene, engine="radiance", size=SIZE, oversample=2, exposure=1 / 15)
    xs = np.linspace(-3.7, 3.9, GRID)  # the walls stand at x = -4 and z = -4
    x, z = np.meshgrid(xs, xs)
    points = np.column_stack([x.ravel(), np.full(x.size, 0.001), z.ravel()])
    lux = om.radiance.illuminance(scene, points, np.tile([0.0, 1.0, 0.0], (len(points), 1))).reshape(GRID, GRID)
    low, high = float(lux.min()), float(lux.max())
    print(f"illuminance on the floor: {low:,.0f} lux (by the walls) to {high:,.0f} lux (under the lamp)")
    cell = SIZE[1] // GRID
    chart = np.repeat(np.repeat(false_colour(lux, low, high), cell, axis=0), cell, axis=1)
    side_by_side([picture, om.Image(chart)]).save(out / "09-lighting-analysis.png")
    print(out / "09-lighting-analysis.png")


if __name__ == "__main__":
    main()
