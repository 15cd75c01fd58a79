"""Light fields: calibrated views, files, frusta bounds, the blending field, and lumigraph rendering against the
GL render of the real scene."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import omnirender as om
from omnirender.compositing.lightfield import blending

from .scenes import CAPTURE, capture_cameras, cube, novel_cameras, textured_scene

C = om.compositing


def view_of(camera: om.Camera, size=(40, 30), depth: float = 5.0) -> C.LightFieldView:
    w, h = size
    image = np.full((h, w, 4), 200, np.uint8)
    return C.LightFieldView.from_camera(camera, image, np.full((h, w), depth, np.float32))


# --- data ----------------------------------------------------------------------------------------------
def test_views_follow_the_camera_conventions():
    camera = om.Camera.look_at((1, 2, 6), (0, 0, 0), fov=40, near=0.5, far=50)
    view = view_of(camera, (64, 48))
    assert np.allclose(view.view, camera.view_matrix())
    assert np.allclose(view.projection(0.5, 50), camera.projection_matrix(64 / 48))
    assert np.allclose(view.center, (1, 2, 6)) and np.allclose(view.axis, -np.array([1, 2, 6]) / math.sqrt(41))
    back = view.camera(0.5, 50)
    assert np.allclose(back.view_matrix(), camera.view_matrix()) and back.fov == pytest.approx(40)
    # a depth sample unprojected to the world projects back onto its pixel centre
    points = view.world_points(step=7)
    clip = np.c_[points, np.ones(len(points))] @ (camera.projection_matrix(64 / 48) @ camera.view_matrix()).T
    ndc = clip[:, :2] / clip[:, 3:]
    px = (ndc[:, 0] + 1) / 2 * 64
    assert np.allclose(np.sort(np.unique(np.round(px - 0.5))), np.arange(0, 64, 7))


def test_views_validate_their_data():
    camera = om.Camera.look_at((0, 0, 5))
    good = dict(image=np.zeros((4, 4, 4), np.uint8), depth=np.ones((4, 4)), intrinsics=(4, 4, 2, 2), view=np.eye(4))
    with pytest.raises(ValueError, match="uint8 RGBA"):
        C.LightFieldView(**{**good, "image": np.zeros((4, 4, 4), np.float32)})
    with pytest.raises(ValueError, match="like the image"):
        C.LightFieldView(**{**good, "depth": np.ones((3, 4))})
    with pytest.raises(ValueError, match="focal lengths"):
        C.LightFieldView(**{**good, "intrinsics": (0, 4, 2, 2)})
    with pytest.raises(ValueError, match="rigid"):
        C.LightFieldView(**{**good, "view": np.diag([2.0, 1, 1, 1])})
    view = C.LightFieldView(**{**good, "depth": np.array([[np.nan, -1, 0, np.inf]] * 4)})
    assert not view.valid().any()  # nan, negative, zero and inf all mean "nothing seen"
    with pytest.raises(ValueError, match="at least 2 views"):
        C.LightField([view_of(camera)])
    with pytest.raises(ValueError, match="no view has any valid depth"):
        C.LightField([view, view])
    with pytest.raises(TypeError, match="not a LightFieldView"):
        C.LightField([view_of(camera), "photo.png"])
    with pytest.raises(ValueError, match="orthographic"):
        C.LightFieldView.from_camera(om.Camera.orthographic((0, 0, 5)), good["image"], good["depth"])


def test_a_light_field_folder_round_trip_and_bad_folders(tmp_path, small_light_field):
    folder = small_light_field.save(tmp_path / "lf")
    spec = json.loads((folder / "cameras.json").read_text())
    assert spec["format"] == "omnirender.lightfield/1" and len(spec["views"]) == len(small_light_field)
    back = C.LightField.load(folder)
    for a, b in zip(small_light_field.views, back.views, strict=True):
        assert np.array_equal(a.image, b.image) and np.array_equal(a.depth, b.depth)
        assert np.allclose(a.view, b.view) and a.intrinsics == b.intrinsics
    with pytest.raises(FileNotFoundError, match="cameras.json"):
        C.LightField.load(tmp_path)
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "cameras.json").write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        C.LightField.load(tmp_path / "bad")
    spec["views"][0]["image"] = "../../etc/passwd"
    (folder / "cameras.json").write_text(json.dumps(spec))
    with pytest.raises(ValueError, match="outside the light-field folder"):
        C.LightField.load(folder)
    (folder / "cameras.json").write_text(json.dumps({"format": "other", "views": []}))
    with pytest.raises(ValueError, match="format"):
        C.LightField.load(folder)


def test_bounds_are_the_box_of_the_intersection_of_the_frusta(small_light_field):
    lf = small_light_field
    lo, hi = lf.bounds
    rng = np.random.default_rng(3)
    margin = 0.5 * (hi - lo)
    points = rng.uniform(lo - margin, hi + margin, size=(150_000, 3))
    inside = np.ones(len(points), bool)
    for view in lf.views:
        planes = view.frustum_planes()
        inside &= np.all(points @ planes[:, :3].T <= planes[:, 3], axis=1)
    assert inside.sum() > 1000
    found = points[inside]
    assert np.all(found >= lo - 1e-6) and np.all(found <= hi + 1e-6)  # every point of the intersection is inside
    extent = hi - lo
    assert np.all(found.min(0) - lo < 0.05 * extent) and np.all(hi - found.max(0) < 0.05 * extent)  # and tight


# --- the blending field ------------------------------------------------------------------------------
def ring_light_field(count: int = 8) -> C.LightField:
    cameras = [om.Camera.look_at((6 * math.sin(a), 0.5, 6 * math.cos(a)), (0, 0, 0), fov=40)
               for a in np.radians(np.linspace(-40, 40, count))]  # fmt: skip
    return C.LightField([view_of(c, (64, 48), depth=np.linalg.norm(c.eye)) for c in cameras])


def test_blending_weights_are_normalised_epipole_consistent_and_limited_to_k():
    lf = ring_light_field()
    points = np.random.default_rng(1).uniform(-0.5, 0.5, size=(50, 3))
    eye = np.array([0.3, 0.4, 6.0])
    weights = blending.blending_weights(lf, points, eye, eye / np.linalg.norm(eye), False, k=4)
    assert weights.shape == (8, 50) and np.allclose(weights.sum(0), 1, atol=1e-5)
    assert np.all((weights > 0).sum(0) <= 3)  # the k-th best sets the threshold: k - 1 contribute
    for i in (0, 3, 7):  # at a camera's centre that camera takes (almost) everything
        at = lf.views[i].center
        w = blending.blending_weights(lf, points, at, at / np.linalg.norm(at), False, k=4)
        assert np.all(w[i] > 0.99)
    # a point no camera sees (behind all of them) gets no weight; one hidden in a depth map neither
    behind = np.array([[0.0, 0.0, 30.0]])
    assert blending.blending_weights(lf, behind, eye, eye, False).sum() == 0
    far = np.array([[0.0, 0.0, -3.0]])  # the depth maps saw a surface at the origin's distance: hidden
    assert blending.blending_weights(lf, far, eye, eye, False, check=np.array([True])).sum() == 0
    assert blending.blending_weights(lf, far, eye, eye, False, check=np.array([False])).sum() == pytest.approx(1)


def test_the_screen_mesh_keeps_triangles_touching_valid_vertices(small_light_field):
    lf = small_light_field
    camera = novel_cameras()[0]
    size = (160, 120)
    view, proj = camera.view_matrix(), camera.projection_matrix(size[0] / size[1])
    eye, toward, ortho = blending.eye_of(view, proj)
    chosen = blending.relevant_views(lf, eye, toward, ortho, 4)
    assert len(set(chosen)) == 4
    depth = blending.warp_depth(lf, chosen, view, proj, size)
    mesh = blending.screen_mesh(lf, view, proj, size, depth, cell=8)
    assert mesh.grid == (20, 15) and len(mesh.positions) == 21 * 16
    assert 0 < mesh.valid.sum() < len(mesh.valid)  # the scene and some empty sky
    assert np.all(mesh.valid[mesh.triangles].any(axis=1))
    all_invalid = ~mesh.valid[np.array([[i, i + 1, i + 22] for i in range(20 * 15)])].any(axis=1)
    assert all_invalid.any() and len(mesh.triangles) < 2 * 20 * 15  # some triangles were removed
    # invalid vertices get a depth within the light field's box (between its nearest and farthest corner)
    from omnirender.geometry.bounds import corners

    box = corners(*lf.bounds) @ view[:3, :3].T + view[:3, 3]
    used = np.unique(mesh.triangles)
    guessed = mesh.positions[used][~mesh.valid[used]].astype(float)
    distance = -(guessed @ view[2, :3] + view[2, 3])
    assert len(guessed) and np.all((distance >= -box[:, 2].max() - 1e-3) & (distance <= -box[:, 2].min() + 1e-3))


# --- rendering ---------------------------------------------------------------------------------------
@pytest.mark.gl
def test_light_field_colour_and_depth_agree_with_the_scene(small_light_field):
    camera = novel_cameras()[1]
    size = (200, 150)
    renderer = C.LightFieldRenderer(small_light_field)
    img = renderer.render(size, camera=camera, background=(0, 0, 0, 0), samples=0)
    ref = om.render(om.Node.transient([camera, textured_scene()]), size=size, background=(0, 0, 0, 0))
    drawn = np.isfinite(img.depth)
    assert np.array_equal(drawn, img.array[..., 3] > 0)  # colour exactly where depth is
    both = drawn & np.isfinite(ref.depth)
    assert both.sum() > 0.9 * np.isfinite(ref.depth).sum()  # it covers the scene
    assert np.median(np.abs(img.depth[both] - ref.depth[both]) / ref.depth[both]) < 0.005
    assert renderer.stats["vertices"] == 26 * 20 and renderer.stats["triangles"] > 0  # a vertex every 8 pixels
    with pytest.raises(TypeError, match="LightField"):
        C.LightFieldRenderer("views/")
    with pytest.raises(ValueError, match="cell"):
        C.LightFieldRenderer(small_light_field, cell=1)
    with pytest.raises(ValueError, match="tolerance"):
        C.LightFieldRenderer(small_light_field, tolerance=0)


@pytest.mark.gl
def test_a_light_field_casts_the_shadow_of_what_it_shows(small_light_field):
    """In a shadow group, the light field's shadow on a floor matches the shadow of the real geometry."""
    axis = np.asarray(CAPTURE["axis"]) / np.linalg.norm(CAPTURE["axis"])
    light = om.PointLight(position=tuple(np.asarray(CAPTURE["center"]) + 7.0 * axis))  # seen from inside the cap
    floor = om.Node(
        "floor", [light, om.Material(diffuse=(0.9, 0.9, 0.9)), om.Box(size=(12, 0.05, 12), center=(0, -1.0, 0))]
    )
    camera = om.Camera.look_at((0, 9, 2), (0, -1, -3), fov=50)  # from above: the shadow behind the objects
    size = (160, 120)

    def darkened(children):
        lit = C.ShadowGroup(light, children, enabled=False).render(size, camera=camera, samples=0)
        shaded = C.ShadowGroup(light, children, resolution=512).render(size, camera=camera, samples=0)
        floor_only = C.SceneRenderer(floor).render(size, camera=camera, samples=0)
        on_floor = np.isfinite(lit.depth) & np.isclose(lit.depth, floor_only.depth, rtol=1e-4)
        return on_floor & (shaded.array[..., :3].sum(2) < 0.7 * lit.array[..., :3].sum(2))

    real = darkened([C.SceneRenderer(floor), C.SceneRenderer(textured_scene())])
    field = darkened([C.SceneRenderer(floor), C.LightFieldRenderer(small_light_field)])
    assert real.sum() > 200
    iou = (real & field).sum() / (real | field).sum()
    assert iou > 0.8, iou


