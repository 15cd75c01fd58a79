"""Review fixes of the analysis engines: subgraphs in place, clipping, per-shape collisions, input checks."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.techniques import count_triangles, world_matrix_of

# -- attribute search on nodes without attributes ---------------------------------


def test_attribute_search_of_a_node_holding_only_a_shape():
    mat = om.Material(diffuse=(1, 0, 0))
    s = om.Node("scene", [mat, om.Translation(1, 0, 0)])
    s.add(om.Node("a", [om.Sphere()]))
    found = om.attribute_search(s, "/scene/a")
    assert found.mono[om.Material] is mat
    assert found[om.Transform][:3, 3] == pytest.approx([1, 0, 0])


def test_attribute_search_of_a_nested_node_without_attributes_ignores_its_childrens():
    color = om.Color(0, 0, 1)
    s = om.Node("scene")
    b = s.add(om.Node("b", [color]))
    c = b.add(om.Node("c"))  # no attributes of its own; its child pushes (and pops) a material
    c.add(om.Node("d", [om.Material(diffuse=(0, 1, 0)), om.Sphere()]))
    c.add(om.Sphere())
    found = om.attribute_search(s, "/scene/b/c")
    assert found.mono[om.Color] is color
    assert om.Material not in found
    # relative paths from a subgraph see what its ancestors apply too
    assert om.attribute_search(b, "c").mono[om.Color] is color


# -- subgraphs are evaluated where they sit -------------------------------------------


def test_bounds_and_world_matrix_below_a_billboard():
    s = om.Node("scene", [om.Camera.look_at(eye=(10, 2, 0), center=(0, 2, 0))])
    holder = s.add(om.Node("holder", [om.Translation(0, 2, 0), om.Billboard()]))
    leaf = holder.add(om.Node("leaf", [om.Box(size=(1, 1, 0.1))]))  # thin along its z: turned to face +x
    lo, hi = om.bounds(leaf)
    assert lo == pytest.approx([-0.05, 1.5, -0.5]) and hi == pytest.approx([0.05, 2.5, 0.5])
    assert om.bounds(s)[0] == pytest.approx(lo)
    m = world_matrix_of(leaf)
    assert m[:3, 3] == pytest.approx([0, 2, 0])
    assert m[:3, 2] == pytest.approx([1, 0, 0])  # the object's +z points at the eye


def test_pick_collisions_and_triangle_count_on_a_subnode_under_a_transformed_parent():
    s = om.Node("scene", [om.Collidable(), om.Tessellation(1), om.Translation(5, 0, 0)])
    group = s.add(om.Node("group"))
    a = group.add(om.Node("a", [om.Sphere()]))
    group.add(om.Node("b", [om.Translation(1.5, 0, 0), om.Sphere()]))
    hits = om.pick(a, ray=((5, 0, 10), (0, 0, -1)))
    assert [h.distance for h in hits] == pytest.approx([9.0, 11.0], abs=1e-9)
    assert hits[0].path == "/scene/group/a"
    assert om.pick(a, ray=((0, 0, 10), (0, 0, -1))) == []  # not at the origin
    assert om.collisions(group) == [("/scene/group/a", "/scene/group/b")]  # tagged above the subnode
    assert count_triangles(a) == count_triangles([om.Tessellation(1), om.Sphere()])
    assert count_triangles(a) < count_triangles([om.Sphere()])
    # image_info of a subgraph passed as the scene uses its root's camera (placed after the translation)
    s.add(om.Camera.look_at(eye=(0, 0, 10), center=(0, 0, 0)))
    x0, _, x1, _ = om.image_info(a, "", (100, 100)).rect
    assert x0 + x1 == 100


# -- image information clips against the near plane --------------------------------


def test_image_info_of_a_floor_crossing_the_eye_plane_covers_the_bottom():
    s = om.Node("scene", [om.Camera.look_at(eye=(0, 1.7, 0), center=(0, 1.7, -10), near=0.1, far=2000)])
    s.add(om.Node("floor", [om.Rectangle(size=(1000, 1000))]))
    info = om.image_info(s, "/scene/floor", (200, 100))
    assert info.rect == (0, 50, 200, 100)  # from the horizon (image middle) to the bottom, full width
    assert info.depth[0] == pytest.approx(0.1)  # starts at the near plane
    assert info.depth[1] == pytest.approx(500.0)
    # a line crossing the eye plane is clipped the same way
    s.add(om.Node("rail", [om.LineSet([[0, 0, 50], [0, 0, -50]])]))
    rail = om.image_info(s, "/scene/rail", (200, 100))
    assert rail.rect[3] == 100 and rail.depth[0] == pytest.approx(0.1)
    # a sphere around the eye falls back to clipped triangles
    s.add(om.Node("dome", [om.Translation(0, 1.7, 0), om.Sphere(radius=5)]))
    dome = om.image_info(s, "/scene/dome", (200, 100))
    assert dome.rect == (0, 0, 200, 100) and dome.depth[0] == pytest.approx(0.1)


# -- text and volume ------------------------------------------------------------------


def test_text_has_bounds_at_its_anchor_and_an_image_rectangle():
    s = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 10))])
    s.add(om.Node("label", [om.Translation(1, 2, 3), om.Text("hello", (1, 0, 0), size=20)]))
    lo, hi = om.bounds(s["/scene/label"])
    assert lo == pytest.approx([2, 2, 3]) and hi == pytest.approx([2, 2, 3])
    s2 = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 10))])
    s2.add(om.Node("label", [om.Text("hello", (0, 0, 0), size=20)]))
    info = om.image_info(s2, "/scene/label", (200, 100))
    assert info.rect == (100, 30, 160, 50)  # 5 * 0.6 * 20 wide, 20 high, anchor at the lower-left corner
    assert info.depth == pytest.approx((10, 10))


def test_volume_bounds_are_the_whole_grid_box():
    z, y, x = np.mgrid[-1:1:9j, -1:1:9j, -1:1:9j]
    blob = np.exp(-4 * (x * x + y * y + z * z))  # the isosurface at 0.8 is a small ball in the middle
    vol = om.Volume(blob, spacing=0.25, iso=0.8)
    lo, hi = om.bounds(om.Node("v", [vol]))
    assert lo == pytest.approx([-1, -1, -1]) and hi == pytest.approx([1, 1, 1])


# -- collisions per shape -------------------------------------------------------------


def test_two_shapes_in_one_node_collide_and_an_arrows_parts_do_not():
    s = om.Node("scene", [om.Collidable()])
    s.add(om.Node("a", [om.Sphere(), om.Translation(1.5, 0, 0), om.Sphere()]))
    assert om.collisions(s) == [("/scene/a#0", "/scene/a#1")]
    s.add(om.Node("b", [om.Translation(0, 10, 0), om.Arrow((0, 0, 0), (0, 3, 0))]))
    assert om.collisions(s) == [("/scene/a#0", "/scene/a#1")]  # shaft and head touch but are one shape
    s.add(om.Node("c", [om.Translation(0, 13, 0), om.Box(size=(0.5, 0.5, 0.5)), om.Rectangle((9, 9))]))
    # the untagged-free node c: box at the arrow's tip; the rectangle (index 1) far from it
    assert ("/scene/b", "/scene/c#0") in om.collisions(s)
    assert ("/scene/c#0", "/scene/c#1") in om.collisions(s)  # the box crosses the rectangle's plane


# -- bad input ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "call",
    [
        lambda x: om.pick(x, ray=((0, 0, 5), (0, 0, -1))),
        lambda x: om.bounds(x),
        lambda x: om.collisions(x),
        lambda x: count_triangles(x),
        lambda x: om.attribute_search(x, "/scene"),
        lambda x: om.image_info(x, "/scene", (10, 10), camera=om.Camera.look_at(eye=(0, 0, 5))),
    ],
)
def test_garbage_scenes_raise_type_errors_naming_the_argument(call):
    with pytest.raises(TypeError, match=r"scene must be an om.Node.*got int"):
        call(42)
    with pytest.raises(TypeError, match=r"scene"):
        call([om.Sphere(), 3.5])


def test_pixel_outside_the_image_and_fractional_sizes_raise():
    s = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 10)), om.Sphere()])
    assert om.pick(s, pixel=(9, 9), size=(10, 10)) == []
    with pytest.raises(ValueError, match=r"pixel \(10, 5\) is outside the 10x10 image"):
        om.pick(s, pixel=(10, 5), size=(10, 10))
    with pytest.raises(ValueError, match="outside"):
        om.pick(s, pixel=(-1, 5), size=(10, 10))
    with pytest.raises(ValueError, match="whole numbers"):
        om.pick(s, pixel=(5, 5), size=(10.5, 10))
    with pytest.raises(ValueError, match="size"):
        om.pick(s, pixel=(5, 5), size=("ten", 10))
    assert om.pick(s, pixel=(5, 5), size=(10.0, 10))  # a whole float is fine
    with pytest.raises(ValueError, match="whole numbers"):
        om.image_info(s, "/scene", (100, 99.5))


def test_analysis_engines_ignore_the_cameras_mask_and_pixel_queries_apply_it():
    s = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 10), mask="!hidden"), om.Collidable()])
    s.add(om.Node("veil", [om.Translation(0, 0, 3), om.Box(size=(4, 4, 0.5))], groups=["hidden"]))
    s.add(om.Node("ball", [om.Translation(0, 0, 2), om.Sphere(radius=0.9)]))
    assert om.bounds(s)[1] == pytest.approx([2, 2, 3.25])  # the hidden veil counts
    assert om.pick(s, ray=((0, 0, 10), (0, 0, -1)))[0].path == "/scene/veil"
    assert om.collisions(s) == [("/scene/ball", "/scene/veil")]
    assert count_triangles(s) > 12
    assert om.attribute_search(s, "/scene/veil").mono[om.Collidable] is s.components[1]
    # what the camera shows is what its pixels pick and where image_info finds things
    assert om.pick(s, pixel=(50, 50), size=(100, 100))[0].path == "/scene/ball"
    assert not om.image_info(s, "/scene/veil", (100, 100)).visible
    assert om.image_info(s, "/scene/ball", (100, 100)).visible


def test_attribute_search_of_the_root_and_of_a_masked_out_node():
    mat = om.Material()
    s = om.Node("scene", [mat, om.Sphere()])
    s.add(om.Node("off", [om.Sphere()], groups=["x"]))
    assert om.attribute_search(s, "/scene").mono[om.Material] is mat
    assert om.attribute_search(om.Node("bare", [om.Sphere()]), "/bare").mono[om.Transform] == pytest.approx(np.eye(4))
    with pytest.raises(ValueError, match="not evaluated"):
        om.attribute_search(s, "/scene/off", mask="!x")
