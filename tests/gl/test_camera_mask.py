"""A camera's group mask selects what the GL engine draws; analysis engines still see everything."""

from __future__ import annotations

import pytest

import omnirender as om


@pytest.mark.gl
def test_camera_mask_hides_debug_geometry_in_gl_only():
    scene = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 6), mask="!debug")])
    scene.add(om.Node("debug", [om.Sphere(radius=1)], groups=["debug"]))
    hidden = om.render(scene, engine="gl", size=(64, 48))
    assert not hidden.mask[24, 32]
    shown = om.render(scene, engine="gl", size=(64, 48), mask="debug")
    assert shown.mask[24, 32]
    assert om.bounds(scene) is not None  # bounds see the whole graph
