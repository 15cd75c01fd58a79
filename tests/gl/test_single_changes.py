"""One change in a big scene costs what the change touches (issue 22, the single-change path).

A few moved transforms find their rows through the move plan's transform -> items map (no pass over every
chain); a moved transform whose nodes declare nothing keeps the scene's declarations; a splice in a root of
one segment moves the last entry into the removed one's place.  Each rule is checked against a fresh engine's
picture of the same scene, and the render index's lists against the installed root.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

from .changes import SIZE, box_grid, fresh, nested_scene

pytestmark = pytest.mark.gl


def test_a_few_moved_transforms_rewrite_their_rows_like_a_fresh_compile():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        declared = e.declared
        steps = [
            [leaves[3].items[0]],  # one leaf
            [groups[1].items[1]],  # a group's rotation: five rows below it
            [leaves[0].items[0], leaves[7].items[0], groups[2].items[0]],  # several, chains overlap
            [leaf.items[0] for leaf in leaves[:8]],  # the most the few-moved path takes
            [leaf.items[0] for leaf in leaves[:9]],  # the array path
        ]
        for frame, moved in enumerate(steps):
            for t in moved:
                if isinstance(t, om.Rotation):
                    t.angle = t.angle + 15.0
                else:
                    t.offset = tuple(np.asarray(t.offset) + (0.1, 0.2 * (frame % 2), 0.15))
            image = e.render(scene)
            assert e.stats["compiled"] is False and e.stats["incremental"] >= len(moved)
            assert np.array_equal(image.array, fresh(scene)), frame
            if len(moved) <= 8:  # nothing moved declares anything: the declarations were kept
                assert e.declared is declared


def test_a_moved_transform_above_a_light_evaluates_the_declarations_again():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    lamp = om.Translation(0.0, 3.0, 4.0)
    scene.add(om.Node("lamp", [lamp, om.PointLight(intensity=2.0)]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        lamp.offset = (-4.0, -2.0, 4.0)
        image = e.render(scene)
        assert e.stats["compiled"] is False
        assert not np.array_equal(image.array, before)
        assert np.array_equal(image.array, fresh(scene))
        leaves[2].items[0].offset = (0.0, 0.5, 1.0)  # a quiet node again: declarations kept, the lamp's place too
        image = e.render(scene)
        assert np.array_equal(image.array, fresh(scene))


def test_moves_after_splices_find_the_new_items_and_skip_the_removed():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    box = om.Box(size=0.5)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        leaves[0].items[0].offset = (0.0, -2.0, 0.5)  # the transform -> items map is made here
        e.render(scene)
        for frame in range(3):
            added = scene.add(om.Node(f"x{frame}", [om.Translation(frame - 1.0, 4.0, 0.0), om.Material(), box]))
            gone = leaves[5 + frame]
            groups[1].remove(gone)
            e.render(scene)
            assert e.stats["compiled"] == "subtrees"
            added.items[0].offset = (frame - 1.0, 4.5, 0.5)
            gone.items[0].offset = (9.0, 9.0, 9.0)  # not drawn any more: nothing to rewrite
            groups[0].items[0].offset = (-3.5, 0.2 * frame, 0.0)
            image = e.render(scene)
            assert e.stats["compiled"] is False
            assert np.array_equal(image.array, fresh(scene)), frame


def test_splices_in_a_root_of_one_segment_keep_the_entries_items_and_index_in_one_order():
    from omnirender.gl import GLEngine

    scene, nodes = box_grid(40, 8, 0.7, eye=(9, 7, 14))
    box = nodes[0].items[2]
    glass = scene.add(om.Node("glass", [om.Translation(0, 3, 1), om.Color(0.5, 0.5, 1, 0.4), om.Sphere(radius=0.5)]))
    with GLEngine(size=SIZE, samples=0, shadows=True) as e:
        e.render(scene)
        e.index.items()  # the index's list exists and must follow the splices
        for frame in range(6):
            j = (frame * 7 + 3) % len(nodes)
            if frame % 3 == 0:
                node = nodes[j]
                node.remove(node.items[1])
                node.insert(1, om.Material(diffuse=(1.0, 0.2 * frame, 0.1)))
            elif frame % 3 == 1:
                scene.remove(nodes.pop(j))
                nodes.append(
                    scene.add(om.Node(f"n{frame}", [om.Translation(frame - 3.0, 3.5, 0.0), om.Material(), box]))
                )
            else:
                scene.remove(glass)
                glass = scene.add(
                    om.Node(
                        f"glass{frame}", [om.Translation(frame - 3.0, 3, 1), om.Color(1, 0.5, 0.5, 0.4), om.Sphere()]
                    )
                )
            image = e.render(scene)
            # a Material replaced by a Material: dirty bits (dirty.py), no splice
            assert e.stats["compiled"] == ("dirty" if frame % 3 == 0 else "subtrees")
            root = e.root_scope
            (segment,) = root.parts
            assert segment.items == root.entries
            assert [s for s in segment.slots] == [it.slot for it in segment.items]
            assert e.index.items() == root.all_items()
            assert sorted(map(id, segment.others)) == sorted(id(it) for it in segment.items if it.transparent)
            for batch in segment.batches:
                assert all(it.slot == (batch, r) for r, it in enumerate(batch.items))
            assert np.array_equal(image.array, fresh(scene, True)), frame


def test_rows_removed_and_appended_keep_the_buffer_places_a_permutation():
    """``Batch.position`` stays a permutation of the buffer places through row edits and its kept inverse
    answers it, also after the drawer sorted the rows again without it."""
    from omnirender.gl.engine.drawlist import Batch, DrawItem
    from omnirender.gl.engine.layout import ROW

    rng = np.random.default_rng(7)
    n = 50
    batch = Batch(None, None)
    items = [DrawItem(None, None, np.full(ROW.stride, float(i), np.float32), False, None, ()) for i in range(n)]
    batch.items = list(items)
    batch.hold(np.stack([it.row for it in items]))
    for r, it in enumerate(items):
        it.slot = (batch, r)  # what the installer sets
    batch.position = rng.permutation(n)  # as the drawer leaves it: sorted front to back
    batch.drawn = n
    batch.uniform = False
    for step in range(200):
        if step % 3 == 2 or len(batch.rows) < 5:
            batch.append_row(DrawItem(None, None, np.full(ROW.stride, 100.0 + step, np.float32), False, None, ()))
        else:
            batch.remove_row(int(rng.integers(len(batch.rows))))
        m = len(batch.rows)
        assert sorted(batch.position.tolist()) == list(range(m))
        for place in (0, m - 1, int(rng.integers(m))):  # the inverse answers (made again when it does not)
            assert batch.position[batch._row_at(place)[0]] == place
        assert all(it.slot == (batch, r) and it.row[0] == batch.rows[r, 0] for r, it in enumerate(batch.items))
        if step == 100:
            batch.position = rng.permutation(m)  # sorted again by the drawer: the inverse is made again


def test_shading_model_values_of_plain_numbers_pack_as_the_general_check():
    from omnirender.gl.deferred.models import ShadingModelError, _value

    for kind, value in [("color", (0.2, 0.4, 1)), ("float", 3), ("float", 2.5), ("vec2", [1, -2.0])]:
        got = _value("m", "p", kind, value)
        assert got == tuple(float(v) for v in np.asarray(value, np.float64).ravel())
        assert all(type(v) is float for v in got)
    for kind, value in [("color", (0.2, 1.5, 0.0)), ("float", float("nan")), ("color", (1, 0)), ("float", True)]:
        if kind == "float" and value is True:
            assert _value("m", "p", kind, value) == (1.0,)  # the general check's answer for a bool
            continue
        with pytest.raises(ShadingModelError, match="'p'"):
            _value("m", "p", kind, value)


def grid(n: int) -> tuple[om.Node, list[om.Translation]]:
    scene = om.Node("scene", [om.Camera.look_at((9, 7, 14), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.7)
    moves = []
    for i in range(n):
        t = om.Translation(i % 10 - 4.5, (i // 10) % 10 - 4.5, i // 100 - 0.5)
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Material(diffuse=(0.2 + 0.6 * (i % 4) / 3, 0.5, 0.4)), box]))
    return scene, moves


def test_a_frame_after_rows_moved_in_place_replays_its_plan_with_the_rows_uploaded():
    """Rows moved in place (a few transforms, then many) keep the recorded frame plan: the moved rows are
    uploaded and the plan replayed; the pictures equal a fresh engine's.  A row moved into the view from the
    culled ones, default shadows and an application's stage draw the frame in full instead."""
    from omnirender.gl import GLEngine

    scene, moves = grid(200)  # big batches: sorted and culled (drawer.SORT_MIN)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        e.render(scene)
        before = e.render(scene).array
        for frame, moved in enumerate([moves[107:108], moves[120:125], moves[::2]]):  # the front layer's first
            for t in moved:
                t.offset = tuple(np.asarray(t.offset) + (0.0, 0.4, 0.3 * (frame + 1)))
            image = e.render(scene)
            assert e.stats["compiled"] is False
            assert not np.array_equal(image.array, before)
            before = image.array
            if len(moved) <= 5:  # (a range of rows of a batch with culled rows is culled again in a full frame)
                assert image.info["replayed"], frame
            assert np.array_equal(image.array, fresh(scene)), frame
    far = moves[42]
    far.offset = (60.0, 0.0, 0.0)  # out of the view when the batch is first sorted: culled
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        assert e.render(scene).info["replayed"]
        far.offset = (0.5, 0.4, 2.0)  # into the view: the batch is culled again, in a full frame
        image = e.render(scene)
        assert not image.info["replayed"]
        assert np.array_equal(image.array, fresh(scene))

    with GLEngine(size=SIZE, samples=0, shadows=True) as e:
        e.render(scene)
        e.render(scene)
        moves[3].offset = (0.0, 0.0, 3.0)
        image = e.render(scene)
        assert not image.info["replayed"]  # the shadow maps follow the moved caster
        assert np.array_equal(image.array, fresh(scene, True))

    class Marker(om.gl.FrameStage):  # an application's stage: replayable, but not said to follow rows
        name = "marker"

        def replayable(self, engine):
            return True

    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.add_stage(Marker(), after="technique")
        e.render(scene)
        assert e.render(scene).info["replayed"]
        moves[4].offset = (1.0, 1.0, 1.0)
        assert not e.render(scene).info["replayed"]


