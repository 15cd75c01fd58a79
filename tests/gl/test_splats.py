"""Gaussian splats in GL against the numpy reference (tests/splat_reference.py): EWA + SH + sorted blending,
composition with opaque meshes (forward and deferred), volumes, post-processing, stereo; the GPU sort."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender.gl.painters import splats as painter
from omnirender.gl.techniques.stereo import eye_matrices

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import splat_reference as ref  # noqa: E402

pytestmark = pytest.mark.gl

SIZE = (128, 96)
CAMERA = om.Camera.look_at((0.6, 1.1, 4.2), (0, 0, 0), fov=40)


def cloud(n: int, degree: int, seed: int = 0, spread: float = 1.0, scale: float = 1.0) -> om.GaussianSplats:
    """``n`` random splats in a cube of half-side ``spread``; SH coefficients of a trained scene's magnitude."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    k = (degree + 1) ** 2
    sh = rng.normal(0.0, 0.25, (n, k, 3))
    sh[:, 0] *= 3.0  # the DC term carries most of the colour
    return om.GaussianSplats(
        rng.uniform(-spread, spread, (n, 3)),
        q / np.linalg.norm(q, axis=1, keepdims=True),
        rng.uniform(0.02, 0.12, (n, 3)) * scale,
        rng.uniform(0.3, 1.0, n),
        sh,
    )


def scene_of(*content, camera=CAMERA, extra=()) -> om.Node:
    return om.Node("scene", [camera, om.Background((0, 0, 0)), *extra, *content])


def matrices(engine: om.gl.GLEngine) -> tuple[np.ndarray, np.ndarray]:
    _, view, proj = engine.camera_matrices()
    return view, proj


def rgb(image: om.Image) -> np.ndarray:
    return image.array[..., :3] / 255.0


@pytest.fixture(scope="module")
def engine():
    e = om.gl.GLEngine(size=SIZE, samples=0)
    yield e
    e.release()


@pytest.mark.parametrize("degree", [0, 3])
def test_gl_matches_the_numpy_reference(engine, degree):
    splats = cloud(10_000, degree, seed=degree)
    image = engine.render(scene_of(om.Node("cloud", [splats])))
    expected, _ = ref.render(splats, np.eye(4), *matrices(engine), SIZE)
    assert ref.psnr(rgb(image), np.clip(expected, 0, 1)) >= 35.0
    assert rgb(image).mean() > 0.1  # the cloud covers the picture


def test_transforms_apply_and_an_orthographic_camera_matches(engine):
    splats = cloud(2000, 1, seed=5)
    model = om.Rotation(35, (0.3, 1, 0.2))
    move = om.Scaling(1.2, 0.8, 1.0)
    for camera in (CAMERA, om.Camera.orthographic(eye=(0.5, 1.0, 4.0), center=(0, 0, 0), height=3.0)):
        image = engine.render(scene_of(om.Node("cloud", [move, model, splats]), camera=camera))
        m = move.matrix @ model.matrix
        expected, _ = ref.render(splats, m, *matrices(engine), SIZE)
        assert ref.psnr(rgb(image), np.clip(expected, 0, 1)) >= 35.0, camera


