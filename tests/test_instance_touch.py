"""``InstanceSet.touch(*arrays)``: which arrays a touch says were written (``written_at``), for any engine."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

import omnirender as om


def make() -> om.InstanceSet:
    return om.InstanceSet(om.Box(), np.zeros((4, 3)), colors=np.full((4, 3), 0.5))


def test_a_touch_naming_arrays_moves_only_theirs():
    s = make()
    at = {name: s.written_at(name) for name in s.ARRAYS}
    s.touch("transforms")
    assert s.written_at("transforms") == s.version > at["transforms"]
    assert s.written_at("colors") == at["colors"], "the colours were not written"
    s.touch("transforms", "colors")
    assert s.written_at("colors") == s.version
    assert s.written_at("scales") == at["scales"]


def test_a_plain_touch_or_an_assignment_writes_every_array():
    s = make()
    s.touch("transforms")
    s.touch()
    assert all(s.written_at(name) == s.version for name in s.ARRAYS)
    s.touch("transforms")
    colors_at = s.written_at("colors")
    s.colors = np.full((4, 3), 0.25)  # a parameter assigned: a change of its own
    assert s.written_at("colors") > colors_at
    s.touch("transforms")  # named touches after it keep what the assignment wrote
    assert s.written_at("colors") == s.version - 1


def test_a_version_bumped_another_way_counts_as_every_array_written():
    from omnirender.core.component import RenderingComponent

    s = make()
    s.touch("transforms")
    RenderingComponent.touch_all([s])  # bumps the version without naming arrays
    assert s.written_at("colors") == s.version
    before = s.version
    s.touch("transforms")
    assert s.written_at("colors") == before, "the bump wrote every array: the colours too"


def test_unknown_names_are_refused_naming_the_arrays():
    s = make()
    with pytest.raises(ValueError, match="'positions' is not one of its arrays; name some of transforms, colors"):
        s.touch("positions")


@pytest.mark.parametrize("clone", [copy.deepcopy, lambda s: pickle.loads(pickle.dumps(s))], ids=["copy", "pickle"])
def test_copies_count_every_array_written_at_their_version(clone):
    s = make()
    s.touch("transforms")
    c = clone(s)
    assert all(c.written_at(name) == c.version for name in c.ARRAYS)
    c.touch("transforms")
    assert c.written_at("colors") == c.version - 1
