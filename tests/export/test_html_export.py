"""om.export(scene, "scene.html"): a self-contained page, checked in headless Chromium against the GL render."""

from __future__ import annotations

import base64
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender.formats import html
from omnirender.formats.gltf import writer as gltf

SIZE = (320, 240)
BACKGROUND = (0.1, 0.12, 0.15)


def _scene() -> om.Node:
    from omnirender.demo import demo_scene

    scene = demo_scene()  # a mesh from a file, primitives, two point lights and a camera
    scene.add(om.Node("debug", [om.Material(diffuse=(0, 1, 0)), om.Box(size=(1, 1, 1), center=(0, 2.8, 0))], "debug"))
    return scene


def _settings(text: str) -> dict:
    found = re.search(r"OmniRenderViewer\.show\(document\.getElementById\(\"omnirender\"\), (\{.*\})\);", text)
    assert found, "the page does not start the viewer"
    return json.loads(found.group(1))


def test_the_page_is_self_contained_and_embeds_the_glb(tmp_path):
    scene = _scene()
    path = tmp_path / "scene.html"
    assert om.export(scene, path) == path
    text = path.read_text()
    assert text.startswith("<!DOCTYPE html>") and "<title>scene</title>" in text
    # offline: nothing is loaded from anywhere (no src/href attributes, no fetch of a URL)
    assert not re.search(r"\s(src|href)\s*=", text) and "import(" not in text
    # three.js's MIT notice travels with the bundle, and the licence file is package data
    assert "@license" in text and "SPDX-License-Identifier: MIT" in text
    assert "MIT License" in (html.ASSETS / "three.LICENSE").read_text()
    settings = _settings(text)
    glb = base64.b64decode(settings["glb"])
    assert glb == gltf.build(scene, size=(960, 720), physical_lights=False)[0]  # the page converts light units
    assert settings["background"] == pytest.approx([0.12, 0.13, 0.16, 1.0])  # the demo's om.Background
    camera = scene.components[0]
    assert settings["distance"] == pytest.approx(np.linalg.norm(np.subtract(camera.center, camera.eye)))


def test_the_group_mask_and_light_units_reach_the_page(tmp_path):
    scene = _scene()
    full = _settings(html.page(scene))
    masked = _settings(html.page(scene, mask="!debug"))
    names = lambda s: [n.get("name") for n in _glb_json(s["glb"])["nodes"]]  # noqa: E731
    assert "debug" in names(full) and "debug" not in names(masked)
    lights = _glb_json(full["glb"])["extensions"]["KHR_lights_punctual"]["lights"]
    assert [li["extras"]["omnirender"]["attenuation"] for li in lights] == [[1.0, 0.0, 0.0]] * 2
    assert html.DEFAULT_BACKGROUND == pytest.importorskip("omnirender.gl.glengine").DEFAULT_BACKGROUND


def test_hostile_titles_cannot_break_out_of_the_page():
    text = html.page(om.Node("x", [om.Sphere()]), title="</title><script>alert(1)</script>")
    assert "<title>&lt;/title&gt;&lt;script&gt;alert(1)&lt;/script&gt;</title>" in text
    assert text.count("<script>") == 2 and text.count("</script>") == 2  # the bundle's and the start-up's
    # the scene travels as base64 and the settings are numbers: neither can hold markup


def _glb_json(b64: str) -> dict:
    data = base64.b64decode(b64)
    length = int.from_bytes(data[12:16], "little")
    return json.loads(data[20 : 20 + length])


def _chromium_screenshot(page: Path, out: Path, size: tuple[int, int]) -> np.ndarray:
    program = shutil.which("chromium") or shutil.which("chromium-browser")
    command = [
        program, "--headless", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox",
        "--disable-gpu", "--disable-background-networking", "--disable-component-update", "--disable-sync",
        "--no-first-run", "--hide-scrollbars", f"--user-data-dir={out.parent / 'chromium-profile'}",
        f"--window-size={size[0]},{size[1]}", "--virtual-time-budget=15000", f"--screenshot={out}", page.as_uri(),
    ]  # fmt: skip
    result = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert out.is_file(), f"Chromium wrote no screenshot: {result.stderr[-2000:]}"
    from PIL import Image

    return np.asarray(Image.open(out).convert("RGB")).astype(int)


def _silhouette(rgb: np.ndarray, background: tuple[float, float, float]) -> np.ndarray:
    return np.abs(rgb - np.round(np.asarray(background) * 255)).sum(axis=2) > 24