def test_view_dependent_colour_changes_with_the_eye(engine):
    """One splat with only the degree-1 x term (-C1 * x * sh[3]) in red: the eye at +x looks along -x."""
    sh = np.zeros((1, 4, 3))
    sh[0, 0] = 0.0
    sh[0, 3, 0] = -0.8
    splat = om.GaussianSplats(np.zeros((1, 3)), [[1.0, 0, 0, 0]], [[0.3, 0.3, 0.3]], [1.0], sh)
    reds = []
    for eye in ((4, 0, 0), (-4, 0, 0)):
        image = engine.render(scene_of(om.Node("s", [splat]), camera=om.Camera.look_at(eye, (0, 0, 0), fov=30)))
        reds.append(image.array[SIZE[1] // 2, SIZE[0] // 2, 0] / 255.0)
    # from +x the direction is (-1, 0, 0): -C1 * (-1) * (-0.8) = -0.8 C1; from -x +0.8 C1; alpha at the centre 0.99
    expected = [(0.5 - ref._sh.C1 * 0.8) * 0.99, (0.5 + ref._sh.C1 * 0.8) * 0.99]
    assert reds == pytest.approx(expected, abs=2 / 255)


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_a_box_half_inside_the_cloud_occludes_and_is_blended_over(pipeline):
    """The box hides the splats behind it; splats in front of it blend over it: the reference composited with
    the box's image and depth (rendered alone) matches where the box is and everywhere else."""
    e = om.gl.GLEngine(size=SIZE, samples=0, pipeline=pipeline)
    try:
        splats = cloud(4000, 2, seed=3)
        box = om.Node("box", [om.Translation(0.4, 0.0, 0.3), om.Material(diffuse=(0.2, 0.5, 0.9)), om.Box(size=1.0)])
        light = [om.DirectionalLight(direction=(-0.3, -1, -0.5), intensity=0.8), om.AmbientLight(intensity=0.3)]
        alone = e.render(scene_of(box, extra=light))
        both = e.render(scene_of(box, om.Node("cloud", [splats]), extra=light))
        expected, _ = ref.render(splats, np.eye(4), *matrices(e), SIZE, depth=alone.depth, background=rgb(alone))
        covered = np.isfinite(alone.depth)
        assert covered.mean() > 0.1
        assert ref.psnr(rgb(both), np.clip(expected, 0, 1)) >= 35.0
        assert ref.psnr(rgb(both)[covered], np.clip(expected, 0, 1)[covered]) >= 35.0
        # without the depth test the picture would differ clearly where the box is
        unoccluded, _ = ref.render(splats, np.eye(4), *matrices(e), SIZE, background=rgb(alone))
        assert ref.psnr(rgb(both)[covered], np.clip(unoccluded, 0, 1)[covered]) < 30.0
    finally:
        e.release()


def test_splats_over_a_volume_behind_them(engine):
    """A volume behind the cloud is a transparent item drawn first: the splats blend over its image."""
    rng = np.random.default_rng(2)
    volume = om.Node("volume", [om.Translation(-1, -1, -3.5), om.Volume(rng.uniform(0.3, 1.0, (8, 8, 8)), spacing=0.3)])
    splats = cloud(1500, 0, seed=4, spread=0.6)
    alone = engine.render(scene_of(volume))
    both = engine.render(scene_of(volume, om.Node("cloud", [splats])))
    expected, _ = ref.render(splats, np.eye(4), *matrices(engine), SIZE, background=rgb(alone))
    assert np.isfinite(alone.depth).mean() > 0.05
    assert ref.psnr(rgb(both), np.clip(expected, 0, 1)) >= 35.0


def test_post_processing_blends_in_linear_light():
    e = om.gl.GLEngine(size=SIZE, samples=0)
    try:
        splats = cloud(3000, 1, seed=6)
        image = e.render(scene_of(om.Node("cloud", [splats]), extra=[om.gl.PostProcess([om.gl.Vignette(0.0)])]))
        linear, _ = ref.render(splats, np.eye(4), *matrices(e), SIZE, space="linear")
        display, _ = ref.render(splats, np.eye(4), *matrices(e), SIZE)
        assert ref.psnr(rgb(image), linear) >= 35.0
        assert ref.psnr(rgb(image), np.clip(display, 0, 1)) < ref.psnr(rgb(image), linear)
    finally:
        e.release()


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_stereo_eyes_match_the_reference_and_keep_their_order(pipeline):
    """Side by side: each eye (its own half of the frame, its own view) matches the reference; the deferred
    pipeline's eyes (drawn whole into an eye target, copied over the frame) match too."""
    e = om.gl.GLEngine(size=SIZE, samples=0, pipeline=pipeline)
    try:
        splats = cloud(2000, 1, seed=7)
        scene = scene_of(om.Node("cloud", [splats]))
        e.stereo = om.gl.Stereo("side-by-side", eye_separation=0.3, convergence=4.0)
        image = rgb(e.render(scene))
        half = SIZE[0] // 2
        view, proj = matrices(e)
        for sign, part in ((-1.0, image[:, :half]), (1.0, image[:, half:])):
            eye_view, eye_proj = eye_matrices(view, proj, half / SIZE[1], sign, 0.3, 4.0)
            expected, _ = ref.render(splats, np.eye(4), eye_view, eye_proj, (half, SIZE[1]))
            assert ref.psnr(part, np.clip(expected, 0, 1)) >= 35.0, sign
        geometry = _geometry(e)
        sorts = geometry.sorter.sorts
        e.render(scene)  # both eyes' orders are kept: a still stereo camera sorts nothing
        assert geometry.sorter.sorts == sorts
    finally:
        e.stereo = None
        e.release()


def _geometry(e: om.gl.GLEngine):
    return next(it.geometry for it in e.draw_items if it.state.kind == "splats")


def test_sorting_happens_only_when_the_view_or_the_splats_change(engine):
    splats = cloud(3000, 0, seed=8)
    node = om.Node("cloud", [splats])
    camera = om.Camera.look_at((0.6, 1.1, 4.2), (0, 0, 0), fov=40)
    scene = scene_of(node, camera=camera)
    engine.render(scene)
    geometry = _geometry(engine)
    assert geometry.sorter.sorts == 1
    engine.render(scene)
    assert geometry.sorter.sorts == 1  # same view: the order is kept
    camera.eye = (1.0, 1.0, 4.0)
    moved = engine.render(scene)
    assert geometry.sorter.sorts == 2
    expected, _ = ref.render(splats, np.eye(4), *matrices(engine), SIZE)
    assert ref.psnr(rgb(moved), np.clip(expected, 0, 1)) >= 35.0
    splats.positions[:, 0] += 0.5  # written in place: touch() tells the engine
    splats.touch()
    shifted = engine.render(scene)
    assert _geometry(engine) is not geometry and _geometry(engine).sorter.sorts == 1
    expected, _ = ref.render(splats, np.eye(4), *matrices(engine), SIZE)
    assert ref.psnr(rgb(shifted), np.clip(expected, 0, 1)) >= 35.0


@pytest.mark.gl_needs(version=430)
def test_the_gpu_sort_orders_back_to_front(engine):
    """The bitonic sort's output (read back) is the splats' indices by ascending view z, for counts that are
    not powers of two and larger than one shared-memory block."""
    assert painter.sort_method(engine) == "gpu bitonic"
    for n in (1, 1000, 5000, 70_001):
        splats = cloud(n, 0, seed=n)
        engine.render(scene_of(om.Node("cloud", [splats])))
        geometry = _geometry(engine)
        view, _ = matrices(engine)
        order_buffer = geometry.sorter.order(view, geometry.textures[0], geometry.width)
        order = np.frombuffer(order_buffer.read(), np.uint32)[:n]
        assert sorted(order.tolist()) == list(range(n))  # a permutation
        z = (splats.positions @ view[2, :3] + view[2, 3]).astype(np.float32)
        assert np.all(np.diff(z[order]) >= -1e-5)  # the GPU's z may differ from numpy's in the last bit


def test_the_numpy_fallback_draws_the_same_picture(monkeypatch):
    """Without compute shaders (OpenGL 4.1) the order comes from np.argsort: the same image."""
    splats = cloud(3000, 1, seed=9)
    scene = scene_of(om.Node("cloud", [splats]))
    images = []
    for compute in (True, False):
        monkeypatch.setattr(painter, "compute_available", lambda ctx, ok=compute: ok and ctx.version_code >= 430)
        e = om.gl.GLEngine(size=SIZE, samples=0)
        try:
            images.append(e.render(scene).array)
            assert painter.sort_method(e) == ("gpu bitonic" if compute and e.ctx.version_code >= 430 else "numpy")
        finally:
            e.release()
    assert np.abs(images[0].astype(int) - images[1].astype(int)).max() <= 1


def test_empty_and_replaced_splats(engine):
    empty = om.GaussianSplats(np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, 1, 3)))
    scene = scene_of(om.Node("cloud", [empty]))
    assert engine.render(scene).array[..., :3].max() == 0
    full = cloud(500, 0, seed=10)
    empty.update(**{name: getattr(full, name) for name in ("positions", "rotations", "scales", "opacities", "sh")})
    image = engine.render(scene)
    expected, _ = ref.render(empty, np.eye(4), *matrices(engine), SIZE)
    assert ref.psnr(rgb(image), np.clip(expected, 0, 1)) >= 35.0


