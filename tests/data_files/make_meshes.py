"""Write the small mesh files the tests load (run: python tests/data_files/make_meshes.py).

* ``cube.obj`` + ``cube.mtl``: unit cube (centred), one Phong material (diffuse red).
* ``cube.ply``: unit cube with per-vertex colours.
* ``tetra.stl``: a tetrahedron (binary STL).
* ``cube.off``: unit cube.
* ``two_parts.glb``: two meshes (a cube at x = -1 and an icosphere at x = +1, radius 0.5),
  PBR materials (green metallic, blue rough).
* ``textured.obj`` + ``textured.mtl`` + its PNG: a 2 x 2 quad facing +z with texture coordinates
  and a 2 x 2 checker texture (red top-left, blue bottom-right).
* ``malformed.obj`` / ``malformed.ply``: broken files for error tests.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np


def write_all(directory: str | Path) -> Path:
    import trimesh
    from trimesh.visual.material import PBRMaterial, SimpleMaterial
    from trimesh.visual.texture import TextureVisuals

    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)

    cube = trimesh.creation.box(extents=(1, 1, 1))
    red = SimpleMaterial(name="red", diffuse=(255, 0, 0, 255), ambient=(50, 0, 0, 255), specular=(255, 255, 255, 255))
    red_cube = trimesh.Trimesh(cube.vertices, cube.faces, process=False)
    red_cube.visual = TextureVisuals(material=red)
    obj_text = trimesh.exchange.obj.export_obj(red_cube, include_texture=True, mtl_name="cube.mtl", return_texture=True)
    text, files = obj_text
    (out / "cube.obj").write_text(text)
    for name, data in files.items():
        (out / name).write_bytes(data)

    colored = trimesh.Trimesh(cube.vertices, cube.faces, process=False)
    colored.visual.vertex_colors = (np.abs(cube.vertices) * 0 + (cube.vertices + 0.5)) * 255
    (out / "cube.ply").write_bytes(trimesh.exchange.ply.export_ply(colored, encoding="ascii"))

    tetra = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], process=False
    )
    (out / "tetra.stl").write_bytes(trimesh.exchange.stl.export_stl(tetra))
    (out / "cube.off").write_text(trimesh.exchange.off.export_off(cube))

    scene = trimesh.Scene()
    a = trimesh.creation.box(extents=(1, 1, 1))
    a.apply_translation((-1, 0, 0))
    a.visual = TextureVisuals(
        material=PBRMaterial(baseColorFactor=(0, 255, 0, 255), metallicFactor=1.0, roughnessFactor=0.2)
    )
    b = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    b.apply_translation((1, 0, 0))
    b.visual = TextureVisuals(
        material=PBRMaterial(baseColorFactor=(0, 0, 255, 255), metallicFactor=0.0, roughnessFactor=0.9)
    )
    scene.add_geometry(a, geom_name="cube")
    scene.add_geometry(b, geom_name="ball")
    (out / "two_parts.glb").write_bytes(scene.export(file_type="glb"))

    # A textured quad (2 x 2 checker texture, red top-left) facing +z.
    from PIL import Image

    checker = np.array([[[255, 0, 0], [255, 255, 255]], [[255, 255, 255], [0, 0, 255]]], dtype=np.uint8)
    quad = trimesh.Trimesh([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 1, 2], [0, 2, 3]], process=False)
    quad.visual = TextureVisuals(
        uv=[[0, 0], [1, 0], [1, 1], [0, 1]],
        material=SimpleMaterial(name="checker", image=Image.fromarray(checker), diffuse=(255, 255, 255, 255)),
    )
    text, files = trimesh.exchange.obj.export_obj(
        quad, include_texture=True, mtl_name="textured.mtl", return_texture=True
    )
    (out / "textured.obj").write_text(text)
    for name, data in files.items():
        (out / name).write_bytes(data)

    (out / "malformed.obj").write_text("v 0 0 0\nv 1 0\nf 1 2 3 4 banana\n")
    (out / "malformed.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n")
    return out


if __name__ == "__main__":
    print(write_all(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent))
