"""Viewer camera maths against hand-computed matrices."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from viewer_helpers import Item

import omnirender as om
from omnirender.viewer import AxisAlignedRotation, Viewer


def viewer(recorder=None, size=(640, 480)) -> Viewer:
    return Viewer(size=size, engine=recorder if recorder is not None else om.Engine())


def test_look_at_matches_hand_computed_matrix():
    v = viewer()
    v.set_eye_to_world((0, 0, 10), (0, 0, 0), (0, 1, 0))
    expected = np.eye(4)
    expected[2, 3] = -10
    assert np.allclose(v.get_view_matrix(), expected)
    # looking down -x from +x with z up: eye x = world -y? right = forward x up = (-1,0,0) x (0,0,1) = (0,1,0)
    v.set_eye_to_world((5, 0, 0), (0, 0, 0), (0, 0, 1))
    t = v.get_eye_to_world()
    assert np.allclose(t[:3, 0], (0, 1, 0))  # screen right
    assert np.allclose(t[:3, 1], (0, 0, 1))  # screen up
    assert np.allclose(t[:3, 2], (1, 0, 0))  # towards the eye
    assert np.allclose(t[:3, 3], (5, 0, 0))
    assert np.allclose(v.get_view_matrix() @ np.array([0, 0, 0, 1.0]), (0, 0, -5, 1))
    assert np.allclose(v.get_view_matrix() @ t, np.eye(4))


def test_set_eye_center_up_recompute_orientation():
    v = viewer()
    v.set_eye_to_world((0, 0, 10), (0, 0, 0), (0, 1, 0))
    v.set_center((0, 0, 5))
    assert np.allclose(v.get_center(), (0, 0, 5)) and np.allclose(v.get_eye(), (0, 0, 10))
    v.set_eye((0, 5, 5))  # now looking straight down -y onto the centre; up must not stay parallel
    assert np.allclose(v.get_view_matrix() @ np.array([0, 0, 5, 1.0]), (0, 0, -5, 1))
    v.set_up_vector((1, 0, 0))
    assert np.allclose(v.get_up_vector(), (1, 0, 0))
    with pytest.raises(ValueError, match="parallel"):
        v.set_up_vector((0, 1, 0))
    with pytest.raises(ValueError, match="differ"):
        v.set_eye((0, 0, 5))


def test_set_eye_to_world_matrix_and_view_matrix_round_trip():
    v = viewer()
    t = np.eye(4)
    c, s = math.cos(0.3), math.sin(0.3)
    t[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    t[:3, 3] = (1, 2, 3)
    v.set_eye_to_world(t)
    assert np.allclose(v.get_eye_to_world(), t)
    assert np.allclose(v.get_view_matrix(), np.linalg.inv(t))
    v.set_view_matrix(np.linalg.inv(t))
    assert np.allclose(v.get_eye_to_world(), t)
    with pytest.raises(ValueError, match="rigid"):
        v.set_eye_to_world(np.diag([2.0, 1, 1, 1]))


def test_all_24_axial_views_are_distinct_proper_rotations():
    members = list(AxisAlignedRotation)
    assert len(members) == 24
    mats = [r.matrix() for r in members]
    for m in mats:
        assert np.allclose(m.T @ m, np.eye(3)) and np.isclose(np.linalg.det(m), 1.0)
        assert set(np.abs(m).ravel()) == {0.0, 1.0}
    for a, b in itertools.combinations(mats, 2):
        assert not np.allclose(a, b)


@pytest.mark.parametrize("rotation", list(AxisAlignedRotation))
def test_axial_view_names_say_which_world_axes_appear_right_and_up(rotation):
    v = viewer()
    v.set_eye_to_world((0, 0, 8), (1, 1, 1), (0, 1, 0))
    distance = np.linalg.norm(v.get_eye() - v.get_center())
    v.set_axial_view(rotation)
    view = v.get_view_matrix()
    right_name, up_name = rotation.name.split("_")
    axes = {"X": (1, 0, 0), "Y": (0, 1, 0), "Z": (0, 0, 1)}
    right = np.array(axes[right_name[-1]]) * (-1 if right_name.startswith("N") else 1)
    up = np.array(axes[up_name[-1]]) * (-1 if up_name.startswith("N") else 1)
    assert np.allclose(view[:3, :3] @ right, (1, 0, 0))  # world axis -> screen right
    assert np.allclose(view[:3, :3] @ up, (0, 1, 0))  # world axis -> screen up
    assert np.allclose(v.get_center(), (1, 1, 1))
    assert np.isclose(np.linalg.norm(v.get_eye() - v.get_center()), distance)


def test_x_z_is_the_front_view_of_a_z_up_world():
    v = viewer()
    v.set_axial_view(om.AxisAlignedRotation.X_Z)
    assert np.allclose(v.get_eye(), (0, -5, 0))
    v.set_axial_view("nx_z")
    assert np.allclose(v.get_eye(), (0, 5, 0))
    with pytest.raises(ValueError, match="RIGHT_UP"):
        v.set_axial_view("up_down")


def test_perspective_defaults_and_explicit_frustum():
    v = viewer(size=(800, 400))
    assert v.vertical_field_of_view == 35.0 and not v.is_orthogonal()
    v.set_perspective(90, 1, 11)
    p = v.get_projection_matrix()
    assert np.isclose(p[1, 1], 1.0) and np.isclose(p[0, 0], 0.5)  # f = 1/tan(45), aspect 2
    assert np.allclose(p, om.perspective_matrix(90, 2.0, 1, 11))
    assert np.isclose(v.view_plane_height, 2.0) and np.isclose(v.view_plane_width, 4.0)
    assert v.view_plane_distance == 1 and v.far_plane_distance == 11
    v.set_perspective(-1, 3, -1, 1, 2, 20)
    p = v.get_projection_matrix()
    # glFrustum by hand: 2n/(r-l) = 1, (r+l)/(r-l) = 0.5, 2n/(t-b) = 2
    assert np.isclose(p[0, 0], 1.0) and np.isclose(p[0, 2], 0.5) and np.isclose(p[1, 1], 2.0)
    assert np.isclose(p[2, 2], -22 / 18) and np.isclose(p[2, 3], -80 / 18) and p[3, 2] == -1
    assert np.isclose(v.vertical_field_of_view, 2 * math.degrees(math.atan(0.5)))
    with pytest.raises(ValueError, match="near"):
        v.set_perspective(35, 0, 10)
    with pytest.raises(TypeError):
        v.set_perspective(1, 2)


def test_orthogonal_projection():
    v = viewer(size=(400, 400))
    v.set_orthogonal(4, 1, 9)
    assert v.is_orthogonal()
    assert np.allclose(v.get_projection_matrix(), om.orthographic_matrix(4, 1.0, 1, 9))
    v.set_orthogonal(-1, 3, -2, 2, 1, 9)
    p = v.get_projection_matrix()
    assert np.isclose(p[0, 0], 0.5) and np.isclose(p[0, 3], -0.5) and np.isclose(p[1, 1], 0.5)
    assert v.view_plane_width == 4 and v.view_plane_height == 4


def _corners_visible(v: Viewer, lo, hi) -> bool:
    pv = v.get_projection_matrix() @ v.get_view_matrix()
    for corner in itertools.product(*zip(lo, hi, strict=True)):
        clip = pv @ np.array([*corner, 1.0])
        ndc = clip[:3] / clip[3]
        if clip[3] <= 0 or np.any(np.abs(ndc) > 1.0):
            return False
    return True


@pytest.mark.parametrize("size", [(640, 480), (300, 900)])
@pytest.mark.parametrize("mode", ["perspective", "ortho"])
def test_auto_fit_makes_every_bound_corner_visible(recorder, size, mode):
    v = viewer(recorder, size)
    a = v.add_renderable(Item("a", position=(10, 0, 0)))
    v.add_renderable(Item("b", position=(12, 4, -3)))
    a.hi = np.array([11.0, 1.0, 6.0])
    v.set_eye_to_world((0, 3, 4), (0, 0, 0), (0, 1, 0))
    lo, hi = v.bounds()
    assert not _corners_visible(v, lo, hi)
    v.auto_fit_perspective() if mode == "perspective" else v.auto_fit_ortho()
    assert v.is_orthogonal() == (mode == "ortho")
    assert _corners_visible(v, lo, hi)
    assert np.allclose(v.get_center(), (lo + hi) / 2)
    # the viewing direction is kept
    assert np.allclose(v.get_eye_to_world()[:3, 2], np.array([0, 3, 4]) / 5)
    # and the fit is tight: the box is not tiny on screen
    pv = v.get_projection_matrix() @ v.get_view_matrix()
    clips = [pv @ np.array([*c, 1.0]) for c in itertools.product(*zip(lo, hi, strict=True))]
    ndc = [clip[:2] / clip[3] for clip in clips]
    assert np.max(np.abs(ndc)) > 0.5


def test_auto_fit_without_renderables_uses_unit_sphere():
    v = viewer()
    v.auto_fit()
    assert np.allclose(v.get_center(), 0) and 1 < np.linalg.norm(v.get_eye()) < 10


def test_orbit_pan_zoom_keep_centre_relations():
    v = viewer()
    v.set_eye_to_world((0, 0, 10), (0, 0, 0), (0, 1, 0))
    v.camera.orbit(90, 0)
    assert np.allclose(v.get_center(), 0) and np.isclose(np.linalg.norm(v.get_eye()), 10)
    assert np.allclose(np.abs(v.get_eye()), (10, 0, 0), atol=1e-9)
    v.camera.zoom(0.5)
    assert np.isclose(np.linalg.norm(v.get_eye()), 5)
    before = v.get_eye() - v.get_center()
    v.camera.pan(0.1, 0.2)
    assert np.allclose(v.get_eye() - v.get_center(), before)
    assert not np.allclose(v.get_center(), 0)


def test_camera_round_trip_through_om_camera():
    v = viewer()
    cam = om.Camera.look_at(eye=(4, 3, 6), center=(0, 0.5, 0), fov=50, near=0.5, far=50)
    v.set_camera(cam)
    assert np.allclose(v.get_view_matrix(), cam.view_matrix())
    assert np.allclose(v.get_projection_matrix(), cam.projection_matrix(640 / 480))
    back = v.camera.to_camera()
    assert np.allclose(back.view_matrix(), cam.view_matrix())


def test_auto_fit_of_a_single_point_still_gives_a_usable_camera(recorder):
    v = viewer(recorder)
    item = v.add_renderable(Item("p", position=(3, 3, 3)))
    item.lo = item.hi = np.array([3.0, 3.0, 3.0])
    v.auto_fit()
    assert np.allclose(v.get_center(), 3)
    assert 0 < v.view_plane_distance < np.linalg.norm(v.get_eye() - 3) < v.far_plane_distance


def test_orthogonal_needs_positive_near_and_resizing_follows_aspect():
    v = viewer(size=(400, 200))
    with pytest.raises(ValueError, match="near"):
        v.set_orthogonal(2, 0, 10)
    v.set_perspective(60, 1, 10)
    assert np.isclose(v.view_plane_width, 2 * v.view_plane_height)
    v.set_size(200, 400)
    assert np.isclose(v.view_plane_width, 0.5 * v.view_plane_height)
    assert np.isclose(v.get_projection_matrix()[0, 0], 2 * v.get_projection_matrix()[1, 1])


def test_vertical_field_of_view_is_settable_and_eye_z_points_back_to_the_eye():
    """ArtiSynth's setVerticalFieldOfView / getEyeZDirection."""
    v = viewer(size=(400, 400))
    v.set_orthogonal(4, 1, 9)
    v.set_vertical_field_of_view(60)
    assert not v.is_orthogonal() and v.get_vertical_field_of_view() == 60
    assert v.view_plane_distance == 1 and v.far_plane_distance == 9  # near and far kept
    assert np.allclose(v.get_projection_matrix(), om.perspective_matrix(60, 1.0, 1, 9))
    v.vertical_field_of_view = 20
    assert v.vertical_field_of_view == 20
    with pytest.raises(ValueError, match="fov"):
        v.set_vertical_field_of_view(180)
    v.set_eye_to_world((1, 2, 3), (1, 2, 0), (0, 1, 0))
    assert np.allclose(v.get_eye_z_direction(), (0, 0, 1))
    v.set_eye_to_world((4, 0, 0), (0, 0, 0), (0, 0, 1))
    assert np.allclose(v.get_eye_z_direction(), (1, 0, 0))


def test_an_explicit_off_centre_frustum_reaches_the_engines_as_a_shifted_camera():
    """The viewer's glFrustum-style window becomes om.Camera.shift, so every engine sees the same window."""
    v = viewer(size=(400, 200))
    v.set_perspective(-1, 3, -0.5, 1.5, 2, 20)  # width 4 = aspect x height 2: the image's window exactly
    cam = v.camera.to_camera()
    assert cam.is_off_axis
    assert np.allclose(cam.projection_matrix(2.0), v.get_projection_matrix())
