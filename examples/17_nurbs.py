"""Example 17: a trimmed NURBS surface, tessellated on the GPU by the GL engine and as a mesh elsewhere.

A bicubic sheet swept into a wave, with a circular window cut by a TrimCurve
(an exact rational circle) and a square window cut by a polyline.  The GL
engine tessellates its Bézier patches in tessellation shaders to half a pixel
and trims per fragment, in the deferred pipeline's G-buffer like any mesh
(left); POV-Ray draws the simplifier's trimmed mesh (right).

    python examples/17_nurbs.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om


def wave(nu: int = 7, nv: int = 5) -> np.ndarray:
    """(nu, nv, 3) control points: a sheet 4 wide and 2.6 deep, rolled up at the back, rippled across."""
    u, v = np.linspace(-2.0, 2.0, nu), np.linspace(0.0, 1.0, nv)
    cp = np.zeros((nu, nv, 3))
    cp[..., 0] = u[:, None]
    cp[..., 2] = 1.3 - 2.6 * v[None, :]
    cp[..., 1] = 0.35 * np.sin(2.2 * u[:, None]) + 1.6 * v[None, :] ** 2
    return cp


def circle(cx: float, cy: float, r: float) -> om.TrimCurve:
    """A clockwise rational quadratic circle in the (u, v) square: it cuts a round hole."""
    corners = [(1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0)]
    points = [(cx + r * a, cy + r * b) for a, b in corners]
    weights = [1, 0.5**0.5] * 4 + [1]
    return om.TrimCurve(points, weights=weights, knots=[0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4], degree=2)


def build_scene() -> om.Node:
    scene = om.Node("scene", [om.Camera.look_at((0.4, 2.6, 5.2), (0, 0.5, 0), fov=40),
                              om.PointLight(position=(3, 5, 4)), om.PointLight(position=(-4, 2, 3), intensity=0.4),
                              om.Background((0.85, 0.88, 0.92)),
                              om.gl.ShadowMaps(resolution=2048, softness=2.0)])  # fmt: skip
    scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.75)), om.Box(size=(8, 0.1, 6), center=(0, -0.5, 0))]))
    square = [(0.62, 0.25), (0.62, 0.55), (0.85, 0.55), (0.85, 0.25)]  # clockwise: a hole
    sheet = om.NURBSSurface(wave(), trim=[circle(0.3, 0.4, 0.14), square])
    material = om.Material(diffuse=(0.95, 0.55, 0.2), specular=(0.6,) * 3, shininess=50)
    scene.add(om.Node("sheet", [material, om.DrawStyle(cull="none"), sheet]))
    return scene


if __name__ == "__main__":
    out = output_dir()
    scene = build_scene()
    gl = om.render(scene, engine="gl", size=(480, 320), pipeline="deferred")
    povray = om.render(scene, engine="povray", size=(480, 320), antialias=True)
    side_by_side([gl, povray]).save(out / "17-nurbs.png")
    print(f"wrote {out / '17-nurbs.png'} (left: GL, tessellated on the GPU; right: POV-Ray, the trimmed mesh)")
