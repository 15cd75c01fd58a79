"""The renderer-tree guidelines (root is a group, no filter first, ...) are checked with paths and fixes."""

from __future__ import annotations

import pytest

import omnirender as om

C = om.compositing


def test_a_well_formed_tree_breaks_no_guideline():
    tree = C.DepthGroup([C.SceneRenderer([om.Sphere()]), C.OcclusionGroup([C.SceneRenderer([om.Box()])]),
                         C.LuminanceFilter()])  # fmt: skip
    assert C.check_tree(tree) == []


def test_each_guideline_is_reported_with_the_renderer_path():
    leaf = C.SceneRenderer([om.Sphere()])
    assert [p.guideline for p in C.check_tree(leaf)] == ["root"]
    first = C.DepthGroup([C.LuminanceFilter(), leaf])
    (problem,) = C.check_tree(first)
    assert problem.guideline == "first-filter" and problem.path == "DepthGroup/[0]LuminanceFilter"
    assert "after the renderers" in str(problem)
    only = C.DepthGroup([leaf, C.DepthGroup([C.LuminanceFilter()])])
    assert {(p.guideline, p.path) for p in C.check_tree(only)} == {
        ("first-filter", "DepthGroup/[1]DepthGroup/[0]LuminanceFilter"),
        ("only-filters", "DepthGroup/[1]DepthGroup"),
    }
    assert [p.guideline for p in C.check_tree(C.DepthGroup([leaf, C.DepthGroup([])]))] == ["empty"]
    loop = C.DepthGroup([leaf])
    loop.add(loop)
    assert [p.guideline for p in C.check_tree(loop)] == ["cycle"]
    shared = C.DepthGroup([leaf, C.DepthGroup([leaf])])  # a DAG is fine
    assert C.check_tree(shared) == []
    with pytest.raises(TypeError, match="Renderer"):
        C.check_tree(om.Sphere())
