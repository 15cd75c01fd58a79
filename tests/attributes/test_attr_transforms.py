"""LookAt and Billboard: modelling transforms in the shared Transform category."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om


def test_lookat_places_origin_at_eye_and_minus_z_towards_center():
    eye, center = np.array([1.0, 2.0, 3.0]), np.array([-2.0, 0.5, 1.0])
    t = om.LookAt(eye=eye, center=center, up=(0, 1, 0))
    m = t.matrix
    assert np.allclose(m @ [0, 0, 0, 1], [*eye, 1], atol=1e-12)
    view = (center - eye) / np.linalg.norm(center - eye)
    assert np.allclose(m @ [0, 0, -1, 0], [*view, 0], atol=1e-12)
    y = (m @ [0, 1, 0, 0])[:3]
    assert y[1] > 0 and abs(np.dot(y, view)) < 1e-12
    assert np.allclose(m[:3, :3].T @ m[:3, :3], np.eye(3), atol=1e-12)  # a rigid motion
    # inverse of the camera's look-at view matrix
    assert np.allclose(m @ om.look_at_matrix(eye, center, (0, 1, 0)), np.eye(4), atol=1e-12)


def test_lookat_setters_recompute_and_compose():
    t = om.LookAt(eye=(0, 0, 0), center=(1, 0, 0))
    t.eye = (0, 5, 0)
    assert np.allclose(t.matrix[:3, 3], (0, 5, 0))
    engine = om.Engine()
    engine.push(om.Translation(1, 0, 0))
    engine.push(t)
    assert np.allclose(engine.model_matrix()[:3, 3], (1, 5, 0))
    engine.pop(om.Transform)
    engine.pop(om.Transform)


class Marker(om.Shape):
    """A test shape whose painter records the model matrix."""

    __slots__ = ()


class RecordingEngine(om.Engine):
    service = "test.record"

    def __init__(self) -> None:
        super().__init__()
        self.matrices: list[np.ndarray] = []


@om.default_for(RecordingEngine)
class MarkerPainter(om.ShapePainter):
    __slots__ = ()
    service = "test.record"
    target = Marker

    def exec(self, shape, engine):
        engine.matrices.append(np.array(engine.model_matrix()))


def _run(eye, items, up=(0, 1, 0)):
    scene = om.Node("scene", [om.Camera.look_at(eye=eye, center=(0, 0, 0), up=up), om.Node("obj", items)])
    engine = RecordingEngine()
    engine.run(scene)
    assert engine.context.is_empty() or not engine.context._mono.get(om.Transform)
    return engine.matrices


@pytest.mark.parametrize(
    "eye, up", [((0, 0, 10), (0, 1, 0)), ((7, 3, -2), (0, 1, 0)), ((-1, 8, 0.5), (0, 0, 1))], ids=str
)
@pytest.mark.parametrize("offset", [(0, 0, 0), (2, -1, 0.5)])
def test_billboard_faces_the_camera_from_three_viewpoints(eye, up, offset):
    [m] = _run(eye, [om.Translation(*offset), om.Rotation(33, (1, 2, 3)), om.Billboard(), Marker()], up=up)
    origin = (m @ [0, 0, 0, 1])[:3]
    z = (m @ [0, 0, 1, 0])[:3]
    to_eye = np.asarray(eye, float) - origin
    assert np.allclose(z / np.linalg.norm(z), to_eye / np.linalg.norm(to_eye), atol=1e-9)
    assert np.allclose(origin, offset, atol=1e-12)  # billboarding only rotates
    # the billboard's up is the camera's up projected onto the billboard plane
    y = (m @ [0, 1, 0, 0])[:3]
    cam_up = np.asarray(up, float) - np.dot(up, to_eye) / np.dot(to_eye, to_eye) * to_eye
    assert np.dot(y, cam_up) > 0


@pytest.mark.parametrize("eye", [(0, 0, 10), (7, 3, -2), (-4, -6, 1)], ids=str)
def test_axis_billboard_turns_only_about_its_axis(eye):
    [m] = _run(eye, [om.Translation(1, 0, 0), om.Billboard(axis=(0, 1, 0)), Marker()])
    origin = (m @ [0, 0, 0, 1])[:3]
    z = (m @ [0, 0, 1, 0])[:3]
    y = (m @ [0, 1, 0, 0])[:3]
    assert np.allclose(y, (0, 1, 0), atol=1e-12)  # the axis stays put
    to_eye = np.asarray(eye, float) - origin
    flat = to_eye - to_eye[1] * np.array([0, 1, 0])
    assert np.allclose(z, flat / np.linalg.norm(flat), atol=1e-9)


def test_billboard_push_pop_balance_and_pushed_transform():
    engine = om.Engine()
    engine.camera = (om.Camera.look_at(eye=(0, 0, 5)), np.eye(4))
    engine.push(om.Translation(5, 0, 0))
    bb = om.Billboard()
    engine.push(bb)
    pushed = engine.context._mono[om.Transform][-1]
    assert isinstance(pushed, om.Matrix) and pushed is not bb
    engine.push(om.Translation(0, 1, 0))
    assert len(engine.context._mono[om.Transform]) == 3
    engine.pop(om.Transform)  # the translation
    assert engine.pop(om.Transform) is bb  # the billboard's frame: pops its computed rotation
    assert len(engine.context._mono[om.Transform]) == 1
    engine.pop(om.Transform)
    assert not engine.context._mono[om.Transform]
    assert np.allclose(engine.model_matrix(), np.eye(4))

    axis = om.Billboard(axis=(1, 0, 0))
    engine.push(axis)
    assert isinstance(engine.context._mono[om.Transform][-1], om.Rotation)
    engine.pop(om.Transform)
    assert not engine.context._mono[om.Transform]


def test_billboard_without_camera_does_nothing_and_stays_balanced():
    engine = om.Engine()
    engine.push(om.Billboard())
    engine.push(om.Translation(1, 0, 0))
    engine.pop(om.Transform)
    engine.pop(om.Transform)
    assert not engine.context._mono.get(om.Transform)
    assert engine.camera is None


def test_billboard_has_no_matrix_and_is_ignored_by_preevaluation():
    with pytest.raises(AttributeError, match="Billboard has no fixed matrix"):
        _ = om.Billboard().matrix
    light = om.PointLight()
    scene = om.Node("s", [om.Translation(0, 2, 0), om.Billboard(), light])
    lights, _ = scene.preevaluate()
    assert np.allclose(lights[0][1][:3, 3], (0, 2, 0))


def test_billboard_in_a_graph_is_balanced_across_siblings():
    items = [om.Billboard(), om.Node("child", [om.Translation(0, 1, 0), Marker()]), Marker()]
    first, second = _run((0, 0, 10), items)
    assert np.allclose(first[:3, 3], (0, 1, 0))
    assert np.allclose(second[:3, 3], (0, 0, 0))
