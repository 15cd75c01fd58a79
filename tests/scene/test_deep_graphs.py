"""Graphs 100,000 levels deep: every engine evaluates them without recursion and in linear memory."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

DEPTH = 100_000
STEP = 1e-5  # each level moves by this much: the sphere at the bottom ends up at x = 1


@pytest.fixture(scope="module")
def chain():
    root = om.Node("n0", [om.Camera.look_at((0, 0, 8), (0, 0, 0))])
    node = root
    for i in range(1, DEPTH):
        node = node.add(om.Node(f"n{i}", [om.Translation(STEP, 0, 0)]))
    node.add(om.Sphere())
    return root, node


def test_flat_programs_stay_linear_in_memory(chain):
    root, leaf = chain
    root.program()
    lengths = []
    node = root
    while True:
        lengths.append(len(node.program()))
        children = node.children
        if not children:
            break
        node = children[0]
    # every node caches a flat program; without a limit on inlining they would sum to DEPTH^2 / 2 ops
    assert sum(lengths) < 100 * DEPTH


def test_trace_bounds_and_pick_reach_the_bottom(chain):
    root, leaf = chain
    program = om.trace(root)
    assert [op for op, _ in program].count("push") == DEPTH  # the camera and every translation
    assert program[len(program) // 2][0] == "eval"  # the sphere, in the middle of pushes and pops
    lo, hi = om.bounds(root)
    assert np.allclose(lo, (STEP * (DEPTH - 1) - 1, -1, -1), atol=1e-6)
    assert np.allclose(hi, (STEP * (DEPTH - 1) + 1, 1, 1), atol=1e-6)
    (hit, *_) = om.pick(root, pixel=(32, 24), size=(64, 48))
    assert hit.shape is leaf.components[1] and hit.path.endswith(f"/n{DEPTH - 2}/n{DEPTH - 1}")


@pytest.mark.gl
@pytest.mark.slow
def test_gl_renders_the_bottom_of_a_deep_chain(chain):
    root, leaf = chain
    img = om.render(root, engine="gl", size=(64, 48), background=(0, 0, 0))
    ys, xs = np.nonzero(img.mask)
    assert 0.05 < img.mask.mean() < 0.2 and xs.mean() > 32  # the unit sphere, moved right by one unit
