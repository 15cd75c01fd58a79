"""The change tracker (issue 22): each kind of change updates only what it touches, and gives what a fresh
engine renders, pixel for pixel.

* list edits (a node added or removed, an attribute replaced) compile only
  the edited subtrees (``stats["compiled"] == "subtrees"``) and patch batch
  rows in place, uploading the changed rows only;
* the render index's derived lists (items, mirrors, bounds, casters' bounds)
  equal the lists computed from scratch after every kind of change;
* declarations (lights, camera) of a root stay valid when plain children
  are added and removed.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.core.component import ChangeJournal

pytestmark = pytest.mark.gl

SIZE = (80, 64)


def grid_scene(n: int) -> tuple[om.Node, list[om.Node], om.Box]:
    scene = om.Node("scene", [om.Camera.look_at((9, 7, 14), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.8)
    nodes = []
    for i in range(n):
        p = (i % 8 - 3.5, (i // 8) % 8 - 3.5, i // 64 - 1.0)
        color = (0.3 + 0.7 * (i % 3) / 2, 0.4, 0.9 - 0.6 * (i % 5) / 4)
        nodes.append(scene.add(om.Node(f"b{i}", [om.Translation(*p), om.Material(diffuse=color), box])))
    return scene, nodes, box


def fresh(scene: om.Node, shadows: bool) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=shadows) as e:
        return e.render(scene).array


def edits(scene: om.Node, nodes: list[om.Node], box: om.Box, frame: int) -> list[tuple[str, object]]:
    """One frame's list edits, as callables with their names (each followed by a render in the tests)."""
    j = (frame * 13 + 5) % len(nodes)

    def replace_matrix() -> None:
        node = nodes[j]
        m = np.eye(4)
        m[:3, 3] = node.items[0].matrix[:3, 3] + (0.0, 0.1, 0.0)  # no overlap: coplanar faces would z-fight
        node.remove(node.items[0])
        node.insert(0, om.Matrix(m))

    def replace_material() -> None:
        node = nodes[j]
        node.remove(node.items[1])
        node.insert(1, om.Material(diffuse=(1.0, 0.1, 0.1)))

    def add_and_remove() -> None:
        scene.remove(nodes.pop(frame * 3))
        nodes.append(scene.add(om.Node(f"x{frame}", [om.Translation(0.0, 4.5, frame), om.Material(), box])))

    def add_new_shape() -> None:  # a geometry no batch holds yet
        scene.add(om.Node(f"ball{frame}", [om.Translation(-4.0, 4.5, frame), om.Sphere(radius=0.5)]))

    return [("matrix", replace_matrix), ("material", replace_material), ("add/remove", add_and_remove),
            ("new shape", add_new_shape)]  # fmt: skip


@pytest.mark.parametrize("n,shadows", [(40, False), (200, True)])
def test_list_edits_compile_only_their_subtrees_and_match_a_fresh_engine(n, shadows):
    from omnirender.gl import GLEngine

    scene, nodes, box = grid_scene(n)
    with GLEngine(size=SIZE, samples=0, shadows=shadows) as e:
        e.render(scene)
        for frame in range(2):
            for name, edit in edits(scene, nodes, box, frame):
                edit()
                image = e.render(scene)
                # an attribute replaced by one of the same role: dirty bits (dirty.py), no subtree compile
                assert e.stats["compiled"] == ("dirty" if name in ("matrix", "material") else "subtrees"), name
                assert e.stats["items"] == len(scene.children), name
                assert np.array_equal(image.array, fresh(scene, shadows)), name
            nodes[0].items[0].offset = (0.0, -4.0, 0.0)  # moves still take the in-place path afterwards
            image = e.render(scene)
            assert e.stats["compiled"] is False and e.stats["incremental"] == 1
            assert np.array_equal(image.array, fresh(scene, shadows))


