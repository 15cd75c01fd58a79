"""Math under the non-rendering engines: ray intersections, the BVH, exact bounds, triangle tests."""

from __future__ import annotations

import numpy as np
import pytest

from omnirender.geometry import bounds as gb
from omnirender.geometry import intersect as gi
from omnirender.geometry.bvh import BVH, EmbreeBVH, build_bvh, embree_available


def icosphere(level: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere mesh built with numpy only (subdivided octahedron)."""
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    f = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    for _ in range(level):
        a, b, c = f[:, 0], f[:, 1], f[:, 2]
        n = len(v)
        mids = np.concatenate([(v[a] + v[b]) / 2, (v[b] + v[c]) / 2, (v[c] + v[a]) / 2])
        m = len(f)
        ab, bc, ca = n + np.arange(m), n + m + np.arange(m), n + 2 * m + np.arange(m)
        v = np.concatenate([v, mids])
        f = np.concatenate([np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]])
    return v / np.linalg.norm(v, axis=1)[:, None], f


def brute_nearest(v, f, o, d):
    tri = v[f]
    hit, t, _, _ = gi.ray_triangles(o[:, None], d[:, None], tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    t = np.where(hit, t, np.inf)
    return t.min(axis=1)


def random_rays(n, seed=0, spread=1.5):
    rng = np.random.default_rng(seed)
    o = rng.normal(size=(n, 3))
    o = 4 * o / np.linalg.norm(o, axis=1)[:, None]
    d = rng.uniform(-spread, spread, size=(n, 3)) * 0.5 - o
    return o, d / np.linalg.norm(d, axis=1)[:, None]


# -- analytic -------------------------------------------------------------------


def test_sphere_through_centre_hits_at_radius_distance():
    t, n = gi.ray_sphere(np.array([0.0, 0, 5]), np.array([0.0, 0, -1]), (0, 0, 0), 2.0)
    np.testing.assert_allclose(t, [3.0, 7.0])
    np.testing.assert_allclose(n, [[0, 0, 1], [0, 0, -1]])


def test_ray_starting_inside_sphere_reports_only_the_exit():
    t, _ = gi.ray_sphere(np.zeros(3), np.array([1.0, 0, 0]), (0, 0, 0), 1.0)
    np.testing.assert_allclose(t, [1.0])


def test_box_entry_and_exit_normals():
    t, n = gi.ray_box(np.array([-5.0, 0.2, 0.1]), np.array([1.0, 0, 0]), (0, 0, 0), (2, 2, 2))
    np.testing.assert_allclose(t, [4.0, 6.0])
    np.testing.assert_allclose(n, [[-1, 0, 0], [1, 0, 0]])
    t, _ = gi.ray_box(np.array([-5.0, 3, 0]), np.array([1.0, 0, 0]), (0, 0, 0), (2, 2, 2))
    assert t.size == 0


def test_cylinder_side_and_caps():
    t, n = gi.ray_cylinder(np.array([-5.0, 0.5, 0]), np.array([1.0, 0, 0]), 1.0, 2.0)
    np.testing.assert_allclose(t, [4.0, 6.0])
    np.testing.assert_allclose(n[0], [-1, 0, 0])
    t, n = gi.ray_cylinder(np.array([0.3, 5, 0]), np.array([0.0, -1, 0]), 1.0, 2.0)
    np.testing.assert_allclose(t, [4.0, 6.0])
    np.testing.assert_allclose(n, [[0, 1, 0], [0, -1, 0]])
    assert gi.ray_cylinder(np.array([0.0, 1.5, -5]), np.array([0.0, 0, 1]), 1.0, 2.0)[0].size == 0


def test_cone_apex_side_and_base():
    # down the axis: apex at y=1, base at y=-1
    t, n = gi.ray_cone(np.array([0.0, 5, 0]), np.array([0.0, -1, 0]), 1.0, 2.0)
    np.testing.assert_allclose(t, [4.0, 6.0], atol=1e-9)
    np.testing.assert_allclose(n[1], [0, -1, 0])
    # horizontally at y=0 the radius is 0.5
    t, n = gi.ray_cone(np.array([-5.0, 0, 0]), np.array([1.0, 0, 0]), 1.0, 2.0)
    np.testing.assert_allclose(t, [4.5, 5.5])
    expected = np.array([-1.0, 0.5, 0.0]) / np.linalg.norm([1.0, 0.5, 0.0])
    np.testing.assert_allclose(n[0], expected)
    assert gi.ray_cone(np.array([-5.0, 0.95, 0.3]), np.array([1.0, 0, 0]), 1.0, 2.0)[0].size == 0


def test_disk_and_rectangle():
    t, n = gi.ray_disk(np.array([0.5, 2, 0]), np.array([0.0, -1, 0]), 1.0)
    np.testing.assert_allclose(t, [2.0])
    assert gi.ray_disk(np.array([0.9, 2, 0.9]), np.array([0.0, -1, 0]), 1.0)[0].size == 0
    t, _ = gi.ray_rectangle(np.array([0.9, 2, 0.4]), np.array([0.0, -1, 0]), (2.0, 1.0))
    np.testing.assert_allclose(t, [2.0])
    assert gi.ray_rectangle(np.array([0.9, 2, 0.6]), np.array([0.0, -1, 0]), (2.0, 1.0))[0].size == 0
    assert gi.ray_rectangle(np.array([0.0, 2, 0]), np.array([1.0, 0, 0]), (2.0, 1.0))[0].size == 0


# -- BVH ------------------------------------------------------------------------


def test_bvh_matches_brute_force_on_random_rays():
    v, f = icosphere(3)
    bvh = BVH(v, f, branching=4, leaf_size=4)
    assert bvh.depth >= 2
    o, d = random_rays(300)
    t, tri, _, _ = bvh.intersect_rays(o, d)
    expected = brute_nearest(v, f, o, d)
    assert np.isfinite(expected).sum() > 50
    np.testing.assert_allclose(t, expected)
    for i in range(0, 300, 7):
        hits = bvh.intersect(o[i], d[i])
        if np.isfinite(expected[i]):
            assert hits.t[0] == pytest.approx(expected[i])
            assert hits.triangle[0] == tri[i]
            assert np.all(np.diff(hits.t) > 0)
        else:
            assert len(hits) == 0


def test_bvh_reports_both_crossings_of_a_closed_mesh():
    v, f = icosphere(4)
    hits = BVH(v, f).intersect([0.01, 0.02, 5], [0, 0, -1])
    assert len(hits) == 2
    np.testing.assert_allclose(hits.t, [4, 6], atol=0.01)


def test_bvh_box_query_matches_brute_force():
    v, f = icosphere(3)
    bvh = BVH(v, f)
    rng = np.random.default_rng(3)
    lo = rng.uniform(-1.2, 1.0, size=(40, 3))
    hi = lo + 0.3
    q, tri = bvh.query_boxes(lo, hi)
    tlo, thi = gi.triangle_bounds(v[f])
    brute = gi.boxes_overlap(lo[:, None], hi[:, None], tlo[None], thi[None])
    assert set(zip(q.tolist(), tri.tolist(), strict=True)) == set(zip(*np.nonzero(brute), strict=True))


def test_bvh_bad_input_raises():
    with pytest.raises(ValueError, match="indices"):
        BVH(np.zeros((3, 3)), [[0, 1, 3]])
    with pytest.raises(ValueError, match="finite"):
        BVH([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]], [[0, 1, 2]])


def test_empty_bvh():
    bvh = BVH(np.zeros((0, 3)), np.zeros((0, 3), int))
    assert len(bvh.intersect([0, 0, 1], [0, 0, -1])) == 0
    assert bvh.bounds is None


@pytest.mark.skipif(not embree_available(), reason="embreex is not importable")
def test_numpy_bvh_and_embree_agree_on_random_rays():
    v, f = icosphere(4)
    v = v * [1.0, 0.6, 1.3] + [0.2, 0.0, -0.1]
    numpy_bvh, embree = BVH(v, f), EmbreeBVH(v, f)
    assert build_bvh(v, f, "embree").backend == "embree"
    o, d = random_rays(500, seed=5)
    t1, tri1, _, _ = numpy_bvh.intersect_rays(o, d)
    t2, tri2, _, _ = embree.intersect_rays(o, d)
    assert np.array_equal(np.isfinite(t1), np.isfinite(t2))
    hit = np.isfinite(t1)
    assert hit.sum() > 100
    np.testing.assert_allclose(t1[hit], t2[hit], rtol=1e-6)
    for i in np.nonzero(hit)[0][:40]:
        a, b = numpy_bvh.intersect(o[i], d[i]), embree.intersect(o[i], d[i])
        np.testing.assert_allclose(a.t, b.t, rtol=1e-6)


# -- bounds ---------------------------------------------------------------------


def rotation(angle_deg, axis):
    from omnirender.core.transform import Rotation

    return Rotation(angle_deg, axis).matrix


def sampled_bounds(points, m):
    p = points @ m[:3, :3].T + m[:3, 3]
    return p.min(axis=0), p.max(axis=0)


def test_support_bounds_match_dense_samples():
    rng = np.random.default_rng(1)
    m = rotation(37, (1, 2, 0.5)) @ np.diag([1.5, 0.7, 1.2, 1.0])
    m[:3, 3] = [0.3, -1, 2]
    th = rng.uniform(0, 2 * np.pi, 200000)
    ph = np.arccos(rng.uniform(-1, 1, 200000))
    unit = np.c_[np.sin(ph) * np.cos(th), np.cos(ph), np.sin(ph) * np.sin(th)]
    ring = np.c_[np.cos(th), np.zeros_like(th), np.sin(th)]
    y = rng.uniform(-1, 1, len(th))
    cases = {
        "sphere": (gb.sphere_bounds((0.5, 0, 0), 2.0, m), 2.0 * unit + [0.5, 0, 0]),
        "disk": (gb.disk_bounds(1.5, m), 1.5 * ring),
        "cylinder": (gb.cylinder_bounds(1.0, 3.0, m), ring + np.c_[0 * y, 1.5 * np.sign(y), 0 * y]),
        "cone": (gb.cone_bounds(1.0, 2.0, m), np.concatenate([ring + [0, -1, 0], [[0, 1, 0]]])),
        "torus": (gb.torus_bounds(1.0, 0.3, m), ring + 0.3 * unit),
    }
    for name, ((lo, hi), pts) in cases.items():
        slo, shi = sampled_bounds(pts, m)
        np.testing.assert_allclose(lo, slo, atol=2e-3, err_msg=name)
        np.testing.assert_allclose(hi, shi, atol=2e-3, err_msg=name)
        assert np.all(lo <= slo + 1e-12) and np.all(hi >= shi - 1e-12), name


def test_box_bounds_after_rotation_is_analytic():
    lo, hi = gb.box_bounds((0, 0, 0), (2, 2, 2), rotation(45, (0, 0, 1)))
    r = np.sqrt(2)
    np.testing.assert_allclose(lo, [-r, -r, -1])
    np.testing.assert_allclose(hi, [r, r, 1])
    lo, hi = gb.rectangle_bounds((2, 4), rotation(90, (1, 0, 0)))
    np.testing.assert_allclose(lo, [-1, -2, 0], atol=1e-12)
    np.testing.assert_allclose(hi, [1, 2, 0], atol=1e-12)


def test_points_bounds_and_union():
    m = np.eye(4)
    m[:3, 3] = [1, 2, 3]
    lo, hi = gb.points_bounds([[0, 0, 0], [1, -1, 2]], m)
    np.testing.assert_allclose(lo, [1, 1, 3])
    np.testing.assert_allclose(hi, [2, 2, 5])
    assert gb.points_bounds(np.zeros((0, 3))) is None
    u = gb.union((lo, hi), (np.zeros(3), np.ones(3)))
    np.testing.assert_allclose(u[0], [0, 0, 0])
    assert gb.union(None, None) is None
    assert gb.corners([0, 0, 0], [1, 2, 3]).shape == (8, 3)


# -- triangle pairs -------------------------------------------------------------


def test_triangle_pairs():
    a = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)
    crossing = np.array([[[0.2, 0.2, -1], [0.2, 0.2, 1], [0.3, 0.8, 0.5]]], float)
    apart = crossing + [0, 0, 3]
    touching = np.array([[[1, 0, 0], [2, 0, 0], [1, 1, 0]]], float)  # shares a vertex
    coplanar_overlap = a + [0.2, 0.2, 0]
    coplanar_apart = a + [1.2, 1.2, 0]
    near_miss = np.array([[[0.6, 0.6, -1], [0.6, 0.6, 1], [0.9, 0.9, 0]]], float)  # beyond the hypotenuse
    got = gi.triangles_intersect(
        np.repeat(a, 6, axis=0),
        np.concatenate([crossing, apart, touching, coplanar_overlap, coplanar_apart, near_miss]),
    )
    assert got.tolist() == [True, False, True, True, False, False]
    with pytest.raises(ValueError):
        gi.triangles_intersect(np.zeros((2, 3, 3)), np.zeros((1, 3, 3)))
