"""``om.render(engine="povray")`` checks its options before writing SDL or starting POV-Ray."""

from __future__ import annotations

import pytest

import omnirender as om


def scene() -> om.Node:
    return om.Node("scene", [om.Camera.look_at(eye=(0, 0, 5)), om.Sphere()])


@pytest.mark.parametrize("quality", ["high", 12, -1, 9.5, True])
def test_bad_quality_names_the_range(quality):
    # before: quality="high" raised int()'s "invalid literal for int() with base 10"
    with pytest.raises(ValueError, match=r"POV-Ray: quality must be a whole number 0\.\.11"):
        om.render(scene(), engine="povray", size=(8, 8), quality=quality)


@pytest.mark.parametrize("antialias", ["yes", -0.5, 4, float("nan")])
def test_bad_antialias_names_the_choices(antialias):
    # before: antialias="yes" raised float()'s "could not convert string to float"
    with pytest.raises(ValueError, match=r"POV-Ray: antialias must be True, False or a threshold in \(0, 3\]"):
        om.render(scene(), engine="povray", size=(8, 8), antialias=antialias)


@pytest.mark.parametrize("threads", [0, -1, "2", 1.5])
def test_bad_thread_counts_are_refused(threads):
    # before: threads=-1 went to POV-Ray as +WT-1 and was ignored silently
    with pytest.raises(ValueError, match=r"POV-Ray: threads must be a whole number >= 1"):
        om.render(scene(), engine="povray", size=(8, 8), threads=threads)


@pytest.mark.povray
@pytest.mark.parametrize("antialias", [0, None, 0.5])
def test_zero_and_none_still_mean_no_antialiasing(antialias):
    image = om.render(scene(), engine="povray", size=(8, 8), quality=0, antialias=antialias)
    assert image.mask[4, 4]


def _near_duplicate_segments() -> om.Node:
    # the second segment's ends differ by 1e-9: equal once written with 7 significant digits
    vertices = [(0, -1, -1), (1, -1, -1), (0, -1, -1), (0, -1 - 1e-9, -1), (0, 0, -1), (0, 1, -1)]
    return om.Node("scene", [om.Camera.look_at(eye=(0, 0, 5)), om.Node("lines", [om.LineSet(vertices)])])


def test_segments_that_round_to_one_point_are_not_written(tmp_path):
    # before: they became "cylinder { <0,-1,-1>, <0,-1,-1>, r }", a fatal "Degenerate cylinder" parse error
    import re

    sdl = om.export(_near_duplicate_segments(), tmp_path / "lines.pov").read_text()
    ends = re.findall(r"cylinder \{ (<[^>]*>), (<[^>]*>),", sdl)
    assert len(ends) == 2 and all(a != b for a, b in ends)


@pytest.mark.povray
def test_near_duplicate_segments_render():
    assert om.render(_near_duplicate_segments(), engine="povray", size=(32, 32), quality=0).mask.any()


@pytest.mark.povray
def test_keep_creates_its_folder(tmp_path):
    om.render(scene(), engine="povray", size=(8, 8), quality=0, keep=tmp_path / "debug" / "run1")
    assert (tmp_path / "debug" / "run1" / "scene.pov").is_file()


def test_camera_axes_are_perpendicular_as_written():
    # before: 9 significant digits left dot products of ~3e-10; POV-Ray warns above 1e-10 and the warning
    # cluttered every POV-Ray error message of scenes with an oblique camera
    import re

    import numpy as np

    from omnirender.povray.engine import camera_sdl

    camera = om.Camera.look_at(eye=(1, 2, 3))
    text = camera_sdl(camera, camera.view_matrix(), (64, 48))
    axes = {
        key: np.array([float(x) for x in re.search(rf"{key} <([^>]*)>", text).group(1).split(",")])
        for key in ("direction", "right", "up")
    }
    for a, b in [("direction", "right"), ("direction", "up"), ("right", "up")]:
        assert abs(axes[a] @ axes[b]) < 1e-12, (a, b)


def test_unknown_options_list_every_render_parameter():
    import inspect

    import omnirender.povray

    with pytest.raises(TypeError) as info:
        om.render(scene(), engine="povray", size=(8, 8), spp=4)
    named = str(info.value).split("takes ", 1)[1]
    params = set(inspect.signature(omnirender.povray.render).parameters) - {"scene", "engine_options"}
    assert all(p in named for p in params), (params, named)
