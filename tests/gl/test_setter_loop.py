"""A simulation's setter loop in GL (issue 22): many ``t.offset = row`` per frame, told at the next frame.

The setters note their transforms for later (``core.component.note_later``);
the frame takes them in one pass, and a frame that moves the same transforms
in the same order as the last one reuses the last frame's look-ups.  Each frame
must still render what a fresh engine renders for the same state, whichever
transforms moved and in whatever order.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def fresh(scene: om.Node) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        return e.render(scene, background=(0, 0, 0)).array


def two_groups(n: int = 70) -> tuple[om.Node, list[om.Translation], list[om.Translation], np.ndarray]:
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 30), (0, 0, 0), fov=50), om.DirectionalLight()])
    grid = np.stack(np.meshgrid(np.arange(14.0), np.arange(10.0)), -1).reshape(-1, 2)[: 2 * n]
    positions = np.zeros((2 * n, 3))
    positions[:, :2] = grid * 1.6 - (10.4, 7.2)
    moves = []
    for i in range(2 * n):
        t = om.Translation(offset=positions[i])
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Color(i / (2 * n), 0.6, 0.3), om.Sphere(radius=0.5)]))
    return scene, moves[:n], moves[n:], positions


def test_setter_loops_of_the_same_or_other_transforms_match_a_fresh_render():
    from omnirender.gl import GLEngine

    scene, a, b, positions = two_groups()
    rows = {id(t): i for i, t in enumerate(a + b)}
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, background=(0, 0, 0))
        # group a three times (the second and third reuse the look-ups), then b (as many, other objects),
        # then a in reverse order (the same objects in another order), then a again
        for frame, group in enumerate((a, a, a, b, a[::-1], a)):
            positions[:, 1] += 0.05  # every row: a group moved later jumps by all the shifts since its last move
            for t in group:
                t.offset = positions[rows[id(t)]]
            image = e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] is False and e.stats["incremental"] >= len(group)  # (all: taken as one array)
            assert [t.offset for t in group] == [tuple(positions[rows[id(t)]].tolist()) for t in group]
            assert np.array_equal(image.array, fresh(scene)), frame


def test_other_engines_see_a_setter_loop_the_gl_engine_drew():
    from omnirender.gl import GLEngine

    scene, a, b, positions = two_groups(8)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, background=(0, 0, 0))
        positions += (0.0, 0.0, -2.0)
        for t, row in zip(a + b, positions, strict=True):
            t.offset = row
        e.render(scene, background=(0, 0, 0))
    lo, hi = om.bounds(scene)
    assert np.allclose([lo[2], hi[2]], [-2.5, -1.5])
    cam = om.Camera.look_at((0, 0, 30), (0, 0, 0), fov=50)
    hits = om.pick(om.Node("p", [cam, *scene.children]), pixel=(48, 36), size=SIZE)
    assert not hits or hits[0].distance == pytest.approx(30.0 + 1.5, abs=0.6)


def test_the_kept_look_ups_follow_splices_and_transforms_the_plan_did_not_hold():
    from omnirender.gl import GLEngine

    scene, a, b, positions = two_groups()
    rows = {id(t): i for i, t in enumerate(a + b)}
    late = om.Translation(0.0, -9.0, 0.0)  # in the loop's list before its node is in the scene
    late_node = om.Node("late", [late, om.Color(1, 1, 1), om.Sphere(radius=0.5)])
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(8):
            if frame == 2:
                scene.add(late_node)  # the late translation is in the plan from now on
            elif frame == 5:
                scene.remove(scene.child("b75"))  # a node of group b leaves: a splice
            else:
                positions[:, 1] += 0.05
                for t in a:
                    t.offset = positions[rows[id(t)]]
                late.offset = (float(frame) - 3.0, -9.0, 0.0)
            image = e.render(scene, background=(0, 0, 0))
            if frame == 5:
                assert e.stats["compiled"] == "subtrees"
            assert np.array_equal(image.array, fresh(scene)), frame
