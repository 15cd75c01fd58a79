"""The cross-engine asset suite (issue 23): files the project writes itself, every engine against GL.

Each asset of ``tests/asset_suite.py`` (vertex colours with an alpha an OPAQUE
material ignores, an emissive map, a texture transform with rotation, offset
and CLAMP_TO_EDGE, a MASK cut-off, a grey metal, binary PLY face colours, an
OBJ with texture coordinates and no MTL, OBJ vertex colours, an OFF file with
mixed winding) is set up as a user would (``om.MeshFile``, a fitted camera, a
directional light, ambient 0.3, a Background) and rendered at 128x96 by every
engine.  Against GL: foreground IoU >= 0.97, mean CIEDE2000 over the shared
foreground <= 8, and at most 2 % of it differing by more than 25 (a white
blob, black speckles or a missing texture show as tens of percent).

The mask and the default background mean the same in every engine: a test per
engine, with and without a Background.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from engines import marks, require

import omnirender as om
from omnirender.attributes.environment import DEFAULT_BACKGROUND

pytest.importorskip("pygltflib")
pytest.importorskip("trimesh")
from asset_suite import ASSETS, OPTIONS, asset_scene, compare, outliers, write_assets  # noqa: E402

SIZE = (128, 96)
OFFLINE = ("povray", "mitsuba", "radiance")
IOU_LIMIT, DELTA_E_LIMIT, OUTLIER_LIMIT = 0.97, 8.0, 0.02


@functools.cache
def _files() -> dict:
    import tempfile
    from pathlib import Path

    return write_assets(Path(tempfile.mkdtemp(prefix="omnirender-assets-")))


@functools.cache
def _render(asset: str, engine: str) -> om.Image:
    return om.render(asset_scene(_files()[asset], SIZE), engine=engine, size=SIZE, **OPTIONS.get(engine, {}))


@pytest.mark.parametrize("asset", list(ASSETS))
@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n, "gl")) for n in OFFLINE])
def test_every_engine_draws_the_asset_like_gl(name, asset):
    require("gl")
    require(name)
    img, gl = _render(asset, name), _render(asset, "gl")
    iou, de = compare(img, gl)
    odd = outliers(img, gl)
    report = f"{asset} in {name}: IoU {iou:.3f}, mean dE2000 {de:.1f}, {odd:.1%} of the foreground off by > 25"
    print(report)
    assert iou >= IOU_LIMIT and de <= DELTA_E_LIMIT and odd <= OUTLIER_LIMIT, report


def _ball(background: om.Background | None) -> om.Node:
    scene = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5), fov=30), om.DirectionalLight(direction=(0, 0, -1))])
    if background is not None:
        scene.add(background)
    scene.add(om.Node("ball", [om.Material(diffuse=(0.9, 0.5, 0.2)), om.Sphere(radius=0.8)]))
    return scene


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ("gl", *OFFLINE)])
@pytest.mark.parametrize("background", ["none", "opaque", "transparent"])
def test_mask_is_coverage_and_the_default_background_is_shared(name, background):
    require(name)
    bg = {"none": None, "opaque": om.Background((0.1, 0.6, 0.2)), "transparent": om.Background((0, 0, 0, 0))}
    img = om.render(_ball(bg[background]), engine=name, size=(48, 48), **({"spp": 4} if name == "mitsuba" else {}))
    # the mask is the disc the sphere covers, whatever is behind it: 0.8 / tan(15 deg) / 5 of the half height
    expected = np.pi * (24 * 0.8 / (5 * np.tan(np.radians(15)) * np.sqrt(1 - (0.8 / 5) ** 2))) ** 2
    assert abs(img.mask.sum() - expected) < 0.05 * expected, (img.mask.sum(), expected)
    assert img.mask[24, 24] and not img.mask[2, 2]
    corner = img.array[2, 2]
    if background == "none":  # the one default: opaque dark grey in every engine
        assert corner[3] == 255 and np.allclose(corner[:3], np.round(np.asarray(DEFAULT_BACKGROUND[:3]) * 255), atol=2)
    elif background == "opaque":
        assert corner[3] == 255 and np.allclose(corner[:3], (26, 153, 51), atol=2), corner
    else:
        assert corner[3] == 0


@pytest.mark.gl
def test_rendering_a_gltf_file_uses_its_camera_and_lights(tmp_path):
    """``omnirender render x.glb`` shows the file as ``om.load_gltf`` reads it (it fitted a camera before)."""
    import math
    import subprocess
    import sys

    from gltf_files import quad_file

    from omnirender.scene.mesh_scene import mesh_scene

    require("gl")
    path = tmp_path / "lit.glb"
    material = {"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1], "metallicFactor": 0}}
    quad_file(path, light={"type": "point", "intensity": 2 * math.pi}, material=material)
    declared = mesh_scene(path).declarations()
    assert np.allclose(declared.camera[1][:3, 3], (0, 0, 3)) and len(declared.lights) == 1
    out = tmp_path / "cli.png"
    cmd = [sys.executable, "-m", "omnirender.cli", "render", str(path), "-e", "gl", "--size", "48x48", "-o", str(out)]
    subprocess.run(cmd, check=True, capture_output=True, timeout=120)
    from PIL import Image

    cli = np.asarray(Image.open(out).convert("RGBA"))
    direct = om.render(om.load_gltf(path), engine="gl", size=(48, 48)).array
    assert np.abs(cli.astype(int) - direct).max() <= 2
