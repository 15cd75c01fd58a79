"""Every shape's default simplifier ends in valid triangles (watertight where the shape is closed)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

import omnirender as om
from omnirender.shapes import simplifiers

DATA = Path(__file__).resolve().parents[1] / "data_files"


def _world_mesh(found) -> trimesh.Trimesh:
    """All collected triangle sets in world space as one trimesh (vertices merged by position)."""
    verts, faces, offset = [], [], 0
    for c in found:
        assert isinstance(c.shape, om.TriangleSet)
        verts.append(c.world_vertices())
        faces.append(c.shape.index_array().astype(np.int64) + offset)
        offset += len(verts[-1])
    return trimesh.Trimesh(np.concatenate(verts), np.concatenate(faces))


def _assert_valid(ts: om.TriangleSet, max_degenerate: float = 0.0) -> None:
    v, i, n = ts.vertex_array(), ts.index_array(), ts.normal_array()
    assert np.all(np.isfinite(v)) and np.all(np.isfinite(n))
    assert i.max() < len(v)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    area = om.geometry.triangle_areas(v, i)
    assert np.mean(area <= 1e-12) <= max_degenerate
    # Vertex normals agree with the winding of the triangles that use them.
    fn = om.geometry.face_normals(v, i)
    agree = np.einsum("ij,ij->i", fn, n[i].mean(axis=1)) > 0
    assert np.mean(agree[area > 1e-12]) > 0.99


CLOSED = [
    (om.Sphere((1, 2, 3), 2.0), 4 / 3 * math.pi * 8, 4 * math.pi * 4),
    (om.Box((1, 2, 3), (0, 1, 0)), 6.0, 22.0),
    (om.Cylinder(0.5, 3.0), math.pi * 0.25 * 3, 2 * math.pi * 0.5 * 3 + 2 * math.pi * 0.25),
    (om.Cone(1.0, 2.0), math.pi * 2 / 3, math.pi * math.hypot(1, 2) + math.pi),
    (om.Torus(2.0, 0.5), 2 * math.pi**2 * 2 * 0.25, 4 * math.pi**2 * 2 * 0.5),
]


@pytest.mark.parametrize(("shape", "volume", "area"), CLOSED, ids=lambda x: type(x).__name__)
def test_closed_shapes_are_watertight_outward_and_close_to_analytic(shape, volume, area, simplify):
    found = simplify(shape, level=4)
    assert len(found) == 1
    _assert_valid(found[0].shape)
    mesh = _world_mesh(found)
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.volume > 0  # outward winding
    assert mesh.volume == pytest.approx(volume, rel=0.02)
    assert mesh.area == pytest.approx(area, rel=0.02)


def test_sphere_normals_point_away_from_the_centre(simplify):
    ts = simplify(om.Sphere((1, 2, 3), 2.0))[0].shape
    radial = ts.vertex_array() - np.array([1, 2, 3], np.float32)
    assert np.allclose(radial / 2.0, ts.normal_array(), atol=1e-5)


@pytest.mark.parametrize("shape", [om.Cylinder(), om.Cone(), om.Box()], ids=lambda s: type(s).__name__)
def test_flat_parts_have_flat_normals(shape, simplify):
    ts = simplify(shape)[0].shape
    v, n, i = ts.vertex_array(), ts.normal_array(), ts.index_array()
    fn = om.geometry.face_normals(v, i)
    flat = np.abs(fn[:, 1]) > 0.999  # caps (box: top and bottom)
    assert flat.any()
    # Every corner of a cap triangle carries the cap's normal exactly: the rim is sharp.
    assert np.allclose(n[i[flat]], fn[flat][:, None, :], atol=1e-6)


def test_cone_geometry_follows_the_convention(simplify):
    v = simplify(om.Cone(1.0, 2.0))[0].shape.vertex_array()
    assert v[:, 1].max() == pytest.approx(1.0) and v[:, 1].min() == pytest.approx(-1.0)
    base = v[np.isclose(v[:, 1], -1.0)]
    assert np.max(np.hypot(base[:, 0], base[:, 2])) == pytest.approx(1.0)
    apex = v[np.isclose(v[:, 1], 1.0)]
    assert np.allclose(apex[:, [0, 2]], 0.0)


@pytest.mark.parametrize(("shape", "area"), [(om.Disk(2.0), math.pi * 4), (om.Rectangle((2, 3)), 6.0)])
def test_flat_shapes_face_up(shape, area, simplify):
    ts = simplify(shape, level=5)[0].shape
    _assert_valid(ts)
    v = ts.vertex_array()
    assert np.allclose(v[:, 1], 0.0)
    assert np.allclose(ts.normal_array(), [0, 1, 0])
    assert np.all(om.geometry.face_normals(v, ts.index_array())[:, 1] > 0.999)
    assert om.geometry.triangle_areas(v, ts.index_array()).sum() == pytest.approx(area, rel=0.01)


@pytest.mark.parametrize(
    "shape", [om.Sphere(), om.Cylinder(), om.Cone(), om.Torus(), om.Disk()], ids=lambda s: type(s).__name__
)
def test_tessellation_level_changes_the_triangle_count(shape, simplify):
    counts = [len(simplify(shape, level=lv)[0].shape.index_array()) for lv in (1, 3, 5)]
    assert counts[0] < counts[1] < counts[2]


def test_without_tessellation_attribute_the_default_level_is_used(simplify):
    default = len(simplify([om.Sphere()])[0].shape.index_array())
    assert default == len(simplify(om.Sphere(), level=simplifiers.DEFAULT_LEVEL)[0].shape.index_array())


def test_results_are_cached_per_version_and_level(simplify):
    s = om.Sphere()
    a = simplify(s, level=2)[0].shape
    assert simplify(s, level=2)[0].shape is a
    assert simplify(s, level=3)[0].shape is not a
    b = simplify(s, level=3)[0].shape
    s.radius = 2
    c = simplify(s, level=3)[0].shape
    assert c is not b
    assert np.max(np.linalg.norm(c.vertex_array(), axis=1)) == pytest.approx(2.0)


def test_arrow_simplifies_to_a_cylinder_and_a_cone():
    arrow = om.Arrow((1, 0, 0), (1, 3, 4), radius=0.1, head_radius=0.3, head_length=1.0)
    result = simplifiers.ArrowSimplifier().exec(arrow, om.Engine(on_missing="skip"))
    kinds = [type(x).__name__ for x in result]
    assert kinds == ["Matrix", "Cylinder", "Translation", "Cone"]
    cyl, cone = result[1], result[3]
    assert cyl.radius == 0.1 and cyl.height == pytest.approx(4.0)
    assert cone.radius == 0.3 and cone.height == pytest.approx(1.0)


def test_arrow_tip_and_tail_land_on_end_and_start(simplify):
    start, end = np.array([1.0, 0, 0]), np.array([1.0, 3, 4])
    found = simplify(om.Arrow(start, end, radius=0.1, head_radius=0.3, head_length=1.0))
    assert [type(c.shape).__name__ for c in found] == ["TriangleSet", "TriangleSet"]
    shaft, head = (c.world_vertices() for c in found)
    axis = (end - start) / 5.0
    # The head's farthest point along the axis is the tip at ``end``; the shaft starts at ``start``.
    assert np.allclose(head[np.argmax(head @ axis)], end, atol=1e-5)
    assert (shaft @ axis).min() == pytest.approx(start @ axis, abs=1e-5)
    assert (shaft @ axis).max() == pytest.approx(start @ axis + 4.0, abs=1e-5)
    mesh = _world_mesh(found[1:])
    assert mesh.is_watertight and mesh.volume == pytest.approx(math.pi * 0.09 / 3, rel=0.02)


def test_arrow_shorter_than_its_head_is_only_a_cone():
    arrow = om.Arrow((0, 0, 0), (0, 0.1, 0), radius=0.1)
    result = simplifiers.ArrowSimplifier().exec(arrow, om.Engine(on_missing="skip"))
    assert [type(x).__name__ for x in result] == ["Matrix", "Cone"]
    assert result[1].height == pytest.approx(0.1)


def test_concave_polygon_triangulates_to_its_area(simplify):
    # An L shape (area 3) in the plane z = 1, counter-clockwise about +z.
    outline = [[0, 0, 1], [2, 0, 1], [2, 1, 1], [1, 1, 1], [1, 2, 1], [0, 2, 1]]
    ts = simplify(om.Polygon(outline, colors=(0, 1, 0)))[0].shape
    _assert_valid(ts)
    assert len(ts.index_array()) == 4
    assert om.geometry.triangle_areas(ts.vertex_array(), ts.index_array()).sum() == pytest.approx(3.0)
    assert np.allclose(ts.normal_array(), [0, 0, 1])
    assert np.allclose(ts.color_array(), [0, 1, 0, 1])


def test_polygon_from_data_sequences(simplify):
    verts = om.data.Array(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float))
    poly = om.Polygon(verts, colors=om.data.Repeat(np.array([[1.0, 0, 0, 1]]), times=4))
    ts = simplify(poly)[0].shape
    assert ts.index_array().shape == (2, 3) and ts.color_array().shape == (4, 4)


def test_polyline_becomes_a_line_set(simplify):
    found = simplify(om.Polyline([[0, 0, 0], [1, 0, 0], [1, 1, 0]], closed=True))
    assert isinstance(found[0].shape, om.LineSet)
    assert found[0].shape.index_array().tolist() == [[0, 1], [1, 2], [2, 0]]


def test_heightfield_grid_placement_and_orientation(simplify):
    h = np.array([[0.0, 1.0, 2.0], [0.0, 1.0, 2.0]])
    hf = om.Heightfield(h, spacing=(0.5, 2.0))
    ts = simplify(hf)[0].shape
    _assert_valid(ts)
    v = ts.vertex_array()
    assert len(ts.index_array()) == 2 * 2 * 1
    assert np.allclose(v[0], [-0.5, 0.0, -1.0]) and np.allclose(v[-1], [0.5, 2.0, 1.0])
    assert np.all(om.geometry.face_normals(v, ts.index_array())[:, 1] > 0)
    lo, hi = hf.bounds()
    assert np.allclose(lo, v.min(axis=0)) and np.allclose(hi, v.max(axis=0))


def test_volume_isosurface_is_a_closed_sphere_in_volume_coordinates(simplify):
    z, y, x = np.mgrid[0:21, 0:17, 0:13].astype(float)
    center = np.array([10.0, 8.0, 6.0])
    data = 5.0 - np.sqrt((z - center[0]) ** 2 + (y - center[1]) ** 2 + (x - center[2]) ** 2)
    vol = om.Volume(data, spacing=(0.5, 0.5, 0.5), transfer_function=[(-1, (1, 0, 0, 0)), (1, (1, 0.5, 0, 1))])
    assert vol.iso_level() == pytest.approx(0.0)
    found = simplify(vol)
    ts = found[0].shape
    _assert_valid(ts)
    mesh = _world_mesh(found)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(4 / 3 * math.pi * 2.5**3, rel=0.05)
    assert np.allclose(mesh.centroid, 0.0, atol=0.05)  # the volume is centred at the origin
    assert np.allclose(ts.color_array(), [1, 0.25, 0, 1])  # the colour at the level, opaque
    lo, hi = vol.bounds()
    assert np.allclose(hi, [3.0, 4.0, 5.0])


def test_volume_surface_touching_the_boundary_is_capped(simplify):
    data = np.ones((4, 5, 6))
    data[0] = 0.0
    vol = om.Volume(data, iso=0.5)
    mesh = _world_mesh(simplify(vol))
    assert mesh.is_watertight and mesh.volume > 0
    lo, hi = vol.bounds()
    assert np.allclose(mesh.bounds[1], hi, atol=1e-4)
    assert mesh.bounds[0][2] == pytest.approx(lo[2] + 0.5, abs=1e-4)


def test_volume_with_level_outside_the_data_yields_nothing(simplify):
    assert simplify(om.Volume(np.zeros((3, 3, 3)), iso=2.0)) == []


def test_text_is_skipped_by_3d_engines(simplify):
    assert simplify(om.Text("label")) == []


def test_every_shape_has_a_default_simplifier():
    engine = om.Engine()
    for name in om.shapes.__all__:
        cls = getattr(om, name, None)
        if isinstance(cls, type) and issubclass(cls, om.Shape) and cls not in (om.TriangleSet, om.LineSet, om.PointSet):
            if cls is om.DeclaredShape:
                continue
            if cls is om.GaussianSplats:  # on purpose: engines paint or refuse it (test_splats.py)
                continue
            assert engine.find_handler(om.SIMPLIFY, cls) is not None, name


# -- mesh files -------------------------------------------------------------------


@pytest.mark.parametrize("name", ["cube.obj", "cube.ply", "cube.off", "tetra.stl"])
def test_mesh_files_load_into_closed_triangle_sets(name, simplify):
    found = simplify(om.MeshFile(DATA / name))
    assert len(found) == 1
    _assert_valid(found[0].shape)
    mesh = _world_mesh(found)
    mesh.merge_vertices()
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(1.0 if "cube" in name else 1 / 6)


def test_obj_material_becomes_a_phong_material(simplify):
    found = simplify(om.MeshFile(DATA / "cube.obj"))
    assert isinstance(found[0].material, om.Material)
    assert np.allclose(found[0].material.diffuse, (1, 0, 0))


def test_ply_vertex_colours_are_kept():
    ((_, ts),) = om.MeshFile(DATA / "cube.ply").parts()
    c = ts.color_array()
    assert c is not None and np.allclose(c[:, :3], ts.vertex_array() + 0.5, atol=0.01)


def test_glb_parts_get_their_own_pbr_materials_and_transforms(simplify):
    found = simplify(om.MeshFile(DATA / "two_parts.glb"))
    assert len(found) == 2
    by_x = {round(float(c.world_vertices().mean(axis=0)[0])): c for c in found}
    assert set(by_x) == {-1, 1}
    assert isinstance(by_x[-1].material, om.PBRMaterial)
    assert np.allclose(by_x[-1].material.base_color, (0, 1, 0)) and by_x[-1].material.metallic == 1.0
    assert np.allclose(by_x[1].material.base_color, (0, 0, 1))


def test_mesh_part_materials_do_not_leak(simplify):
    found = simplify([om.Material(diffuse=(0.1, 0.2, 0.3)), om.MeshFile(DATA / "cube.obj"), om.Sphere()])
    assert np.allclose(found[0].material.diffuse, (1, 0, 0))
    assert np.allclose(found[1].material.diffuse, (0.1, 0.2, 0.3))


@pytest.mark.parametrize("name", ["malformed.obj", "malformed.ply"])
def test_malformed_mesh_files_raise_with_path_and_reason(name):
    mf = om.MeshFile(DATA / name)  # parsing is lazy
    with pytest.raises(ValueError, match=name) as info:
        mf.parts()
    assert "cannot load" in str(info.value)


def test_mesh_file_deleted_after_construction_raises_file_not_found(tmp_path):
    path = tmp_path / "gone.off"
    path.write_bytes((DATA / "cube.off").read_bytes())
    mf = om.MeshFile(path)
    path.unlink()
    with pytest.raises(FileNotFoundError, match="gone.off"):
        mf.parts()


def test_unsupported_extension_and_empty_file(tmp_path):
    (tmp_path / "a.xyz").write_text("1 2 3\n")
    with pytest.raises(ValueError, match="unsupported extension"):
        om.MeshFile(tmp_path / "a.xyz")
    (tmp_path / "empty.obj").write_text("# nothing\n")
    with pytest.raises(ValueError, match="empty.obj"):
        om.MeshFile(tmp_path / "empty.obj").parts()


def test_textured_obj_yields_material_texture_and_texcoords():
    engine = om.Engine(on_missing="skip")
    (part,) = simplifiers.MeshFileSimplifier().exec(om.MeshFile(DATA / "textured.obj"), engine)
    material, texture, triangles = part.items
    assert isinstance(material, om.Material) and isinstance(texture, om.Texture)
    image = texture.image_array() if hasattr(texture, "image_array") else np.asarray(texture.image)
    assert image.shape[:2] == (2, 2)
    assert tuple(image[0, 0, :3]) == (255, 0, 0)  # row 0 is the top of the image
    assert triangles.texcoord_array().tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]


def test_mesh_file_errors_during_evaluation_name_the_node(tmp_path):
    node = om.Node("scene")
    model = node.add(om.Node("model"))
    model.add(om.MeshFile(DATA / "malformed.obj"))
    with pytest.raises(ValueError, match="malformed.obj") as info:
        node.evaluate(om.Engine(on_missing="skip"))
    assert "model" in str(info.value)


def test_mesh_file_parameters_round_trip():
    mf = om.MeshFile(DATA / "cube.off")
    copy = type(mf)(**mf.parameters())
    assert copy.path == mf.path and copy.triangle_count == 12


def _write_gltf(path, embedded: bool) -> None:
    """A text glTF: one red quad (2 triangles) in the xy plane, its buffer in a .bin file or a data URI."""
    import base64
    import json

    positions = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]], dtype=np.float32)
    indices = np.array([0, 1, 2, 0, 2, 3], dtype=np.uint16)
    blob = positions.tobytes() + indices.tobytes()
    if embedded:
        uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    else:
        uri = path.with_suffix(".bin").name
        path.with_suffix(".bin").write_bytes(blob)
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "translation": [0, 0, 5]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1], "metallicFactor": 0.0}}],
        "buffers": [{"uri": uri, "byteLength": len(blob)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions.nbytes, "target": 34962},
            {"buffer": 0, "byteOffset": positions.nbytes, "byteLength": indices.nbytes, "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [2, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
    }
    path.write_text(json.dumps(doc))


@pytest.mark.parametrize("embedded", [False, True], ids=["separate-bin", "data-uri"])
def test_text_gltf_mesh_files_load(tmp_path, embedded, simplify):
    path = tmp_path / "quad.gltf"
    _write_gltf(path, embedded)
    found = simplify(om.MeshFile(path))
    assert len(found) == 1
    part = found[0]
    assert len(part.shape.index_array()) == 2
    world = part.world_vertices()
    assert world.min(axis=0) == pytest.approx([0, 0, 5]) and world.max(axis=0) == pytest.approx([2, 1, 5])
    assert isinstance(part.material, om.PBRMaterial)
    assert part.material.base_color[:3] == pytest.approx((1, 0, 0))
    lo, hi = om.bounds(om.Node("m", [om.MeshFile(path)]))
    assert lo == pytest.approx([0, 0, 5]) and hi == pytest.approx([2, 1, 5])
