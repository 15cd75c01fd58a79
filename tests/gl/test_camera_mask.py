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


@pytest.mark.gl
def test_handlers_see_pre_evaluated_lights_through_engine_lights():
    seen = []

    class Probe(om.ShapePainter):
        __slots__ = ()
        service = "gl.paint"
        target = om.Sphere

        def exec(self, shape, engine):
            seen.append(len(engine.lights()))

    lamp = om.Node("lamp", [om.PointLight(position=(0, 3, 0))])
    scene = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 6)), Probe(), om.Sphere()])
    scene.add(om.Node("a", [om.Translation(1, 0, 0), lamp]))
    scene.add(om.Node("b", [om.Translation(-1, 0, 0), lamp]))
    om.render(scene, engine="gl", size=(32, 24))
    assert seen == [2]