def test_a_spliced_batch_uploads_only_the_rows_that_changed(monkeypatch):
    import moderngl

    from omnirender.gl import GLEngine

    scene, nodes, box = grid_scene(200)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        e.render(scene)
        writes: list[int] = []
        original = moderngl.Buffer.write

        def write(self, data, offset=0):
            writes.append(len(data))
            return original(self, data, offset=offset)

        monkeypatch.setattr(moderngl.Buffer, "write", write)
        scene.remove(nodes[17])
        scene.add(om.Node("extra", [om.Translation(0.0, 4.5, 0.0), om.Material(), box]))
        e.render(scene)
        assert e.stats["compiled"] == "subtrees"
        (batch,) = [b for b in e.batches if len(b.rows) == 200]
        stride = batch.layout.stride * 4
        assert writes and max(writes) <= stride and len(writes) <= 3  # the moved row, the new row: no range


def derived_from_scratch(engine) -> tuple:
    from omnirender.gl.engine.drawlist import world_bounds
    from omnirender.gl.engine.state import casts_shadows
    from omnirender.gl.techniques.mirrors import mirror_items

    items = engine.root_scope.all_items()
    bounds = world_bounds([it for it in items if not it.state.overlay])
    casters = world_bounds([it for it in items if not it.transparent and casts_shadows(it)])
    return items, [m for m, _ in mirror_items(items)], bounds, casters


def test_the_render_index_lists_equal_the_lists_computed_from_scratch():
    from omnirender.gl import GLEngine

    scene, nodes, box = grid_scene(80)
    mirror = scene.add(om.Node("mirror", [om.Translation(0, -5, 0), om.Mirror(), om.Rectangle(size=(12, 12))]))
    glass = scene.add(om.Node("glass", [om.Translation(2, 5, 0), om.Color(0.5, 0.5, 1, 0.4), om.Sphere(radius=0.6)]))
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        steps = [lambda: None, lambda: setattr(nodes[3].items[0], "offset", (9.0, 9.0, 9.0))]
        steps += [edit for _, edit in edits(scene, nodes, box, 0)]
        steps += [lambda: scene.remove(glass), lambda: scene.remove(mirror)]
        for step in steps:
            step()
            e.render(scene)
            items, mirrors, bounds, casters = derived_from_scratch(e)
            assert sorted(map(id, e.index.items())) == sorted(map(id, items))
            assert [m for m, _ in e.index.mirror_items()] == mirrors
            for got, want in ((e.index.bounds(), bounds), (e.index.caster_bounds()[0], casters)):
                assert (got is None) == (want is None)
                if want is not None:
                    assert np.allclose(got[0], want[0]) and np.allclose(got[1], want[1])


def test_edits_the_tracker_does_not_follow_fall_back_to_the_full_compile():
    from omnirender.gl import GLEngine

    scene, nodes, box = grid_scene(30)
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        light = om.PointLight(position=(0, 6, 0))
        scene.add(om.Node("lamp", [light]))  # a new light: every item's lighting changes
        image = e.render(scene)
        assert e.stats["compiled"] is True
        assert np.array_equal(image.array, fresh(scene, True))
        scene.insert(2, om.Node("early", [om.Translation(0, 4, 0), box]))  # not appended: order matters
        image = e.render(scene)
        assert e.stats["compiled"] is True
        assert np.array_equal(image.array, fresh(scene, True))
        group = scene.add(om.Node("group", [om.Color(1, 0, 0)]))
        e.render(scene)
        group.add(om.Node("inner", [box]))  # below a node whose components follow its children? no: appended
        image = e.render(scene)
        assert np.array_equal(image.array, fresh(scene, True))


def test_a_journal_records_list_edits_in_order_and_overflows_to_none():
    from omnirender.core import component

    journal = ChangeJournal()
    root = om.Node("root")
    child = om.Node("child")
    box = om.Box()
    child.add(box)
    root.add(child)
    root.remove(child)
    assert journal.drain_edits() == [(child, "insert", box, 0), (root, "insert", child, 0), (root, "remove", child, 0)]
    for _ in range(component.EDIT_LIMIT + 3):
        child.add(om.Box())
    assert journal.drain_edits() is None
    assert journal.drain_edits() == []


