"""The non-rendering engines on small graphs: picking, bounds, collisions, attribute search, image info."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om
from omnirender.geometry.bvh import embree_available
from omnirender.techniques import PickEngine


def scene_with_camera(eye=(0, 0, 10), **kw) -> om.Node:
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=eye, center=(0, 0, 0), **kw))
    return s


# -- picking ----------------------------------------------------------------------


def test_ray_through_sphere_centre_hits_at_radius_distance():
    s = om.Node("scene")
    s.add(om.Sphere(center=(0, 0, 0), radius=2.0))
    hits = om.pick(s, ray=((0, 0, 10), (0, 0, -1)))
    assert [h.distance for h in hits] == pytest.approx([8.0, 12.0])
    assert hits[0].point == pytest.approx([0, 0, 2])
    assert hits[0].normal == pytest.approx([0, 0, 1])
    assert hits[0].path == "/scene" and hits[0].primitive == -1
    assert isinstance(hits[0].shape, om.Sphere)
    # the direction need not be unit length: distances stay in world units
    assert om.pick(s, ray=((0, 0, 10), (0, 0, -7)))[0].distance == pytest.approx(8.0)


def test_transformed_shapes_report_world_points_and_normals():
    s = om.Node("scene")
    body = s.add(om.Node("body"))
    body.add(om.Translation(3, 0, 0))
    body.add(om.Scaling(2, 1, 1))  # an ellipsoid with semi-axis 2 along x
    body.add(om.Sphere())
    hits = om.pick(s, ray=((10, 0, 0), (-1, 0, 0)))
    assert [h.distance for h in hits] == pytest.approx([5.0, 9.0])
    assert hits[0].point == pytest.approx([5, 0, 0])
    assert hits[0].normal == pytest.approx([1, 0, 0])
    assert hits[0].path == "/scene/body"
    # an oblique ray: the world normal is the inverse-transpose normal, unit length
    h = om.pick(s, ray=((3, 5, 0.0), (0, -1, 0)))[0]
    assert h.distance == pytest.approx(4.0) and h.normal == pytest.approx([0, 1, 0])


@pytest.mark.parametrize(
    "shape",
    [
        om.Sphere(center=(0.1, 0.2, 0), radius=0.8),
        om.Box(size=(1.0, 0.6, 1.4), center=(0.1, 0, 0)),
        om.Cylinder(radius=0.7, height=1.5),
        om.Cone(radius=0.8, height=1.6),
        om.Disk(radius=0.9),
        om.Rectangle(size=(1.2, 0.8)),
    ],
    ids=lambda s: type(s).__name__,
)
def test_analytic_intersectors_agree_with_their_tessellation(shape):
    rng = np.random.default_rng(7)
    transform = om.Matrix(
        om.Translation(0.3, -0.2, 0.1).matrix @ om.Rotation(33, (1, 2, 3)).matrix @ om.Scaling(1.3, 0.9, 1.1).matrix
    )
    analytic = om.Node("a", [transform, shape])
    tessellated = om.Node("t", [transform, om.Tessellation(6)])
    tessellated.add(om.Node("mesh", list(_simplified(shape))))
    agree = 0
    for _ in range(60):
        target = rng.uniform(-0.6, 0.6, 3)
        origin = rng.normal(size=3)
        origin = 5 * origin / np.linalg.norm(origin)
        ray = (origin, target - origin)
        a = om.pick(analytic, ray=ray)
        t = om.pick(tessellated, ray=ray)
        if a and t:
            assert a[0].distance == pytest.approx(t[0].distance, abs=0.02)
            assert abs(a[0].normal @ t[0].normal) > 0.9
            assert np.linalg.norm(a[0].normal) == pytest.approx(1.0)
            assert a[0].normal @ (target - origin) < 0  # faces the ray's origin
            agree += 1
        else:
            # near a silhouette the tessellation may differ: then the hit is grazing
            assert not a or abs(a[0].normal @ (target - origin)) / np.linalg.norm(target - origin) < 0.35
    assert agree > 20


def _simplified(shape):
    engine = om.Engine()
    engine.push(om.Tessellation(6))
    simplifier = engine.find_handler(om.SIMPLIFY, type(shape))
    return simplifier.exec(shape, engine)


def test_hits_are_nearest_first_across_shapes():
    s = om.Node("scene")
    for name, z in (("mid", 0.0), ("far", -5.0), ("near", 4.0)):
        n = s.add(om.Node(name))
        n.add(om.Translation(0, 0, z))
        n.add(om.Box(size=(1, 1, 1)))
    hits = om.pick(s, ray=((0, 0, 10), (0, 0, -1)))
    assert [h.path for h in hits] == ["/scene/near"] * 2 + ["/scene/mid"] * 2 + ["/scene/far"] * 2
    assert np.all(np.diff([h.distance for h in hits]) > 0)
    nearest = om.pick(s, ray=((0, 0, 10), (0, 0, -1)), nearest=True)
    assert len(nearest) == 1 and nearest[0].path == "/scene/near" and nearest[0].distance == pytest.approx(5.5)


def test_torus_is_picked_through_its_simplifier_with_triangle_index():
    s = om.Node("scene")
    s.add(om.Torus(major_radius=1, minor_radius=0.25))
    hits = om.pick(s, ray=((1, 5, 0), (0, -1, 0)))
    assert len(hits) == 2
    assert hits[0].distance == pytest.approx(4.75, abs=0.01)
    assert isinstance(hits[0].shape, om.Torus) and isinstance(hits[0].part, om.TriangleSet)
    assert 0 <= hits[0].primitive < hits[0].part.triangle_count
    assert om.pick(s, ray=((0, 5, 0), (0, -1, 0))) == []  # through the hole


def test_pixel_picking_hits_the_object_at_the_image_centre():
    s = scene_with_camera(eye=(0, 3, 8))
    target = s.add(om.Node("target"))
    target.add(om.Sphere(radius=0.5))
    hits = om.pick(s, pixel=(160, 120), size=(320, 240))
    assert hits and hits[0].path == "/scene/target"
    assert hits[0].distance == pytest.approx(math.hypot(3, 8) - 0.5, abs=0.01)
    assert om.pick(s, pixel=(5, 5), size=(320, 240)) == []
    # a pixel on the right half hits points with x > 0 (pixel x grows to the right, y downwards)
    right = om.pick(s, pixel=(170, 120), size=(320, 240))[0]
    below = om.pick(s, pixel=(160, 128), size=(320, 240))[0]
    assert right.point[0] > 0 and below.point[1] < hits[0].point[1]


def test_pixel_picking_uses_the_camera_where_it_sits_and_orthographic_cameras():
    s = om.Node("scene")
    rig = s.add(om.Node("rig"))
    rig.add(om.Translation(5, 0, 0))
    rig.add(om.Camera.look_at(eye=(0, 0, 10), center=(0, 0, 0)))
    s.add(om.Node("left", [om.Sphere(center=(0, 0, 0), radius=1)]))
    s.add(om.Node("right", [om.Sphere(center=(5, 0, 0), radius=1)]))
    assert om.pick(s, pixel=(50, 50), size=(100, 100))[0].path == "/scene/right"
    ortho = om.Camera.orthographic(eye=(0, 0, 10), center=(0, 0, 0), height=4)
    # with height 4 over 100 pixels, pixel 87 is at x = (87.5 / 100) * 4 - 2 = 1.5: beyond the left sphere
    assert om.pick(s, pixel=(50, 50), size=(100, 100), camera=ortho)[0].path == "/scene/left"
    assert om.pick(s, pixel=(87, 50), size=(100, 100), camera=ortho) == []
    hit = om.pick(s, pixel=(62, 50), size=(100, 100), camera=ortho)[0]  # pixel centre (62.5, 50.5): x = 0.5, y = -0.02
    assert hit.point[:2] == pytest.approx([0.5, -0.02])
    assert hit.distance == pytest.approx(10 - math.sqrt(1 - 0.25 - 0.02**2))


def test_clip_planes_discard_hits_on_the_clipped_side():
    s = om.Node("scene")
    s.add(om.Translation(0, 0, 1))
    s.add(om.ClipPlane(normal=(0, 0, -1), offset=0.0))  # keeps z <= 1 in world space
    s.add(om.Sphere(radius=1))
    hits = om.pick(s, ray=((0, 0, 10), (0, 0, -1)))
    assert [h.distance for h in hits] == pytest.approx([10.0])  # the exit point at z = 0 survives
    sibling = om.Node("scene2", [om.Node("clipped", [om.ClipPlane((0, 0, -1), 5.0)]), om.Sphere(radius=1)])
    assert len(om.pick(sibling, ray=((0, 0, 10), (0, 0, -1)))) == 2  # a sibling's plane does not apply


def test_group_masks_select_what_is_picked():
    s = om.Node("scene")
    s.add(om.Node("debug", [om.Box(size=(1, 1, 1))], groups=["debug"]))
    s.add(om.Node("main", [om.Translation(0, 0, -3), om.Box(size=(1, 1, 1))]))
    ray = ((0, 0, 10), (0, 0, -1))
    assert {h.path for h in om.pick(s, ray=ray)} == {"/scene/debug", "/scene/main"}
    assert {h.path for h in om.pick(s, ray=ray, mask="!debug")} == {"/scene/main"}


def test_triangle_set_bvh_is_cached_per_version_and_backends_agree():
    rng = np.random.default_rng(2)
    v = rng.normal(size=(300, 3))
    mesh = om.TriangleSet(v, indices=rng.integers(0, 300, size=(400, 3)))
    s = om.Node("scene", [om.Rotation(20, (0, 1, 0)), mesh])
    backends = ["numpy"] + (["embree"] if embree_available() else [])
    for _ in range(25):
        o = rng.normal(size=3) * 4
        ray = (o, rng.normal(size=3) * 0.3 - o)
        results = [om.pick(s, ray=ray, backend=b) for b in backends]
        for other in results[1:]:
            assert [h.distance for h in other] == pytest.approx([h.distance for h in results[0]], rel=1e-6)
            assert [h.primitive for h in other] == [h.primitive for h in results[0]]
    from omnirender.geometry.bvh import bvh_for

    first = bvh_for(mesh, "numpy")
    assert bvh_for(mesh, "numpy") is first


def test_pick_bad_input():
    s = om.Node("scene", [om.Sphere()])
    with pytest.raises(ValueError, match="exactly one"):
        om.pick(s)
    with pytest.raises(ValueError, match="size"):
        om.pick(s, pixel=(1, 2))
    with pytest.raises(ValueError, match="no camera"):
        om.pick(s, pixel=(1, 2), size=(10, 10))
    with pytest.raises(ValueError, match="zero"):
        om.pick(s, ray=((0, 0, 0), (0, 0, 0)))
    with pytest.raises(ValueError, match="backend"):
        PickEngine((0, 0, 0), (1, 0, 0), backend="cuda")


# -- bounds -----------------------------------------------------------------------


def test_box_bounds_after_rotation_is_analytic():
    s = om.Node("scene")
    n = s.add(om.Node("box"))
    n.add(om.Translation(1, 2, 3))
    n.add(om.Rotation(45, (0, 0, 1)))
    n.add(om.Box(size=(2, 2, 2)))
    lo, hi = om.bounds(s)
    r = math.sqrt(2)
    assert lo == pytest.approx([1 - r, 2 - r, 2])
    assert hi == pytest.approx([1 + r, 2 + r, 4])


def test_bounds_of_a_subgraph_are_in_world_space_and_empty_is_none():
    s = om.Node("scene")
    s.add(om.Translation(10, 0, 0))
    arm = s.add(om.Node("arm", [om.Scaling(2), om.Sphere(radius=1)]))
    s.add(om.Node("other", [om.Sphere(center=(0, 5, 0))]))
    lo, hi = om.bounds(arm)
    assert lo == pytest.approx([8, -2, -2]) and hi == pytest.approx([12, 2, 2])
    assert om.bounds(s)[1] == pytest.approx([12, 6, 2])
    assert om.bounds(om.Node("empty")) is None
    # simplifier fallback (Arrow) and vertex shapes
    lo, hi = om.bounds(om.Node("x", [om.Arrow((0, 0, 0), (0, 3, 0)), om.PointSet([[5, 5, 5]])]))
    assert hi == pytest.approx([5, 5, 5]) and lo[1] == pytest.approx(0, abs=1e-9)


def test_torus_bounds_are_exact():
    s = om.Node("scene", [om.Rotation(90, (1, 0, 0)), om.Torus(major_radius=2, minor_radius=0.5)])
    lo, hi = om.bounds(s)
    assert lo == pytest.approx([-2.5, -2.5, -0.5]) and hi == pytest.approx([2.5, 2.5, 0.5])


# -- collisions -------------------------------------------------------------------


def two_tori(offset, angle=0.0, minor=0.25) -> om.Node:
    s = om.Node("scene")
    s.add(om.Collidable())
    s.add(om.Node("a", [om.Torus(major_radius=1, minor_radius=minor)]))
    s.add(om.Node("b", [om.Translation(*offset), om.Rotation(angle, (1, 0, 0)), om.Torus(1, minor)]))
    return s


def test_overlapping_tori_collide_and_distant_ones_do_not():
    assert om.collisions(two_tori((1.5, 0, 0))) == [("/scene/a", "/scene/b")]  # coplanar rings cross
    assert om.collisions(two_tori((0.3, 0, 0), angle=90)) == [("/scene/a", "/scene/b")]  # tubes cut each other
    assert om.collisions(two_tori((5, 0, 0))) == []
    assert om.collisions(two_tori((2.6, 0, 0))) == []  # 0.1 apart at the closest


def test_linked_rings_without_contact_do_not_collide():
    # each ring passes through the other's centre: the centre lines stay 1 apart, the tubes 0.5 apart
    s = two_tori((1, 0, 0), angle=90)
    a, b = om.bounds(s["/scene/a"]), om.bounds(s["/scene/b"])
    assert np.all(a[0] <= b[1]) and np.all(b[0] <= a[1])  # boxes overlap, surfaces do not
    assert om.collisions(s) == []


def test_touching_boxes_collide_and_untagged_shapes_are_skipped():
    s = om.Node("scene")
    s.add(om.Node("a", [om.Collidable(), om.Box(size=(1, 1, 1))]))
    s.add(om.Node("b", [om.Collidable(), om.Translation(1, 0, 0), om.Box(size=(1, 1, 1))]))
    s.add(om.Node("c", [om.Collidable(), om.Translation(1.001, 1.0, 0), om.Box(size=(1, 1, 1))]))
    s.add(om.Node("ghost", [om.Box(size=(5, 5, 5))]))  # not collidable
    s.add(om.Node("off", [om.Collidable(enabled=False), om.Box(size=(5, 5, 5))]))
    assert om.collisions(s) == [("/scene/a", "/scene/b"), ("/scene/b", "/scene/c")]


def test_non_collidable_subgraphs_are_not_simplified():
    calls = []

    class Spy(om.ShapeSimplifier):
        __slots__ = ()
        target = om.Torus

        def exec(self, shape, engine):
            calls.append(engine.node_path)
            return [om.Box(size=(1, 1, 1))]

    spy = Spy()
    s = om.Node("scene", [spy])
    s.add(om.Node("free", [om.Torus()]))
    s.add(om.Node("tagged", [om.Collidable(), om.Torus()]))
    om.collisions(s)
    assert calls == ["/scene/tagged"]


# -- attribute search --------------------------------------------------------------


def test_attribute_search_sees_a_material_two_levels_up_and_not_a_siblings():
    s = om.Node("scene")
    light = s.add(om.PointLight(position=(5, 5, 5)))
    cam = s.add(om.Camera.look_at(eye=(0, 0, 5)))
    mat = om.Material(diffuse=(1, 0, 0))
    top = s.add(om.Node("top", [mat, om.Translation(1, 0, 0)]))
    sibling = top.add(om.Node("sibling", [om.Material(diffuse=(0, 1, 0)), om.Color(0, 0, 1), om.Sphere()]))
    mid = top.add(om.Node("mid", [om.Translation(0, 2, 0)]))
    leaf = mid.add(om.Node("leaf", [om.ClipPlane((0, 1, 0), 0.0), om.Sphere()]))
    found = om.attribute_search(s, "/scene/top/mid/leaf")
    assert found.mono[om.Material] is mat
    assert om.Color not in found
    assert found.poly[om.Light] == [light]
    assert found.mono[om.Camera] is cam
    assert len(found.poly[om.ClipPlane]) == 1
    assert found[om.Transform][:3, 3] == pytest.approx([1, 2, 0])
    assert om.attribute_search(s, "top/sibling").mono[om.Color] is sibling.components[1]
    assert leaf.path == "/scene/top/mid/leaf"
    with pytest.raises(KeyError, match="closest existing prefix"):
        om.attribute_search(s, "/scene/top/nope")


def test_attribute_search_respects_light_switches():
    s = om.Node("scene", [om.DirectionalLight(direction=(0, -1, 0))])
    s.add(om.Node("dark", [om.LightSwitch(on=False), om.Sphere()]))
    assert om.Light not in om.attribute_search(s, "/scene/dark")


# -- image information -------------------------------------------------------------


def test_image_info_of_a_centred_sphere_is_symmetric_and_analytic():
    s = scene_with_camera(eye=(0, 0, 10), fov=40)
    s.add(om.Node("ball", [om.Sphere(radius=1.5)]))
    s.add(om.Node("elsewhere", [om.Translation(3, 0, 0), om.Box()]))
    info = om.image_info(s, "/scene/ball", (400, 300))
    x0, y0, x1, y1 = info.rect
    assert x0 + x1 == 400 and y0 + y1 == 300
    # analytic: the silhouette's half angle is asin(r / d); its half size in pixels follows from the focal length
    focal = 150 / math.tan(math.radians(20))
    half = focal * math.tan(math.asin(1.5 / 10))
    assert info.extent[2] - info.extent[0] == pytest.approx(2 * half, rel=1e-9)
    assert info.extent[3] - info.extent[1] == pytest.approx(2 * half, rel=1e-9)
    assert info.depth == pytest.approx((8.5, 11.5))
    # the tessellated torus goes through its simplifier's vertices; a transformed sphere too
    s.add(om.Node("ring", [om.Scaling(1, 2, 1), om.Sphere(radius=1)]))
    ring = om.image_info(s, "/scene/ring", (400, 300))
    assert ring.depth[0] == pytest.approx(9.0, abs=0.01) and ring.rect[1] < y0


def test_image_info_outside_the_view_and_orthographic():
    s = scene_with_camera(eye=(0, 0, 10))
    s.add(om.Node("behind", [om.Translation(0, 0, 20), om.Sphere()]))
    assert not om.image_info(s, "/scene/behind", (100, 100)).visible
    ortho = om.Camera.orthographic(eye=(0, 0, 10), height=4)
    s.add(om.Node("ball", [om.Sphere(radius=1)]))
    info = om.image_info(s, "/scene/ball", (100, 100), camera=ortho)
    assert info.rect == (25, 25, 75, 75) and info.depth == pytest.approx((9, 11))


# -- statistics --------------------------------------------------------------------


def test_statistics_count_triangles_after_simplification():
    s = om.Node("scene", [om.Box(size=(1, 1, 1))])
    s.add(om.Node("mesh", [om.TriangleSet([[0, 0, 0], [1, 0, 0], [0, 1, 0]])]))
    s.add(om.LineSet([[0, 0, 0], [1, 1, 1]]))
    assert om.statistics(s)["triangles"] == 12 + 1


def test_every_shape_goes_through_every_technique(tmp_path):
    rng = np.random.default_rng(0)
    tf = om.TransferFunction([(0, (0, 0, 0, 0)), (1, (1, 1, 1, 1))])
    obj = tmp_path / "tetra.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    shapes = [
        om.Sphere(),
        om.Box(),
        om.Cylinder(),
        om.Cone(),
        om.Torus(),
        om.Disk(),
        om.Rectangle(),
        om.Arrow((0, 0, 0), (0, 1, 0)),
        om.TriangleSet([[0, 0, 0], [1, 0, 0], [0, 1, 0]]),
        om.Polygon([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]),
        om.LineSet([[0, 0, 0], [1, 1, 1]]),
        om.Polyline([[0, 0, 0], [1, 0, 0], [1, 1, 0]]),
        om.PointSet([[0, 0, 0]]),
        om.Heightfield(rng.random((5, 5)), 0.5),
        om.Volume(rng.random((8, 8, 8)), (0.2, 0.2, 0.2), tf),
        om.MeshFile(obj),
        om.Text("label", (0, 0, 0), size=12),
    ]
    # the small box m crosses these surfaces; it sits inside the closed sphere, box, cylinder (no contact),
    # in the torus' hole, and lines, points and labels have no volume
    crossing = {"Cone", "Disk", "Rectangle", "Arrow", "TriangleSet", "Polygon", "Heightfield", "Volume", "MeshFile"}
    for shape in shapes:
        tag = om.Collidable()
        s = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 10)), tag])
        s.add(om.Node("n", [shape]))
        s.add(om.Node("m", [om.Translation(0.2, 0.1, 0.1), om.Box((0.5, 0.5, 0.5))]))
        name = type(shape).__name__
        assert len(om.pick(s, ray=((0.1, 0.1, 10), (0, 0, -1)))) >= 2, name
        assert om.bounds(s["/scene/n"]) is not None, name
        assert om.image_info(s, "/scene/n", (100, 100)).visible, name
        expected = [("/scene/m", "/scene/n")] if name in crossing else []
        assert om.collisions(s) == expected, name
        found = om.attribute_search(s, "/scene/n")
        assert found.mono[om.Collidable] is tag and isinstance(found.mono[om.Camera], om.Camera), name
        assert om.statistics(s)["triangles"] >= 12, name


def test_pixel_picks_follow_the_cameras_group_mask():
    s = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 10), mask="!hidden")])
    s.add(om.Node("veil", [om.Translation(0, 0, 2), om.Box()], groups=["hidden"]))
    s.add(om.Node("ball", [om.Sphere()]))
    assert om.pick(s, pixel=(50, 50), size=(100, 100))[0].path == "/scene/ball"
    assert om.pick(s, pixel=(50, 50), size=(100, 100), mask="hidden | !hidden")[0].path == "/scene/veil"
    assert not om.image_info(s, "/scene/veil", (100, 100)).visible


def test_technique_bad_input_and_empty_results():
    s = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 10)), om.Node("n", [om.Sphere()])])
    with pytest.raises(ValueError, match="size"):
        om.image_info(s, "/scene/n", (0, 10))
    with pytest.raises(KeyError, match="closest existing prefix"):
        om.image_info(s, "/scene/missing", (10, 10))
    with pytest.raises(TypeError, match="Camera"):
        om.pick(s, pixel=(1, 1), size=(10, 10), camera="front")
    assert om.collisions(s) == []  # nothing is tagged Collidable


def test_instances_of_an_instance_set_are_bodies_and_picks_of_their_own():
    positions = np.array([(0.0, 0.0, 0.0), (0.5, 0.0, 0.0), (5.0, 0.0, 0.0)])
    swarm = om.InstanceSet(om.Box(size=1.0), positions)
    wall = om.Node("wall", [om.Translation(5.6, 0, 0), om.Box(size=1.0)])
    scene = om.Node("s", [om.Collidable(True), om.Node("set", [swarm]), wall])
    assert om.collisions(scene) == [("/s/set[0]", "/s/set[1]"), ("/s/set[2]", "/s/wall")]
    positions[1] = (-3.0, 0.0, 0.0)  # moved apart in place
    swarm.touch()
    assert om.collisions(scene) == [("/s/set[2]", "/s/wall")]
    hits = om.pick(scene, ray=((-10.0, 0.0, 0.0), (1.0, 0.0, 0.0)))
    assert [h.instance for h in hits[:3]] == [1, 1, 0]  # entering and leaving instance 1, then instance 0


def test_hits_report_the_pick_ids_active_for_the_shape():
    """VRS pick ids: a hit names the innermost om.PickId (ids nest), also for triangle sets and CSG."""
    s = om.Node("s")
    car = s.add(om.Node("car", [om.PickId("car")]))
    wheel = car.add(om.Node("wheel", [om.PickId(7), om.Translation(0, 0, -3)]))
    wheel.add(om.Sphere(radius=0.5))
    car.add(om.Node("body", [om.Translation(3, 0, -3), om.Torus(major_radius=0.6, minor_radius=0.3)]))
    s.add(om.Node("plain", [om.Translation(-3, 0, -3), om.Sphere(radius=0.5)]))
    s.add(om.Node("csg", [om.PickId("csg"), om.Translation(0, 3, -3),
                          om.CSG("difference", om.Box(size=(1, 1, 1)), om.Sphere(radius=0.2))]))  # fmt: skip
    hit = om.pick(s, ray=((0, 0, 0), (0, 0, -1)), nearest=True)[0]
    assert hit.pick_id == 7 and hit.pick_ids == ("car", 7)
    hit = om.pick(s, ray=((3.6, 0, 0), (0, 0, -1)), nearest=True)[0]
    assert hit.path == "/s/car/body" and hit.pick_id == "car" and hit.primitive >= 0
    hit = om.pick(s, ray=((-3, 0, 0), (0, 0, -1)), nearest=True)[0]
    assert hit.pick_id is None and hit.pick_ids == ()
    hit = om.pick(s, ray=((0, 3, 0), (0, 0, -1)), nearest=True)[0]
    assert hit.path == "/s/csg" and hit.pick_id == "csg"
