"""Geometry helpers: triangulation, normals, matrices, isosurfaces, raw tessellation."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from omnirender import geometry as g
from omnirender.geometry import tessellate as T


def _polygon_area_2d(p: np.ndarray) -> float:
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def _inside(point: np.ndarray, poly: np.ndarray) -> bool:
    """Even-odd rule."""
    x, y = point
    inside = False
    for (x1, y1), (x2, y2) in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def _star(n: int = 7, r1: float = 1.0, r2: float = 0.4) -> np.ndarray:
    a = np.linspace(0, 2 * math.pi, 2 * n, endpoint=False)
    r = np.where(np.arange(2 * n) % 2 == 0, r1, r2)
    return np.stack([r * np.cos(a), r * np.sin(a)], axis=1)


@pytest.mark.parametrize(
    "outline",
    [
        np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float),
        np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float),  # L shape
        _star(),
        np.array([[0, 0], [4, 0], [4, 3], [3, 3], [3, 1], [1, 1], [1, 3], [0, 3]], float),  # U shape
        np.array([[math.cos(t), math.sin(t)] for t in np.linspace(0, 2 * math.pi, 50, endpoint=False)]),
    ],
    ids=["square", "L", "star", "U", "circle"],
)
@pytest.mark.parametrize("clockwise", [False, True])
def test_triangulation_covers_the_polygon_exactly(outline, clockwise):
    p = outline[::-1].copy() if clockwise else outline
    tris = g.triangulate_polygon(p)
    assert tris.shape == (len(p) - 2, 3) and tris.dtype == np.uint32
    a, b, c = p[tris[:, 0]], p[tris[:, 1]], p[tris[:, 2]]
    signed = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    total = _polygon_area_2d(p)
    # Same winding as the outline, and the areas add up (no overlap, no gap).
    assert np.all(np.sign(signed[np.abs(signed) > 1e-12]) == np.sign(total))
    assert signed.sum() == pytest.approx(total)
    assert np.abs(signed).sum() == pytest.approx(abs(total))
    # Every triangle's centroid lies inside the polygon.
    for centroid in (a + b + c) / 3.0:
        assert _inside(centroid, p)


def test_triangulation_of_a_tilted_3d_polygon_keeps_its_normal():
    l_shape = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)
    m = g.rotation_matrix(37, (1, 2, 3))
    p = g.transform_points(m, l_shape)
    tris = g.triangulate_polygon(p)
    normal = g.newell_normal(p)
    fn = g.face_normals(p, tris)
    assert np.allclose(fn, normal / np.linalg.norm(normal), atol=1e-9)
    assert g.triangle_areas(p, tris).sum() == pytest.approx(3.0)


def test_degenerate_polygon_raises():
    with pytest.raises(ValueError, match="zero area"):
        g.triangulate_polygon(np.array([[0, 0, 0], [1, 1, 1], [2, 2, 2]], float))
    with pytest.raises(ValueError, match="at least 3"):
        g.triangulate_polygon(np.zeros((2, 3)))


def test_smooth_normals_are_area_weighted_and_unit():
    # A "roof": two triangles of different areas sharing an edge.
    v = np.array([[0, 0, 0], [0, 0, 1], [-1, 1, 0], [3, 3, 0]], float)
    i = np.array([[0, 1, 2], [1, 0, 3]])
    n = g.smooth_normals(v, i)
    assert n.dtype == np.float32
    assert np.allclose(np.linalg.norm(n, axis=1), 1)
    fn = g.face_normals(v, i, normalize=False)
    expected = fn.sum(axis=0) / np.linalg.norm(fn.sum(axis=0))
    assert np.allclose(n[0], expected, atol=1e-6)
    # An unused vertex gets +y.
    n2 = g.smooth_normals(np.vstack([v, [[9, 9, 9]]]), i)
    assert np.allclose(n2[4], [0, 1, 0])


def test_matrix_helpers():
    r = g.rotation_between((0, 1, 0), (1, 0, 0))
    assert np.allclose(g.transform_directions(r, [[0, 1, 0]]), [[1, 0, 0]])
    r = g.rotation_between((0, 1, 0), (0, -1, 0))
    assert np.allclose(g.transform_directions(r, [[0, 1, 0]]), [[0, -1, 0]])
    assert np.allclose(g.rotation_between((1, 1, 1), (2, 2, 2)), np.eye(4))
    a = g.align_y_matrix((1, 2, 3), (0, 0, 5))
    assert np.allclose(g.transform_points(a, [[0, 1, 0]]), [[1, 2, 4]])
    s = g.scaling_matrix((2, 1, 1))
    n = g.transform_normals(s, [[1, 1, 0]])
    assert np.allclose(n, [[1 / math.sqrt(5), 2 / math.sqrt(5), 0]])  # stays perpendicular to the scaled plane
    t = g.translation_matrix((1, 0, 0)) @ g.rotation_matrix(90, (0, 0, 1))
    assert np.allclose(g.transform_points(t, [[1, 0, 0]]), [[1, 1, 0]])
    persp = np.eye(4)
    persp[3] = (0, 0, 1, 0)
    assert np.allclose(g.transform_points(persp, [[2, 4, 2]]), [[1, 2, 1]])


def test_isosurface_of_a_box_region_is_closed_and_outward():
    data = np.zeros((10, 10, 10))
    data[2:8, 3:7, 4:6] = 1.0
    mesh = g.isosurface(data, 0.5)
    tm = trimesh.Trimesh(mesh.vertices, mesh.indices)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    # Half-way crossings: the region spans 6 x 4 x 2 voxels, the surface is one voxel larger minus one.
    assert np.allclose(tm.bounds[1] - tm.bounds[0], [2, 4, 6])
    fn = g.face_normals(mesh.vertices, mesh.indices)
    assert np.mean(np.einsum("ij,ij->i", fn, mesh.normals[mesh.indices].mean(axis=1)) > 0) > 0.99
    assert g.isosurface(data, 2.0) is None


def test_tessellation_functions_return_consistent_arrays():
    for m in (T.sphere(), T.box(), T.cylinder(), T.cone(), T.torus(), T.disk(), T.rectangle()):
        assert m.vertices.dtype == np.float32 and m.indices.dtype == np.uint32
        assert m.normals.shape == m.vertices.shape and m.texcoords.shape == (len(m.vertices), 2)
        assert m.indices.max() < len(m.vertices)
        assert np.all((m.texcoords >= -1e-6) & (m.texcoords <= 1 + 1e-6))
    merged = T.merge_meshes([T.box(), T.box(center=(3, 0, 0))])
    tm = trimesh.Trimesh(merged.vertices, merged.indices)
    assert len(tm.split()) == 2 and tm.volume == pytest.approx(2.0)
    with pytest.raises(ValueError, match="segments"):
        T.sphere(segments=2)


def test_open_cylinder_and_cone_have_no_caps():
    m = T.cylinder(segments=16, capped=False)
    assert len(m.indices) == 32
    assert not trimesh.Trimesh(m.vertices, m.indices).is_watertight
    assert len(T.cone(segments=16, capped=False).indices) == 16
