"""Shared by the command-line tests: a small scene file."""

from __future__ import annotations

from pathlib import Path

import pytest

import omnirender as om


@pytest.fixture
def scene_file(tmp_path: Path) -> Path:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 1.5, 6), center=(0, 0.5, 0), fov=40))
    scene.add(om.PointLight(position=(4, 6, 6)))
    floor = scene.add(om.Node("floor"))
    floor.add(om.Material(diffuse=(0.7, 0.7, 0.7)))
    floor.add(om.Box(size=(6, 0.1, 6), center=(0, -0.05, 0)))
    body = scene.add(om.Node("body"))
    body.add(om.Translation(0, 1, 0))
    body.add(om.Material(diffuse=(0.9, 0.2, 0.2)))
    body.add(om.Sphere(radius=0.8))
    debug = scene.add(om.Node("marker", groups=["debug"]))
    debug.add(om.Material(diffuse=(0.1, 0.9, 0.1)))
    debug.add(om.Box(size=(0.6, 0.6, 0.6), center=(-1.8, 0.3, 1)))
    path = tmp_path / "scene.json"
    om.save(scene, path)
    return path
