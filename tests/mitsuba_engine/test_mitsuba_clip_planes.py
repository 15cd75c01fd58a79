"""ClipPlane in the Mitsuba engine: geometry clipped before Mitsuba sees it, as the GL engine clips it."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.mitsuba

W, H = 80, 60
CAMERA = om.Camera.look_at(eye=(0.5, 1.0, 4.0), center=(0, 0, 0), fov=40)


def _scene(*items, clip=None) -> om.Node:
    scene = om.Node("scene", [CAMERA, om.DirectionalLight(direction=(-1, -1, -2))])
    if clip is not None:
        scene.add(clip)
    for item in items:
        scene.add(item)
    return scene


def _positions(mesh) -> np.ndarray:
    mi = om.mitsuba._mi.mitsuba()
    return np.array(mi.traverse(mesh)["vertex_positions"], np.float64).reshape(-1, 3)


def _meshes(engine) -> list:
    return [v for v in engine.shapes.values() if not isinstance(v, dict)]


def _ball() -> om.Node:
    return om.Node("ball", [om.Color(0.8, 0.3, 0.2), om.Sphere(radius=1.0)])


@pytest.mark.gl
def test_a_cut_sphere_loses_the_clipped_half_and_matches_gl():
    # the plane is given in rotated coordinates: x >= 0.2 there is a tilted plane in the world
    clip = [om.Rotation(30, (0, 0, 1)), om.ClipPlane((1, 0, 0), 0.2)]
    whole = om.render(_scene(_ball()), engine="mitsuba", size=(W, H), spp=8)
    cut = om.render(_scene(*clip, _ball()), engine="mitsuba", size=(W, H), spp=8)
    gl = om.render(_scene(*clip, _ball()), engine="gl", size=(W, H))
    assert 0.25 < cut.mask.sum() / whole.mask.sum() < 0.6  # a bit less than half of the disc survives
    assert not (cut.mask & ~whole.mask).any()
    # the kept side is +x (rotated): the left part of the image is empty, the rest moves right
    xs, whole_xs = np.nonzero(cut.mask)[1], np.nonzero(whole.mask)[1]
    assert xs.min() > 0.35 * W and xs.mean() > whole_xs.mean() + 5
    agree = (cut.mask == gl.mask).mean()
    assert agree >= 0.97, agree


def test_native_shapes_become_clipped_meshes_and_fully_clipped_shapes_are_skipped():
    e = om.mitsuba.MitsubaEngine((W, H))
    shapes = [om.Sphere(radius=0.5), om.Box(), om.Cylinder(), om.Disk(), om.Rectangle()]
    e.run(_scene(*shapes, clip=om.ClipPlane((0, 1, 0), -0.2)))
    assert len(e.shapes) == len(shapes)
    for mesh in _meshes(e):
        assert _positions(mesh)[:, 1].min() >= -0.2 - 1e-5
    assert not any(isinstance(v, dict) for v in e.shapes.values())  # nothing left native (uncuttable)
    e.run(_scene(*shapes, clip=om.ClipPlane((0, 1, 0), 5.0)))
    assert e.shapes == {}
    e.run(_scene(*shapes))  # no clip plane: the native plugins again
    assert all(isinstance(v, dict) for v in e.shapes.values())


def test_plane_coordinates_are_the_model_matrix_where_it_was_added_and_scope_ends_with_the_node():
    tri = om.TriangleSet(
        vertices=[(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)],
        indices=[(0, 1, 2), (0, 2, 3)],
        colors=[(1, 0, 0, 1), (0, 1, 0, 1), (0, 0, 1, 1), (1, 1, 1, 1)],
        texcoords=[(0, 0), (1, 0), (1, 1), (0, 1)],
    )
    clipped = om.Node("clipped", [om.Translation(0, 0.5, 0), om.ClipPlane((0, 1, 0), 0.0), om.Translation(0, 5, 0)])
    clipped.add(tri)
    e = om.mitsuba.MitsubaEngine((W, H))
    # a vertex-coloured mesh becomes one Mitsuba mesh per colour of ambient glow: gather them per node
    e.run(_scene(clipped, om.Node("free", [om.Translation(0, 100, 0), tri])))
    points = np.concatenate([_positions(m) for m in _meshes(e)])
    first, second = points[points[:, 1] < 50], points[points[:, 1] >= 50] - (0, 100, 0)
    # the plane y >= 0 sits under Translation(0, 0.5, 0): world y >= 0.5; the later translation moves only
    # the mesh (to y in [4.5, 6.5]), which is then entirely on the kept side
    assert first[:, 1].min() == pytest.approx(4.5) and len(np.unique(first.round(6), axis=0)) == 4
    e.run(om.Node("s", [CAMERA, om.Translation(0, 0.5, 0), om.ClipPlane((0, 1, 0), 0.0), tri]))
    cut = np.unique(np.concatenate([_positions(m) for m in _meshes(e)]).round(6), axis=0)
    assert np.isclose(cut[:, 1].min(), 0.5) and np.isclose(cut[:, 1].max(), 1.5)  # the upper half of the quad
    assert len(cut) == 5  # the two upper corners, the cuts of both sides and of the shared diagonal
    assert second[:, 1].min() == pytest.approx(-1.0)  # the sibling node is not clipped


def test_lines_points_and_wireframes_are_clipped_like_gl():
    line = om.LineSet(vertices=[(-1, 0, 0), (1, 0, 0)])
    points = om.PointSet(vertices=[(-1, 0.5, 0), (1, -0.5, 0)], sizes=[6, 6])
    clip = om.ClipPlane((1, 0, 0), 0.0)
    e = om.mitsuba.MitsubaEngine((W, H))
    e.run(_scene(line, points, clip=clip))
    tubes = _positions(_meshes(e)[0])
    assert tubes[:, 0].min() == pytest.approx(0.0, abs=1e-5) and tubes[:, 0].max() == pytest.approx(1.0, abs=1e-5)
    spheres = [v for v in e.shapes.values() if isinstance(v, dict)]
    assert len(spheres) == 1 and spheres[0]["center"][0] == pytest.approx(1.0)
    e.run(_scene(om.PointSet(vertices=[(-1, 0, 0)]), clip=clip))
    assert e.shapes == {}
    wire = om.DrawStyle(mode="wireframe", line_width=2)
    quad = om.TriangleSet(vertices=[(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], indices=[(0, 1, 2), (0, 2, 3)])
    e.run(_scene(wire, quad, clip=clip))
    edges = _positions(_meshes(e)[0])
    assert edges[:, 0].min() > -0.05  # tube radius only past the plane