def test_adding_and_removing_plain_children_keeps_the_root_declarations_without_a_walk(monkeypatch):
    from omnirender.scene import node as node_module

    scene, nodes, box = grid_scene(50)
    before = scene.declarations()
    walked: list[int] = []
    original = node_module._relevant_items

    def counting(node, mask_fn):
        found = original(node, mask_fn)
        walked.append(len(found[0]))  # the items a walk of this node visits
        return found

    monkeypatch.setattr(node_module, "_relevant_items", counting)
    scene.add(om.Node("extra", [om.Translation(1, 1, 1), box]))
    scene.remove(nodes[4])
    after = scene.declarations()
    assert [c for c, _ in after.placements] == [c for c, _ in before.placements]
    assert all(n < 10 for n in walked), walked  # the new child's subtree only, never the root's 50 children
    lamp = scene.add(om.Node("lamp", [om.PointLight(position=(0, 3, 0))]))
    assert len(scene.declarations().lights) == len(before.lights) + 1
    scene.remove(lamp)
    assert len(scene.declarations().lights) == len(before.lights)


def test_a_splice_after_a_move_walks_only_what_declares(monkeypatch):
    """A move leaves the root's result stale (a new version); a splice after it must not walk every child."""
    from omnirender.scene import node as node_module

    scene, nodes, box = grid_scene(50)
    lamp = scene.add(om.Node("lamp", [om.Translation(0, 3, 0), om.PointLight(position=(0, 0, 0))]))
    scene.declarations()
    nodes[7].items[0].offset = (5.0, 5.0, 5.0)  # a plain node moved: the root's version moves
    lamp.items[0].offset = (1.0, 4.0, 0.0)  # and the lamp: the root's result must follow it
    walked: list[int] = []
    original = node_module._relevant_items

    def counting(node, mask_fn):
        found = original(node, mask_fn)
        walked.append(len(found[0]))
        return found

    monkeypatch.setattr(node_module, "_relevant_items", counting)
    node = nodes[11]
    node.remove(node.items[0])  # a transform replaced in a node that declares nothing
    node.insert(0, om.Matrix(np.eye(4)))
    (world,) = [m for light, m in scene.declarations().lights if light is lamp.items[1]]
    assert np.allclose(world[:3, 3], (1.0, 4.0, 0.0))
    assert all(n < 10 for n in walked), walked  # the root's relevant items only, never its 50 children


