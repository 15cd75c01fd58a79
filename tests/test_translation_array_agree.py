"""Translations bound to one array (``om.TranslationArray``) mean the same in every engine (issue 22).

A ``touch()`` after writing the array places each node where its row says:
GL, POV-Ray, Mitsuba and Radiance draw the spheres there (masks against the
analytic reference), and GL's in-place path gives the same picture a fresh
engine gives.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from engines import marks, require
from test_engines_agree import hit_sphere, pixel_rays

import omnirender as om

SIZE = (120, 90)
ENGINES = ("gl", "povray", "mitsuba", "radiance")
RADIUS = 0.4
THRESHOLD = 0.98


def camera() -> om.Camera:
    return om.Camera.look_at(eye=(0.0, 4.0, 5.0), center=(0.0, 0.0, 0.0), fov=45)


def moved() -> np.ndarray:
    i = np.arange(6)
    return np.stack([(i % 3 - 1) * 1.3, 0.3 * (i // 3), (i // 3 - 0.5) * 1.4], axis=1)


def scene() -> tuple[om.Node, om.TranslationArray, np.ndarray]:
    positions = np.zeros((6, 3))  # built at the origin, then moved through the array
    moves = om.TranslationArray(positions)
    s = om.Node("scene", [camera(), om.DirectionalLight(direction=(0.0, -1.0, -0.6))])
    for i in range(6):
        s.add(om.Node(f"ball{i}", [moves[i], om.Color(0.9, 0.5, 0.2), om.Sphere(radius=RADIUS)]))
    positions[:] = moved()
    moves.touch()
    return s, moves, positions


def analytic_mask() -> np.ndarray:
    o, d = pixel_rays(camera(), SIZE)
    o = np.ascontiguousarray(o)
    mask = np.zeros(d.shape[:-1], bool)
    for p in moved():
        mask |= hit_sphere(o, d, p, RADIUS)
    return mask


@functools.cache
def rendered(name: str) -> om.Image:
    options = {"povray": {"threads": 2}, "mitsuba": {"spp": 16}}.get(name, {})
    return om.render(scene()[0], engine=name, size=SIZE, **options)


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ENGINES])
def test_the_array_places_the_nodes_in_every_engine(name):
    require(name)
    ref = analytic_mask()
    assert 0.05 < ref.mean() < 0.5
    score = float(np.mean(rendered(name).mask == ref))
    assert score >= THRESHOLD, f"{name}: the translation array's mask agrees with the analytic one on {score:.2%}"


@pytest.mark.gl
def test_gl_moves_the_array_in_place_and_matches_a_fresh_engine():
    from omnirender.gl import GLEngine

    require("gl")
    s, moves, positions = scene()
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(s)
        for step in range(3):
            positions[:, 1] += 0.2 * (step + 1)
            positions[step, 0] -= 0.5
            moves.touch()
            image = e.render(s)
            assert e.stats["compiled"] is False and e.stats["incremental"] == len(moves)
            with GLEngine(size=SIZE, samples=0) as fresh:
                assert np.array_equal(image.array, fresh.render(s).array)
