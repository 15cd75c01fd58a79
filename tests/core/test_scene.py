"""Scene graph: paths, DAGs, masks, pre-evaluation, versions, statistics, inspection."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.core.mask import MaskError, compile_mask


class S(om.Shape):
    __slots__ = ("label",)

    def __init__(self, label="s"):
        super().__init__()
        self.label = label


class Lamp(om.Light):
    __slots__ = ("name",)

    def __init__(self, name):
        super().__init__()
        self.name = name


class LightProbe(om.Engine):
    """Records, for each shape, the names of the lights that reach it and their world x."""

    service = "probe"

    def __init__(self, **kw):
        super().__init__(**kw)
        self.seen = {}


class ProbePainter(om.ShapePainter):
    __slots__ = ()
    service = "probe"
    target = S

    def exec(self, shape, engine):
        engine.seen[shape.label] = [(light.name, float(m[0, 3])) for light, m in engine.lights()]


def probe(**kw):
    e = LightProbe(**kw)
    e.install(ProbePainter())
    return e


# --- paths and structure ----------------------------------------------------------------------


def build():
    scene = om.Node("scene")
    body = scene.add(om.Node("body"))
    arm = body.add(om.Node("arm"))
    arm.add(S("hand"))
    scene.add(om.Node("floor"))
    return scene, body, arm


def test_paths_and_lookup():
    scene, body, arm = build()
    assert arm.path == "/scene/body/arm"
    assert scene["/scene/body/arm"] is arm
    assert scene["/body/arm"] is arm
    assert scene["body"] is body
    assert body["arm"] is arm
    assert scene["/scene"] is scene
    assert arm.parent is body and scene.parent is None
    assert [c.name for c in scene.children] == ["body", "floor"]


def test_lookup_miss_names_closest_prefix():
    scene, body, arm = build()
    with pytest.raises(KeyError) as info:
        scene["/scene/body/leg/foot"]
    assert "'/scene/body'" in str(info.value) and "'leg'" in str(info.value) and "arm" in str(info.value)


def test_dag_paths_name_the_first_parent_and_cycles_are_refused():
    scene, body, arm = build()
    floor = scene["floor"]
    floor.add(arm)  # shared
    assert arm.parents == (body, floor)
    assert arm.path == "/scene/body/arm"
    assert scene["/scene/floor/arm"] is arm
    trace = om.trace(scene)
    assert [obj.label for op, obj in trace if op == "eval"] == ["hand", "hand"]
    with pytest.raises(ValueError, match="cycle"):
        arm.add(scene)
    with pytest.raises(ValueError, match="cycle"):
        arm.add(arm)


def test_insert_remove_iteration():
    n = om.Node("n")
    a, b, c = S("a"), S("b"), S("c")
    n.add(a)
    n.add(c)
    assert n.insert(1, b) is b
    assert [x.label for x in n] == ["a", "b", "c"] and len(n) == 3
    n.remove(b)
    assert b not in n and [x.label for x in n] == ["a", "c"]
    with pytest.raises(ValueError, match="not in this node"):
        n.remove(b)
    with pytest.raises(TypeError, match="cannot add int"):
        n.add(3)
    with pytest.raises(ValueError, match="name"):
        om.Node("a/b")


def test_inspect_walks_structure_without_engine():
    scene, body, arm = build()
    body.insert(0, om.Translation(1, 0, 0))
    events = []

    class V(om.Visitor):
        def enter_node(self, node):
            events.append(("enter", node.name))

        def leave_node(self, node):
            events.append(("leave", node.name))

        def visit(self, component, node):
            events.append((type(component).__name__, node.name))

    scene.inspect(V())
    assert events == [
        ("enter", "scene"),
        ("enter", "body"),
        ("Translation", "body"),
        ("enter", "arm"),
        ("S", "arm"),
        ("leave", "arm"),
        ("leave", "body"),
        ("enter", "floor"),
        ("leave", "floor"),
        ("leave", "scene"),
    ]


# --- versions -----------------------------------------------------------------------------------


def test_versions_propagate_to_ancestors_only():
    scene, body, arm = build()
    floor = scene["floor"]
    hand = arm.components[0]
    v_scene, v_body, v_arm, v_floor, v_hand = scene.version, body.version, arm.version, floor.version, hand.version
    hand.label = "palm"
    assert hand.version == v_hand + 1
    assert arm.version > v_arm and body.version > v_body and scene.version > v_scene
    assert floor.version == v_floor
    v = scene.version
    floor.add(S("tile"))
    assert scene.version > v


def test_compiled_program_follows_changes():
    scene, body, arm = build()
    assert [o.label for op, o in om.trace(scene) if op == "eval"] == ["hand"]
    arm.add(S("thumb"))
    assert [o.label for op, o in om.trace(scene) if op == "eval"] == ["hand", "thumb"]
    body.remove(arm)
    assert [o for op, o in om.trace(scene) if op == "eval"] == []


# --- masks ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "expr, groups, expected",
    [
        ("left", {"left"}, True),
        ("left", {"right"}, False),
        ("!debug", {"left"}, True),
        ("!debug", {"debug"}, False),
        ("!debug & (left | shared)", {"shared"}, True),
        ("!debug & (left | shared)", {"shared", "debug"}, False),
        ("!debug & (left | shared)", {"right"}, False),
        ("a | b & c", {"a"}, True),  # & binds tighter than |
        ("(a | b) & c", {"a"}, False),
        ("!!a", {"a"}, True),
    ],
)
def test_mask_semantics(expr, groups, expected):
    assert compile_mask(expr)(frozenset(groups)) is expected


@pytest.mark.parametrize(
    "expr, position",
    [("left &", 6), ("(left | right", 13), ("left right", 5), ("a $ b", 2), ("", 0), ("& a", 0)],
)
def test_bad_mask_expressions_report_the_position(expr, position):
    with pytest.raises(MaskError, match=f"position {position}"):
        compile_mask(expr)


def test_engine_mask_skips_subgraphs():
    scene = om.Node("scene")
    scene.add(om.Node("left", [S("l")], groups=["left"]))
    scene.add(om.Node("debug", [S("d")], groups=["debug", "left"]))
    scene.add(om.Node("plain", [S("p")]))
    evals = lambda mask: [o.label for op, o in om.trace(scene, mask=mask) if op == "eval"]  # noqa: E731
    assert evals(None) == ["l", "d", "p"]
    assert evals("left & !debug") == ["l", "p"]
    assert evals("debug") == ["d", "p"]
    with pytest.raises(MaskError):
        om.trace(scene, mask="left &")


# --- declarative pre-evaluation -----------------------------------------------------------


def test_light_placed_after_the_shapes_still_lights_them():
    scene = om.Node("scene")
    scene.add(om.Node("obj", [S("first")]))
    lamp_node = scene.add(om.Node("lamp"))
    lamp_node.add(om.Translation(7, 0, 0))
    lamp_node.add(Lamp("sun"))
    engine = probe()
    scene.evaluate(engine)
    assert engine.seen["first"] == [("sun", 7.0)]
    assert engine.poly(om.Light) == ()  # pre-evaluated lights are gone after the frame


def test_light_switch_turns_lights_off_in_a_subgraph():
    a, b = Lamp("a"), Lamp("b")
    scene = om.Node("scene", [a, b])
    scene.add(om.Node("dark", [om.LightSwitch(on=False), S("dark")]))
    scene.add(om.Node("only_a", [om.LightSwitch(on=True, lights=[a]), S("only_a")]))
    scene.add(om.Node("not_a", [om.LightSwitch(on=False, lights=[a]), S("not_a")]))
    scene.add(S("lit"))
    engine = probe()
    scene.evaluate(engine)
    assert engine.seen["dark"] == []
    assert [n for n, _ in engine.seen["only_a"]] == ["a"]
    assert [n for n, _ in engine.seen["not_a"]] == ["b"]
    assert [n for n, _ in engine.seen["lit"]] == ["a", "b"]


def test_masked_out_lights_are_not_pre_evaluated():
    scene = om.Node("scene", [S("x")])
    scene.add(om.Node("lamps", [Lamp("hidden")], groups=["debug"]))
    engine = probe(mask="!debug")
    scene.evaluate(engine)
    assert engine.seen["x"] == []


def test_camera_is_pre_evaluated_with_its_world_transform():
    scene = om.Node("scene", [S("x")])
    rig = scene.add(om.Node("rig", [om.Translation(0, 0, 10)]))
    cam = rig.add(om.Camera.look_at(eye=(0, 0, 0), center=(0, 0, -1)))
    engine = probe()
    scene.evaluate(engine)
    camera, world = engine.camera
    assert camera is cam and world[2, 3] == 10
    np.testing.assert_allclose(engine.view_matrix() @ [0, 0, 0, 1], [0, 0, -10, 1])


def test_camera_matrices():
    cam = om.Camera.look_at(eye=(0, 0, 5), center=(0, 0, 0), up=(0, 1, 0), fov=90, near=1, far=10)
    v = cam.view_matrix()
    np.testing.assert_allclose(v @ [0, 0, 0, 1], [0, 0, -5, 1])
    p = cam.projection_matrix(2.0)
    clip = p @ [1, 1, -1, 1]
    ndc = clip[:3] / clip[3]
    np.testing.assert_allclose(ndc, [0.5, 1, -1], atol=1e-12)
    ortho = om.Camera.orthographic(eye=(0, 0, 5), height=4, near=1, far=11)
    clip = ortho.projection_matrix(1.0) @ [2, -2, -11, 1]
    np.testing.assert_allclose(clip[:3], [1, -1, 1], atol=1e-12)
    with pytest.raises(ValueError, match="parallel"):
        om.Camera.look_at(eye=(0, 5, 0), center=(0, 0, 0), up=(0, 1, 0))
    with pytest.raises(ValueError, match="near"):
        om.Camera.look_at(eye=(0, 0, 5), near=0)


# --- trace and statistics ------------------------------------------------------------------


def test_statistics_counts():
    scene, body, arm = build()
    body.add(om.Translation(0, 1, 0))
    stats = om.statistics(scene)
    assert stats["nodes"] == 4 and stats["shapes"] == 1 and stats["attributes"] == 1
    assert stats["by_class"] == {"S": 1, "Translation": 1}


def test_evaluate_components_without_node():
    engine = probe()
    lamp = Lamp("l")
    engine.evaluate([lamp, S("a")])
    assert engine.seen["a"] == [("l", 0.0)]
    assert engine.poly(om.Light) == ()


def test_camera_mask_selects_what_it_sees_unless_the_engine_has_a_mask():
    class Imaging(om.TraceEngine):
        uses_camera_mask = True

    scene = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 5), mask="!debug")])
    scene.add(om.Node("dbg", [S("d")], groups=["debug"]))
    scene.add(S("x"))

    def evals(engine):
        scene.evaluate(engine)
        return [o.label for op, o in engine.program if op == "eval"]

    assert evals(Imaging()) == ["x"]
    assert evals(Imaging(mask="debug")) == ["d", "x"]
    assert evals(om.TraceEngine()) == ["d", "x"]  # analysis engines see the whole graph
    with pytest.raises(ValueError, match="Camera: bad mask.*position"):
        om.Camera.look_at(eye=(0, 0, 5), mask="a &")


def test_shared_light_shines_from_every_placement():
    lamp = Lamp("lamp")
    lamp_node = om.Node("lamp", [lamp])
    scene = om.Node("scene", [S("x")])
    scene.add(om.Node("left", [om.Translation(-3, 0, 0), lamp_node]))
    scene.add(om.Node("right", [om.Translation(4, 0, 0), lamp_node]))
    engine = probe()
    scene.evaluate(engine)
    assert sorted(engine.seen["x"]) == [("lamp", -3.0), ("lamp", 4.0)]


def test_deep_graphs_need_no_deep_recursion():
    root = node = om.Node("n0")
    for i in range(1, 3000):
        node = node.add(om.Node(f"n{i}", [om.Translation(1, 0, 0)]))
    node.add(S("deep"))
    engine = probe()
    root.evaluate(engine)
    assert "deep" in engine.seen
    assert om.statistics(root)["nodes"] == 3000
    assert node.path.count("/") == 3000
    node.add(S("again"))  # touch through 3000 ancestors
    assert [o.label for op, o in om.trace(root) if op == "eval"] == ["deep", "again"]


def test_touch_visits_each_ancestor_once_in_a_dag():
    # 20 layers, each node shared by two parents: 2**20 paths, 40 ancestors
    bottom = om.Node("bottom")
    layer = [bottom]
    for i in range(20):
        a, b = om.Node(f"a{i}"), om.Node(f"b{i}")
        for n in layer:
            a.add(n)
            b.add(n)
        layer = [a, b]
    top = om.Node("top", layer)
    before = top.version
    bottom.add(S("x"))
    assert top.version == before + 1


def test_a_string_is_one_group():
    assert om.Node("n", groups="debug").groups == frozenset({"debug"})


def test_a_node_is_adapted_to_a_renderable_by_the_viewer_package():
    from omnirender.viewer import TRANSPARENT, IsRenderable, RenderList, as_renderable

    solid = om.Node("solid", [om.Sphere(radius=2)])
    glass = om.Node("glass", [om.Material(opacity=0.5), om.Sphere(radius=1)])
    assert not isinstance(solid, IsRenderable)  # the scene graph knows nothing of viewers
    assert not hasattr(solid, "prerender")
    solid_r, glass_r = as_renderable(solid), as_renderable(glass)
    assert isinstance(solid_r, IsRenderable)
    assert solid_r.render_hints() & TRANSPARENT == 0 and glass_r.render_hints() & TRANSPARENT
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    solid_r.update_bounds(lo, hi)
    np.testing.assert_allclose([lo, hi], [[-2, -2, -2], [2, 2, 2]])
    rl = RenderList()
    rl.prerender([solid, glass])
    assert solid in [getattr(r, "node", r) for r in rl.opaque]
    assert glass in [getattr(r, "node", r) for r in rl.transparent]


def test_lights_added_by_hand_use_their_model_matrix_and_are_forgotten_when_removed():
    engine = probe()
    lamp = Lamp("hand")
    engine.push(om.Translation(2, 0, 0))
    engine.add(lamp)
    engine.pop(om.Transform)
    assert [(light.name, m[0, 3]) for light, m in engine.lights()] == [("hand", 2.0)]
    engine.remove(lamp)
    assert engine.lights() == [] and engine._light_matrices == {}
