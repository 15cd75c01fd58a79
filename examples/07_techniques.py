"""Example 7: the VRS paper's Figure 16 — techniques put into the scene like attributes.

Four panels, each one scene graph with techniques placed before the shapes
they apply to:

(a) enhanced silhouettes: a textured ball and a ring under a Phong-highlight
    technique and a silhouette surface style (the paper's nesting: texture,
    highlight, style, shape);
(b) haloed wire-frame: an octahedron and a coarse ring as lines that break
    where they pass behind other lines;
(c) planar reflection: a floor mirror (``om.Mirror``) under a ball and a ring;
(d) reflection combined with shadows: the same mirror, a wall behind, the
    ball's shadow on the wall seen in the mirror (shadow maps are on by
    default in GL).

The GL engine runs every technique; POV-Ray renders the same graphs with its
own shadows and reflections and ignores the GL-only line styles.

    python examples/07_techniques.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir

import omnirender as om

PANELS = ("a", "b", "c", "d")
SIZE = (360, 270)


def checker(n: int = 8) -> np.ndarray:
    """A small red-and-cream checker texture (RGBA)."""
    cells = (np.indices((64, 64)).sum(axis=0) // (64 // n)) % 2
    out = np.empty((64, 64, 4), np.uint8)
    out[...] = (240, 225, 190, 255)
    out[cells == 1] = (200, 60, 40, 255)
    return out


def octahedron() -> om.TriangleSet:
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)
    f = [[2, 4, 0], [2, 0, 5], [2, 5, 1], [2, 1, 4], [3, 0, 4], [3, 5, 0], [3, 1, 5], [3, 4, 1]]
    return om.TriangleSet(v * 0.9, f)


def stage(eye=(0.0, 2.2, 6.0), background=(0.92, 0.93, 0.95), light=(2.5, 5.0, 4.0)) -> om.Node:
    scene = om.Node("scene", [om.Camera.look_at(eye, (0, 0.7, 0), fov=38), om.Background(background)])
    scene.add(om.PointLight(position=light, intensity=0.9))
    scene.add(om.AmbientLight(intensity=0.15))
    return scene


def ball(center=(-0.9, 0.75, 0.0)) -> om.Node:
    return om.Node("ball", [om.Material(diffuse=(0.9, 0.35, 0.25), specular=(0.8, 0.8, 0.8), shininess=50),
                            om.Sphere(center=center, radius=0.6)])  # fmt: skip


def ring() -> om.Node:
    return om.Node("ring", [om.Translation(1.0, 0.75, 0.0), om.Rotation(70, (1, 0, 0)),
                            om.Material(diffuse=(0.25, 0.5, 0.9), specular=(0.8, 0.8, 0.8), shininess=60),
                            om.Torus(major_radius=0.5, minor_radius=0.18)])  # fmt: skip


def floor(mirror: bool) -> om.Node:
    items = [om.Material(diffuse=(0.55, 0.56, 0.6))] + ([om.Mirror(0.7)] if mirror else [])
    return om.Node("floor", [*items, om.Rectangle(size=(7, 7))])


def build_scene(panel: str) -> om.Node:
    """The scene of Figure 16 (``panel`` a, b, c or d)."""
    if panel == "a":
        scene = stage()
        highlight = om.gl.PhongHighlight(om.Texture(om.gl.PhongHighlight.lobe(30)))
        style = om.gl.SurfaceStyle("silhouette", width=3, color=(0.05, 0.05, 0.1))
        styled = scene.add(om.Node("styled", [om.Texture(checker()), highlight, style]))  # the paper's nesting
        styled.add(ball())
        styled.add(ring())
        scene.add(floor(mirror=False))
        return scene
    if panel == "b":
        scene = stage(background=(1.0, 1.0, 1.0))
        wire = scene.add(om.Node("wire", [om.gl.SurfaceStyle("haloed", width=2, halo=4, color=(0.1, 0.1, 0.2)),
                                          om.Tessellation(1)]))  # fmt: skip
        wire.add(om.Node("gem", [om.Translation(-0.9, 0.8, 0.0), om.Rotation(25, (0, 1, 0)), octahedron()]))
        wire.add(ring())
        return scene
    # (d): a low light in front throws the ball's shadow onto the wall, and the mirror shows it
    scene = stage(eye=(0.0, 2.6, 6.5), light=(1.5, 2.4, 5.5) if panel == "d" else (2.5, 5.0, 4.0))
    scene.add(floor(mirror=True))
    scene.add(ball(center=(-0.5, 0.9, 0.2)))
    scene.add(ring())
    if panel == "d":
        scene.add(
            om.Node("wall", [om.Material(diffuse=(0.85, 0.8, 0.7)), om.Box(size=(7, 3, 0.2), center=(0, 1.5, -1.6))])
        )
    return scene


def figure(engine: str = "gl", size: tuple[int, int] = SIZE) -> om.Image:
    """The four panels as one 2x2 image."""
    images = [om.render(build_scene(p), engine=engine, size=size).array for p in PANELS]
    top = np.concatenate(images[:2], axis=1)
    bottom = np.concatenate(images[2:], axis=1)
    return om.Image(np.concatenate([top, bottom], axis=0))


if __name__ == "__main__":
    out = output_dir()
    figure().save(out / "07-techniques.png")
    print(f"wrote {out / '07-techniques.png'} (Figure 16: (a) silhouettes, (b) haloed wire-frame, (c) mirror, "
          "(d) mirror and shadows)")  # fmt: skip
