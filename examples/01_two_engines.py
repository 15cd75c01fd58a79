"""Example 1: two engines, one scene.

A floor, a mesh read from a file lit by two point lights, and a POV-Ray
``finish`` that only POV-Ray understands (the GL engine ignores it).  The GL
engine gives the real-time preview, POV-Ray the final image; both come from
the very same scene graph.  Writes 01-two-engines.png (preview | final).

    python examples/01_two_engines.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om


def write_knot_obj(path, p=2, q=3, tube=0.28, segments=240, sides=16):
    """A (p, q) torus-knot tube as a Wavefront OBJ file: our 'mesh from a file'."""
    t = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    r = 2 + np.cos(q * t)
    c = np.stack([r * np.cos(p * t), np.sin(q * t), r * np.sin(p * t)], axis=1) * 0.5
    tangent = np.roll(c, -1, axis=0) - np.roll(c, 1, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.cross(tangent, (0, 1, 0))
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    binormal = np.cross(tangent, normal)
    a = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.cos(a)[None, :, None] * normal[:, None] + np.sin(a)[None, :, None] * binormal[:, None]
    verts = (c[:, None] + tube * ring).reshape(-1, 3)
    faces = []
    for i in range(segments):
        for j in range(sides):
            v00 = i * sides + j
            v01 = i * sides + (j + 1) % sides
            v10 = (i + 1) % segments * sides + j
            v11 = (i + 1) % segments * sides + (j + 1) % sides
            faces += [(v00, v11, v10), (v00, v01, v11)]  # counter-clockwise seen from outside
    with open(path, "w") as f:
        f.write("# torus knot written by examples/01_two_engines.py\n")
        f.writelines(f"v {x:.5f} {y:.5f} {z:.5f}\n" for x, y, z in verts)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
    return path


def build_scene(mesh_path) -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 3.2, 6.5), center=(0, 0.7, 0), fov=35))
    scene.add(om.Background((0.55, 0.62, 0.72)))
    scene.add(om.PointLight(position=(4, 6, 4), color=(1.0, 0.95, 0.9), intensity=1.0))
    scene.add(om.PointLight(position=(-5, 3, 2), color=(0.5, 0.6, 1.0), intensity=0.6))
    floor = scene.add(om.Node("floor"))
    floor.add(om.Material(diffuse=(0.75, 0.75, 0.72)))
    floor.add(om.Box(size=(8, 0.1, 8), center=(0, -0.05, 0)))
    knot = scene.add(om.Node("knot"))
    knot.add(om.Translation(0, 0.95, 0))
    knot.add(om.Material(diffuse=(0.85, 0.35, 0.15), specular=(1, 1, 1), shininess=60))
    knot.add(om.povray.Finish(phong=0.9, reflection=0.15))  # POV-Ray reads it; others take its phong
    knot.add(om.MeshFile(mesh_path))
    return scene


def main() -> list:
    out = output_dir()
    scene = build_scene(write_knot_obj(out / "knot.obj"))
    size = (480, 360)
    preview = om.render(scene, engine="gl", size=size)
    written = [preview.save(out / "01-gl-preview.png")]
    ok, why = om.engines()["povray"]
    if ok:
        final = om.render(scene, engine="povray", size=size, antialias=True)
        written.append(final.save(out / "01-povray-final.png"))
        written.append(side_by_side([preview, final]).save(out / "01-two-engines.png"))
    else:
        print(f"POV-Ray unavailable ({why}): only the GL preview was rendered")
        written.append(preview.save(out / "01-two-engines.png"))
    for path in written:
        print(path)
    return written


if __name__ == "__main__":
    main()
