"""Rendering with the povray program: exact camera, transforms, colours, errors, clean-up."""

from __future__ import annotations

import os
import sys
import tempfile
import time

import numpy as np
import pytest

import omnirender as om
from omnirender.povray import POVRayError

sys.path.insert(0, os.path.dirname(__file__))
from raycast import box_mask, pixel_rays, sphere_mask  # noqa: E402

pytestmark = pytest.mark.povray
SIZE = (160, 100)


def _render(scene, size=SIZE, **kw):
    kw.setdefault("threads", 1)
    return om.render(scene, engine="povray", size=size, **kw)


@pytest.mark.parametrize(
    "camera",
    [
        om.Camera.look_at(eye=(3, 2, 7), center=(0.3, 0.2, 0), fov=40),
        om.Camera.orthographic(eye=(3, 2, 7), center=(0.3, 0.2, 0), height=4),
    ],
    ids=["perspective", "orthographic"],
)
def test_mask_matches_the_gl_camera_exactly(camera):
    s = om.Node("s")
    s.add(camera)
    s.add(om.Sphere(center=(1, 0.5, 0), radius=0.8))
    moved = s.add(om.Node("moved"))
    moved.add(om.Translation(-1, -0.5, 0.5))
    moved.add(om.Scaling(0.5, 0.25, 1))
    moved.add(om.Box(size=(2, 2, 2)))
    img = _render(s)
    o, d = pixel_rays(camera, SIZE)
    ref = sphere_mask(o, d, (1, 0.5, 0), 0.8) | box_mask(o, d, (-1.5, -0.75, -0.5), (-0.5, -0.25, 1.5))
    assert ref.sum() > 1000
    assert (img.mask != ref).sum() <= 4  # only pixels whose centre is within rounding of an edge


def test_colours_lights_and_background():
    s = om.Node("s")
    s.add(om.Camera.look_at(eye=(0, 0, 5), fov=40))
    s.add(om.PointLight(position=(0, 0, 10)))
    s.add(om.Background((0.0, 0.0, 1.0, 1.0)))
    s.add(om.Material(diffuse=(1, 0, 0), ambient=(0, 0, 0)))
    s.add(om.Sphere(radius=1))
    img = _render(s)
    r, g, b, a = img.pixel(80, 50)
    assert r > 240 and g < 10 and b < 10 and a == 255  # lit head-on: the material colour
    assert img.pixel(2, 2) == (0, 0, 255, 255)  # opaque blue background


def test_transparent_background_and_mask():
    s = om.Node("s")
    s.add(om.Camera.look_at(eye=(0, 0, 5), fov=40))
    s.add(om.Background((0, 0, 0, 0)))
    s.add(om.Sphere(radius=1))
    img = _render(s)
    assert img.pixel(0, 0)[3] == 0 and img.mask[50, 80] and not img.mask[0, 0]
    assert img.depth is None and img.engine == "povray"


def test_vertex_colours_and_texture_orientation():
    s = om.Node("s")
    s.add(om.Camera.orthographic(eye=(0, 0, 5), height=2))
    s.add(om.AmbientLight(intensity=0.8))  # + GL's global ambient 0.2
    s.add(om.Material(ambient=(1, 1, 1), diffuse=(1, 1, 1)))
    quad = s.add(om.Node("quad"))
    quad.add(om.Translation(-1, 0, 0))
    quad.add(
        om.TriangleSet(
            vertices=[[-1, -1, 0], [0, -1, 0], [0, 1, 0], [-1, 1, 0]],
            indices=[[0, 1, 2], [0, 2, 3]],
            colors=[[1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0]],
        )
    )
    tex = np.zeros((2, 2, 3), np.uint8)
    tex[0, :] = (0, 0, 255)  # top row blue
    tex[1, :] = (255, 255, 0)  # bottom row yellow
    textured = s.add(om.Node("textured"))
    textured.add(om.Texture(tex, filter="nearest"))
    textured.add(
        om.TriangleSet(
            vertices=[[0, -1, 0], [1, -1, 0], [1, 1, 0], [0, 1, 0]],
            indices=[[0, 1, 2], [0, 2, 3]],
            texcoords=[[0, 0], [1, 0], [1, 1], [0, 1]],
        )
    )
    img = _render(s, size=(100, 50))
    bottom_left, top_left = img.pixel(12, 45), img.pixel(12, 4)
    assert bottom_left[0] > 200 and bottom_left[1] < 100  # red at the bottom (colours interpolate)
    assert top_left[1] > 200 and top_left[0] < 100  # green at the top
    bottom_right, top_right = img.pixel(62, 45), img.pixel(62, 4)
    assert bottom_right[0] > 200 and bottom_right[1] > 200 and bottom_right[2] < 50  # texcoord v=0: bottom row
    assert top_right[2] > 200 and top_right[0] < 50


