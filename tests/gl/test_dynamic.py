"""Moving objects every frame: the in-place path gives exactly what a fresh engine renders for the same state."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def fresh(scene: om.Node) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0) as e:
        return e.render(scene, background=(0, 0, 0)).array


def moving_scene(n: int = 40) -> tuple[om.Node, list[om.Translation]]:
    scene = om.Node("scene", [om.Camera.look_at((0, 6, 12), (0, 0, 0), fov=40)])
    scene.add(om.PointLight(position=(3, 8, 4)))
    scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.8)), om.Box(size=(12, 0.1, 12), center=(0, -1, 0))]))
    moves = []
    group = scene.add(om.Node("group", [om.Translation(0.0, 0.0, 0.0)]))
    for i in range(n):
        t = om.Translation(float(i % 8 - 3.5), 0.5, float(i // 8 - 2))
        moves.append(t)
        group.add(om.Node(f"b{i}", [t, om.Color(i / n, 0.5, 1 - i / n), om.Sphere(radius=0.3)]))
    return scene, moves


def test_moved_transforms_take_the_in_place_path_and_match_a_fresh_render():
    from omnirender.gl import GLEngine

    scene, moves = moving_scene()
    rng = np.random.default_rng(1)
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(4):
            for t in moves[frame::3]:  # some move, the others stay
                x, y, z = t.offset
                t.offset = (x + float(rng.normal(0, 0.2)), y, z + float(rng.normal(0, 0.2)))
            image = e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] is False and e.stats["incremental"] == len(moves[frame::3])
            assert np.array_equal(image.array, fresh(scene))  # shadows and all, byte for byte


def test_a_moved_ancestor_moves_every_item_below_it_and_the_lights_with_it():
    from omnirender.gl import GLEngine

    scene, moves = moving_scene(16)
    group = scene["/scene/group"]
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene, background=(0, 0, 0))
        group.components[0].offset = (1.0, 0.0, -0.5)
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["incremental"] == 16
        assert np.array_equal(image.array, fresh(scene))
        lamp = om.Node("lamp", [om.Translation(0.0, 0.0, 0.0), om.PointLight(position=(0, 3, 3))])
        scene.add(lamp)
        e.render(scene, background=(0, 0, 0))
        lamp.components[0].offset = (-4.0, 0.0, 0.0)  # a light below a moved transform
        image = e.render(scene, background=(0, 0, 0))
        assert np.array_equal(image.array, fresh(scene))


def test_other_changes_still_compile():
    from omnirender.gl import GLEngine

    scene, moves = moving_scene(8)
    color = scene["/scene/group/b3"].components[1]
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene, background=(0, 0, 0))
        moves[0].offset = (0.0, 1.0, 0.0)
        color.r = 1.0  # a colour changed too: not only transforms
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] is True
        assert np.array_equal(image.array, fresh(scene))
        scene["/scene/group/b5"].add(om.Scaling(2.0))  # a list changed: that node is compiled again, alone
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] == "subtrees" and np.array_equal(image.array, fresh(scene))


def test_changes_to_another_scene_do_not_disturb_this_one():
    from omnirender.gl import GLEngine

    scene, moves = moving_scene(8)
    other, other_moves = moving_scene(8)
    with GLEngine(size=SIZE, samples=0) as e:
        first = e.render(scene, background=(0, 0, 0)).array
        other_moves[0].offset = (9.0, 9.0, 9.0)
        again = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] is False and np.array_equal(again.array, first)


def _filtered_batches(engine) -> set[int]:
    return {id(b) for s in engine.scopes for group in s.filtered.values() for bs in group.values() for b in bs}


def test_shadow_casters_selected_once_follow_moves_and_replaced_items():
    """The shadow passes' selection of casters is planned once; moved or replaced rows flow into it (Batch.follow)."""
    from omnirender.gl import GLEngine

    scene, moves = moving_scene(24)
    scene["/scene/floor"].insert(0, om.Shadowing(cast=False))  # not every item casts: the passes select
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene, background=(0, 0, 0))
        planned = _filtered_batches(e)
        assert planned  # the shadow-map passes draw a selection (the items that cast shadows)
        moves[3].offset = (0.5, 1.5, 0.5)
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] is False and np.array_equal(image.array, fresh(scene))
        node = scene["/scene/group/b7"]
        node.remove(moves[7])
        moves[7] = node.insert(0, om.Translation(-2.0, 1.0, 1.0))  # replaced, not moved: compiled in place
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["incremental"] and np.array_equal(image.array, fresh(scene))
        assert _filtered_batches(e) == planned


def test_when_every_item_casts_the_shadow_passes_draw_the_scenes_own_batches():
    """No selection is planned when every opaque item casts shadows: the maps draw the batches the frame draws,
    and rows that a full map redraw uploads first are still culled again for the frame's view."""
    from omnirender.gl import GLEngine

    scene, moves = moving_scene(80)  # big enough for the batch to be culled to the view (drawer.SORT_MIN)
    far = moves[5]
    far.offset = (40.0, 0.5, 0.0)  # out of the frame's view, still a caster
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene, background=(0, 0, 0))
        assert not _filtered_batches(e)
        far.offset = (0.5, 0.8, 1.0)  # into the view; the casters' bounds shrink: the maps are redrawn in full
        image = e.render(scene, background=(0, 0, 0))
        maps = e.stats["shadow_maps"]
        assert e.stats["compiled"] is False and maps["full"] >= 1 and not maps["partial"]
        assert np.array_equal(image.array, fresh(scene))
        for frame in range(3):  # moves of some, partial map updates
            for t in moves[frame::7]:
                x, y, z = t.offset
                t.offset = (x + 0.1, y, z - 0.1)
            image = e.render(scene, background=(0, 0, 0))
            assert np.array_equal(image.array, fresh(scene))
        assert not _filtered_batches(e)


def test_a_culled_node_moved_into_the_view_is_drawn():
    """A big batch is culled to the frame's view; one row moved from outside it into it is culled again (the row
    alone changed: a sparse upload would have left it among the culled rows)."""
    from omnirender.gl import GLEngine

    scene, moves = moving_scene(80)
    moves[5].offset = (40.0, 0.5, 0.0)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e, GLEngine(size=SIZE, samples=0, shadows=False) as f:
        e.render(scene, background=(0, 0, 0))
        moves[5].offset = (0.5, 0.8, 1.0)
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] is False
        assert np.array_equal(image.array, f.render(scene, background=(0, 0, 0)).array)
