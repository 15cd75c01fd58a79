"""Finite is not enough: magnitude limits, invertible matrices, colours and normals in range, node names,
iteration while removing, two Backgrounds in one node."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.core.limits import MAX_MAGNITUDE


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: om.Sphere(radius=1e308), r"Sphere: radius must be at most 1e\+15"),
        (lambda: om.Sphere(radius=10**400), "Sphere: radius must be at most 1e\\+15 .* an integer of 401 digits"),
        (lambda: om.Torus(major_radius=1e308), "Torus: major_radius"),
        (lambda: om.Translation(1e39, 0, 0), "Translation: offset"),
        (lambda: om.Scaling(1e-300), "Scaling: factors must be at least 1e-15"),
        (lambda: om.Camera.look_at(eye=(0, 0, 1e39)), "Camera: eye"),
        (lambda: om.Camera.look_at(eye=(0, 0, 5), far=1e308), "Camera: far"),
        (lambda: om.TriangleSet([(1e39, 0, 0), (1, 0, 0), (0, 1, 0)]), r"TriangleSet: vertices .*\(row 0 is"),
        (lambda: om.PointLight(position=(0, 0, 1e39)), "PointLight: position"),
        (lambda: om.Material(shininess=10**400), "Material: shininess"),
    ],
)
def test_huge_values_are_refused_naming_the_component(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_values_at_the_limit_are_accepted():
    om.Sphere(radius=MAX_MAGNITUDE)
    om.Translation(-MAX_MAGNITUDE, 0, 0)
    om.Scaling(1e-15)


def test_an_accumulated_transform_beyond_the_limit_is_refused_with_its_node():
    far = om.Node("far", [om.Scaling(1e6), om.Node("deeper", [om.Scaling(1e6), om.Scaling(1e6), om.Sphere()])])
    with pytest.raises(ValueError, match=r"accumulated model matrix exceeds 1e\+15.*in node /s/far/deeper"):
        om.bounds(om.Node("s", [far]))
    fine = om.Node("s", [om.Scaling(1e6), om.Scaling(1e6), om.Sphere()])  # 1e12: fine
    lo, hi = om.bounds(fine)
    assert np.allclose(hi, 1e12)


@pytest.mark.parametrize(
    "matrix, message",
    [
        (np.zeros((4, 4)), "singular"),
        (np.diag([1.0, 0.0, 1.0, 1.0]), "singular"),
        ([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 0]], "bottom row must be"),
        ([["a"] * 4] * 4, "4x4 numbers"),
        (np.eye(3), "4x4"),
    ],
)
def test_a_matrix_must_be_affine_and_invertible_like_a_scaling(matrix, message):
    with pytest.raises(ValueError, match=f"Matrix: .*{message}"):
        om.Matrix(matrix)
    with pytest.raises(ValueError, match="non-zero"):
        om.Scaling(0, 0, 0)  # the same rule


def test_vertex_colours_and_normals_must_mean_something():
    tri = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    with pytest.raises(ValueError, match=r"TriangleSet: colors must be in \[0, 1\] \(row 0 is \[5\.0"):
        om.TriangleSet(tri, colors=[(5, 0, 0)] * 3)
    with pytest.raises(ValueError, match=r"colors must be in \[0, 1\].*divide 0-255 values by 255"):
        om.TriangleSet(tri, colors=[(0, 0, 0), (-1, 0, 0), (0, 0, 0)])
    with pytest.raises(ValueError, match=r"TriangleSet: normals must have non-zero length \(row 1"):
        om.TriangleSet(tri, normals=[(0, 0, 1), (0, 0, 0), (0, 0, 1)])
    with pytest.raises(ValueError, match="Polygon: normals must have non-zero length"):
        om.Polygon(tri, normals=(0, 0, 0))
    given = om.TriangleSet(tri, normals=[(0, 0, 2)] * 3)  # given normals are used as unit vectors
    assert np.allclose(given.normal_array(), [(0, 0, 1)] * 3)


@pytest.mark.parametrize("name", ["a\x00b", "a\nb", "tab\there", "bell\x07"])
def test_node_and_group_names_refuse_control_characters(name):
    with pytest.raises(ValueError, match="control characters"):
        om.Node(name)
    with pytest.raises(ValueError, match="control characters"):
        om.Node("n", groups=[name])
    om.Node("caf\u00e9 \u4e2d")  # printable text of any script is fine


def test_removing_while_iterating_removes_everything():
    items = [om.Sphere(radius=i + 1) for i in range(9)]
    node = om.Node("n", items + [om.Node(f"c{i}") for i in range(4)])
    seen = []
    for item in node:
        seen.append(item)
        node.remove(item)
    assert len(node) == 0 and seen[:9] == items  # every item visited once, in order


def test_of_two_backgrounds_in_one_node_the_later_one_is_the_scenes():
    first, later = om.Background((1, 0, 0)), om.Background((0, 0, 1))
    scene = om.Node("s", [first, om.Node("child", [om.Background((0, 1, 0))]), later])
    assert scene.declarations().first(om.Background)[0] is later  # on the root's stack at the end
    deeper = om.Node("s", [om.Node("child", [first, later])])
    assert deeper.declarations().first(om.Background)[0] is later
    two_cameras = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.Camera.look_at(eye=(0, 0, 9))])
    assert two_cameras.declarations().camera[0].eye == (0.0, 0.0, 9.0)  # the same stack rule
