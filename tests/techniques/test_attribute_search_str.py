"""``print(om.attribute_search(...))`` reads as one line per category."""

from __future__ import annotations

import omnirender as om


def test_attribute_search_prints_one_line_per_category():
    light = om.PointLight(position=(1, 1, 1))
    scene = om.Node(
        "s",
        [om.Camera.look_at(eye=(0, 0, 5)), light, om.Node("n", [om.Material(), om.Translation(1, 0, 0), om.Sphere()])],
    )
    text = str(om.attribute_search(scene, "/s/n"))
    lines = text.splitlines()
    assert lines[0] == "attributes at /s/n:"
    assert any(line.startswith("  Material: Material(") for line in lines)
    assert any(line.startswith("  Camera: Camera(eye=(0.0, 0.0, 5.0)") for line in lines)
    assert "  Transform: [[1., 0., 0., 1.]," in lines
    assert f"  Light (1): {light!r}" in lines
    assert "<class" not in text  # categories are named, not shown as class objects
