"""One or a few moved transforms take the lean path (issue 22, engineer ``one``): every picture as a fresh engine's.

The lean path writes a moved ``Translation``'s offset into the plan's matrix
and, for an item whose chain is that one translation without a shape-local
matrix, only the translation column of its row; it skips the pre-evaluation
when the moved transforms sit in nodes whose subtrees declare nothing
(``omnirender.scene.node.declarations_kept``).  Each case here is one a wrong
shortcut would draw wrongly: a nested move, a parent moved under its moved
child, a shape with a local matrix, a translucent item (a row of its own), a
culled node moved back into view, a light below or beside a moved transform,
a node shared by two parents.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.scene.node import declarations_kept

pytestmark = pytest.mark.gl

SIZE = (72, 56)


def fresh(scene: om.Node, shadows: bool = False) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=shadows) as e:
        return e.render(scene, read_depth=False).array


def scene_of_kinds() -> tuple[om.Node, dict[str, om.Node]]:
    """Plain nodes (Translation, Material, shared Box), a group whose children are plain nodes, a node with a
    shape placed by a local matrix (a Box of unequal sides), a translucent node and a sphere."""
    scene = om.Node("scene", [om.Camera.look_at((6, 5, 11), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=1.0)  # (its shape-local matrix is the identity: the rows of one Translation)
    nodes: dict[str, om.Node] = {}
    for i in range(6):
        nodes[f"p{i}"] = scene.add(
            om.Node(f"p{i}", [om.Translation(1.1 * i - 3.0, -1.5, 0.0), om.Material(diffuse=(0.2 * i, 0.6, 0.4)), box])
        )
    group = nodes["group"] = scene.add(om.Node("group", [om.Translation(0.0, 1.0, 0.0)]))
    for i in range(3):
        nodes[f"c{i}"] = group.add(
            om.Node(f"c{i}", [om.Translation(1.2 * i - 1.2, 0.0, 0.0), om.Material(diffuse=(0.9, 0.3 * i, 0.2)), box])
        )
    nodes["local"] = scene.add(
        om.Node(
            "local", [om.Translation(2.5, 1.0, 1.0), om.Material(diffuse=(0.3, 0.3, 0.9)), om.Box(size=(1.2, 0.3, 0.5))]
        )
    )
    nodes["glass"] = scene.add(
        om.Node("glass", [om.Translation(-2.5, 1.0, 1.0), om.Material(diffuse=(0.9, 0.9, 0.2), opacity=0.5), box])
    )
    nodes["ball"] = scene.add(om.Node("ball", [om.Translation(0.0, 0.0, 2.0), om.Sphere(radius=0.5)]))
    return scene, nodes


def test_one_moved_translation_of_each_kind_draws_as_a_fresh_engine():
    from omnirender.gl import GLEngine

    scene, nodes = scene_of_kinds()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, read_depth=False)
        declared = e.declared
        steps = [
            ["p1"],  # a plain node: its row's translation alone
            ["c1"],  # below a group's translation: a chain of two, the product
            ["group"],  # the group itself: its three children's rows
            ["group", "c2"],  # a parent and, in the same frame, a child below it
            ["local"],  # a shape-local matrix: the product with it
            ["glass"],  # translucent: a row of its own, no batch
            ["p1", "p4", "ball"],  # a few at once
            ["p1"],  # the same one again
        ]
        for frame, names in enumerate(steps):
            for name in names:
                t = nodes[name].items[0]
                x, y, z = t.offset
                t.offset = (x + 0.3, y + 0.2 * (frame % 2 - 0.5), z - 0.25)
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False and e.stats["incremental"] >= len(names), names
            assert np.array_equal(image.array, fresh(scene)), names
            assert e.declared is declared  # nothing moved declares anything: the pre-evaluation was skipped


def test_a_node_moved_out_of_view_and_back_draws_as_a_fresh_engine():
    """A row culled in a big batch and moved back into the view: the frame after it draws it again."""
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [om.Camera.look_at((0, 4, 16), (0, 0, 0), fov=45)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.5)
    moves = []
    for i in range(150):  # a batch big enough to be sorted and culled
        t = om.Translation((i % 15) - 7.0, (i // 15) * 0.6 - 3.0, 0.0)
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Material(diffuse=(0.3, 0.5 + (i % 5) * 0.1, 0.7)), box]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, read_depth=False)
        e.render(scene, read_depth=False)
        home = moves[40].offset
        for offset in ((80.0, 0.0, 0.0), home, (0.5, 0.5, 3.0)):  # out of view, back, somewhere new
            moves[40].offset = offset
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False
            assert np.array_equal(image.array, fresh(scene)), offset
            steady = e.render(scene, read_depth=False)
            assert np.array_equal(steady.array, image.array)


def test_a_light_below_or_beside_a_moved_transform_is_placed_again():
    """A moved transform whose node (or a node below it) holds a light: the declarations are evaluated again."""
    from omnirender.gl import GLEngine

    scene, nodes = scene_of_kinds()
    beside = om.Translation(0.0, 2.0, 3.0)
    scene.add(om.Node("lamp", [beside, om.PointLight(intensity=3.0, color=(1.0, 0.4, 0.4))]))
    above = om.Translation(-1.0, 0.0, 2.0)
    scene.add(om.Node("holder", [above, om.Node("bulb", [om.PointLight(intensity=3.0, color=(0.3, 0.4, 1.0))])]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene, read_depth=False).array
        for t, offset in (
            (beside, (2.0, -1.0, 3.0)),
            (above, (2.5, 1.5, 2.0)),
            (nodes["p2"].items[0], (0.0, 0.0, 1.0)),
        ):
            t.offset = offset
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False
            assert not np.array_equal(image.array, before)
            before = image.array
            assert np.array_equal(image.array, fresh(scene)), offset


def test_a_node_shared_by_two_parents_moves_both_occurrences():
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [om.Camera.look_at((0, 3, 10), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    move = om.Translation(0.0, 0.5, 0.0)
    shared = om.Node("shared", [move, om.Material(diffuse=(0.8, 0.4, 0.2)), om.Sphere(radius=0.6)])
    scene.add(om.Node("left", [om.Translation(-2.0, 0.0, 0.0), shared]))
    scene.add(om.Node("right", [om.Translation(2.0, 0.0, 0.0), shared]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, read_depth=False)
        for y in (-1.0, 1.5):
            move.offset = (0.0, y, 0.5)
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False and e.stats["incremental"] == 2
            assert np.array_equal(image.array, fresh(scene)), y


def test_one_moved_node_with_default_shadows_draws_as_a_fresh_engine():
    from omnirender.gl import GLEngine

    scene, nodes = scene_of_kinds()
    with GLEngine(size=SIZE, samples=0, shadows=True) as e:
        e.render(scene, read_depth=False)
        e.render(scene, read_depth=False)
        for frame, name in enumerate(["p2", "c0", "group", "p2"]):
            t = nodes[name].items[0]
            x, y, z = t.offset
            t.offset = (x - 0.4, y + 0.3, z + 0.2 * frame)
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False
            assert np.array_equal(image.array, fresh(scene, True)), name
            assert np.array_equal(e.render(scene, read_depth=False).array, image.array)


def test_declarations_kept_answers_only_what_the_last_pre_evaluation_shows():
    plain = om.Translation(1.0, 0.0, 0.0)
    lit = om.Translation(0.0, 1.0, 0.0)
    above = om.Translation(0.0, 0.0, 1.0)
    scene = om.Node("scene", [om.Camera()])
    scene.add(om.Node("plain", [plain, om.Box()]))
    scene.add(om.Node("lamp", [lit, om.PointLight()]))
    scene.add(om.Node("holder", [above, om.Node("bulb", [om.PointLight()])]))
    loose = om.Translation()
    assert not declarations_kept([plain])  # never pre-evaluated: not known
    scene.declarations()
    assert declarations_kept([plain])
    assert not declarations_kept([lit])  # its node declares a light
    assert not declarations_kept([above])  # a node below it does
    assert not declarations_kept([plain, lit])
    assert not declarations_kept([loose])  # in no node
    assert not declarations_kept([plain], mask_fn=lambda groups: True)  # pre-evaluated under another mask
    elsewhere = om.Node("elsewhere", [plain])  # a second owner, never pre-evaluated
    assert not declarations_kept([plain])
    elsewhere.remove(plain)
    assert declarations_kept([plain])
    scene.items[1].add(om.SpotLight())  # the node's list changed: its last result says nothing now
    assert not declarations_kept([plain])


def test_a_moved_node_whose_translation_is_replaced_then_moves_by_its_new_transform():
    """The lean path's answer for an item (its model is one Translation) follows a replaced transform: a
    Rotation or a Scaling in the Translation's place, then moved, is composed, not written as an offset."""
    from omnirender.gl import GLEngine

    scene, nodes = scene_of_kinds()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, read_depth=False)
        for name, new in (("p2", om.Rotation(20.0, (0, 0, 1))), ("p3", om.Scaling(1.5, 0.6, 1.0))):
            node = nodes[name]
            node.items[0].offset = (node.items[0].offset[0], -1.0, 0.5)  # the lean path answers for its item
            e.render(scene, read_depth=False)
            node.remove(node.items[0])
            node.insert(0, new)
            image = e.render(scene, read_depth=False)
            assert np.array_equal(image.array, fresh(scene)), name
            if isinstance(new, om.Rotation):
                new.angle = 55.0
            else:
                new.factors = (0.7, 1.8, 1.0)
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False
            assert np.array_equal(image.array, fresh(scene)), name
            node.remove(new)
            node.insert(0, om.Translation(0.5, 0.5, 0.5))  # a Translation again
            e.render(scene, read_depth=False)
            node.items[0].offset = (-0.5, 0.8, 1.0)
            image = e.render(scene, read_depth=False)
            assert np.array_equal(image.array, fresh(scene)), name