@pytest.mark.gl
@pytest.mark.slow
def test_lumigraph_rendering_of_novel_views_reaches_28_db_on_the_foreground(capsys):
    """20 cameras on a sphere cap, novel views inside the captured region, 640x480, against the real scene."""
    from omnirender.gl import GLEngine

    size = (640, 480)
    scene = textured_scene()
    lf = C.capture_light_field(scene, capture_cameras(20), size=size)
    renderer = C.LightFieldRenderer(lf)
    results = []
    with GLEngine(size=size) as engine:
        for camera in novel_cameras():
            reference = engine.render(om.Node.transient([camera, scene]), background=(0, 0, 0, 1))
            tree = renderer.as_scene("gl", size, camera)
            engine.render(tree, background=(0, 0, 0, 1))  # the first frame uploads the light field
            image = engine.render(tree, background=(0, 0, 0, 1))
            foreground = np.isfinite(reference.depth)
            error = (image.array[..., :3].astype(float) - reference.array[..., :3].astype(float))[foreground]
            results.append((10 * np.log10(255**2 / (error**2).mean()), renderer.stats["frame_ms"]))
    with capsys.disabled():
        print("\nlumigraph PSNR on the foreground / frame time at 640x480:",
              ", ".join(f"{p:.1f} dB / {t:.0f} ms" for p, t in results))  # fmt: skip
    assert all(psnr >= 28.0 for psnr, _ in results), results


