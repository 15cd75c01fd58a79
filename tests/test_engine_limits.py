"""Every engine: sizes refused before allocating (with the limit), options checked, the scene's Background
chosen by one rule, external programs killed by a signal reported as such."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender.options import SizeLimits, check_image_size, check_integer, check_real, check_timeout

ENGINES = ["gl", "povray", "mitsuba", "radiance"]
LIMITS = {"gl": "268,435,456", "povray": "67,108,864", "mitsuba": "16384", "radiance": "33,554,432"}


def _scene() -> om.Node:
    return om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.PointLight(position=(2, 2, 5)), om.Sphere()])


@pytest.mark.parametrize("engine", ENGINES)
def test_a_size_the_engine_cannot_render_is_refused_with_its_limit(engine):
    with pytest.raises(ValueError, match=LIMITS[engine]):
        om.render(_scene(), engine=engine, size=(100_000, 100_000))


@pytest.mark.parametrize("size", [(math.nan, 5), (0, 5), (5.5, 5), (True, 5), ("8", "6"), (8, 6, 1), None])
def test_sizes_are_whole_positive_pixel_counts(size):
    with pytest.raises(ValueError, match="size must be"):
        om.render(_scene(), engine="gl", size=size)


def test_the_option_checks():
    assert check_timeout("X", None) is None and check_timeout("X", 2) == 2.0
    for bad in (math.nan, math.inf, -1, 0, "1", True):
        with pytest.raises(ValueError, match="X: timeout must be"):
            check_timeout("X", bad)
    assert check_integer("X", "n", 3.0, 1, 5) == 3
    for bad in (math.nan, 2**64, "3", 3.5, False):
        with pytest.raises(ValueError, match="X: n must be a whole number in 1..5"):
            check_integer("X", "n", bad, 1, 5)
    with pytest.raises(ValueError, match=r"X: a must be a finite number in \[0, 1\]"):
        check_real("X", "a", math.nan, 0.0, 1.0)
    limits = SizeLimits(100, 5000, "a test")
    assert check_image_size("X", (100, 50), limits) == (100, 50)
    with pytest.raises(ValueError, match="at most 100 pixels per side and 5,000 pixels in all \\(a test\\)"):
        check_image_size("X", (80, 80), limits)


@pytest.mark.povray
@pytest.mark.parametrize("timeout", [math.nan, "1", -1, math.inf])
def test_povray_refuses_a_timeout_that_is_not_one(timeout):
    with pytest.raises(ValueError, match="POV-Ray: timeout must be"):
        om.render(_scene(), engine="povray", size=(8, 6), timeout=timeout)


def _fake_program(tmp_path: Path, name: str) -> None:
    folder = tmp_path / "bin"
    folder.mkdir(exist_ok=True)
    program = folder / name
    program.write_text("#!/bin/sh\necho 'Configuration warning: cannot open povray.conf' >&2\nkill -9 $$\n")
    program.chmod(0o755)


def test_povray_killed_by_a_signal_says_so(tmp_path, monkeypatch):
    _fake_program(tmp_path, "povray")
    monkeypatch.setenv("PATH", f"{tmp_path / 'bin'}{os.pathsep}{os.environ['PATH']}")
    with pytest.raises(om.povray.POVRayError, match=r"POV-Ray was killed by signal 9 \(SIGKILL: .*out-of-memory"):
        om.render(_scene(), engine="povray", size=(8, 6))


def _two_backgrounds() -> om.Node:
    scene = _scene()
    scene.add(om.Background((1.0, 0.0, 0.0)))
    scene.add(om.Background((0.0, 0.0, 1.0)))
    return scene


@pytest.mark.parametrize("engine", ENGINES)
def test_every_engine_shows_the_later_of_two_backgrounds_in_a_node(engine, request):
    request.applymarker(getattr(pytest.mark, engine))
    options = {"spp": 4} if engine == "mitsuba" else {}
    corner = om.render(_two_backgrounds(), engine=engine, size=(16, 12), **options).array[0, 0]
    assert tuple(int(c) for c in corner[:3]) == (0, 0, 255), corner


def test_exported_files_carry_the_later_background(tmp_path):
    from omnirender.formats.gltf import writer as gltf

    _, engine = gltf.build(_two_backgrounds())
    assert engine.background.color[:3] == (0.0, 0.0, 1.0)
    text, engine = om.povray.scene_sdl(_two_backgrounds())
    assert engine.background.color[:3] == (0.0, 0.0, 1.0)


def test_the_viewer_takes_the_later_background():
    from omnirender.viewer.window import _scene_background

    assert _scene_background(_two_backgrounds()).color[:3] == (0.0, 0.0, 1.0)


@pytest.mark.gl
def test_textures_too_large_for_any_gpu_are_refused_before_copying():
    huge = np.broadcast_to(np.zeros((1, 1, 4), np.uint8), (100_000, 100_000, 4))  # no memory behind it
    with pytest.raises(ValueError, match="Texture: image is 100000x100000 pixels; textures are at most 32768"):
        om.Texture(huge)
