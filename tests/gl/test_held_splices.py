"""Splices held until the next frame of moves (issue 22, one node added and one removed).

A frame that only adds and removes nodes leaves the move plan (its chain arrays, its translation map) as it
was: the updater holds the splices and the next frame that moves rows follows them all at once
(``TransformUpdater._settled``, ``merged_splices``).  Each picture is compared with a fresh engine's picture of
the same scene (``changes.fresh``): the held splices must move exactly the rows a plan that followed every
splice at once would move.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.gl.engine import dynamic
from omnirender.gl.engine.dynamic import merged_splices

from .changes import SIZE, fresh

pytestmark = pytest.mark.gl


def place(k: int, columns: int, lift: float = 0.0) -> tuple[float, float, float]:
    """Grid place ``k``: no two places' boxes overlap (coincident boxes would draw in either order)."""
    half = (columns - 1) / 2
    return (k % columns - half + lift, k // columns - half, 2.0 * lift)


def grid_scene(n: int = 36) -> tuple[om.Node, list[om.Translation], om.Box]:
    """A camera, a light and ``n`` boxes in a grid (a Translation, a Material each, one shared Box)."""
    columns = int(np.ceil(np.sqrt(n)))
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 16), (0, 0, 0), fov=50)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.6)
    moves = []
    for i in range(n):
        t = om.Translation(*place(i, columns))
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Material(diffuse=(0.3 + 0.6 * i / n, 0.5, 0.4)), box]))
    return scene, moves, box


def extra(name: str, at: tuple[float, float, float], box: om.Box) -> om.Node:
    return om.Node(name, [om.Translation(*at), om.Material(diffuse=(1.0, 0.2, 0.1)), box])


def check(e: object, scene: om.Node, what: str, compiled: object) -> np.ndarray:
    image = e.render(scene).array  # type: ignore[attr-defined]
    assert e.stats["compiled"] == compiled, what  # type: ignore[attr-defined]
    assert np.array_equal(image, fresh(scene)), what
    return image


def held(e: object) -> int:
    return len(e.updater._held)  # type: ignore[attr-defined]


def test_merged_splices_keep_what_the_splices_do_in_order():
    a, b, c, d, e = (object() for _ in range(5))
    # b added then removed: neither; c (held before) moved then removed: removed; d moved and kept: moved
    merged = merged_splices([([a], [b], [c, d]), ([b], [e], [d]), ([c], [], [])])
    assert merged == ([a, c], [e], [d])
    one = ([a], [b], [])
    assert merged_splices([one]) is one


def test_frames_adding_and_removing_nodes_hold_their_splices_until_a_few_transforms_move():
    from omnirender.gl import GLEngine

    scene, moves, box = grid_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        moves[0].offset = (-2.5, -2.5, 1.0)  # the move plan is made
        check(e, scene, "the plan made", False)
        added: list[om.Node] = []
        for frame in range(4):
            if frame % 2:
                scene.remove(added.pop(0))
            added.append(scene.add(extra(f"x{frame}", (frame - 1.5, 3.4, 0.5), box)))
            check(e, scene, f"splice {frame}", "subtrees")
        assert held(e) == 4
        # a node added and removed while held; the last row of the batch moved into a removed row's place
        scene.remove(scene.child("b7"))
        check(e, scene, "an original node removed", "subtrees")
        moves[35].offset = (2.5, 2.5, 1.5)  # the batch's last original row, moved twice over by the removals
        added[-1].items[0].offset = (0.0, -3.4, 1.0)  # an added node's transform, still held
        check(e, scene, "a few moved after held splices", False)
        assert held(e) == 0
        moves[3].offset = (0.5, -2.5, -1.0)
        check(e, scene, "moved again", False)


def test_held_splices_then_every_transform_moved_use_the_translation_map_with_the_new_rows():
    from omnirender.gl import GLEngine

    scene, moves, box = grid_scene(100)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        for frame in range(3):
            for k, t in enumerate(moves):  # all of them: the translation map writes the rows
                t.offset = place(k, 10, 0.1 * frame)
            check(e, scene, f"loop {frame}", False)
            for step in range(3):
                node = scene.add(extra(f"x{frame}_{step}", (step - 1.0, 3.4 - frame, 1.5), box))
                moves.append(node.items[0])
                if step == 1:
                    gone = scene.child(f"b{frame * 7}")
                    moves.remove(gone.items[0])
                    scene.remove(gone)
                check(e, scene, f"splice {frame}.{step}", "subtrees")
            assert held(e) == 3


def test_a_transform_replaced_after_held_splices_replaces_it_in_the_new_nodes_row():
    from omnirender.gl import GLEngine

    scene, moves, box = grid_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        moves[1].offset = (-1.5, -2.5, 1.0)
        check(e, scene, "the plan made", False)
        node = scene.add(extra("x", (0.0, 3.4, 0.5), box))
        check(e, scene, "added", "subtrees")
        scene.remove(scene.child("b2"))
        check(e, scene, "removed", "subtrees")
        assert held(e) == 2
        m = np.eye(4)
        m[:3, 3] = (1.0, -3.4, 1.5)
        node.remove(node.items[0])
        node.insert(0, om.Matrix(m))
        check(e, scene, "the added node's Translation replaced by a Matrix", "dirty")
        assert held(e) == 0
        moves[0].offset = (-2.5, -2.5, 2.0)
        check(e, scene, "moved after the replacement", False)


def test_splices_beyond_the_held_limit_are_followed_without_a_move(monkeypatch: pytest.MonkeyPatch):
    from omnirender.gl import GLEngine

    monkeypatch.setattr(dynamic, "_HELD_SPLICES", 3)
    scene, moves, box = grid_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        moves[0].offset = (-2.5, -2.5, 1.0)
        check(e, scene, "the plan made", False)
        nodes = []
        for frame in range(5):
            nodes.append(scene.add(extra(f"x{frame}", (frame - 2.0, 3.4, 0.5), box)))
            if frame == 3:
                scene.remove(nodes.pop(1))
            check(e, scene, f"splice {frame}", "subtrees")
            assert held(e) == (frame + 1) % 3
        for k, node in enumerate(nodes):
            node.items[0].offset = (k - 2.0, -3.4, 1.0)
        check(e, scene, "the added nodes moved", False)


def test_held_splices_then_a_translation_array_touched():
    from omnirender.gl import GLEngine

    positions = np.array([(i % 6 - 2.5, i // 6 - 2.5, 0.0) for i in range(36)])
    bulk = om.TranslationArray(positions)
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 16), (0, 0, 0), fov=50)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.6)
    for i in range(36):
        scene.add(om.Node(f"b{i}", [bulk[i], om.Material(diffuse=(0.3 + 0.6 * i / 36, 0.5, 0.4)), box]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        positions[:, 2] += 0.5
        bulk.touch()
        check(e, scene, "the array touched", False)
        scene.add(extra("x", (0.0, 3.4, 0.5), box))
        check(e, scene, "added", "subtrees")
        scene.remove(scene.child("b35"))  # the last row takes no other's place
        scene.remove(scene.child("b4"))
        check(e, scene, "removed", "subtrees")
        assert held(e) == 2
        positions[:, 1] += 0.3
        bulk.touch()
        check(e, scene, "the array touched after held splices", False)
