"""Viewer misuse gives messages naming the fix, not errors from inside Python or moderngl."""

from __future__ import annotations

import pytest

import omnirender as om


@pytest.mark.parametrize("color", ["red", (1, 0), None])
def test_bad_background_colours_name_the_format(color):
    # before: "red" raised float()'s "could not convert string to float: 'r'"
    viewer = om.Viewer(size=(16, 16))
    with pytest.raises(ValueError, match=r"Viewer\.background: need 3 or 4 (numbers|values) in \[0, 1\]"):
        viewer.set_background_color(color)
    with pytest.raises(ValueError, match=r"Viewer\.background"):
        om.Viewer(size=(16, 16), background=color)


def test_a_missing_light_index_says_how_many_there_are():
    viewer = om.Viewer(size=(16, 16))
    viewer.clear_lights()
    with pytest.raises(IndexError, match=r"no light 0; it has none yet"):
        viewer.get_light(0)
    light = om.PointLight(position=(1, 2, 3))
    viewer.add_light(light)
    assert viewer.get_light(0) is light and viewer.get_light(-1) is light
    with pytest.raises(IndexError, match=r"no light 3; indices 0\.\.0"):
        viewer.get_light_space(3)
