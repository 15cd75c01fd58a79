"""``omnirender view``: what the scene's camera hides is neither drawn nor picked."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.viewer import Viewer
from omnirender.viewer.picking import pick_in_viewer
from omnirender.viewer.window import open_scene

pytestmark = pytest.mark.gl

SIZE = (120, 90)


def _scene() -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 0, 6), center=(0, 0, 0), fov=40, mask="!debug"))
    scene.add(om.Node("torus", [om.Material(diffuse=(0.9, 0.2, 0.2)), om.Torus(major_radius=1, minor_radius=0.3)]))
    debug = scene.add(om.Node("debug", groups=["debug"]))
    debug.add(om.Material(diffuse=(0.1, 0.9, 0.1)))
    debug.add(om.Sphere(radius=1.6))  # around the torus: it would be hit first
    return scene


def test_the_window_draws_and_picks_through_the_cameras_mask():
    scene = _scene()
    viewer = Viewer(size=SIZE)
    try:
        open_scene(viewer, scene)
        assert viewer.mask == "!debug"
        image = viewer.rerender().array.astype(int)
        green = (image[:, :, 1] > image[:, :, 0] + 60) & (image[:, :, 1] > image[:, :, 2] + 60)
        assert not green.any()  # the debug sphere is not drawn
        x = int(SIZE[0] / 2 + SIZE[1] / 2 * (1.0 / 6.0) / np.tan(np.radians(20)))  # on the torus ring
        hit = pick_in_viewer(viewer, scene, x, SIZE[1] // 2)
        assert hit is not None and hit.path == "/scene/torus"
        viewer.mask = None  # everything: the sphere around the torus is hit first
        assert pick_in_viewer(viewer, scene, x, SIZE[1] // 2).path == "/scene/debug"
        image = viewer.rerender().array.astype(int)
        assert ((image[:, :, 1] > image[:, :, 0] + 60) & (image[:, :, 1] > image[:, :, 2] + 60)).any()
        with pytest.raises(ValueError):
            viewer.mask = "debug &"
    finally:
        viewer.close()
