"""``om.TranslationArray`` in GL (issue 22): a touch writes the array into the batch rows at once.

A touched array reaches the engine as one journal entry; its rows are written
into every batch row below one of its translations with one numpy operation
per batch (the move plan's translation map, ``gl/engine/translations.py``)
and uploaded as the changed range.  Every case below is compared pixel for
pixel with a fresh engine: translations below a rotated and scaled parent
(the linear part ``L`` and the constant ``c`` of the map), shape-local
matrices, transparent items (no batch), an item below two translations of one
array (recomposed from its chain), one translation assigned between touches,
another transform moving in the same frame, and nodes added and removed
between touches (the map follows the splices).
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def fresh(scene: om.Node) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0) as e:
        return e.render(scene).array


def start(n: int = 12) -> np.ndarray:
    i = np.arange(n)
    rows = (n + 5) // 6
    return np.stack([(i % 6 - 2.5) * 0.9, (i // 6 - rows / 2) * 0.45, 0.3 * (i % 2)], axis=1).astype(np.float64)


def scene_of(n: int = 12) -> tuple[om.Node, om.TranslationArray, np.ndarray, om.Rotation]:
    """Half the nodes below a rotated, scaled group; some shapes with a local matrix (a cone), a translucent one."""
    positions = start(n)
    moves = om.TranslationArray(positions)
    spin = om.Rotation(20.0, (0.3, 1.0, 0.2))
    group = om.Node("group", [spin, om.Scaling(0.9, 1.1, 1.0), om.Translation(0.2, -0.1, 0.0)])
    scene = om.Node("scene", [om.Camera.look_at((0, 1.0, 9.0), (0, 0, 0), fov=50)])
    scene.add(om.DirectionalLight(direction=(-0.3, -0.5, -1.0)))
    for i in range(n):
        shape = om.Cone(radius=0.18, height=0.35) if i % 3 == 0 else om.Box(size=0.3)
        color = om.Material(diffuse=(0.3 + 0.05 * (i % 12), 0.5, 0.9 - 0.05 * (i % 12)), opacity=0.6 if i == 5 else 1.0)
        node = om.Node(f"n{i}", [moves[i], color, shape])
        (group if i % 2 else scene).add(node)
    scene.add(group)
    return scene, moves, positions, spin


def test_a_touched_array_is_written_at_once_and_matches_a_fresh_engine():
    from omnirender.gl import GLEngine

    scene, moves, positions, _ = scene_of()
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        for step in range(3):
            positions[:, 1] += 0.15
            positions[step, 0] -= 0.4
            moves.touch()
            image = e.render(scene).array
            assert e.stats["compiled"] is False and e.stats["incremental"] == len(moves)
            assert (image != image[0, 0]).any(axis=2).mean() > 0.01  # the shapes are in view
            assert np.array_equal(image, fresh(scene))
        assert [t.offset for t in moves] == [tuple(row) for row in positions.tolist()]


def test_writes_after_touch_wait_for_the_next_touch():
    from omnirender.gl import GLEngine

    scene, moves, positions, _ = scene_of()
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        positions[:, 0] += 0.3
        moves.touch()
        positions[:, 0] += 5.0  # not touched: the translations keep the offsets of the last touch
        image = e.render(scene).array
        positions[:, 0] -= 5.0
        assert np.array_equal(image, fresh(scene))
        assert np.allclose(moves.offsets, positions)


def test_single_assignments_and_other_transforms_in_the_same_frame_follow():
    from omnirender.gl import GLEngine

    scene, moves, positions, spin = scene_of()
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        positions[:, 2] -= 0.2
        moves.touch()
        moves[3].offset = (0.0, 2.0, 0.5)  # after the touch: wins until the next touch
        spin.angle = 35.0  # the group's rotation: the map's L and c of half the items change
        image = e.render(scene).array
        assert e.stats["compiled"] is False
        assert np.array_equal(image, fresh(scene))
        positions[:, 1] -= 0.3  # the next touch moves every row again, the group's with the new rotation
        moves.touch()
        image = e.render(scene).array
        assert moves[3].offset == tuple(positions[3].tolist())
        assert np.array_equal(image, fresh(scene))


def test_nodes_added_and_removed_between_touches():
    from omnirender.gl import GLEngine

    scene, moves, positions, _ = scene_of()
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        extra = scene.add(om.Node("extra", [om.Translation(0, -2.0, 0), om.Sphere(radius=0.3)]))
        e.render(scene)
        positions[:, 1] += 0.2
        moves.touch()
        assert np.array_equal(e.render(scene).array, fresh(scene))
        scene.remove(extra)
        e.render(scene)
        positions[:, 1] -= 0.4
        moves.touch()
        assert np.array_equal(e.render(scene).array, fresh(scene))


def test_an_item_below_two_translations_of_one_array_takes_the_general_path():
    from omnirender.gl import GLEngine

    positions = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-1.0, 0.5, 0.0]])
    moves = om.TranslationArray(positions)
    inner = om.Node("inner", [moves[1], om.Box(size=0.4)])
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 6), (0, 0, 0)), om.Node("outer", [moves[0], inner])])
    scene.add(om.Node("third", [moves[2], om.Sphere(radius=0.3)]))
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        positions += (0.2, -0.3, 0.1)
        moves.touch()
        image = e.render(scene).array
        assert e.stats["compiled"] is False
        assert np.array_equal(image, fresh(scene))


def test_a_touch_moves_versions_and_names_a_bad_row_with_its_node():
    positions = start(4)
    moves = om.TranslationArray(positions)
    scene = om.Node("scene", [om.Node(f"n{i}", [moves[i], om.Box()]) for i in range(4)])
    versions = [t.version for t in moves]
    before = scene.version
    positions[1, 2] = 7.0
    moves.touch()
    assert [t.version for t in moves] == [v + 1 for v in versions]
    assert scene.version != before and moves[1].matrix[2, 3] == 7.0
    positions[2, 0] = np.nan
    with pytest.raises(ValueError, match="translation 2 .*in node /scene/n2"):
        moves.touch()
    assert moves[2].offset == tuple(start(4)[2].tolist())  # nothing applied


def test_many_translations_moved_by_setters_take_the_same_rows_write():
    """A setter loop over most of the plan's translations is written like an array (the plan's own map)."""
    from omnirender.gl import GLEngine

    n = 96
    scene, moves, positions, spin = scene_of(n)
    translations = list(moves)
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene)
        for step in range(2):
            for i, t in enumerate(translations):
                t.offset = positions[i] + (0.1 * step, -0.2, 0.05 * (i % 3))  # a numpy row each
            if step:
                spin.angle = 10.0  # another transform in the same frame: the general path
            image = e.render(scene).array
            assert e.stats["compiled"] is False and e.stats["incremental"] == n
            assert np.array_equal(image, fresh(scene))
        for t in translations[: n // 4]:  # a quarter moved: the general path
            t.offset = (t.offset[0], t.offset[1] + 0.3, t.offset[2])
        assert np.array_equal(e.render(scene).array, fresh(scene))