@pytest.mark.mitsuba
def test_capture_with_mitsuba_gives_depth_and_premultiplied_colour():
    cameras = [om.Camera.look_at((x, 0.5, 5), (0, 0, 0), fov=35) for x in (-0.5, 0.5)]
    lf = C.capture_light_field(cube(light=True), cameras, size=(32, 24), engine="mitsuba", spp=4)
    view = lf.views[0]
    assert view.valid().any() and not view.valid().all()
    assert (view.image[~view.valid()][:, 3] == 0).mean() > 0.9  # nothing seen: transparent (edges aside)
    assert np.all(view.image[..., :3] <= view.image[..., 3:4])  # colour premultiplied by coverage


# --- several light fields ------------------------------------------------------------------------------
def _arc(t: float) -> np.ndarray:
    """A direction on the great circle from field A's axis (t = 0) to field B's (t = 1), 55 degrees apart."""
    a, b = np.array([-0.55, 0.35, 1.0]), np.array([0.55, 0.35, 1.0])
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    angle = np.arccos(a @ b)
    return (np.sin((1 - t) * angle) * a + np.sin(t * angle) * b) / np.sin(angle)


@pytest.mark.gl
def test_a_camera_moving_between_two_light_fields_passes_smoothly_from_one_to_the_other():
    """Smooth transitions between several light fields (the compositing paper): two fields captured 55 degrees
    apart, drawn as one.  At either end the image is that field's alone; between adjacent camera positions
    (0.22 degrees apart) the image changes by at most 1.5/255 on average anywhere on the way (the real scene
    changes by about 0.45/255 there), where switching from one field to the other halfway would jump by over
    5/255 (14/255 on the foreground measured)."""
    center, radius, size = (0.0, -0.2, 0.0), 7.0, (200, 150)
    fields = [
        C.capture_light_field(textured_scene(), C.sphere_cap_cameras(center, radius, 10, cap=10.0,
                                                                     axis=tuple(_arc(t)), fov=35), size=size)
        for t in (0.0, 1.0)
    ]  # fmt: skip
    both = C.LightFieldRenderer(fields)
    assert len(both.light_field) == 20 and len(C.LightField.combine(*fields)) == 20
    kw = dict(background=(0, 0, 0, 0), samples=0)

    def camera(t: float) -> om.Camera:
        return om.Camera.look_at(tuple(np.asarray(center) + radius * _arc(t)), center, fov=35)

    def image(renderer: C.LightFieldRenderer, t: float) -> np.ndarray:
        return renderer.render(size, camera=camera(t), **kw).array.astype(float)

    for end, field in ((0.0, fields[0]), (1.0, fields[1])):
        assert np.abs(image(both, end) - image(C.LightFieldRenderer(field), end)).max() <= 1, end
    step = 0.004
    changes = [np.abs(image(both, t + step) - image(both, t)).mean() for t in np.linspace(0.0, 1.0 - step, 11)]
    assert max(changes) <= 1.5, changes
    switch = np.abs(image(C.LightFieldRenderer(fields[0]), 0.5) - image(C.LightFieldRenderer(fields[1]), 0.5))
    assert switch.mean() > 5.0  # what a transition that switches fields would show
    with pytest.raises(TypeError, match="field 1 is a str"):
        C.LightField.combine(fields[0], "views/")