def test_parse_errors_carry_povrays_lines_and_the_node(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # a private temp folder: other runs cannot interfere
    s = om.Node("s")
    s.add(om.Camera.look_at(eye=(0, 0, 5)))
    s.add(om.Node("fine", [om.Sphere(radius=0.1)]))
    s.add(om.Node("broken", [om.povray.Raw("sphere { <0,0,0>, 1 texture { finsh { } } }")]))
    s.add(om.Node("later", [om.Box()]))
    with pytest.raises(POVRayError, match=r"(?s)File 'scene.pov' line \d+: Parse Error.*finsh") as info:
        _render(s, size=(8, 8))
    assert "POV-Ray failed" in str(info.value)
    assert "was written for node /s/broken" in str(info.value)
    assert list(tmp_path.iterdir()) == []  # the temporary folder is gone after the failure


def test_an_exception_in_the_progress_callback_stops_povray_and_reaches_the_caller(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    s = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.Sphere()])
    calls = []

    def progress(done, total):
        calls.append(done)
        raise ValueError("progress display broke")

    t0 = time.perf_counter()
    with pytest.raises(ValueError, match="progress display broke"):
        _render(s, size=(400, 400), progress=progress, antialias=True, quality=11)
    assert len(calls) == 1  # not called again after failing
    assert time.perf_counter() - t0 < 30
    assert list(tmp_path.iterdir()) == []