@pytest.mark.gl
@pytest.mark.chromium
@pytest.mark.slow
def test_chromium_shows_what_gl_renders(tmp_path):
    scene = _scene()
    scene.components[1].color = BACKGROUND  # the demo's om.Background
    gl = om.render(scene, engine="gl", size=SIZE, mask="!debug").array[:, :, :3].astype(int)
    page = tmp_path / "scene.html"
    om.export(scene, page, mask="!debug")
    shot = _chromium_screenshot(page, tmp_path / "page.png", SIZE)
    assert shot.shape == gl.shape
    a, b = _silhouette(gl, BACKGROUND), _silhouette(shot, BACKGROUND)
    assert 0.3 < a.mean() < 0.9  # the picture shows the scene, not an empty page
    agreement = float((a == b).mean())
    print(f"silhouette agreement GL vs Chromium: {agreement:.2%}")
    assert agreement >= 0.95, f"silhouettes agree on {agreement:.1%} of the pixels"
    # the masked-out debug box is absent in the page too: its pixels show the background in both
    box = om.render(scene, engine="gl", size=SIZE).array[:, :, :3].astype(int)
    only_box = _silhouette(box, BACKGROUND) & ~a
    assert only_box.sum() > 100 and b[only_box].mean() < 0.05
    # shading agrees roughly too: the mean colour of the pixels both cover
    both = a & b
    assert np.abs(gl[both].mean(axis=0) - shot[both].mean(axis=0)).max() < 40


