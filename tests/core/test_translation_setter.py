"""``Translation.offset`` as a property with the generic attribute store (issue 22, sim3).

The setter is one Python function (no ``__setattr__`` in front of it): these
tests pin what that must not change: one version bump per assignment, the
node and the journals told once, the value copied out of the caller's array,
a kept matrix that follows every new value, pickles and copies of the value,
and subclasses whose own public parameters still touch.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

import omnirender as om
from omnirender.core.component import ChangeJournal


def test_each_assignment_bumps_the_version_by_one_and_the_node_and_journal_hear_once():
    t = om.Translation()
    node = om.Node("n", [t])
    scene = om.Node("scene", [node])
    journal = ChangeJournal()
    before, node_before, root_before = t.version, node.version, scene.version
    values = [np.array([1.0, 2.0, 3.0]), (4.0, 5.0, 6.0), [7, 8, 9], np.array([1, 2, 3]), (np.float32(1.5), 2.0, 3.0)]
    for k, value in enumerate(values, start=1):
        t.offset = value
        assert t.version == before + k
    assert t.offset == (1.5, 2.0, 3.0)
    assert node.version > node_before and scene.version > root_before
    assert journal.drain() == [t]
    assert journal.drain() == []


def test_the_value_is_copied_out_of_the_callers_array_and_read_back_as_a_tuple_of_floats():
    positions = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    t = om.Translation()
    t.offset = positions[0]
    positions[0] = (-1.0, -1.0, -1.0)  # the application writes its array in place afterwards
    assert t.offset == (1.0, 2.0, 3.0)
    assert type(t.offset) is tuple and all(type(c) is float for c in t.offset)
    assert t.parameters() == {"offset": [1.0, 2.0, 3.0]}
    assert np.array_equal(t.matrix[:3, 3], [1.0, 2.0, 3.0])


def test_the_kept_matrix_follows_every_new_value_also_an_equal_one():
    t = om.Translation(0.0, 0.0, 0.0)
    rows = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    for row in rows:
        t.offset = row
        m = t.matrix
        assert np.array_equal(m[:3, 3], row) and not m.flags.writeable
        assert np.array_equal(m[:3, :3], np.eye(3))
    same = (3.0, 4.0, 5.0)
    t.offset = same
    assert np.array_equal(t.matrix[:3, 3], same)
    t.offset = same  # the same tuple object again: the matrix made from it holds, and is right
    assert np.array_equal(t.matrix[:3, 3], same)
    t.offset = (3.0, 4.0, 6.0)
    assert np.array_equal(t.matrix[:3, 3], (3.0, 4.0, 6.0))


def test_a_refused_value_leaves_version_value_and_matrix_alone():
    t = om.Translation(1.0, 2.0, 3.0)
    node = om.Node("body", [t])
    om.Node("scene", [node])
    journal = ChangeJournal()
    t.matrix  # noqa: B018 - made and kept
    before = t.version
    for bad in (np.array([0.0, np.nan, 0.0]), np.array([1.0, 2.0]), (1.0, 2.0), "xyz", (1e300, 0.0, 0.0)):
        with pytest.raises(ValueError, match=r"Translation \(in node /scene/body\): offset"):
            t.offset = bad
    assert t.version == before and t.offset == (1.0, 2.0, 3.0)
    assert np.array_equal(t.matrix[:3, 3], (1.0, 2.0, 3.0))
    assert journal.drain() == []


def test_pickles_and_copies_carry_an_offset_set_from_a_numpy_row():
    t = om.Translation()
    t.offset = np.array([1.0, 2.0, 3.0])
    node = om.Node("n", [t])
    for other in (pickle.loads(pickle.dumps(node)).items[0], copy.deepcopy(node).items[0], copy.copy(t)):
        assert other.offset == (1.0, 2.0, 3.0) and type(other.offset) is tuple
        assert np.array_equal(other.matrix[:3, 3], (1.0, 2.0, 3.0))
        other.offset = np.array([7.0, 8.0, 9.0])
        assert t.offset == (1.0, 2.0, 3.0)  # nothing shared with the original


def test_other_attributes_store_as_before_and_unknown_names_are_refused():
    t = om.Translation()
    with pytest.raises(AttributeError):
        t.offsett = (1.0, 2.0, 3.0)  # a misspelt parameter is not silently kept
    with pytest.raises(AttributeError):
        t.version = 3  # type: ignore[misc]


def test_a_subclass_with_its_own_parameter_touches_for_it_and_once_for_offset():
    class Labelled(om.Translation):
        __slots__ = ("label",)

    t = Labelled(1.0, 0.0, 0.0)
    node = om.Node("n", [t])
    journal = ChangeJournal()
    before = t.version
    t.label = "marker"
    assert t.version == before + 1
    t.offset = np.array([2.0, 0.0, 0.0])
    assert t.version == before + 2 and t.offset == (2.0, 0.0, 0.0)
    assert journal.drain() == [t] and node.version > 0
