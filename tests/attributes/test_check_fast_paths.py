"""The checks' fast paths (a new Material's colours, a new Matrix's invertibility) decide as the general ones."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.attributes._params import _numbers, check_color
from omnirender.core.transform import _invertible


def general_color(value):
    arr = _numbers("Material", "diffuse", value)
    if arr.size not in (3, 4) or np.any(arr < 0.0) or np.any(arr > 1.0):
        return None
    return tuple(float(c) for c in arr)


@pytest.mark.parametrize(
    "value",
    [
        (1, 0, 0),
        [0.25, 0.5, 1.0, 0.5],
        (np.float64(0.3), 0.2, 1),
        np.array([0.1, 0.2, 0.3]),
        np.array([0.1, 0.2, 0.3], np.float32),
        (np.float32(0.5), 0.5, 0.5),
        (True, 0.0, 0.0),
        [[0.1, 0.2, 0.3]],
        (0.0, 1.0, 1.0000001),
        (-0.0, 0.5, 0.5),
    ],
)
def test_a_colour_is_taken_as_the_general_check_takes_it(value):
    want = general_color(value)
    if want is None:
        with pytest.raises(ValueError, match="Material: diffuse"):
            check_color("Material", "diffuse", value)
    else:
        got = check_color("Material", "diffuse", value)
        assert got == want and all(type(c) is float for c in got)


@pytest.mark.parametrize("value", [(float("nan"), 0, 0), (0, float("inf"), 0), (0.5, 0.5), "red"])
def test_colours_the_fast_path_declines_get_the_general_message(value):
    with pytest.raises(ValueError, match="Material: diffuse"):
        om.Material(diffuse=value)


def test_invertibility_agrees_with_the_matrix_rank():
    rng = np.random.default_rng(3)
    cases = [np.eye(3), np.zeros((3, 3)), np.diag([1.0, 1.0, 0.0]), np.diag([1e-12, 1.0, 1.0])]
    cases += [np.diag([1e-16, 1.0, 1.0]), np.diag([1e-15, 1e3, 1e3]), np.diag([1e8, 1e8, 1e-8])]
    for _ in range(200):
        u, _, vt = np.linalg.svd(rng.normal(size=(3, 3)))
        s = 10.0 ** rng.uniform(-17, 3, 3)
        cases.append(u @ np.diag(s) @ vt)
    for m in cases:
        assert _invertible(m) == (np.linalg.matrix_rank(m) == 3), m
    with pytest.raises(ValueError, match="singular"):
        om.Matrix(np.diag([1.0, 1e-17, 1.0, 1.0]))


@pytest.mark.parametrize(
    "entry, message", [(float("nan"), "finite"), (float("inf"), "finite"), (-float("inf"), "finite"), (2e15, "at most")]
)
@pytest.mark.parametrize("place", [(0, 0), (1, 3), (2, 1)])
def test_a_matrix_entry_the_fast_check_declines_gets_the_general_message(entry, message, place):
    m = np.eye(4)
    m[place] = entry
    with pytest.raises(ValueError, match=f"Matrix: matrix must be {message}"):
        om.Matrix(m)


def test_matrix_entries_at_the_limit_and_sums_beyond_it_are_decided_as_each_entry():
    at_limit = np.diag([1e15, -1e15, 1e15, 1.0])
    at_limit[:3, 3] = (-1e15, 1e15, 0.5)
    assert np.array_equal(om.Matrix(at_limit).matrix, at_limit)  # the sum of the entries is no entry
    huge = np.full((4, 4), 1e300)  # the sum overflows: the general checks name the magnitude
    huge[3] = (0.0, 0.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="Matrix: matrix must be at most"):
        om.Matrix(huge)


def test_a_constructor_value_given_again_is_stored_as_its_first_check_gave_it():
    """The same immutable object again (a default, a constant) is not checked again, and gives the same value;
    a list given again is checked again (it may have changed), a bad value is refused every time."""
    shared = (0.25, 0.5, 1)
    first = om.Material(diffuse=shared, shininess=12)
    again = om.Material(diffuse=shared, shininess=12)
    assert again.diffuse == first.diffuse == (0.25, 0.5, 1.0) and all(type(c) is float for c in again.diffuse)
    assert again.shininess == first.shininess == 12.0 and om.Material().ambient == (0.2, 0.2, 0.2)
    colour = [0.1, 0.2, 0.3]
    assert om.Material(diffuse=colour).diffuse == (0.1, 0.2, 0.3)
    colour[0] = 2.0
    with pytest.raises(ValueError, match=r"Material: diffuse values must be in \[0, 1\]"):
        om.Material(diffuse=colour)
    bad = (0.5, float("nan"), 0.5)
    for _ in range(2):
        with pytest.raises(ValueError, match="Material: diffuse"):
            om.Material(diffuse=bad)
