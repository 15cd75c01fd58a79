"""The Jupyter view: om.show / om.Viewer in a notebook, driven through jupyter_rfb's Python event API."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import omnirender as om

pytest.importorskip("jupyter_rfb")
pytestmark = pytest.mark.gl

SIZE = (240, 180)


def _scene() -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 1, 6), center=(0, 0.5, 0), fov=40))
    scene.add(om.PointLight(position=(3, 5, 5)))
    scene.add(om.Background((0.1, 0.1, 0.12)))
    scene.add(
        om.Node("ball", [om.Translation(-1, 0.5, 0), om.Material(diffuse=(0.9, 0.2, 0.2)), om.Sphere(radius=0.7)])
    )
    scene.add(om.Node("box", [om.Material(diffuse=(0.2, 0.4, 0.9)), om.Box(size=(1, 1, 1), center=(1.3, 0.5, 0))]))
    return scene


def _send(widget, kind: str, x: float = 0, y: float = 0, button: int = 1, **extra) -> None:
    """A message as the browser sends it (jupyter_rfb adds the old-style keys and calls handle_event)."""
    event = {"type": kind, "x": x, "y": y, "button": button, "buttons": [button], "modifiers": [], "timestamp": 0}
    event.update(extra)
    widget._rfb_handle_msg(widget, event, [])


def _pixel(widget, point) -> tuple[float, float]:
    """Where the world point appears in the widget (top-left origin)."""
    v = widget.viewer
    clip = v.get_projection_matrix() @ v.get_view_matrix() @ np.array([*point, 1.0])
    ndc = clip[:3] / clip[3]
    w, h = v.size
    return (ndc[0] + 1) / 2 * w, (1 - ndc[1]) / 2 * h


def test_show_gives_a_widget_that_renders_the_scene_like_om_render():
    scene = _scene()
    widget = om.show(scene, size=SIZE)
    assert isinstance(widget, om.viewer.notebook.ViewerWidget)
    frame = widget.get_frame()
    assert frame.shape == (SIZE[1], SIZE[0], 4) and frame.dtype == np.uint8
    reference = om.render(scene, engine="gl", size=SIZE).array
    fg = lambda a: np.abs(a[:, :, :3].astype(int) - (26, 26, 31)).sum(axis=2) > 30  # noqa: E731
    assert (fg(frame) == fg(reference)).mean() > 0.99  # the scene's camera, lights and background


def test_drag_orbits_right_drag_pans_wheel_zooms():
    widget = om.show(_scene(), size=SIZE)
    cam = widget.viewer
    center, eye = cam.get_center().copy(), cam.get_eye().copy()
    _send(widget, "pointer_down", 100, 90)
    _send(widget, "pointer_move", 150, 90)  # 50 px to the right
    _send(widget, "pointer_up", 150, 90)
    moved = cam.get_eye()
    assert np.linalg.norm(moved - center) == pytest.approx(np.linalg.norm(eye - center))
    a, b = (eye - center)[[0, 2]], (moved - center)[[0, 2]]
    angle = math.degrees(math.acos(np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b)))
    assert angle == pytest.approx(50 * 0.4, abs=0.5)  # ORBIT_DEGREES_PER_PIXEL
    assert widget.picked is None  # a drag is not a click
    before = cam.get_center().copy()
    _send(widget, "pointer_down", 100, 90, button=2)
    _send(widget, "pointer_move", 100, 120, button=2)
    _send(widget, "pointer_up", 100, 120, button=2)
    assert np.linalg.norm(cam.get_center() - before) > 0.05  # panned
    distance = np.linalg.norm(cam.get_eye() - cam.get_center())
    _send(widget, "wheel", 100, 90, dx=0, dy=-100)  # one notch towards the scene
    assert np.linalg.norm(cam.get_eye() - cam.get_center()) == pytest.approx(0.9 * distance)


def test_a_click_picks_and_highlights_the_shape_under_the_pointer():
    widget = om.show(_scene(), size=SIZE)
    before = widget.get_frame().copy()
    x, y = _pixel(widget, (-1, 0.5, 0))  # the ball's centre
    _send(widget, "pointer_down", x, y)
    _send(widget, "pointer_up", x, y)
    assert widget.picked is not None and widget.picked.path == "/scene/ball"
    assert widget.title == "/scene/ball"
    after = widget.get_frame()
    assert np.abs(after.astype(int) - before).max() > 50  # the highlight is drawn
    x, y = _pixel(widget, (1.3, 0.5, 0))
    _send(widget, "pointer_down", x, y)
    _send(widget, "pointer_up", x, y)
    assert widget.picked.path == "/scene/box"


def test_keys_and_resize():
    widget = om.show(_scene(), size=SIZE)
    widget.handle_event({"type": "key_down", "key": "3", "modifiers": ()})  # top view
    eye, center = widget.viewer.get_eye(), widget.viewer.get_center()
    direction = (eye - center) / np.linalg.norm(eye - center)
    assert direction[1] == pytest.approx(1.0)
    widget.handle_event({"type": "key_down", "key": "r", "modifiers": ()})  # back to the scene's camera
    assert widget.viewer.get_eye() == pytest.approx((0, 1, 6))
    _send(widget, "resize", width=300, height=200, ratio=1)
    assert widget.viewer.size == (300, 200) and widget.get_frame().shape == (200, 300, 4)


def test_viewers_show_the_widget_in_a_kernel_and_a_png_everywhere(monkeypatch):
    from omnirender.viewer import notebook

    viewer = om.Viewer(size=SIZE)
    viewer.add_renderable(_scene())
    plain = viewer._repr_mimebundle_()
    assert set(plain) == {"text/plain", "image/png"}  # outside a kernel: the static picture
    monkeypatch.setattr(notebook, "in_kernel", lambda: True)
    bundle = viewer._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle and "image/png" in bundle
    assert bundle["application/vnd.jupyter.widget-view+json"]["model_id"] == viewer.widget().model_id
    monkeypatch.setattr(notebook, "widget_available", lambda: (False, "not installed"))
    fallback = om.show(_scene(), size=SIZE)
    assert isinstance(fallback, om.Viewer) and fallback._repr_png_().startswith(b"\x89PNG")


@pytest.mark.slow
def test_the_example_notebook_executes(tmp_path):
    pytest.importorskip("nbconvert")
    notebook = Path(__file__).resolve().parents[2] / "examples" / "10_notebook.ipynb"
    out = tmp_path / "executed.ipynb"
    result = subprocess.run(
        [sys.executable, "-m", "jupyter", "nbconvert", "--to", "notebook", "--execute", str(notebook),
         "--ExecutePreprocessor.timeout=180", "--output", str(out)],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr[-3000:]
    import nbformat

    cells = [c for c in nbformat.read(out, as_version=4).cells if c.cell_type == "code"]
    outputs = [o for c in cells for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    kinds = [set(o.get("data", {})) for o in outputs]
    assert any("application/vnd.jupyter.widget-view+json" in k and "image/png" in k for k in kinds)
    assert any(o.get("text", "").startswith("picked: /scene/") for o in outputs)
    assert sum("image/png" in k for k in kinds) >= 3
