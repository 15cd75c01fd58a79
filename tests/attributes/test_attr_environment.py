"""Clip planes, fog, background, tessellation, highlight, pick ids, collidable."""

from __future__ import annotations

import math

import numpy as np
import pytest

import omnirender as om


def test_clip_plane_keeps_the_normal_side():
    c = om.ClipPlane(normal=(0, 2, 0), offset=1)
    assert c.normal == (0.0, 1.0, 0.0)
    assert c.keeps((0, 1.5, 0)) and c.keeps((0, 1, 0)) and not c.keeps((3, 0.5, 3))
    assert np.array_equal(c.keeps(np.array([[0, 2, 0], [0, 0, 0]])), [True, False])
    assert c.distance((0, 3, 0)) == pytest.approx(2.0)
    assert np.allclose(c.plane(), (0, 1, 0, -1))


def test_clip_plane_world_plane():
    c = om.ClipPlane(normal=(1, 0, 0), offset=1)  # keeps x >= 1
    m = om.Translation(2, 0, 0).matrix  # in world: keeps x >= 3
    p = c.world_plane(m)
    assert np.allclose(p, (1, 0, 0, -3))


def test_fog_factor_modes():
    lin = om.Fog(start=10, end=20)
    assert lin.factor(5) == 1.0 and lin.factor(15) == pytest.approx(0.5) and lin.factor(25) == 0.0
    e = om.Fog(mode="exp", density=0.1)
    assert e.factor(10) == pytest.approx(math.exp(-1))
    e2 = om.Fog(mode="exp2", density=0.1)
    assert e2.factor(20) == pytest.approx(math.exp(-4))
    assert np.allclose(lin.factor(np.array([10, 20])), [1, 0])


def test_background_is_rgba():
    assert om.Background((0.1, 0.2, 0.3)).color == (0.1, 0.2, 0.3, 1.0)
    assert om.Background((0, 0, 0, 0)).color == (0.0, 0.0, 0.0, 0.0)


def test_tessellation_segments():
    assert om.Tessellation(0).segments(4) == 4
    assert om.Tessellation(3).segments(4) == 32
    assert om.Tessellation(8).segments(2) == 512
    assert om.Tessellation(0).segments(1) == 3
    assert om.Tessellation().level == om.Tessellation.DEFAULT_LEVEL
    engine = om.Engine()
    assert om.Tessellation.segments_for(engine, 4) == 32
    engine.push(om.Tessellation(1))
    assert om.Tessellation.segments_for(engine, 4) == 8
    engine.pop(om.Tessellation)


def test_tags():
    assert om.Highlight().color == (1.0, 1.0, 0.0)
    assert om.PickId(3.0).id == 3
    assert om.Collidable().enabled is True
