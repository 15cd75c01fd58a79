"""Mesh files through trimesh keep their colours (issue 14): PLY face colours, an OBJ material with Ns 0."""

from __future__ import annotations

import os
import shutil

import pytest
from engines import require

import omnirender as om

DATA = os.path.join(os.path.dirname(__file__), "data_files")
PLY = """ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
property uchar red
property uchar green
property uchar blue
end_header
-1 -1 0
1 -1 0
1 1 0
-1 1 0
3 0 1 2 255 0 0
3 0 2 3 0 0 255
"""


def _scene(shape) -> om.Node:
    s = om.Node("s", [om.Camera.orthographic(eye=(0, 0, 5), height=2.2), om.AmbientLight(intensity=0.8)])
    s.add(om.Node("file", [shape]))
    return s


@pytest.mark.parametrize("name", [pytest.param(n, marks=getattr(pytest.mark, n)) for n in ("gl", "povray", "mitsuba")])
def test_ply_face_colours_show_per_face(tmp_path, name):
    require(name)
    pytest.importorskip("trimesh")
    (tmp_path / "faces.ply").write_text(PLY)
    img = om.render(_scene(om.MeshFile(tmp_path / "faces.ply")), engine=name, size=(48, 48),
                    **({"spp": 4} if name == "mitsuba" else {}))  # fmt: skip
    lower_right, upper_left = img.rgb[38, 38].astype(int), img.rgb[10, 10].astype(int)
    assert lower_right[0] > 150 > 60 > lower_right[2], lower_right  # the red face
    assert upper_left[2] > 150 > 60 > upper_left[0], upper_left  # the blue face


@pytest.mark.gl
def test_obj_material_with_shininess_zero_shows_its_texture(tmp_path):
    require("gl")
    pytest.importorskip("trimesh")
    for name in ("textured.obj", "checker.png"):
        shutil.copy(os.path.join(DATA, name), tmp_path / name)
    mtl = open(os.path.join(DATA, "textured.mtl")).read().replace("Ns 1.00000000", "Ns 0").replace("Ks 0.4", "Ks 1.0")
    (tmp_path / "textured.mtl").write_text(mtl.replace("Ks 1.00000000", "Ks 1.0").replace("0000000 1.0", "0 1.0"))
    parts = om.MeshFile(tmp_path / "textured.obj").parts()
    assert parts[0][0]["specular"] == (0.0, 0.0, 0.0)  # Ns 0: no highlight
    scene = _scene(om.MeshFile(tmp_path / "textured.obj"))
    scene.add(om.DirectionalLight(direction=(0, 0, -1)))
    img = om.render(scene, engine="gl", size=(48, 48))
    values = img.rgb[8:40, 8:40].astype(int).mean(axis=2)
    assert values.max() - values.min() > 100  # the checker shows; not a white square
