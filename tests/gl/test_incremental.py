"""The compiled draw list stays correct when scenes change between frames."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.gl.engine.layout import ROW

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(64, 48), samples=0)
    yield e
    e.release()


def fresh(scene: om.Node) -> np.ndarray:
    return om.render(scene, engine="gl", size=(64, 48), samples=0).array


def test_incremental_frames_equal_fresh_renders(engine):
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 8)))
    color = s.add(om.Color(1, 0, 0))
    kids = []
    for i in range(6):
        n = s.add(om.Node(f"k{i}"))
        n.add(om.Translation(i - 2.5, 0, 0))
        kids.append(n)
        n.add(om.Sphere(radius=0.4))
    changes = [
        lambda: kids[2].add(om.Color(0, 1, 0)),  # a child's own list changes
        lambda: setattr(color, "g", 1.0),  # an attribute before all children changes
        lambda: s.remove(kids[0]),  # structure changes
        lambda: kids[3].insert(0, om.Translation(0, 1, 0)),
        lambda: setattr(kids[4], "groups", ["hidden"]),
    ]
    for change in changes:
        engine.render(s)
        change()
        assert engine.render(s).array.tobytes() == fresh(s).tobytes()


def test_shared_node_under_two_transforms(engine):
    shared = om.Node("ball")
    shared.add(om.Sphere(radius=0.5))
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6)))
    for x in (-1.0, 1.0):
        n = s.add(om.Node(f"at{x}"))
        n.add(om.Translation(x, 0, 0))
        n.add(shared)
    img = engine.render(s)
    assert len(engine.draw_items) == 2
    x = ROW.at("model", 0) + 12  # the translation's x in the column-major model matrix
    centres = sorted(float(it.row[x]) for it in engine.draw_items)
    assert centres == [-1.0, 1.0]
    assert img.mask[24, 16] and img.mask[24, 48]


def test_mask_selects_groups_and_invalidates(engine):
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6)))
    a = s.add(om.Node("left", groups=["left"]))
    a.add(om.Translation(-1, 0, 0))
    a.add(om.Sphere(radius=0.5))
    b = s.add(om.Node("right", groups=["right"]))
    b.add(om.Translation(1, 0, 0))
    b.add(om.Sphere(radius=0.5))
    try:
        left = engine.render(s, mask="left")
        assert left.mask[24, 16] and not left.mask[24, 48]
        right = engine.render(s, mask="right")
        assert right.mask[24, 48] and not right.mask[24, 16]
    finally:
        engine.mask = None  # a mask given to render() stays the engine's: the module shares this engine


def test_light_added_later_lights_everything(engine):
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6)))
    s.add(om.Color(1, 1, 1))
    s.add(om.Sphere())
    engine.render(s)
    s.add(om.DirectionalLight(direction=(1, 0, 0), color=(1, 0, 0)))  # after the shape: still applies
    img = engine.render(s)
    left = img.pixel(22, 24)
    assert left[0] > left[1] + 60  # red light on top of the white ambient term


def test_technique_in_a_node_takes_over_the_rest(engine):
    from omnirender.core.technique import Technique

    class Twice(Technique):
        __slots__ = ()

        def __init__(self) -> None:
            super().__init__(passes=2)

    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 5)))
    n = s.add(om.Node("n"))
    n.add(om.Color(1, 0, 0))
    n.add(Twice())
    n.add(om.Sphere(radius=0.5))
    s.add(om.Box(size=0.2, center=(1, 1, 0)))
    engine.render(s)
    items = engine.draw_items
    kinds = [it.geometry.label for it in items]
    assert kinds == ["unit sphere", "unit box"]  # compiled once: the technique's passes run at draw time
    red = ROW.at("color", "r")
    assert float(items[0].row[red]) == 1.0  # the colour before the technique applies inside it
    assert float(items[1].row[red]) != 1.0 or float(items[1].row[red + 1]) != 0.0  # and not after the node
    passes = [(p["name"], p["draw_calls"]) for p in engine.stats["passes"] if p["draw_calls"]]
    assert passes == [("opaque", 1), ("opaque/Twice[0]/opaque", 1), ("opaque/Twice[1]/opaque", 1)]
