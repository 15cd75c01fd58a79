"""``om.trace`` and ``om.statistics`` name what they take when given something else."""

from __future__ import annotations

import pytest

import omnirender as om


@pytest.mark.parametrize("bad", [5, None, "scene"])
def test_trace_and_statistics_refuse_non_scenes(bad):
    # before: AttributeError "'int' object has no attribute 'inspect'" / "'int' object is not iterable"
    with pytest.raises(TypeError, match=r"trace: scene must be an om\.Node or a list of components"):
        om.trace(bad)
    with pytest.raises(TypeError, match=r"statistics: scene must be an om\.Node.*om\.Node\('scene'"):
        om.statistics(bad)


def test_trace_still_takes_nodes_and_component_lists():
    shape = om.Sphere()
    assert [op for op, _ in om.trace(om.Node("n", [shape]))] == ["eval"]
    assert [op for op, _ in om.trace([om.Color(1, 0, 0), shape])] == ["push", "eval", "pop"]
    assert om.statistics(om.Node("n", [shape]))["shapes"] == 1
