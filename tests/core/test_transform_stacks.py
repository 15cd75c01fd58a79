"""Transforms set from a simulation loop: fast setters that still refuse bad values, and matrix stacks."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om


def _transforms() -> dict[type, list[om.Transform]]:
    rng = np.random.default_rng(0)
    return {
        om.Translation: [om.Translation(*rng.normal(0, 5, 3)) for _ in range(5)],
        om.Rotation: [om.Rotation(float(a), tuple(rng.normal(0, 1, 3))) for a in (0.0, 30.0, -75.0, 180.0, 359.0)],
        om.Scaling: [om.Scaling(1, 2, 3), om.Scaling(-0.5), om.Scaling(1e-3, 4, 1)],
        om.Matrix: [om.Matrix(np.diag([1.0, 2.0, 3.0, 1.0]))],
    }


@pytest.mark.parametrize("cls", [om.Translation, om.Rotation, om.Scaling, om.Matrix])
def test_a_stack_of_matrices_is_each_transform_s_matrix(cls):
    ts = _transforms()[cls]
    stack = cls.stack_matrices(ts)
    assert stack.shape == (len(ts), 4, 4)
    assert np.allclose(stack, np.stack([t.matrix for t in ts]), atol=1e-14)
    assert cls.stack_matrices([]).shape == (0, 4, 4)


@pytest.mark.parametrize(
    ("make", "name", "good", "bad"),
    [
        (lambda: om.Translation(0, 0, 0), "offset", (1.0, -2.0, 3.5), [(math.nan, 0.0, 0.0), (1e16, 0.0, 0.0)]),
        (lambda: om.Rotation(10, (0, 1, 0)), "angle", 42.0, [math.nan, math.inf, 1e300]),
        (
            lambda: om.Scaling(1),
            "factors",
            (2.0, 0.5, -1.0),
            [(0.0, 1.0, 1.0), (1e-20, 1.0, 1.0), (math.inf, 1.0, 1.0)],
        ),
    ],
)
def test_fast_setters_take_good_values_and_refuse_bad_ones(make, name, good, bad):
    t = make()
    node = om.Node("n", [t])
    before = node.version
    setattr(t, name, good)
    assert getattr(t, name) == good and node.version > before  # the owner saw the change
    expected = type(t).stack_matrices([t])[0]
    assert np.allclose(t.matrix, expected)
    for value in bad:
        with pytest.raises(ValueError, match=type(t).__name__):
            setattr(t, name, value)
        assert getattr(t, name) == good  # a refused value changes nothing