def _pixels(camera: om.Camera, points: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """(N, 2) integer pixel coordinates (x right, y down) of world points seen by ``camera``."""
    homogeneous = np.column_stack([points, np.ones(len(points))])
    clip = homogeneous @ (camera.projection_matrix(size[0] / size[1]) @ camera.view_matrix()).T
    ndc = clip[:, :2] / clip[:, 3:]
    return np.column_stack([(ndc[:, 0] + 1) / 2 * size[0], (1 - ndc[:, 1]) / 2 * size[1]]).astype(int)


@pytest.mark.gl
@pytest.mark.chromium
@pytest.mark.slow
def test_chromium_shows_instance_sets_as_gl_does(tmp_path):
    """The page's three.js draws EXT_mesh_gpu_instancing: a ramp of 24 colours (``_COLOR_0``) and two colours
    (one material each) under a rotated node, where GL draws them."""
    from omnirender.colorimetry import cielab, delta_e2000

    n, size = 24, (480, 240)
    x = np.linspace(-4, 4, n)
    ramp = np.column_stack([np.linspace(1, 0, n), np.full(n, 0.3), np.linspace(0, 1, n)])
    balls = np.column_stack([x, np.full(n, 0.8), np.zeros(n)])
    boxes = np.column_stack([x, np.full(n, -0.8), np.zeros(n)])
    two = np.array([(1, 0.8, 0.1), (0.1, 0.8, 0.3)])[np.arange(n) % 2]
    camera = om.Camera.look_at(eye=(0, 0, 10), center=(0, 0, 0), fov=30)
    turn = om.Rotation(10, (0, 0, 1))
    scene = om.Node("scene", [camera, om.Background(BACKGROUND), om.DirectionalLight(direction=(0, 0, -1))])
    scene.add(om.Node("ramp", [om.InstanceSet(om.Sphere(radius=0.15), balls, colors=ramp)]))
    scene.add(om.Node("two", [turn, om.InstanceSet(om.Box(size=0.2), boxes, colors=two)]))
    gl = om.render(scene, engine="gl", size=size).array[:, :, :3].astype(int)
    page = tmp_path / "instances.html"
    om.export(scene, page)
    assert '"EXT_mesh_gpu_instancing"' in json.dumps(_glb_json(_settings(page.read_text())["glb"]))
    shot = _chromium_screenshot(page, tmp_path / "page.png", size)
    a, b = _silhouette(gl, BACKGROUND), _silhouette(shot, BACKGROUND)
    assert a.mean() > 0.04 and (a & b).sum() / (a | b).sum() > 0.9  # every instance drawn, not one copy
    agreement = float((a == b).mean())
    assert agreement >= 0.99, f"silhouettes agree on {agreement:.1%} of the pixels"
    # each instance has its own colour in both (three.js's physical light against GL's Phong: a few dE)
    for points, world in ((balls, np.eye(4)), (boxes, turn.matrix)):
        centres = _pixels(camera, (np.column_stack([points, np.ones(n)]) @ world.T)[:, :3], size)
        rows, cols = centres[:, 1], centres[:, 0]
        delta = delta_e2000(cielab(gl[rows, cols]), cielab(shot[rows, cols]))
        print(f"instance colours GL vs Chromium: dE max {delta.max():.1f}")
        assert delta.max() < 10


def test_phong_materials_keep_their_parameters_for_the_page():
    scene = om.Node("s", [om.Material(diffuse=(0.7, 0.7, 0.7), specular=(0.1, 0.1, 0.1), shininess=8), om.Sphere()])
    glb, _ = gltf.build(scene)
    doc = json.loads(glb[20 : 20 + int.from_bytes(glb[12:16], "little")])
    phong = doc["materials"][0]["extras"]["omnirender"]["phong"]
    assert phong["shininess"] == 8.0 and phong["specular"] == pytest.approx([0.0100] * 3, abs=2e-4)  # linear


@pytest.mark.gl
@pytest.mark.chromium
@pytest.mark.slow
def test_the_page_has_gl_shadows_and_no_floor_glare(tmp_path):
    """Issue 23: the demo's page had no shadows and a bright specular glare on the floor that GL does not have."""
    from omnirender.demo import demo_scene

    def luminance(rgb: np.ndarray) -> np.ndarray:
        return rgb[..., :3] @ np.array([0.2126, 0.7152, 0.0722])

    scene = demo_scene()
    lit_scene = demo_scene()
    lit_scene.insert(0, om.Shadowing(cast=False))
    gl = luminance(om.render(scene, engine="gl", size=SIZE).array.astype(float))
    lit = luminance(om.render(lit_scene, engine="gl", size=SIZE).array.astype(float))
    floor_only = demo_scene()
    for name in ("knot", "torus", "ball"):
        floor_only.remove(floor_only.child(name))
    full, alone = (om.render(s, engine="gl", size=SIZE) for s in (lit_scene, floor_only))
    with np.errstate(invalid="ignore"):
        floor = np.isfinite(full.depth) & (np.abs(full.depth - alone.depth) < 1e-3)
    shadow = floor & (gl < 0.8 * lit)
    om.export(scene, tmp_path / "demo.html")
    page = luminance(_chromium_screenshot(tmp_path / "demo.html", tmp_path / "page.png", SIZE).astype(float))
    assert shadow.sum() > 300
    darker = float(np.mean(page[shadow] < 0.85 * lit[shadow]))
    print(f"page darker than GL's unshadowed floor on {darker:.1%} of GL's shadow pixels")
    assert darker > 0.8  # the page's shadows fall where GL's do
    assert np.percentile(page[floor & ~shadow], 99) < np.percentile(lit[floor], 99) + 20  # no glare


@pytest.mark.gl
@pytest.mark.chromium
@pytest.mark.slow
def test_chromium_lights_the_floor_with_a_rect_area_light_as_gl_does(tmp_path):
    """The page turns the glTF's spot + extras record back into a three.js RectAreaLight (issue 26): the floor
    under it is as bright as GL draws it (no shadows in three.js: the scene has no occluder)."""
    size = (320, 240)
    light = om.RectLight(position=(0, 1.2, 0), direction=(0, -1, 0), width=1.5, height=0.8, intensity=2.5)
    scene = om.Node("scene", [om.Camera.look_at((0, 3, 3.5), (0, 0, 0), fov=45), light])
    scene.add(om.Background((0.0, 0.0, 0.0)))
    scene.add(om.Node("floor", [om.Material(diffuse=(0.7, 0.7, 0.7), ambient=(0, 0, 0), specular=(0, 0, 0)),
                                om.Box(size=(6, 0.1, 6), center=(0, -0.05, 0))]))  # fmt: skip
    gl = om.render(scene, engine="gl", size=size, samples=0).array[:, :, :3].astype(float)
    page = tmp_path / "area.html"
    om.export(scene, page)
    shot = _chromium_screenshot(page, tmp_path / "area.png", size).astype(float)
    centre = (slice(size[1] // 2 - 6, size[1] // 2 + 6), slice(size[0] // 2 - 6, size[0] // 2 + 6))
    corner = (slice(2, 10), slice(2, 10))
    print(f"centre GL {gl[centre].mean():.1f} page {shot[centre].mean():.1f}")
    assert shot[centre].mean() > 60  # lit by the area light (a page without it would be black)
    assert abs(gl[centre].mean() - shot[centre].mean()) < 25
    assert shot[corner].mean() < shot[centre].mean() - 30  # falls off away from the light