@pytest.mark.parametrize("with_colors", [True, False])
def test_instance_positions_alone_are_written_in_place_and_colours_converted_once(with_colors, monkeypatch):
    from omnirender.gl import GLEngine
    from omnirender.gl.engine import instancing

    n = 300
    rng = np.random.default_rng(3)
    positions = rng.uniform(-4, 4, (n, 3))
    colors = np.concatenate([rng.uniform(0.2, 1.0, (n, 3)), np.ones((n, 1))], axis=1) if with_colors else None
    balls = om.InstanceSet(om.Box(size=0.3), positions, colors=colors)
    scene = om.Node("scene", [om.Camera.look_at((0, 6, 14), (0, 0, 0), fov=45)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    scene.add(om.Node("set", [om.Translation(0.5, 0.0, 0.0), balls]))
    made: list[int] = []
    original = instancing.instance_rows

    def counting(*args, **kwargs):
        made.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(instancing, "instance_rows", counting)
    monkeypatch.setattr("omnirender.gl.engine.dynamic.instance_rows", counting)
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        for step in range(3):
            positions[:, 1] += 0.2
            positions[step, 0] = -3.0
            balls.touch()
            made.clear()
            image = e.render(scene)
            assert e.stats["compiled"] is False and not made  # rows not made again: translations written
            assert np.array_equal(image.array, fresh(scene, True))
        if with_colors:
            colors[:10, :3] = (1.0, 0.0, 0.0)  # colours changed: the rows are made again, once
            balls.touch()
            image = e.render(scene)
            assert made and np.array_equal(image.array, fresh(scene, True))


def test_moves_between_splices_of_nested_transforms_match_a_fresh_engine():
    """The move plan follows splices in place (new transforms, longer chains, removed items): moving a group's or
    a leaf's transform afterwards rewrites exactly the rows below it."""
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [om.Camera.look_at((9, 7, 14), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.6)
    groups = [scene.add(om.Node(f"g{g}", [om.Translation(2.0 * g - 3.0, 0.0, 0.0)])) for g in range(4)]
    leaves = [
        group.add(om.Node(f"l{i}", [om.Translation(0.0, i - 2.5, 0.0), om.Material(diffuse=(0.2 * i, 0.5, 0.8)), box]))
        for group in groups
        for i in range(6)
    ]
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        for frame in range(3):
            groups[frame].items[0].offset = (2.0 * frame - 3.0, 0.3, 0.0)  # six rows below one transform
            assert np.array_equal(e.render(scene).array, fresh(scene, False))
            assert e.stats["incremental"] == 6
            leaf = leaves[frame * 7]
            m = np.eye(4)
            m[:3, 3] = leaf.items[0].offset + np.array([0.0, 0.0, 0.5])
            leaf.remove(leaf.items[0])  # a new transform in the plan
            leaf.insert(0, om.Matrix(m))
            deeper = om.Node(f"d{frame}", [om.Translation(0.0, 0.0, 1.0), om.Material(diffuse=(1, 0, 0)), box])
            leaves[frame * 7 + 1].add(om.Node(f"w{frame}", [om.Translation(0.0, 3.5, 0.0), deeper]))
            groups[3].remove(leaves[18 + frame])  # a removed item: its transforms move nothing any more
            e.render(scene)
            assert e.stats["compiled"] == "subtrees"
            assert np.array_equal(e.render(scene).array, fresh(scene, False))
            # a group's transform (above the new Matrix), a new leaf's, a removed item's (nothing to draw)
            for moved in (groups[frame].items[0], deeper.items[0], leaves[18 + frame].items[0]):
                moved.offset = tuple(np.asarray(moved.offset) + (0.0, 0.0, 0.25))
                assert np.array_equal(e.render(scene).array, fresh(scene, False))


def test_the_casters_bounds_follow_moves_on_and_off_them_without_a_pass_over_every_caster():
    """Rows on the casters' bounds are counted: moving one of many rows that lie on a bound keeps the bounds
    without computing them again; moving the last one off a bound, or a row past it, gives the bounds computed
    from scratch (checked after every move)."""
    from omnirender.gl import GLEngine
    from omnirender.gl.engine import index as index_module

    scene = om.Node("scene", [om.Camera.look_at((0, 8, 14), (0, 0, 0), fov=50)])
    scene.add(om.DirectionalLight(direction=(-0.3, -1.0, -0.4)))
    box = om.Box(size=0.5)
    moves = []
    for i in range(48):  # a 4 x 3 x 4 grid: many rows on each side of the bounds
        t = om.Translation(float(i % 4) - 1.5, float(i // 16), float((i // 4) % 4) - 1.5)
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Material(diffuse=(0.6, 0.5, 0.4)), box]))
    computed = []
    original = index_module.RenderIndex._compute

    def counting(self, keep):
        computed.append(keep)
        return original(self, keep)

    def check() -> None:
        *_, casters = derived_from_scratch(e)
        got = e.index.caster_bounds()[0]
        assert np.array_equal(got[0], casters[0]) and np.array_equal(got[1], casters[1])

    corner = moves[0]  # one of the 12 rows on the lower x bound
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        index_module.RenderIndex._compute = counting
        try:
            for offset in ((-1.3, 0.0, -1.5), (-3.0, 0.0, -1.5)):  # off the bound (11 stay), then past it
                corner.offset = offset
                e.render(scene)
                check()
            assert not computed  # followed: the bounds kept, then grown
            corner.offset = (-1.3, 0.0, -1.5)  # the last row on the new bound left it
            e.render(scene)
            check()
            assert computed  # computed again: they shrank
            rng = np.random.default_rng(5)
            for _ in range(12):
                t = moves[int(rng.integers(len(moves)))]
                x, y, z = t.offset
                t.offset = (x + float(rng.uniform(-0.4, 0.4)), y + float(rng.uniform(-0.4, 0.4)), z)
                e.render(scene)
                check()
        finally:
            index_module.RenderIndex._compute = original