def test_a_frame_after_a_splice_of_rows_replays_its_plan_with_the_new_counts():
    """A splice that only removes and appends rows of existing batches (an attribute replaced, a plain node
    added and another removed) keeps the frame plan: the rows are uploaded, the draws take the new instance
    counts, and the pictures equal a fresh engine's.  A node of a new shape (a new batch) draws in full."""
    from omnirender.gl import GLEngine

    scene, moves = grid(200)
    nodes = scene.children
    box = nodes[0].items[2]
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        before = e.render(scene).array
        steps = [
            lambda: (nodes[130].remove(nodes[130].items[1]), nodes[130].insert(1, om.Material(diffuse=(1, 0, 0)))),
            lambda: (nodes[150].remove(nodes[150].items[0]), nodes[150].insert(0, om.Matrix(np.diag([1, 2, 1, 1.0])))),
            lambda: scene.add(om.Node("x", [om.Translation(0.2, 0.3, 2.5), om.Material(diffuse=(0, 1, 0)), box])),
            lambda: scene.remove(nodes[125]),
            lambda: (
                scene.remove(scene.child("x")),
                scene.add(om.Node("y", [om.Translation(1, 1, 2.5), om.Material(diffuse=(0.3, 0.3, 1)), box])),
            ),
        ]
        for step, edit in enumerate(steps):
            edit()
            image = e.render(scene)
            # (an attribute replaced by one of the same role: dirty bits, no splice)
            assert e.stats["compiled"] == ("dirty" if step < 2 else "subtrees") and image.info["replayed"], step
            assert e.stats["items"] == len(scene.children)
            assert not np.array_equal(image.array, before), step
            assert np.array_equal(image.array, fresh(scene)), step
            before = image.array
        scene.add(om.Node("ball", [om.Translation(-1, 1, 2.5), om.Sphere(radius=0.4)]))  # a new batch
        image = e.render(scene)
        assert not image.info["replayed"]
        assert np.array_equal(image.array, fresh(scene))
        assert e.render(scene).info["replayed"]