def test_a_transform_replaced_before_any_move_then_moved_draws_as_a_fresh_engine():
    """An item asked whether its row is its one Translation's matrix (then a move writes only the translation)
    is asked when its row holds that: a node compiled with a rotating Matrix whose Matrix is replaced by a
    Translation before any move, then moved, draws without the rotation; so do a node whose Translation is
    replaced by that Matrix and back, and nodes never moved before or moved twice."""
    from omnirender.gl import GLEngine

    scene, nodes = scene_of_kinds()
    spin = np.eye(4)
    spin[:3, :3] = [[0.0, -1.6, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, 1.0]]
    for name in ("p2", "p3"):
        node = nodes[name]
        spin[:3, 3] = node.items[0].offset
        node.remove(node.items[0])
        node.insert(0, om.Matrix(spin))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, read_depth=False)
        node = nodes["p2"]
        node.remove(node.items[0])  # the first change: the transform -> items map is made for it
        node.insert(0, om.Translation(-0.8, -1.2, 0.6))
        image = e.render(scene, read_depth=False)
        assert np.array_equal(image.array, fresh(scene))
        for frame, name in enumerate(("p2", "p0", "p0", "p2", "p3")):
            node = nodes[name]
            if name == "p3" and isinstance(node.items[0], om.Matrix):
                node.remove(node.items[0])
                node.insert(0, om.Translation(1.0, -1.0, 0.2))
                e.render(scene, read_depth=False)
            t = node.items[0]
            t.offset = (t.offset[0] + 0.2, t.offset[1] + 0.1 * frame, 0.3)
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False, name
            assert np.array_equal(image.array, fresh(scene)), (frame, name)