def test_the_transparent_depth_pass_writes_the_depth_of_dense_splats(engine):
    """The forward technique's depth-only pass gives the image a depth where a splat is at least half opaque
    (as it does for transparent meshes), without drawing the splats a second time."""
    splat = om.GaussianSplats([[0, 0, 0]], [[1.0, 0, 0, 0]], [[0.4, 0.4, 0.4]], [0.6], [[[1.0, 1.0, 1.0]]])
    image = engine.render(scene_of(om.Node("s", [splat]), camera=om.Camera.look_at((0, 0, 4), (0, 0, 0), fov=30)))
    centre = image.depth[SIZE[1] // 2, SIZE[0] // 2]
    assert centre == pytest.approx(4.0, abs=0.01)
    assert not np.isfinite(image.depth[0, 0])
    # drawn once: the centre is colour * alpha (0.6), not 1 - (1 - 0.6)^2
    assert image.array[SIZE[1] // 2, SIZE[0] // 2, 0] / 255.0 == pytest.approx((0.5 + ref._sh.C0) * 0.6, abs=2 / 255)


def test_a_ply_through_gltf_and_usd_renders_the_same_image(tmp_path, engine):
    """Issue 28's file target: .ply -> omnirender -> glTF -> omnirender -> USD -> omnirender, each scene rendered
    in GL: the same picture (at most 2/255), and the picture of the arrays written."""
    pytest.importorskip("pxr")
    splats = cloud(3000, 3, seed=11)
    om.save_splats(splats, tmp_path / "capture.ply")
    first = om.Node(
        "cloud", [om.Translation(0.2, 0.0, 0.0), om.Rotation(20, (0, 1, 0)), om.load_splats(tmp_path / "capture.ply")]
    )
    om.export(om.Node("root", [first]), tmp_path / "capture.glb")
    second = om.load_gltf(tmp_path / "capture.glb")
    om.export(om.Node("root", [second]), tmp_path / "capture.usdc")
    third = om.load_usd(tmp_path / "capture.usdc")
    images = [engine.render(scene_of(root)).array[..., :3].astype(int) for root in (first, second, third)]
    assert images[0].std() > 10
    for other in images[1:]:
        assert np.abs(other - images[0]).max() <= 2
    original = engine.render(
        scene_of(om.Node("cloud", [om.Translation(0.2, 0.0, 0.0), om.Rotation(20, (0, 1, 0)), splats]))
    )
    assert np.abs(original.array[..., :3].astype(int) - images[0]).max() <= 2


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_anaglyph_eyes_keep_their_colour_masks(pipeline):
    """The pass's colour mask reaches the splat drawer: red is the left eye's image, green and blue the right's."""
    e = om.gl.GLEngine(size=SIZE, samples=0, pipeline=pipeline)
    try:
        scene = scene_of(om.Node("cloud", [cloud(1500, 0, seed=12)]))
        eyes = {}
        for mode in ("anaglyph", "left", "right"):
            e.stereo = om.gl.Stereo(mode, eye_separation=0.3, convergence=4.0)
            eyes[mode] = e.render(scene).array[..., :3].astype(int)
        assert np.abs(eyes["anaglyph"][..., 0] - eyes["left"][..., 0]).max() <= 1
        assert np.abs(eyes["anaglyph"][..., 1:] - eyes["right"][..., 1:]).max() <= 1
        assert np.abs(eyes["left"] - eyes["right"]).max() > 50  # the eyes differ: the test can fail
    finally:
        e.stereo = None
        e.release()
