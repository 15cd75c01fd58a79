"""Multitexturing and bump mapping (issue 10): texture layers with their own UV sets, blend modes and opacity.

The GL engine blends up to four layers in one pass; the offline engines get
them baked into one texture (``attributes.texturing.bake_layers``), so the
same surface looks the same: GL's one-pass blending is checked against the
bake, and every engine shows the road layer over the terrain at known pixels.
"""

from __future__ import annotations

import numpy as np
import pytest
from engines import require

import omnirender as om
from omnirender.attributes.texturing import bake_layers

SIZE = (64, 64)


def terrain() -> np.ndarray:
    """A green and brown 'satellite image' (16 x 16)."""
    y, x = np.mgrid[0:16, 0:16]
    img = np.zeros((16, 16, 4), np.uint8)
    img[..., 0] = 60 + 8 * (x % 4)
    img[..., 1] = 140 - 4 * (y % 5)
    img[..., 2] = 50
    img[..., 3] = 255
    return img


def roads() -> np.ndarray:
    """A road network: an opaque grey cross on a transparent image (8 x 8)."""
    img = np.zeros((8, 8, 4), np.uint8)
    img[3:5, :] = (200, 200, 200, 255)
    img[:, 3:5] = (200, 200, 200, 255)
    return img


def quad(uv1: bool = False) -> om.TriangleSet:
    uv = [[0, 0], [1, 0], [1, 1], [0, 1]]
    return om.TriangleSet([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 1, 2], [0, 2, 3]],
                          texcoords=uv, texcoords1=[[0, 0], [2, 0], [2, 2], [0, 2]] if uv1 else None)  # fmt: skip


def scene(*attrs, uv1: bool = False) -> om.Node:
    s = om.Node("s", [om.Camera.orthographic(eye=(0, 0, 5), height=2.0), om.Background((0, 0, 0))])
    s.add(om.AmbientLight(intensity=0.8))  # lit by ambient light only: the texture's colour shows evenly
    s.add(om.Node("terrain", [om.Material(diffuse=(1, 1, 1), ambient=(1, 1, 1)), *attrs, quad(uv1)]))
    return s


LAYERS = [
    om.TextureLayer(om.Texture(roads(), filter="nearest", mipmap=False, scale=(2, 2)), "over", 0.9),
    om.TextureLayer(om.Texture(np.ones((2, 2, 3)) * np.array([1.0, 0.8, 0.6])), "multiply", 0.5),
]


def _base() -> om.Texture:
    return om.Texture(terrain(), filter="nearest", mipmap=False)


@pytest.mark.gl
def test_gl_blends_the_layers_in_one_pass_as_the_bake_does():
    require("gl")
    layered = om.render(scene(_base(), om.MultiTexture(LAYERS)), engine="gl", size=SIZE)
    baked_image = bake_layers(terrain(), LAYERS, limit=64)
    baked = om.render(scene(om.Texture(baked_image, filter="nearest", mipmap=False)), engine="gl", size=SIZE)
    diff = np.abs(layered.rgb.astype(int) - baked.rgb.astype(int))
    assert np.median(diff) <= 2 and np.mean(diff) < 6, (np.median(diff), np.mean(diff))
    opaque = layered.info["passes"][0]
    assert opaque["name"] == "opaque" and opaque["draw_calls"] == 1  # every layer in one draw


@pytest.mark.gl
def test_a_layer_on_the_second_uv_set_tiles_with_its_own_coordinates():
    require("gl")
    on_uv1 = om.Texture(roads(), filter="nearest", mipmap=False, uv_set=1)
    img = om.render(scene(_base(), om.MultiTexture([on_uv1]), uv1=True), engine="gl", size=SIZE)
    grey = (np.abs(img.rgb[..., 0].astype(int) - img.rgb[..., 1]) < 12) & (img.rgb[..., 0] > 150)
    # set 1 repeats the cross twice across the quad: roads at 1/4 and 3/4 of the width, along a middle row
    row = grey[SIZE[1] // 2 + 2]
    runs = int(np.count_nonzero(row[1:] != row[:-1]))
    column = grey[:, SIZE[0] // 8]
    assert runs >= 4 and column.sum() >= 4, (runs, column.sum())


@pytest.mark.parametrize("name", [pytest.param(n, marks=getattr(pytest.mark, n)) for n in ("gl", "povray", "mitsuba")])
def test_roads_show_over_the_terrain_in_every_engine(name):
    require(name)
    layers = om.MultiTexture([om.TextureLayer(om.Texture(roads(), filter="nearest", mipmap=False), "over", 1.0)])
    img = om.render(scene(_base(), layers), engine=name, size=SIZE, **({"spp": 8} if name == "mitsuba" else {}))
    road = img.rgb[32, 10].astype(int)  # on the horizontal road (texel rows 3-4 of 8: the middle)
    field = img.rgb[10, 10].astype(int)  # a corner of the terrain
    assert abs(road[0] - road[1]) < 15 and road[0] > 120, road  # grey
    assert field[1] > field[2] + 30, field  # green terrain


def test_layers_are_validated():
    with pytest.raises(ValueError, match="at most 4 layers"):
        om.MultiTexture([_base()] * 5)
    with pytest.raises(ValueError, match="layers\\[0\\] must be an om.TextureLayer"):
        om.MultiTexture(["image.png"])
    with pytest.raises(ValueError, match="blend must be one of"):
        om.TextureLayer(_base(), "screen")
