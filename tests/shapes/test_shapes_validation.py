"""Shape declarations: validation errors name the class and parameter; parameters round-trip."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om

TRI = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
QUAD = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]


@pytest.mark.parametrize(
    ("factory", "words"),
    [
        (lambda: om.Sphere(radius=-1), ("Sphere", "radius")),
        (lambda: om.Sphere(radius=0), ("Sphere", "radius")),
        (lambda: om.Sphere(center=(0, math.nan, 0)), ("Sphere", "center")),
        (lambda: om.Sphere(center=(0, 0)), ("Sphere", "center")),
        (lambda: om.Box(size=(1, -1, 1)), ("Box", "size")),
        (lambda: om.Box(center=(math.inf, 0, 0)), ("Box", "center")),
        (lambda: om.Cylinder(radius=-0.5), ("Cylinder", "radius")),
        (lambda: om.Cylinder(height=0), ("Cylinder", "height")),
        (lambda: om.Cone(radius=math.nan), ("Cone", "radius")),
        (lambda: om.Cone(height=-2), ("Cone", "height")),
        (lambda: om.Torus(major_radius=-1), ("Torus", "major_radius")),
        (lambda: om.Torus(minor_radius="x"), ("Torus", "minor_radius")),
        (lambda: om.Disk(radius=-1), ("Disk", "radius")),
        (lambda: om.Rectangle(size=(1, 0)), ("Rectangle", "size")),
        (lambda: om.Arrow((0, 0, 0), (0, 0, 0)), ("Arrow", "start and end")),
        (lambda: om.Arrow((0, 0, 0), (1, 0, 0), radius=-1), ("Arrow", "radius")),
        (lambda: om.Arrow((0, 0, 0), (1, 0, 0), head_length=0), ("Arrow", "head_length")),
        (lambda: om.TriangleSet([[0, 0, 0], [1, 0, 0]]), ("TriangleSet", "vertices")),
        (lambda: om.TriangleSet([[0, 0], [1, 0], [0, 1]]), ("TriangleSet", "vertices")),
        (lambda: om.TriangleSet([[0, 0, 0], [1, math.nan, 0], [0, 1, 0]]), ("TriangleSet", "vertices")),
        (lambda: om.TriangleSet(TRI, indices=[[0, 1, 3]]), ("TriangleSet", "indices", "3")),
        (lambda: om.TriangleSet(TRI, indices=[[0, 1, -1]]), ("TriangleSet", "indices")),
        (lambda: om.TriangleSet(TRI, indices=[0, 1]), ("TriangleSet", "indices")),
        (lambda: om.TriangleSet(TRI, indices=[[0.5, 1, 2]]), ("TriangleSet", "indices")),
        (lambda: om.TriangleSet(QUAD), ("TriangleSet", "multiple of 3")),
        (lambda: om.TriangleSet(TRI, normals=[[0, 0, 1]]), ("TriangleSet", "normals")),
        (lambda: om.TriangleSet(TRI, colors=[[1, 0, 0]] * 2), ("TriangleSet", "colors")),
        (lambda: om.TriangleSet(TRI, texcoords=[[0, 0, 0]] * 3), ("TriangleSet", "texcoords")),
        (lambda: om.TriangleSet([[0, 0, 0], [1, 0], [0, 1, 0]]), ("TriangleSet", "vertices")),
        (lambda: om.Polygon(TRI[:2]), ("Polygon", "vertices")),
        (lambda: om.Polygon([[0, 0, 0], [1, 0, 0], [2, 0, 0]]), ("Polygon", "zero area")),
        (lambda: om.Polygon(QUAD, normals=[[0, 0, 1]] * 3), ("Polygon", "normals")),
        (lambda: om.LineSet([[0, 0, 0]]), ("LineSet", "vertices")),
        (lambda: om.LineSet(TRI), ("LineSet", "even")),
        (lambda: om.LineSet(TRI, indices=[[0, 5]]), ("LineSet", "indices")),
        (lambda: om.Polyline([[0, 0, 0]]), ("Polyline", "vertices")),
        (lambda: om.Polyline(TRI, closed="yes"), ("Polyline", "closed")),
        (lambda: om.PointSet(np.zeros((0, 3))), ("PointSet", "vertices")),
        (lambda: om.PointSet(TRI, sizes=[1, 2]), ("PointSet", "sizes")),
        (lambda: om.PointSet(TRI, sizes=-1), ("PointSet", "sizes")),
        (lambda: om.Heightfield(np.zeros(5)), ("Heightfield", "heights")),
        (lambda: om.Heightfield(np.zeros((1, 4))), ("Heightfield", "heights")),
        (lambda: om.Heightfield(np.full((2, 2), np.nan)), ("Heightfield", "heights")),
        (lambda: om.Heightfield(np.zeros((3, 3)), spacing=(1, -1)), ("Heightfield", "spacing")),
        (lambda: om.Volume(np.zeros((3, 3))), ("Volume", "data")),
        (lambda: om.Volume(np.zeros((3, 3, 3)), spacing=0), ("Volume", "spacing")),
        (lambda: om.Volume(np.zeros((3, 3, 3)), transfer_function=[]), ("TransferFunction", "control point")),
        (lambda: om.Volume(np.zeros((3, 3, 3)), transfer_function=[(0, (1, 1))]), ("TransferFunction", "colour")),
        (lambda: om.Volume(np.zeros((3, 3, 3)), iso=math.nan), ("Volume", "iso")),
        (lambda: om.Text(3), ("Text", "string")),
        (lambda: om.Text("a", size=0), ("Text", "size")),
        (lambda: om.Text("a", position=(1, 2, 3, 4)), ("Text", "position")),
        (lambda: om.MeshFile(123), ("MeshFile", "path")),
    ],
)
def test_bad_input_raises_value_error_naming_the_parameter(factory, words):
    with pytest.raises(ValueError) as info:
        factory()
    for word in words:
        assert word in str(info.value)


def test_missing_mesh_file_raises_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothere.obj"):
        om.MeshFile(tmp_path / "nothere.obj")


def test_setters_validate_and_bump_the_version():
    s = om.Sphere(radius=1)
    v = s.version
    s.radius = 2
    assert s.radius == 2.0 and s.version > v
    v = s.version
    with pytest.raises(ValueError, match="Sphere: radius"):
        s.radius = -3
    assert s.radius == 2.0 and s.version == v


def test_setting_indices_is_checked_against_vertices_and_update_changes_both():
    ts = om.TriangleSet(QUAD, indices=[[0, 1, 2], [0, 2, 3]])
    with pytest.raises(ValueError, match="index 3 out of range"):
        ts.vertices = TRI
    ts.update(vertices=TRI, indices=[[0, 1, 2]])
    assert ts.index_array().shape == (1, 3)
    assert ts.vertex_array().shape == (3, 3)


def test_accessors_are_cached_per_version():
    ts = om.TriangleSet(QUAD, indices=[[0, 1, 2], [0, 2, 3]])
    n = ts.normal_array()
    assert ts.normal_array() is n
    assert np.allclose(n, [0, 0, 1])
    ts.vertices = np.array(QUAD, float) * 2
    assert ts.normal_array() is not n
    assert np.allclose(ts.vertex_array()[2], [2, 2, 0])


def test_touch_rebuilds_arrays_after_in_place_change():
    data = np.array(QUAD, dtype=float)
    ts = om.TriangleSet(data, indices=[[0, 1, 2], [0, 2, 3]])
    data[2] = (5, 5, 0)
    assert np.allclose(ts.vertex_array()[2], (1, 1, 0))  # validated copy
    ts.touch()
    assert np.allclose(ts.vertex_array()[2], (5, 5, 0))


@pytest.mark.parametrize(
    "shape",
    [
        om.Sphere((1, 2, 3), 0.5),
        om.Box((1, 2, 3), (0, 1, 0)),
        om.Cylinder(0.5, 3),
        om.Cone(0.5, 3),
        om.Torus(2, 0.5),
        om.Disk(2),
        om.Rectangle((2, 3)),
        om.Arrow((0, 0, 0), (1, 1, 1), radius=0.1),
        om.TriangleSet(QUAD, indices=[[0, 1, 2], [0, 2, 3]], colors=(1, 0, 0)),
        om.Polygon(QUAD, normals=(0, 0, 1)),
        om.LineSet(QUAD, colors=[[1, 0, 0, 1]] * 4),
        om.Polyline(QUAD, closed=True),
        om.PointSet(QUAD, sizes=3),
        om.Heightfield(np.arange(12.0).reshape(3, 4), spacing=0.5),
        om.Volume(np.random.default_rng(1).random((3, 4, 5)), spacing=(1, 2, 3), iso=0.3),
        om.Text("hello", (1, 2), 20),
    ],
    ids=lambda s: type(s).__name__,
)
def test_parameters_rebuild_an_equal_shape(shape):
    copy = type(shape)(**shape.parameters())
    for name, value in shape.parameters().items():
        other = copy.parameters()[name]
        if isinstance(value, (np.ndarray, list)) or hasattr(value, "array"):
            assert np.array_equal(np.asarray(value, dtype=object), np.asarray(other, dtype=object)), name
        else:
            assert value == other, name
    for accessor in ("vertex_array", "index_array", "color_array", "size_array", "data_array", "height_array"):
        if hasattr(shape, accessor):
            a, b = getattr(shape, accessor)(), getattr(copy, accessor)()
            assert (a is None and b is None) or np.array_equal(a, b)


def test_data_sequences_are_accepted():
    verts = om.data.Array(np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [1, 1, 0], [0, 2, 0]], float))
    red = om.data.Repeat(np.array([[1.0, 0.0, 0.0, 1.0]]), times=5)
    poly = om.Polygon(verts, colors=red)
    assert poly.color_array().shape == (5, 4)
    assert np.allclose(poly.color_array(), [1, 0, 0, 1])
    ts = om.TriangleSet(
        verts, indices=om.data.Array(np.array([[0, 1, 2], [0, 2, 4]])), colors=om.data.Constant((0, 1, 0), 5)
    )
    assert ts.color_array().shape == (5, 4) and ts.index_array().dtype == np.uint32


def test_array_accessor_types_and_hints():
    ts = om.TriangleSet(QUAD, indices=[0, 1, 2, 0, 2, 3], colors=[[1, 0, 0, 0.5]] * 4, texcoords=np.zeros((4, 2)))
    assert ts.vertex_array().dtype == np.float32 and ts.vertex_array().shape == (4, 3)
    assert ts.index_array().dtype == np.uint32 and ts.index_array().shape == (2, 3)
    assert ts.normal_array().dtype == np.float32
    assert ts.texcoord_array().shape == (4, 2)
    assert "transparent" in ts.hints
    assert om.TriangleSet(QUAD[:3]).hints == frozenset()
    assert om.Text("x").hints == frozenset({"2d"})
    with pytest.raises(ValueError):
        ts.vertex_array()[0, 0] = 3  # read-only
    lines = om.Polyline(QUAD, closed=True)
    assert lines.index_array().tolist() == [[0, 1], [1, 2], [2, 3], [3, 0]]
    ls = om.LineSet(QUAD)
    assert ls.index_array().dtype == np.uint32 and ls.index_array().shape == (2, 2)
    ps = om.PointSet(QUAD, sizes=2)
    assert ps.size_array().tolist() == [2, 2, 2, 2] and ps.color_array() is None


def test_transfer_function_lookup_table_and_iso():
    tf = om.TransferFunction([(1.0, (0, 0, 1, 1)), (0.0, (1, 0, 0, 0))])
    assert np.allclose(tf.lookup([0.5]), [[0.5, 0, 0.5, 0.5]])
    assert np.allclose(tf.lookup(-1), [1, 0, 0, 0])
    t = tf.table(5)
    assert t.shape == (5, 4) and t.dtype == np.float32
    assert np.allclose(t[:, 3], np.linspace(0, 1, 5))
    assert tf.iso_level() == pytest.approx(0.5)
    vol = om.Volume(np.zeros((2, 3, 4)), spacing=(1, 2, 3), transfer_function=tf)
    lo, hi = vol.bounds()
    assert np.allclose(hi, [1.5, 2.0, 1.5]) and np.allclose(lo, -hi)
    assert vol.iso_level() == pytest.approx(0.5)


def test_changing_one_parameter_keeps_the_other_validated_arrays():
    data = np.random.default_rng(0).random((4, 4, 4))
    vol = om.Volume(data)
    before = vol.data_array()
    vol.iso = 0.25
    assert vol.data_array() is before and vol.iso_level() == 0.25
    vol.touch()  # after an in-place change the data is converted again
    assert vol.data_array() is not before
    ts = om.TriangleSet(TRI)
    v = ts.vertex_array()
    ts.colors = (1, 0, 0)
    assert ts.vertex_array() is v and ts.color_array().shape == (3, 4)


def test_non_planar_polygon_raises_naming_the_deviation():
    with pytest.raises(ValueError, match=r"Polygon: the 4 vertices are not planar: .*deviates by 0\.13"):
        om.Polygon([[0, 0, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0]])
    # within 1e-6 of the extent counts as planar (rounding in data files)
    assert len(om.Polygon([[0, 0, 0], [10, 0, 0], [10, 10, 1e-6], [0, 10, 0]]).triangle_indices()) == 2
    with pytest.raises(ValueError, match="not planar"):
        om.Polygon([[0, 0, 0], [10, 0, 0], [10, 10, 1e-3], [0, 10, 0]])


def test_bow_tie_polygon_is_reported_as_self_intersecting():
    with pytest.raises(ValueError, match=r"self-intersecting: edge 0-1 crosses edge 2-3"):
        om.Polygon([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match="self-intersecting"):  # a star drawn in one stroke
        angles = np.radians(90 + 144 * np.arange(5))
        om.Polygon(np.stack([np.cos(angles), np.sin(angles), np.zeros(5)], axis=1))
    # concave and touching outlines stay valid
    assert len(om.Polygon([[0, 0, 0], [2, 0, 0], [2, 2, 0], [1, 0.5, 0], [0, 2, 0]]).triangle_indices()) == 3


def test_simplifiers_import_attributes_only_lazily():
    """Dependency rule: shapes import only core/data/geometry at module level (attributes lazily, by exception)."""
    import ast
    from pathlib import Path

    import omnirender.shapes as shapes_pkg

    for path in Path(shapes_pkg.__file__).parent.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in tree.body:  # module level only
            if isinstance(node, ast.ImportFrom) and node.level >= 2:
                names = [node.module.split(".")[0]] if node.module else [alias.name for alias in node.names]
                for name in names:
                    assert name in ("core", "data", "geometry"), f"{path.name} imports ..{name} at module level"