def test_keep_writes_the_scene_and_its_textures(tmp_path):
    tex = np.zeros((4, 4, 3), np.uint8)
    s = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.Texture(tex), om.Rectangle(size=(2, 2))])
    _render(s, size=(16, 16), keep=tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["om_tex0.png", "scene.pov"]
    assert '"om_tex0.png"' in (tmp_path / "scene.pov").read_text()


def test_temporary_files_are_removed_and_progress_is_reported(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # a private temp folder: other runs cannot interfere
    seen = []
    s = om.Node("s")
    s.add(om.Camera.look_at(eye=(0, 0, 5)))
    s.add(om.Fog(mode="exp", density=0.1))  # two passes, more files
    s.add(om.Sphere())
    img = _render(s, size=(64, 64), progress=lambda done, total: seen.append((done, total)), depth=True)
    assert list(tmp_path.iterdir()) == []
    assert seen and seen[-1] == (64 * 64, 64 * 64)
    assert img.mask[32, 32] and not img.mask[0, 0]  # fog does not make the background opaque


def test_timeout_stops_povray(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    s = om.Node("s")
    s.add(om.Camera.look_at(eye=(0, 0, 5)))
    s.add(om.povray.GlobalSettings(radiosity={"count": 1600, "recursion_limit": 3}))
    s.add(om.PointLight(position=(3, 3, 3)))
    s.add(om.Sphere())
    with pytest.raises(POVRayError, match="timeout"):
        _render(s, size=(400, 400), timeout=0.3, antialias=True)
    assert list(tmp_path.iterdir()) == []  # the temporary folder is gone after the timeout


def test_every_conversion_parses_and_renders():
    """All lights, fog, background, clip plane, PBR/Phong/transparent materials and POV-Ray attributes at once."""
    s = om.Node("s")
    s.add(om.Camera.look_at(eye=(0, 3, 8), center=(0, 0.5, 0)))
    s.add(om.PointLight(position=(0, 4, 0), constant=1, linear=0.1, quadratic=0.05))
    s.add(om.SpotLight(position=(0, 4, 2), direction=(0, -1, -0.3), cutoff=25, exponent=3))
    s.add(om.DirectionalLight(direction=(-1, -1, -1), intensity=0.5))
    s.add(om.AmbientLight(intensity=0.2))
    s.add(om.Fog(color=(0.8, 0.8, 0.9), mode="linear", start=2, end=30))
    s.add(om.povray.GlobalSettings(max_trace_level=5))
    a = s.add(om.Node("a"))
    a.add(om.ClipPlane(normal=(0, 1, 0), offset=0.5))
    a.add(om.Translation(0, 0.5, 0))
    a.add(om.PBRMaterial(base_color=(0.9, 0.8, 0.2), metallic=1, roughness=0.3))
    a.add(om.Sphere())
    b = s.add(om.Node("b"))
    b.add(om.Translation(-2, 0, 0))
    b.add(om.Material(diffuse=(0.2, 0.8, 0.2), opacity=0.5, emission=(0.1, 0, 0)))
    b.add(om.povray.Normal(pattern="bumps", amount=0.5, scale=0.1))
    b.add(om.Cylinder(radius=0.5, height=1))
    c = s.add(om.Node("c"))
    c.add(om.Translation(2, 0, 0))
    c.add(om.povray.Pigment(pattern="checker", scale=0.2))
    c.add(om.povray.Interior(ior=1.3))
    c.add(om.Cone(radius=0.5, height=1.5))
    f = s.add(om.Node("f"))
    f.add(om.Texture(np.full((4, 4, 3), 200, np.uint8)))
    f.add(om.Box(size=(8, 0.1, 8), center=(0, -0.8, 0)))
    f.add(om.Disk(radius=0.3))
    f.add(om.Rectangle(size=(0.5, 0.5)))
    lines = s.add(om.Node("lines"))
    lines.add(om.LineSet(vertices=[[0, 2, 0], [1, 2, 0]]))
    lines.add(om.PointSet(vertices=[[0, 2.5, 0]]))
    img = _render(s, size=(64, 48), antialias=True)
    # clipped sphere: nothing of it above y = 0.5 + 1 - its cap; the top of the image is fog-coloured background
    assert img.mask.mean() > 0.3
    assert not img.mask[1, 32]  # the background is not fogged into the mask
    assert img.pixel(32, 1)[3] == 255  # the shared default background (no om.Background)


@pytest.mark.parametrize("ortho", [False, True], ids=["perspective", "orthographic"])
def test_depth_pass_gives_eye_space_depth(ortho):
    if ortho:
        cam = om.Camera.orthographic(eye=(3, 2, 7), center=(0.3, 0.2, 0), height=4, far=100)
    else:
        cam = om.Camera.look_at(eye=(3, 2, 7), center=(0.3, 0.2, 0), fov=40, far=100)
    s = om.Node("s")
    s.add(cam)
    moved = s.add(om.Node("moved"))
    moved.add(om.Translation(1, 0.5, 0))
    moved.add(om.Scaling(0.8))
    moved.add(om.Sphere())
    s.add(om.TriangleSet(vertices=[[-3, -1, -1], [-1, -1, -1], [-2, 0, -1]], colors=[[1, 0, 0]] * 3))
    img = _render(s, depth=True)
    o, d = pixel_rays(cam, SIZE)
    oc = o - np.array([1, 0.5, 0])
    b = np.sum(oc * d, -1)
    disc = b * b - (np.sum(oc * oc, -1) - 0.64)
    t = -b - np.sqrt(np.maximum(disc, 0))
    forward = np.array([-2.7, -1.8, -7.0]) / np.linalg.norm([-2.7, -1.8, -7.0])
    ref = np.where(disc >= 0, t * (d @ forward) + (o - cam.eye) @ forward, np.inf)
    sphere = np.isfinite(ref)
    assert np.abs(img.depth[sphere] - ref[sphere]).max() < 1e-4  # 16-bit coarse + fine digits of far=100
    triangle = np.isfinite(img.depth) & ~sphere
    assert triangle.sum() > 50  # the vertex-coloured mesh is in the depth pass too
    assert np.array_equal(img.mask, np.isfinite(img.depth))


def test_light_switch_limits_lights_to_a_subgraph():
    a, b = om.PointLight(position=(5, 0, 3)), om.PointLight(position=(-5, 0, 3))
    s = om.Node("s", [om.Camera.look_at(eye=(0, 0, 8)), a, b])
    s.add(om.Node("only_a", [om.Translation(-1.2, 0, 0), om.LightSwitch(on=True, lights=[a]), om.Sphere()]))
    s.add(om.Node("both", [om.Translation(1.2, 0, 0), om.Sphere()]))
    img = _render(s, size=(160, 80))
    # ambient only on the left (grey 0.8 reflects the ambient 0.2 as in GL): light a is on the right
    assert img.pixel(50, 40)[0] < 110 < 150 < img.pixel(72, 40)[0]
    assert img.pixel(90, 40)[0] > 150 and img.pixel(112, 40)[0] > 150  # both lights
