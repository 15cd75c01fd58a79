"""Every example runs as a script and writes a non-blank image into the folder it is given."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def run_example(name: str, out: Path, *args: str) -> str:
    result = subprocess.run(
        [sys.executable, str(EXAMPLES / name), str(out), *args],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=EXAMPLES.parent,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return result.stdout


def check_image(path: Path, min_colors: int = 50) -> np.ndarray:
    from PIL import Image

    assert path.is_file(), f"{path} was not written"
    rgb = np.asarray(Image.open(path).convert("RGB")).astype(int)
    assert rgb.std() > 10, f"{path.name} looks blank"
    colors = len(np.unique(rgb.reshape(-1, 3), axis=0))
    assert colors >= min_colors, f"{path.name} has only {colors} colours"
    return rgb


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
def test_01_two_engines(tmp_path):
    out = run_example("01_two_engines.py", tmp_path)
    both = check_image(tmp_path / "01-two-engines.png")
    gl = check_image(tmp_path / "01-gl-preview.png")
    pov = check_image(tmp_path / "01-povray-final.png")
    assert both.shape[1] == gl.shape[1] + pov.shape[1] + 4  # side by side
    assert (tmp_path / "knot.obj").is_file() and "01-two-engines.png" in out
    # the knot (orange) is in the middle of both renders
    for img in (gl, pov):
        h, w, _ = img.shape
        centre = img[h // 3 : 2 * h // 3, w // 3 : 2 * w // 3]
        orange = (centre[:, :, 0] > centre[:, :, 2] + 60).mean()
        assert orange > 0.2


@pytest.mark.gl
def test_02_data_sequences(tmp_path):
    run_example("02_data_sequences.py", tmp_path)
    img = check_image(tmp_path / "02-data-sequences.png")
    yellowish = (img[:, :, 0] > 200) & (img[:, :, 1] > 150) & (img[:, :, 2] < 150)
    magenta = (img[:, :, 0] > 180) & (img[:, :, 1] < 150) & (img[:, :, 2] > 100)
    assert yellowish.sum() > 200 and magenta.sum() > 200  # both alternating colours show


@pytest.mark.gl
def test_03_custom_shape(tmp_path):
    out = run_example("03_custom_shape.py", tmp_path)
    img = check_image(tmp_path / "03-custom-shape.png")
    h, w, _ = img.shape
    left, right = img[:, : w // 2], img[:, w // 2 :]
    assert (left[:, :, 2] > left[:, :, 0] + 60).sum() > 2000  # blue stars from the simplifier
    assert (right[:, :, 0] > right[:, :, 2] + 60).sum() > 2000  # orange stars from the painter
    assert "picked: /scene/simplified/" in out and "StarPrism" in out
    lines = EXAMPLES.joinpath("03_custom_shape.py").read_text().splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("class StarPrism"))
    end = next(i for i, ln in enumerate(lines) if ln.startswith("# --- using them"))
    part = lines[start:end]
    while not part[-1].strip():
        part.pop()
    assert len(part) < 40  # "a custom shape in under 40 lines": physical lines, blank ones included


@pytest.mark.slow
@pytest.mark.gl
def test_04_simulation(tmp_path):
    out = run_example("04_simulation.py", tmp_path)
    img = check_image(tmp_path / "04-simulation.png")
    assert img.shape[1] > 4 * 320  # four moments and the top view
    frames = [img[:, i * 324 : i * 324 + 320] for i in range(4)]
    assert not np.array_equal(frames[0], frames[3])  # the balls moved
    assert "physics steps" in out


@pytest.mark.gl
def test_05_picking(tmp_path):
    out = run_example("05_picking.py", tmp_path)
    check_image(tmp_path / "05-picking.png")
    assert "/scene/toys/ball" in out and "/scene/toys/ring" in out and "/scene/toys/cone" in out
    assert "nothing (background)" in out


def test_features_scene_camera_skips_the_debug_group():
    import omnirender as om

    scene = om.load(EXAMPLES / "scenes" / "features.yaml")
    lights, (camera, _) = scene.preevaluate()
    assert camera.mask == "!debug"  # POV-Ray and Mitsuba pictures leave out the wireframe debug sphere
    assert "debug" in scene["/demo/debug"].groups
    sys.path.insert(0, str(EXAMPLES / "scenes"))
    try:
        from make_demo_scene import features_scene
    finally:
        sys.path.pop(0)
    built = features_scene()
    built_camera = built.preevaluate()[1][0]
    assert built_camera.parameters() == camera.parameters()  # the file is what the script writes


@pytest.mark.gl
def test_demo_file_renders_what_omnirender_demo_renders():
    import omnirender as om
    from omnirender.demo import demo_scene

    from_file = om.render(om.load(EXAMPLES / "scenes" / "demo.yaml"), engine="gl", size=(160, 120)).array
    built = om.render(demo_scene(), engine="gl", size=(160, 120)).array
    assert np.array_equal(from_file, built)


@pytest.mark.gl
def test_features_scene_renders_without_the_debug_sphere():
    import omnirender as om

    scene = om.load(EXAMPLES / "scenes" / "features.yaml")
    shown = om.render(scene, engine="gl", size=(96, 72), samples=0).array
    scene.remove(scene["/demo/debug"])
    without = om.render(scene, engine="gl", size=(96, 72), samples=0).array
    assert np.abs(shown.astype(int) - without.astype(int)).max() <= 1


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
def test_06_outline_technique(tmp_path):
    out = run_example("06_outline_technique.py", tmp_path)
    both = check_image(tmp_path / "06-outline-technique.png")
    assert "06-outline-technique.png" in out
    half = (both.shape[1] - 4) // 2
    gl, pov = both[:, :half], both[:, half + 4 :]
    ring = (slice(80, 115), slice(90, 230))  # the top of the ring, away from the floor and its shadows
    dark = lambda img: (img[ring].max(axis=2) < 40).sum()  # noqa: E731
    assert dark(gl) > 150 and dark(pov) < dark(gl) / 5  # the outline is GL's; POV-Ray renders the scene without it


@pytest.mark.slow
@pytest.mark.gl
def test_07_techniques(tmp_path):
    out = run_example("07_techniques.py", tmp_path)
    figure = check_image(tmp_path / "07-techniques.png")
    assert "07-techniques.png" in out and figure.shape[:2] == (540, 720)  # 2x2 panels of 360x270
    wire = figure[:270, 360:]
    assert (wire.max(axis=2) < 100).mean() < 0.1 and (wire.min(axis=2) > 240).mean() > 0.8  # lines on white


@pytest.mark.gl
def test_08_custom_effect(tmp_path):
    out = run_example("08_custom_effect.py", tmp_path)
    figure = check_image(tmp_path / "08-custom-effect.png")
    assert "08-custom-effect.png" in out and figure.shape[:2] == (300, 804)  # two panels of 400x300
    source = (Path(EXAMPLES) / "08_custom_effect.py").read_text()
    assert len(source.splitlines()) <= 30
    colour, grey = figure[:, :400], figure[:, 404:]
    assert np.abs(colour[..., 0] - colour[..., 2]).max() > 100  # the chain alone keeps colours
    assert np.abs(grey[..., 0] - grey[..., 2]).max() <= 1 and np.abs(grey[..., 0] - grey[..., 1]).max() <= 1
    assert abs(grey.mean() - colour.mean()) < 20  # luminance kept, colour gone


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
def test_11_turntable(tmp_path):
    args = ("--seconds", "1", "--fps", "2", "--size", "96x72")
    out = run_example("11_turntable.py", tmp_path, *args)
    assert "GL preview: 2 written" in out and "POV-Ray final: 2 written" in out
    from PIL import Image

    for name in ("11-turntable-gl.mp4", "11-turntable-povray.mp4"):
        assert (tmp_path / name).stat().st_size > 1000
    with Image.open(tmp_path / "11-turntable.gif") as gif:
        assert gif.n_frames == 2 and gif.size == (96, 72)
    first = check_image(tmp_path / "11-frames-povray" / "0000.png", min_colors=20)
    second = check_image(tmp_path / "11-frames-povray" / "0001.png", min_colors=20)
    assert np.abs(first - second).mean() > 5  # the scene turned
    again = run_example("11_turntable.py", tmp_path, *args)
    assert "POV-Ray final: 0 written, 2 already there" in again  # a second run resumes: nothing left to do


@pytest.mark.radiance
def test_09_lighting_analysis(tmp_path):
    out = run_example("09_lighting_analysis.py", tmp_path)
    img = check_image(tmp_path / "09-lighting-analysis.png")
    low, high = (float(v.replace(",", "")) for v in re.findall(r"([\d,]+) lux", out))
    # sky alone: 179 * pi * 10 lux = 5,623 lux on open floor; the lamp (60 pi W/sr, 2.5 m up) adds 5,400 below it
    assert 500 < low < 5623 < high < 5623 + 5400 + 100
    chart = img[:, img.shape[1] // 2 + 10 :]
    assert (chart[:, :, 0] > 200).any() and (chart[:, :, 2] > 150).any()  # red under the lamp, blue in the corner


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
@pytest.mark.mitsuba
def test_12_assets(tmp_path):
    run_example("12_assets.py", tmp_path)
    img = check_image(tmp_path / "12-assets.png")
    assert (tmp_path / "12-asset.glb").is_file()
    w = (img.shape[1] - 8) // 3
    # the ball's glowing band is bright yellow in the middle of every engine's picture
    for i in range(3):
        band = img[110:135, i * (w + 4) + 130 : i * (w + 4) + 190]
        yellow = (band[..., 0] > 200) & (band[..., 1] > 170) & (band[..., 2] < 150)
        assert yellow.mean() > 0.3, i


@pytest.mark.slow
@pytest.mark.gl
def test_13_renderer_tree(tmp_path):
    out = run_example("13_renderer_tree.py", tmp_path)
    assert "13-occlusion.png" in out
    occlusion = check_image(tmp_path / "13-occlusion.png")
    w = (occlusion.shape[1] - 8) // 3
    plain, visible, semi = (occlusion[:, i * (w + 4) : i * (w + 4) + w] for i in range(3))
    vessels = lambda img: ((img[..., 2] > img[..., 0] + 60) | (img[..., 0] > img[..., 1] + 120)).sum()  # noqa: E731
    assert vessels(plain) < 20 < vessels(semi) < vessels(visible)  # hidden, shown through the organ, shown fully
    shadows = check_image(tmp_path / "13-shadows.png")
    w = (shadows.shape[1] - 4) // 2
    without, with_ = shadows[:, :w].astype(int), shadows[:, w + 4 :].astype(int)
    darker = with_.sum(axis=2) < 0.7 * without.sum(axis=2)
    assert darker.sum() > 1000 and darker[: shadows.shape[0] // 3].sum() < 50  # shadows on the floor, not the sky
    fields = check_image(tmp_path / "13-light-fields.png")
    right = fields[:, fields.shape[1] // 2 + 80 :]
    statue = (right.max(axis=2) - right.min(axis=2) < 4) & (right.max(axis=2) > 60) & (right.max(axis=2) < 230)
    assert statue.sum() > 800  # the grey (luminance-filtered) light field


@pytest.mark.slow
@pytest.mark.gl
def test_14_user_renderer(tmp_path):
    out = run_example("14_user_renderer.py", tmp_path)
    assert "RayTracedSphere follows the four integration rules" in out
    both = check_image(tmp_path / "14-user-renderer.png")
    left = both[:, : (both.shape[1] - 4) // 2]
    red = (left[..., 0] > 150) & (left[..., 1] < 110)
    blue = (left[..., 2] > 150) & (left[..., 0] < 110)
    ys, xs = np.nonzero(red)
    row = int(ys.mean())
    # the slab cuts through the sphere: along the sphere's middle row, blue shows on both sides of red
    assert red.sum() > 2000 and blue[row, : xs.min()].any() and blue[row, xs.max() + 1 :].any()
    lines = [line for line in (EXAMPLES / "14_user_renderer.py").read_text().splitlines()]
    start = next(i for i, line in enumerate(lines) if line.startswith("class RayTracedSphere"))
    end = next(i for i, line in enumerate(lines) if line.startswith("LIGHT ="))
    assert end - start < 42  # the renderer, blank lines included, in about 40 lines


@pytest.mark.slow
@pytest.mark.gl
def test_15_toon_model(tmp_path):
    out = run_example("15_toon_model.py", tmp_path)
    both = check_image(tmp_path / "15-toon-model.png")
    assert both.shape[1] == 2 * 480 + 4 and "toon" in out
    toon, plain = both[:, :480], both[:, 484:]

    def banded(rgb: np.ndarray) -> float:  # how much of the blue ball its six most common shades cover
        _, counts = np.unique(rgb[rgb[..., 2] > rgb[..., 0] + 40] // 4, axis=0, return_counts=True)
        return float(np.sort(counts)[::-1][:6].sum() / counts.sum())

    assert banded(toon) > 0.85 and banded(plain) < 0.5  # flat bands instead of a smooth gradient


@pytest.mark.slow
@pytest.mark.gl
def test_16_see_through(tmp_path):
    run_example("16_see_through.py", tmp_path)
    both = check_image(tmp_path / "16-see-through.png")
    opened, closed = both[:, :480], both[:, 484:]

    def yellow(rgb: np.ndarray) -> int:
        return int(((rgb[..., 0] > 150) & (rgb[..., 1] > 100) & (rgb[..., 2] < 80)).sum())

    assert yellow(opened) > 1000 and yellow(closed) == 0


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
def test_17_nurbs(tmp_path):
    run_example("17_nurbs.py", tmp_path)
    both = check_image(tmp_path / "17-nurbs.png")
    gl, povray = both[:, :480].astype(int), both[:, 484:].astype(int)

    def orange(rgb: np.ndarray) -> np.ndarray:
        return (rgb[..., 0] > 150) & (rgb[..., 0] - rgb[..., 2] > 90)

    a, b = orange(gl), orange(povray)
    assert a.sum() > 30000 and (a ^ b).sum() < 0.05 * (a | b).sum()  # the same sheet in both engines
    rows = np.nonzero(a.any(axis=1))[0]
    middle = a[(rows.min() + rows.max()) // 2]
    runs = np.count_nonzero(np.diff(middle.astype(int)) == 1) + middle[0]
    assert runs >= 2  # a window cuts the sheet's middle row


@pytest.mark.slow
@pytest.mark.gl
def test_18_portal(tmp_path):
    out = run_example("18_portal.py", tmp_path)
    img = check_image(tmp_path / "18-portal.png")
    assert "garden view" in out and "security camera" in out
    portal = img[130:250, 150:330]  # the garden through the portal: sky above, lawn below
    assert (portal[:40, :, 2] > portal[:40, :, 0] + 40).mean() > 0.8
    assert (portal[-40:, :, 1] > portal[-40:, :, 2] + 20).mean() > 0.5
    monitor = img[200:320, 460:600]  # the room seen by the security camera: the red torus on the monitor
    assert (monitor[..., 0].astype(int) - monitor[..., 1] > 60).sum() > 30
    ball = img[275:355, 318:400].astype(int)  # the glass ball: the torus and the portal's lawn refracted
    assert (ball[..., 0] - ball[..., 1] > 60).sum() > 30 and (ball[..., 1] - ball[..., 0] > 30).sum() > 30


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
@pytest.mark.mitsuba
@pytest.mark.radiance
def test_19_usd(tmp_path):
    pytest.importorskip("pxr")
    from omnirender.formats.usd.writer import validate

    run_example("19_usd.py", tmp_path)
    img = check_image(tmp_path / "19-usd.png")
    assert validate(tmp_path / "19-robot-again.usdz") == []
    panels = (img.shape[1] + 4) // 324
    assert panels == 4
    for i in range(panels):  # the robot's orange body in the middle of every engine's picture
        body = img[95:120, i * 324 + 150 : i * 324 + 170]
        orange = (body[..., 0] > 150) & (body[..., 1] < 150) & (body[..., 2] < 90)
        assert orange.mean() > 0.5, i


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.mitsuba
def test_20_gaussian_splats(tmp_path):
    out = run_example("20_gaussian_splats.py", tmp_path, "quick")
    img = check_image(tmp_path / "20-gaussian-splats.png")
    assert (tmp_path / "20-room.glb").is_file() and (tmp_path / "20-room.usda").is_file()
    assert (tmp_path / "20-capture.ply").is_file() and "splat" in out
    w = (img.shape[1] - 4) // 2
    for panel in (img[:, :w], img[:, w + 4 :]):  # GL, Mitsuba: the red torus in front of the splat room
        h = panel.shape[0]
        red = (panel[..., 0] > 150) & (panel[..., 1] < 110) & (panel[..., 2] < 100)
        assert red[h // 2 :].sum() > 200
        bricks = (panel[: h // 3, :, 0] > panel[: h // 3, :, 2] + 40).mean()
        assert bricks > 0.2  # the brick wall's splats fill the top of the picture