def test_a_splice_after_a_lean_move_patches_the_declarations_instead_of_walking_every_child(monkeypatch):
    """The lean path leaves the root's declaration result at an older version (nothing it declares moved); a
    node added to or removed from the root afterwards still patches that result (its lists are a guide), so
    the next pre-evaluation walks only the root's declaring items, not each of its children; and a light
    added after such a move is found."""
    from omnirender.gl import GLEngine
    from omnirender.scene import node as node_module

    scene = om.Node("scene", [om.Camera.look_at((0, 12, 30), (0, 0, 0), fov=50)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=1.0)
    moves = [om.Translation((i % 20) - 10.0, (i // 20) * 1.2 - 3.0, 0.0) for i in range(120)]
    for i, t in enumerate(moves):
        scene.add(om.Node(f"b{i}", [t, om.Material(diffuse=(0.4, 0.6, 0.2 + 0.005 * i)), box]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, read_depth=False)
        moves[7].offset = (0.0, 0.0, 2.0)
        e.render(scene, read_depth=False)  # the lean path: no pre-evaluation
        extra = scene.add(om.Node("extra", [om.Translation(1.0, 1.0, 1.0), om.Material(), box]))
        checked = []
        original = node_module._Local.valid
        monkeypatch.setattr(node_module._Local, "valid", lambda self, n, m: checked.append(n) or original(self, n, m))
        image = e.render(scene, read_depth=False)
        monkeypatch.undo()
        assert e.stats["compiled"] == "subtrees"
        assert len(checked) < 10, len(checked)  # not one per child of the root
        assert np.array_equal(image.array, fresh(scene))
        moves[8].offset = (1.0, 0.0, 2.0)
        e.render(scene, read_depth=False)
        scene.remove(extra)
        scene.add(om.Node("lamp", [om.Translation(0.0, 0.0, 4.0), om.PointLight(color=(1.0, 0.2, 0.2), intensity=4.0)]))
        image = e.render(scene, read_depth=False)
        assert len(e.declared.lights) == 2
        assert np.array_equal(image.array, fresh(scene))


def shadow_scene() -> tuple[om.Node, list[om.Translation]]:
    """Boxes over a ground slab under a light from above: each box's shadow shows on the ground."""
    scene = om.Node("scene", [om.Camera.look_at((0, 9, 9), (0, 0, 0), fov=45)])
    scene.add(om.DirectionalLight(direction=(-0.3, -1.0, -0.2)))
    scene.add(om.Node("ground", [om.Translation(0.0, -0.6, 0.0), om.Box(size=(12.0, 0.2, 12.0))]))
    box = om.Box(size=1.0)
    moves = []
    for i in range(9):
        t = om.Translation(2.2 * (i % 3) - 2.2, 1.0, 2.2 * (i // 3) - 2.2)
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Material(diffuse=(0.8, 0.3 + 0.05 * i, 0.3)), box]))
    return scene, moves


def test_a_moved_caster_updates_its_shadow_and_replays_the_frame_plan():
    """With default shadows, a caster moved inside the casters' fitted bounds redraws the region of the map its
    old and new places cover, then the recorded frame is replayed; a move that changes the fitted bounds draws
    the frame in full.  Every picture is a fresh engine's."""
    from omnirender.gl import GLEngine

    scene, moves = shadow_scene()
    with GLEngine(size=SIZE, samples=0, shadows=True) as e:
        e.render(scene, read_depth=False)
        before = e.render(scene, read_depth=False).array
        assert e.render(scene, read_depth=False).info["replayed"]
        for step, (k, offset) in enumerate(((4, (0.4, 1.0, 0.3)), (0, (-2.0, 1.0, -1.6)), (4, (0.0, 1.0, 0.0)))):
            moves[k].offset = offset
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False
            assert image.info["replayed"], step
            assert e.stats["shadow_maps"]["partial"] == 1, e.stats["shadow_maps"]
            assert not np.array_equal(image.array, before)
            before = image.array
            assert np.array_equal(image.array, fresh(scene, True)), step
            assert np.array_equal(e.render(scene, read_depth=False).array, image.array)
        moves[8].offset = (9.0, 1.0, 2.2)  # beyond the casters' bounds: other light cameras, a full frame
        image = e.render(scene, read_depth=False)
        assert not image.info["replayed"]
        assert np.array_equal(image.array, fresh(scene, True))


def test_nodes_spliced_in_after_a_lean_move_are_moved_by_their_own_shape_local_matrices():
    """Which items' shape-local matrices are the identity is asked of the installed items at once on the first
    lean move; items spliced in later (a scaled box, a unit box) are asked one by one when they first move."""
    from omnirender.gl import GLEngine

    scene, nodes = scene_of_kinds()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, read_depth=False)
        nodes["p0"].items[0].offset = (-3.0, -1.2, 0.3)
        e.render(scene, read_depth=False)
        small = om.Translation(-1.0, 2.2, 0.0)
        unit = om.Translation(1.0, 2.2, 0.0)
        scene.add(om.Node("small", [small, om.Material(diffuse=(0.2, 0.8, 0.8)), om.Box(size=0.4)]))
        scene.add(om.Node("unit", [unit, om.Material(diffuse=(0.8, 0.2, 0.8)), om.Box(size=1.0)]))
        e.render(scene, read_depth=False)
        for t, offset in ((small, (-1.5, 2.0, 0.5)), (unit, (1.5, 2.0, 0.5)), (small, (-0.5, 1.8, 1.0))):
            t.offset = offset
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False
            assert np.array_equal(image.array, fresh(scene)), offset


def test_one_moved_node_reaches_every_engine_drawing_the_scene():
    """One pending change is told to every live journal (two engines) and its nodes' versions move once."""
    from omnirender.gl import GLEngine

    scene, nodes = scene_of_kinds()
    with GLEngine(size=SIZE, samples=0, shadows=False) as a, GLEngine(size=SIZE, samples=0, shadows=False) as b:
        a.render(scene, read_depth=False)
        b.render(scene, read_depth=False)
        version = scene.version
        nodes["p3"].items[0].offset = (0.2, -1.0, 1.2)
        assert scene.version > version
        for e in (a, b):
            image = e.render(scene, read_depth=False)
            assert e.stats["compiled"] is False and e.stats["incremental"] == 1
            assert np.array_equal(image.array, fresh(scene))


def test_a_highlight_after_moves_and_a_highlighted_node_moved_draw_as_a_fresh_engine():
    """Whether some row of a batch is highlighted is kept while only model matrices change (moves): a node
    moved, then highlighted (its Material replaced by a highlighting one: a dirty bit), then moved again, and
    the highlight taken away, each draw as a fresh engine's picture."""
    from omnirender.gl import GLEngine

    scene, nodes = scene_of_kinds()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, read_depth=False)
        node = nodes["p3"]
        for step in range(5):
            if step == 1:
                node.insert(2, om.Highlight(color=(1.0, 0.9, 0.1)))  # the node's shape highlighted
            if step == 4:
                node.remove(node.items[2])
            t = node.items[0]
            t.offset = (t.offset[0], t.offset[1] + 0.15, 0.2 * step)
            nodes["p1"].items[0].offset = (-1.9, -1.5 + 0.1 * step, 0.0)
            image = e.render(scene, read_depth=False)
            assert np.array_equal(image.array, fresh(scene)), step
