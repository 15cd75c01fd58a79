"""A USD stage renders as the same scene built in omnirender, in every engine, and like its glTF export.

The stage (``usd_stages.shapes_stage``: camera, distant light, a mesh floor,
sphere, cube, cylinder and cone with UsdPreviewSurface materials) is written
with usd-core; its omnirender equivalent follows the documented mapping.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from engines import marks, require

import omnirender as om
from omnirender.colorimetry import cielab, delta_e2000

pytest.importorskip("pxr")
from usd_stages import equivalent_shapes, shapes_stage  # noqa: E402

SIZE = (160, 120)
ENGINES = ("gl", "povray", "mitsuba", "radiance")
#: pixels inside the sphere, the cube's front, the cylinder and the floor (away from highlights and edges)
PATCHES = {"ball": (40, 85), "crate": (80, 95), "drum": (120, 100), "floor": (150, 113)}


@functools.cache
def _stage_path(tmp_root: str) -> str:
    from pathlib import Path

    return str(shapes_stage(Path(tmp_root)))


@pytest.fixture(scope="module")
def stage(tmp_path_factory) -> str:
    return _stage_path(str(tmp_path_factory.mktemp("usd")))


@functools.cache
def _rendered(path: str, name: str) -> om.Image:
    options = {"mitsuba": {"spp": 64}, "povray": {"threads": 2}}.get(name, {})
    return om.render(om.load_usd(path), engine=name, size=SIZE, **options)


def _patch(img: om.Image, xy: tuple[int, int]) -> np.ndarray:
    x, y = xy
    return img.rgb[y - 3 : y + 4, x - 3 : x + 4].reshape(-1, 3).astype(np.float64).mean(axis=0)


@pytest.mark.gl
def test_the_stage_renders_exactly_as_the_same_scene_built_in_omnirender(stage):
    require("gl")
    a = _rendered(stage, "gl")
    b = om.render(equivalent_shapes(), engine="gl", size=SIZE)
    diff = np.abs(a.rgb.astype(np.float64) - b.rgb.astype(np.float64)).mean()
    assert diff <= 2.0, f"mean |diff| {diff:.2f}/255"
    assert 0.2 < a.mask.mean() < 0.8


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks("gl", n)) for n in ENGINES if n != "gl"])
def test_every_engine_agrees_with_gl_on_the_stage(stage, name):
    require("gl")
    require(name)
    gl, other = _rendered(stage, "gl"), _rendered(stage, name)
    score = float(np.mean(gl.mask == other.mask))
    assert score >= 0.98, f"{name}: masks agree on {score:.2%}"
    for what, xy in PATCHES.items():
        de = float(delta_e2000(cielab(_patch(gl, xy)), cielab(_patch(other, xy))))
        assert de <= 8.0, f"{name}: {what} CIEDE2000 {de:.1f} from GL ({_patch(other, xy)} vs {_patch(gl, xy)})"


@pytest.mark.gl
def test_the_stage_agrees_with_the_glTF_export_of_its_omnirender_equivalent(stage, tmp_path):
    require("gl")
    om.export(equivalent_shapes(), tmp_path / "same.glb")
    gltf = om.render(om.load_gltf(tmp_path / "same.glb"), engine="gl", size=SIZE)
    usd = _rendered(stage, "gl")
    assert float(np.mean(gltf.mask == usd.mask)) >= 0.98
    for what, xy in PATCHES.items():
        de = float(delta_e2000(cielab(_patch(gltf, xy)), cielab(_patch(usd, xy))))
        assert de <= 8.0, f"{what}: CIEDE2000 {de:.1f} between the glTF and USD paths"


@pytest.mark.gl
def test_a_point_instancer_with_a_sphere_and_a_dome_light_renders_as_the_same_omnirender_scene(tmp_path):
    require("gl")
    from usd_stages import crowd_stage, equivalent_crowd

    a = om.render(om.load_usd(crowd_stage(tmp_path)), engine="gl", size=SIZE)
    b = om.render(equivalent_crowd(), engine="gl", size=SIZE)
    diff = np.abs(a.rgb.astype(np.float64) - b.rgb.astype(np.float64)).mean()
    assert diff <= 2.0, f"mean |diff| {diff:.2f}/255"
    assert 0.1 < a.mask.mean()
