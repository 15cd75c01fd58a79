"""Every shader variant compiles and draws: combinations of features on each primitive kind."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

DATA_TEXTURE = np.array([[[255, 0, 0], [0, 255, 0]], [[0, 0, 255], [255, 255, 255]]], np.uint8)


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(48, 36))
    yield e
    e.release()


def shapes() -> list:
    v = np.array([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], np.float32)
    return [
        om.TriangleSet(v, [(0, 1, 2)], colors=[(1, 0, 0), (0, 1, 0), (0, 0, 1)], texcoords=[(0, 0), (1, 0), (0.5, 1)]),
        om.Sphere(radius=0.8),
        om.LineSet(v, [(0, 1), (1, 2)], colors=[(1, 1, 0)] * 3),
        om.PointSet(v, sizes=[3, 5, 7]),
    ]


@pytest.mark.parametrize(
    "clip, fog, flat, texture, pbr, highlight, ortho",
    [c for c in itertools.product([False, True], repeat=7) if sum(c) <= 3][::5],
)
def test_feature_combinations_render(engine, clip, fog, flat, texture, pbr, highlight, ortho):
    s = om.Node("scene")
    if ortho:
        s.add(om.Camera.orthographic(eye=(0, 0, 5), height=3))
    else:
        s.add(om.Camera.look_at(eye=(0, 0, 5)))
    s.add(om.SpotLight(position=(0, 0, 3), direction=(0, 0, -1), cutoff=40))
    s.add(om.DirectionalLight(direction=(0, -1, -1)))
    if clip:
        s.add(om.ClipPlane(normal=(0, 1, 0), offset=-0.5))
    if fog:
        s.add(om.Fog(start=1, end=8, mode="exp", density=0.1))
    if flat:
        s.add(om.DrawStyle(shading="flat"))
    if texture:
        s.add(om.Texture(DATA_TEXTURE, filter="nearest"))
    s.add(om.PBRMaterial(metallic=0.5) if pbr else om.Material(specular=(1, 1, 1)))
    if highlight:
        s.add(om.Highlight())
    for shape in shapes():
        s.add(shape)
    img = engine.render(s)
    assert img.mask.any()
