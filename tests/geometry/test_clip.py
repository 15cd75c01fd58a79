"""omnirender.geometry.clip: triangles, segments and points against ClipPlane half-spaces."""

from __future__ import annotations

import numpy as np
import pytest

from omnirender.geometry import tessellate as T
from omnirender.geometry.clip import clip_segments, clip_triangles, keep_points, plane_rows
from omnirender.geometry.normals import face_normals, triangle_areas


def _area(vertices, indices) -> float:
    return float(np.sum(triangle_areas(np.asarray(vertices, np.float64), np.asarray(indices))))


@pytest.fixture(scope="module")
def sphere():
    return T.sphere(1.0, segments=64)


@pytest.mark.parametrize(
    "normal", [(0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (1.0, 2.0, 3.0), (-0.3, 0.5, 0.2)]
)
def test_plane_through_the_centre_keeps_half_the_sphere(sphere, normal):
    full = _area(sphere.vertices, sphere.indices)
    out = clip_triangles(sphere.vertices, sphere.indices, [(normal, 0.0)], normals=sphere.normals)
    assert abs(_area(out.vertices, out.indices) / full - 0.5) < 0.02
    n = np.asarray(normal) / np.linalg.norm(normal)
    assert (out.vertices @ n).min() >= -1e-6  # nothing on the clipped side
    # the cut edge lies on the plane and on the sphere (interpolated between two sphere vertices)
    on_plane = np.abs(out.vertices @ n) < 1e-6
    assert on_plane.sum() >= 32
    assert np.allclose(np.linalg.norm(out.normals, axis=1), 1.0, atol=1e-5)


def test_offset_keeps_a_cap(sphere):
    # cap above y = 0.5 on a unit sphere: area 2 pi h with h = 0.5 -> a quarter of 4 pi
    out = clip_triangles(sphere.vertices, sphere.indices, [((0, 1, 0), 0.5)])
    assert abs(_area(out.vertices, out.indices) / _area(sphere.vertices, sphere.indices) - 0.25) < 0.02
    assert out.vertices[:, 1].min() >= 0.5 - 1e-6


def test_two_planes_keep_a_quarter(sphere):
    out = clip_triangles(sphere.vertices, sphere.indices, [((0, 1, 0), 0.0), ((1, 0, 0), 0.0)])
    assert abs(_area(out.vertices, out.indices) / _area(sphere.vertices, sphere.indices) - 0.25) < 0.02


def test_no_plane_leaves_the_mesh_unchanged(sphere):
    out = clip_triangles(sphere.vertices, sphere.indices, [], normals=sphere.normals)
    assert np.array_equal(out.vertices, sphere.vertices)
    assert np.array_equal(out.indices, sphere.indices)
    assert np.array_equal(out.normals, sphere.normals)
    assert out.texcoords is None and out.colors is None


def test_plane_keeping_everything_leaves_the_mesh_unchanged(sphere):
    out = clip_triangles(sphere.vertices, sphere.indices, [((0, 1, 0), -2.0)])
    assert len(out.indices) == len(sphere.indices)
    assert np.allclose(_area(out.vertices, out.indices), _area(sphere.vertices, sphere.indices))


def test_everything_clipped_is_empty(sphere):
    out = clip_triangles(sphere.vertices, sphere.indices, [((0, 1, 0), 1.5)], normals=sphere.normals)
    assert out.vertices.shape == (0, 3) and out.indices.shape == (0, 3) and out.normals.shape == (0, 3)


def test_winding_is_kept(sphere):
    out = clip_triangles(sphere.vertices, sphere.indices, [((0.2, 1, -0.4), 0.1)])
    centres = out.vertices[out.indices].mean(axis=1)
    normals = face_normals(out.vertices.astype(np.float64), out.indices)
    big = triangle_areas(out.vertices.astype(np.float64), out.indices) > 1e-9
    assert np.all(np.einsum("ij,ij->i", normals[big], centres[big]) > 0.0)  # still facing outwards


def test_attributes_are_interpolated_on_new_vertices():
    vertices = np.array([[0.0, -1.0, 0.0], [2.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    texcoords = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    colors = np.array([[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]])
    normals = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    out = clip_triangles(vertices, [[0, 1, 2]], [((0, 1, 0), 0.0)], normals, texcoords, colors)
    # one vertex (index 2) above y = 0: one triangle with the two edge midpoints (0-2 at t=0.5, 1-2 at t=0.5)
    assert out.indices.shape == (1, 3)
    points = {tuple(np.round(p, 6)) for p in out.vertices}
    assert points == {(0.0, 1.0, 0.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0)}
    i = int(np.argmin(np.linalg.norm(out.vertices - [1.0, 0.0, 0.0], axis=1)))
    assert np.allclose(out.texcoords[i], [0.5, 0.5])
    assert np.allclose(out.colors[i], [0.0, 0.5, 0.5, 1.0])
    assert np.allclose(out.normals[i], np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0))
    # two vertices kept: a quad of two triangles, area of the trapezoid below y = 0 clipped away
    out = clip_triangles(vertices, [[0, 1, 2]], [((0, -1, 0), 0.0)], texcoords=texcoords)
    assert out.indices.shape == (2, 3)
    assert np.isclose(_area(out.vertices, out.indices), 1.5)  # 2 - 0.5 (the clipped corner)
    assert np.all(face_normals(out.vertices.astype(np.float64), out.indices)[:, 2] > 0.0)  # same winding


def test_shared_edges_get_one_new_vertex():
    # a quad of two triangles cut across the shared diagonal: the cut point on the diagonal is shared
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    out = clip_triangles(vertices, [[0, 1, 2], [0, 2, 3]], [((1, 0, 0), 0.5)])
    assert len(out.vertices) == 5  # 1, 2 kept; cuts on 0-1, 0-2 and 2-3
    assert np.isclose(_area(out.vertices, out.indices), 0.5)


def test_four_vector_planes_match_normal_offset_planes(sphere):
    a = clip_triangles(sphere.vertices, sphere.indices, [((0, 2, 0), 0.6)])  # normal normalised: y >= 0.3
    b = clip_triangles(sphere.vertices, sphere.indices, [(0.0, 1.0, 0.0, -0.3)])
    assert np.allclose(a.vertices, b.vertices)
    with pytest.raises(ValueError, match="non-zero normal"):
        plane_rows([((0, 0, 0), 1.0)])


def test_segments_and_points():
    a = np.array([[-1.0, 0.0, 0.0], [-1.0, 1.0, 0.0], [1.0, 2.0, 0.0]])
    b = np.array([[1.0, 0.0, 0.0], [-0.5, 1.0, 0.0], [3.0, 2.0, 0.0]])
    ca, cb, kept = clip_segments(a, b, [((1, 0, 0), 0.0)])
    assert kept.tolist() == [0, 2]
    assert np.allclose(ca, [[0.0, 0.0, 0.0], [1.0, 2.0, 0.0]])
    assert np.allclose(cb, [[1.0, 0.0, 0.0], [3.0, 2.0, 0.0]])
    ca, cb, kept = clip_segments(b, a, [((1, 0, 0), 0.0)])  # reversed direction: the other end is cut
    assert np.allclose(cb[0], [0.0, 0.0, 0.0])
    assert keep_points(a, [((1, 0, 0), 0.0)]).tolist() == [False, False, True]
