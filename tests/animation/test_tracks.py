"""Keyframe tracks, orbits, turntables and scenes at a time t."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om
from omnirender.animation import AnimationError, Keyframes, Orbit, frame_times, parse_frames, scene_at, set_time
from omnirender.animation.interpolate import interpolate, slerp


def _quat(angle_deg: float, axis=(0.0, 1.0, 0.0)) -> np.ndarray:
    h = math.radians(angle_deg) / 2
    return np.array([math.cos(h), *(math.sin(h) * np.asarray(axis, float))])


# -- interpolation -------------------------------------------------------------------
def test_step_linear_and_clamping():
    times = np.array([0.0, 1.0, 3.0])
    values = np.array([[0.0], [10.0], [30.0]])
    assert interpolate(times, values, 0.5, "linear")[0] == pytest.approx(5.0)
    assert interpolate(times, values, 2.0, "linear")[0] == pytest.approx(20.0)
    assert interpolate(times, values, 2.9, "step")[0] == 10.0
    assert interpolate(times, values, -1.0, "linear")[0] == 0.0  # before the first key
    assert interpolate(times, values, 9.0, "cubic")[0] == 30.0  # after the last key
    assert interpolate(times, values, 1.0, "step")[0] == 10.0  # a key's own time gives its value


def test_cubic_passes_through_keys_smoothly_and_reproduces_a_line():
    times = np.array([0.0, 1.0, 2.5, 4.0])
    values = np.array([[0.0], [2.0], [1.0], [3.0]])
    for t, v in zip(times, values, strict=True):
        assert interpolate(times, values, float(t), "cubic")[0] == pytest.approx(v[0])
    eps = 1e-6  # continuous first derivative at an inner key
    left = (interpolate(times, values, 1.0, "cubic") - interpolate(times, values, 1.0 - eps, "cubic")) / eps
    right = (interpolate(times, values, 1.0 + eps, "cubic") - interpolate(times, values, 1.0, "cubic")) / eps
    assert left[0] == pytest.approx(right[0], rel=1e-3)
    line = 3.0 * times[:, None] + 1.0  # Catmull-Rom slopes make a straight line exact, even for uneven keys
    for t in np.linspace(0, 4, 17):
        assert interpolate(times, line, float(t), "cubic")[0] == pytest.approx(3.0 * t + 1.0)
    # explicit Hermite tangents (glTF CUBICSPLINE): zero slopes give the smoothstep curve
    zero = (np.zeros((2, 1)), np.zeros((2, 1)))
    assert interpolate(np.array([0.0, 2.0]), np.array([[0.0], [1.0]]), 0.5, "cubic", tangents=zero)[0] == (
        pytest.approx(3 * 0.25**2 - 2 * 0.25**3)
    )


def test_slerp_has_constant_angular_speed_and_takes_the_short_way():
    q0, q1 = _quat(0), _quat(120)
    for u in (0.1, 0.25, 0.5, 0.9):
        q = slerp(q0, q1, u)
        assert np.linalg.norm(q) == pytest.approx(1.0)
        assert 2 * math.degrees(math.acos(min(1.0, q[0]))) == pytest.approx(120 * u)
    # -q1 is the same rotation: the interpolation must not go the long way round
    assert np.allclose(np.abs(slerp(q0, -q1, 0.5)), np.abs(_quat(60)))


# -- Keyframes on components -------------------------------------------------------------
def test_keyframes_drive_offsets_colours_rotations_and_discrete_values():
    move = om.Translation(0, 0, 0)
    Keyframes(move, "offset", [0, 2], [(0, 0, 0), (4, 2, 0)]).apply(0.5)
    assert move.offset == (1.0, 0.5, 0.0)
    mat = om.Material(diffuse=(1, 0, 0))
    Keyframes(mat, "diffuse", [0, 1], [(1, 0, 0), (0, 0, 1)], "step").apply(0.99)
    assert mat.diffuse == (1.0, 0.0, 0.0)
    turn = om.Rotation(0, (0, 1, 0))
    track = Keyframes(turn, "quaternion", [0, 1], [_quat(0), _quat(90)])
    track.apply(0.5)
    expected = om.Rotation(45, (0, 1, 0)).matrix
    assert np.allclose(turn.matrix, expected, atol=1e-12)
    style = om.DrawStyle()
    Keyframes(style, "mode", [0, 1], ["filled", "wireframe"], "step").apply(1.5)
    assert style.mode == "wireframe"
    tess = om.Tessellation(2)
    Keyframes(tess, "level", [0, 1], [2, 5]).apply(0.5)
    assert tess.level == 4 and isinstance(tess.level, int)  # integers are rounded


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Keyframes(om.Sphere(), "radiuss", [0], [1]), r"Sphere has no parameter 'radiuss' \(parameters: "),
        (lambda: Keyframes(om.Sphere(), "radius", [0, 1, 1], [1, 2, 3]), r"key 2 \(1.0\) follows 1.0"),
        (lambda: Keyframes(om.Sphere(), "radius", [0, 1], [1]), r"expected 2 numbers"),
        (lambda: Keyframes(om.Translation(), "offset", [0, 1], [1, 2]), r"2 vectors of 3"),
        (lambda: Keyframes(om.DrawStyle(), "mode", [0, 1], ["filled", "points"]), r"interpolation='step'"),
        (lambda: Keyframes(om.Sphere(), "radius", [0, 1], [1, 2], "spline"), r"one of \('step', 'linear', 'cubic'\)"),
        (lambda: Keyframes("sphere", "radius", [0], [1]), r"target must be a component"),
        (lambda: Keyframes(om.Sphere(), "radius", [0, float("nan")], [1, 2]), r"finite"),
        (lambda: om.Animation(Keyframes(om.Sphere(), "radius", [0], [1])), r"must be a list"),
        (lambda: om.Animation([42]), r"tracks\[0\] is a int"),
    ],
)
def test_bad_tracks_are_refused_with_the_fix(make, message):
    with pytest.raises((ValueError, TypeError), match=message):
        make()


def test_a_track_failing_at_some_time_names_track_time_and_node():
    ball = om.Sphere(radius=1)
    scene = om.Node("scene", [om.Node("ball", [ball])])
    scene.add(om.Animation([Keyframes(ball, "radius", [0, 1], [1.0, -1.0])]))
    set_time(scene, 0.25)
    assert ball.radius == pytest.approx(0.5)
    with pytest.raises(AnimationError, match=r"Keyframes\(Sphere.radius\) at t=0.75 s \(in node /scene\): .*> 0"):
        set_time(scene, 0.75)


# -- Animation, scene_at, set_time ----------------------------------------------------------
def _scene():
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 2, 8), center=(0, 0, 0)))
    scene.add(om.PointLight(position=(3, 5, 5)))
    body = scene.add(om.Node("body"))
    move = body.add(om.Translation(0, 0, 0))
    body.add(om.Material(diffuse=(0.8, 0.3, 0.2)))
    body.add(om.Box(size=(1, 1, 1)))
    anim = scene.add(om.Animation(fps=10))
    anim.keyframes(move, "offset", {0: (0, 0, 0), 2: (2, 0, 0)})
    return scene, move, anim


def test_scene_at_leaves_the_users_graph_alone_and_set_time_changes_it():
    scene, move, anim = _scene()
    seen = []
    anim.add(lambda t, root: seen.append((t, root.name)))
    version = scene.version
    later = scene_at(scene, 1.5)
    assert move.offset == (0.0, 0.0, 0.0) and scene.version == version
    assert later["/scene/body"].components[0].offset == (1.5, 0.0, 0.0)
    assert om.bounds(later)[0][0] == pytest.approx(1.0)  # every engine sees the moved box
    assert set_time(scene, 1.0) is scene and move.offset == (1.0, 0.0, 0.0)
    assert seen == [(1.5, "scene"), (1.0, "scene")]  # callables get the root they are set on
    assert anim.duration == 2.0 and anim.frame_count() == 20
    anim.duration = 3
    assert anim.frame_count(fps=24) == 72


def test_frame_numbers_and_times():
    scene, _, _ = _scene()
    assert frame_times(scene)[:3] == [(0, 0.0), (1, 0.1), (2, 0.2)] and len(frame_times(scene)) == 20
    assert frame_times(scene, "4-6", fps=2) == [(4, 2.0), (5, 2.5), (6, 3.0)]
    assert frame_times(scene, [0.0, 0.25]) == [(0, 0.0), (1, 0.25)]  # floats are times, numbered in order
    assert parse_frames("0-10:5,12") == [0, 5, 10, 12]
    for bad in ("5-2", "a-b", "-3"):
        with pytest.raises(ValueError, match="frames"):
            parse_frames(bad)
    with pytest.raises(ValueError, match="twice"):
        frame_times(scene, [1, 1])


def test_engines_ignore_the_animation(tmp_path):
    scene, _, anim = _scene()
    assert ("add", anim) in om.trace(scene)
    plain = om.Node("scene", [c for c in scene.items if c is not anim])
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for ext in (".pov", ".rib", ".glb"):
        a, b = tmp_path / "a" / f"scene{ext}", tmp_path / "b" / f"scene{ext}"
        om.export(scene, a)
        om.export(plain, b)
        assert a.read_bytes() == b.read_bytes(), ext
    scene.remove(anim)


@pytest.mark.gl
def test_gl_renders_an_animated_scene_as_its_current_state():
    scene, move, anim = _scene()
    before = om.render(scene, size=(96, 72)).array
    scene.remove(anim)
    assert np.array_equal(before, om.render(scene, size=(96, 72)).array)


# -- orbits and turntables ---------------------------------------------------------------------
def test_orbit_turns_the_camera_about_the_axis_through_the_center():
    cam = om.Camera.look_at(eye=(0, 1, 5), center=(1, 1, 0))
    track = om.orbit(cam, seconds=4.0, center=(1, 0, 0))
    track.apply(1.0)  # a quarter turn, counter-clockwise seen from +y: +z goes to +x
    assert np.allclose(cam.eye, (1 + 5, 1, 1), atol=1e-12)
    assert np.allclose(cam.center, (1, 1, 0), atol=1e-12) and np.allclose(cam.up, (0, 1, 0))
    track.apply(4.0)
    assert np.allclose(cam.eye, (0, 1, 5), atol=1e-9)
    track.apply(-3.0)  # before the start: the start position, whatever was set before
    assert np.allclose(cam.eye, (0, 1, 5), atol=1e-12)
    with pytest.raises(ValueError, match="cannot orbit a Sphere"):
        Orbit(om.Sphere(), seconds=1)


def test_turntable_turns_nested_lights_about_the_world_axis():
    scene = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 6))])
    lamp = om.PointLight(position=(0, 0, 0))
    scene.add(om.Node("rig", [om.Translation(3, 2, 0), om.Scaling(2), om.Node("lamp", [lamp])]))
    scene.add(om.Node("body", [om.Sphere(center=(0, 0, 0))]))
    om.turntable(scene, seconds=2.0, center=(0, 0, 0))
    later = scene_at(scene, 0.5)  # a quarter turn
    lights, (camera, world) = later.preevaluate()
    light, matrix = lights[0]
    assert np.allclose(light.world_position(matrix), (0, 2, -3), atol=1e-9)  # (3, 2, 0) turned by 90 degrees
    assert np.allclose(camera.eye, (6, 0, 0), atol=1e-9)
    with pytest.raises(ValueError, match="no camera"):
        om.turntable(om.Node("empty", [om.Sphere()]), 1.0)


@pytest.mark.gl
def test_a_turntable_looks_like_the_scene_turning_under_a_fixed_camera_and_lights():
    """Orbiting camera and lights by +a must give the picture of the content turned by -a (analytic check)."""

    def build(turn: float) -> om.Node:
        scene = om.Node("scene")
        scene.add(om.Camera.look_at(eye=(1, 2.5, 6), center=(1, 0.5, 0), fov=40))
        scene.add(om.PointLight(position=(4, 5, 3)))
        scene.add(om.DirectionalLight(direction=(-1, -1, -0.5), intensity=0.4))
        content = scene.add(om.Node("content", [om.Translation(1, 0, 0), om.Rotation(turn, (0, 1, 0))]))
        content.add(om.Material(diffuse=(0.8, 0.5, 0.2), specular=(0.5, 0.5, 0.5), shininess=20))
        content.add(om.Box(size=(1.6, 0.8, 0.5), center=(0.3, 0.4, 0)))
        content.add(om.Node("post", [om.Material(diffuse=(0.2, 0.5, 0.9)), om.Cylinder(radius=0.2, height=1.5)]))
        return scene

    spinning = build(0.0)
    om.turntable(spinning, seconds=4.0, center=(1, 0, 0))
    for t, angle in ((1.0, 90.0), (1.5, 135.0)):
        a = om.render(scene_at(spinning, t), size=(160, 120)).array.astype(int)
        b = om.render(build(-angle), size=(160, 120)).array.astype(int)
        differs = np.abs(a - b).max(axis=2) > 12
        assert differs.mean() < 0.01, (t, differs.mean())


def test_camera_path_flies_through_the_keys():
    cam = om.Camera.look_at(eye=(0, 0, 5))
    anim = om.Animation(om.camera_path(cam, [0, 1, 2], [(0, 0, 5), (5, 0, 0), (0, 0, -5)], [(0, 0, 0)] * 3))
    scene = om.Node("s", [cam, anim])
    assert scene_at(scene, 1.0).components[0].eye == (5.0, 0.0, 0.0)
    mid = np.asarray(scene_at(scene, 0.5).components[0].eye)
    assert np.linalg.norm(mid) > 5 / math.sqrt(2)  # the cubic curve bulges outwards, unlike the straight chord


@pytest.mark.parametrize("fmt", ["json", "yaml"])
def test_animations_round_trip_through_scene_files(tmp_path, fmt):
    scene, move, anim = _scene()
    anim.keyframes(scene["/scene/body"].components[1], "diffuse", [(0, (0.8, 0.3, 0.2)), (2, (0.2, 0.3, 0.8))], "cubic")
    om.turntable(scene, seconds=4.0, turns=0.5)
    path = tmp_path / f"anim.{fmt}"
    om.save(scene, path)
    loaded = om.load(path)
    for t in (0.0, 0.7, 1.9, 3.0):
        a, b = scene_at(scene, t), scene_at(loaded, t)
        assert a.preevaluate()[1][0].eye == pytest.approx(b.preevaluate()[1][0].eye)
        assert a.preevaluate()[0][0][0].position == pytest.approx(b.preevaluate()[0][0][0].position)
        assert a["/scene/body"].components[0].offset == b["/scene/body"].components[0].offset
        assert a["/scene/body"].components[1].diffuse == pytest.approx(b["/scene/body"].components[1].diffuse)
    anim.add(lambda t, root: None)
    with pytest.raises(ValueError, match="Animation.tracks: .*Python code"):
        om.save(scene, tmp_path / "callable.json")
