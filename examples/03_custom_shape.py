"""Example 3: a custom shape in under 40 lines, then a faster GL painter for one subgraph.

``StarPrism`` is a new shape: a declaration holding parameters only.  Its
simplifier turns it into a TriangleSet, which makes it renderable by *every*
engine (GL, POV-Ray, Mitsuba, picking, bounds) at once.  The GL painter is an
optional speed-up: it builds the GPU geometry once per shape version and skips
the simplifier; installed in one node, it serves only that subgraph.
Writes 03-custom-shape.png (left row: simplifier, right row: painter).

    python examples/03_custom_shape.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import time

import numpy as np
from _common import output_dir

import omnirender as om
from omnirender.gl import GLEngine
from omnirender.gl.engine.geometry import Geometry


# --- the shape, its simplifier and a GL painter: under 40 lines ---------------------------------
class StarPrism(om.Shape):
    """A star with ``tips`` points extruded along y by ``height``."""

    __slots__ = ("tips", "outer", "inner", "height")

    def __init__(self, tips: int = 5, outer: float = 1.0, inner: float = 0.45, height: float = 0.3) -> None:
        super().__init__()
        self.tips, self.outer, self.inner, self.height = int(tips), float(outer), float(inner), float(height)

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        n, a = 2 * self.tips, np.arange(2 * self.tips) * np.pi / self.tips
        r = np.where(np.arange(n) % 2 == 0, self.outer, self.inner)
        ring = np.stack([r * np.sin(a), np.zeros(n), r * np.cos(a)], axis=1)
        h = np.array([0, self.height / 2, 0])
        v = np.concatenate([ring + h, ring - h, [h, -h]])  # top ring, bottom ring, two centres
        i, j = np.arange(n), (np.arange(n) + 1) % n
        top, bottom = np.stack([np.full(n, 2 * n), i, j], 1), np.stack([np.full(n, 2 * n + 1), j + n, i + n], 1)
        return v, np.concatenate([top, bottom, np.stack([i, i + n, j + n], 1), np.stack([i, j + n, j], 1)])


@om.default_for(om.Engine)
class StarPrismSimplifier(om.ShapeSimplifier):
    target = StarPrism

    def exec(self, shape: StarPrism, engine: om.Engine) -> list:
        return [om.TriangleSet(*shape.mesh())]  # now every engine can draw, pick and bound it


class FastStarPrismPainter(om.ShapePainter):
    service, target = "gl.paint", StarPrism

    def exec(self, shape: StarPrism, engine: GLEngine) -> None:
        geometry = engine.geometry_cache.get(shape)
        if geometry is None:  # once per shape version: flat-shaded, unindexed triangles
            v, f = shape.mesh()
            n = np.repeat(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), 3, axis=0)
            geometry = Geometry("triangles", v[f].reshape(-1, 3), n / np.linalg.norm(n, axis=1, keepdims=True))
            engine.geometry_cache.put(shape, geometry)
        engine.submit(geometry)


# --- using them -------------------------------------------------------------------------------
def build_scene() -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 6, 7), center=(0, 0, 0.3), fov=40))
    scene.add(om.Background((0.9, 0.92, 0.95)))
    scene.add(om.PointLight(position=(3, 8, 6)))
    for name, x, color in (("simplified", -2.2, (0.2, 0.5, 0.9)), ("painted", 2.2, (0.95, 0.55, 0.1))):
        row = scene.add(om.Node(name))
        if name == "painted":
            row.add(FastStarPrismPainter())  # installed here: serves this subgraph only
        row.add(om.Material(diffuse=color, specular=(0.6, 0.6, 0.6), shininess=30))
        for k in range(9):
            star = row.add(om.Node(f"star{k}"))
            star.add(om.Translation(x + (k % 3 - 1) * 1.3, 0, (k // 3 - 1) * 1.3))
            star.add(om.Rotation(15 * k, (0, 1, 0)))
            star.add(StarPrism(tips=5 + k % 3, outer=0.6, inner=0.27, height=0.25))
    return scene


def main() -> list:
    out = output_dir()
    scene = build_scene()
    engine = GLEngine(size=(720, 400))
    try:
        image = engine.render(scene)
        for name in ("simplified", "painted"):  # what re-evaluating a changed row costs
            row = scene[f"/scene/{name}"]
            t0 = time.perf_counter()
            for _ in range(20):
                for star in row.children:
                    star.touch()
                engine.compile(scene)
            print(f"{name:10s} row: {(time.perf_counter() - t0) / 20 * 1000:.2f} ms per re-evaluation")
    finally:
        engine.release()
    hits = om.pick(scene, pixel=(230, 180), size=(720, 400))  # the new shape is pickable too
    print("picked:", hits[0].path if hits else None, type(hits[0].shape).__name__ if hits else "")
    path = image.save(out / "03-custom-shape.png")
    print(path)
    return [path]


if __name__ == "__main__":
    main()
