"""The viewer driving the GL engine: images, passes, caching, lights, highlight, picking."""

from __future__ import annotations

import io

import numpy as np
import pytest

import omnirender as om
from omnirender.viewer import TRANSPARENT, TWO_DIMENSIONAL, Viewer

pytestmark = pytest.mark.gl

SIZE = (160, 120)


def scene_with_sphere(color=(0.9, 0.2, 0.2)) -> om.Node:
    scene = om.Node("scene")
    body = scene.add(om.Node("body"))
    body.add(om.Material(diffuse=color))
    body.add(om.Sphere(radius=1.0))
    return scene


class Ball:
    """A renderable sphere at a position cached by prerender."""

    def __init__(self, position, color, hints=0, radius=0.5, opacity=1.0):
        self.position = np.array(position, dtype=float)
        self.color = color
        self.hints = hints
        self.radius = radius
        self.opacity = opacity
        self.renders = 0
        self._cached = self.position.copy()

    def prerender(self, render_list):
        self._cached = self.position.copy()

    def render(self, renderer, flags):
        self.renders += 1
        renderer.push(om.Translation(*self._cached))
        renderer.push(om.Material(diffuse=self.color, opacity=self.opacity))
        renderer.eval(om.Sphere(radius=self.radius))
        renderer.pop(om.Material)
        renderer.pop(om.Transform)

    def update_bounds(self, pmin, pmax):
        np.minimum(pmin, self.position - self.radius, out=pmin)
        np.maximum(pmax, self.position + self.radius, out=pmax)

    def render_hints(self):
        return self.hints


@pytest.fixture
def viewer():
    v = Viewer(size=SIZE, samples=0)
    yield v
    v.close()


def red(img):
    a = img.array.astype(int)
    return (a[:, :, 0] > a[:, :, 1] + 60) & (a[:, :, 0] > a[:, :, 2] + 60)


def test_node_fits_in_view_and_background_colour(viewer):
    viewer.add_renderable(scene_with_sphere())
    viewer.background = (0.0, 0.0, 1.0)
    viewer.auto_fit()
    img = viewer.rerender()
    assert img.size == SIZE and img.engine == "gl"
    mask = red(img)
    assert 0.1 * mask.size < mask.sum() < 0.6 * mask.size
    assert not (mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())
    assert img.pixel(0, 0)[:3] == (0, 0, 255)
    assert viewer.image() is img
    png = viewer._repr_png_()
    assert png.startswith(b"\x89PNG")
    from PIL import Image

    assert Image.open(io.BytesIO(png)).size == SIZE


def test_viewer_matches_om_render_with_the_same_camera_and_lights(viewer):
    scene = scene_with_sphere()
    scene.add(om.PointLight(position=(3, 4, 5)))
    cam = om.Camera.look_at(eye=(1, 2, 5), center=(0, 0, 0), fov=35, near=1, far=20)
    viewer.clear_lights()
    viewer.add_renderable(scene)
    viewer.set_camera(cam)
    viewer.background = (0.1, 0.1, 0.1)
    mine = viewer.rerender().array.astype(int)
    with_cam = om.Node("root", [cam, om.Background((0.1, 0.1, 0.1)), scene])
    ref = om.render(with_cam, engine="gl", size=SIZE, samples=0).array.astype(int)
    assert np.abs(mine - ref).max() <= 2


def test_repaint_calls_render_of_every_custom_renderable(viewer):
    """The ArtiSynth contract: prerender caches state, every repaint redraws it with render()."""
    ball = Ball((0, 0, 0), (0.9, 0.1, 0.1))
    viewer.add_renderable(ball)
    viewer.auto_fit()
    viewer.rerender()
    assert ball.renders == 1
    viewer.camera.orbit(40, 10)
    moved = viewer.repaint()
    assert ball.renders == 2  # repaint calls render() again
    assert red(moved).sum() > 100
    ball.position = np.array([0.6, 0.0, 0.0])
    same = viewer.repaint()  # no prerender: render() draws the cached position
    assert ball.renders == 3 and np.array_equal(same.array, moved.array)
    after = viewer.rerender()
    assert ball.renders == 4 and not np.array_equal(after.array, moved.array)


class Blinker(Ball):
    """A renderable whose render() draws something else every time (what a replayed cache would miss)."""

    def render(self, renderer, flags):
        self._cached = np.array([0.0, 0.0, 0.0]) if self.renders % 2 == 0 else np.array([0.0, 5.0, 0.0])
        super().render(renderer, flags)


def test_repaint_shows_what_render_draws_each_time_beside_replayed_nodes(viewer):
    blinker = Blinker((0, 0, 0), (0.9, 0.1, 0.1))
    viewer.add_renderable(blinker)
    viewer.add_renderable(om.Node("floor", [om.Material(diffuse=(0.1, 0.1, 0.9)), om.Box(size=(4, 0.1, 4))]))
    viewer.set_eye_to_world((0, 1, 8), (0, 0, 0), (0, 1, 0))
    shown = [red(viewer.rerender()).sum()] + [red(viewer.repaint()).sum() for _ in range(3)]
    assert blinker.renders == 4
    assert shown[0] > 100 and shown[2] > 100  # at the origin
    assert shown[1] < shown[0] and shown[3] < shown[0]  # moved up, mostly out of the picture


def test_node_renderables_replay_their_draw_list(viewer):
    import omnirender.viewer.renderable as rmod

    viewer.add_renderable(scene_with_sphere())
    viewer.auto_fit()
    viewer.rerender()
    runs = []
    original = rmod._draw
    rmod._draw = lambda *a: (runs.append(1), original(*a))
    try:
        viewer.camera.orbit(40, 10)
        moved = viewer.repaint()
    finally:
        rmod._draw = original
    assert runs == []  # the installed list is drawn again, nodes are not traversed
    assert red(moved).sum() > 100


def test_two_dimensional_pass_draws_over_nearer_geometry(viewer):
    viewer.set_eye_to_world((0, 0, 10), (0, 0, 0), (0, 1, 0))
    viewer.set_perspective(35, 1, 50)
    front = Ball((0, 0, 2), (0.1, 0.1, 0.9), radius=1.5)
    behind = Ball((0, 0, -2), (0.9, 0.1, 0.1), radius=0.5)
    viewer.add_renderable(front)
    viewer.add_renderable(behind)
    assert red(viewer.rerender()).sum() == 0  # hidden behind the blue ball
    behind.hints = TWO_DIMENSIONAL
    assert red(viewer.rerender()).sum() > 50  # drawn after everything with the depth test off


def test_transparent_renderable_blends_over_opaque(viewer):
    viewer.set_eye_to_world((0, 0, 10), (0, 0, 0), (0, 1, 0))
    viewer.add_renderable(Ball((0, 0, -1), (0.9, 0.1, 0.1), radius=1.0))
    glass = viewer.add_renderable(Ball((0, 0, 1), (0.1, 0.1, 0.9), hints=TRANSPARENT, radius=1.5, opacity=0.5))
    r, g, b, _ = viewer.rerender().pixel(SIZE[0] // 2, SIZE[1] // 2)
    assert r > 40 and b > 40  # both colours contribute
    glass.opacity = 1.0
    r2, _, b2, _ = viewer.rerender().pixel(SIZE[0] // 2, SIZE[1] // 2)
    assert r2 < r - 20 and b2 > b  # the red ball no longer shows through


def test_lights_change_at_next_repaint_and_highlight(viewer):
    scene = scene_with_sphere((0.6, 0.6, 0.6))
    viewer.add_renderable(scene)
    viewer.auto_fit()
    lit = viewer.rerender().array[SIZE[1] // 2, SIZE[0] // 2, :3].astype(int)
    assert abs(lit[0] - lit[2]) < 10  # grey under the white default lights
    viewer.clear_lights()
    lamp = om.PointLight(position=(0, 0, 10), color=(1, 0, 0))
    viewer.add_light(lamp, space="camera")
    reddish = viewer.repaint().array[SIZE[1] // 2, SIZE[0] // 2, :3].astype(int)
    assert reddish[0] > reddish[1] + 40
    viewer.remove_light(lamp)
    viewer.add_light(om.DirectionalLight(direction=(0, 0, -1), color=(0, 0, 1)), space="camera")
    bluish = viewer.repaint().array[SIZE[1] // 2, SIZE[0] // 2, :3].astype(int)
    assert bluish[2] > bluish[0] + 40
    viewer.remove_light(0)
    viewer.add_light(lamp, space="camera")
    reddish = viewer.repaint().array[SIZE[1] // 2, SIZE[0] // 2, :3].astype(int)
    viewer.set_highlight(scene)
    highlighted = viewer.repaint().array[SIZE[1] // 2, SIZE[0] // 2, :3].astype(int)
    assert not np.array_equal(highlighted, reddish)


def test_wireframe_override_draws_fewer_pixels(viewer):
    viewer.add_renderable(scene_with_sphere())
    viewer.auto_fit()
    filled = red(viewer.rerender()).sum()
    viewer.wireframe = True
    wire = red(viewer.repaint()).sum()
    assert 0 < wire < 0.8 * filled


def test_pick_highlight_overlay(viewer):
    from omnirender.viewer.picking import pick_in_viewer

    scene = om.Node("scene")
    left = scene.add(om.Node("left"))
    left.add(om.Translation(-1.5, 0, 0))
    left.add(om.Material(diffuse=(0.2, 0.2, 0.9)))
    left.add(om.Box(size=(1, 1, 1)))
    right = scene.add(om.Node("right"))
    right.add(om.Translation(1.5, 0, 0))
    right.add(om.Material(diffuse=(0.2, 0.2, 0.9)))
    right.add(om.Sphere(radius=0.6))
    viewer.add_renderable(scene)
    viewer.set_eye_to_world((0, 0, 8), (0, 0, 0), (0, 1, 0))
    before = viewer.rerender()
    x, y = 120, 60  # the sphere on the right
    hit = pick_in_viewer(viewer, scene, x, y)
    assert hit is not None and hit.path == "/scene/right" and isinstance(hit.shape, om.Sphere)
    assert pick_in_viewer(viewer, None, 80, 5) is None
    viewer.set_picked(hit)
    after = viewer.rerender()
    p0, p1 = before.pixel(x, y), after.pixel(x, y)
    assert p1[0] > p0[0] + 40 and p1[1] > p0[1] + 40 and p1[2] < p0[2]  # yellow-ish overlay on the blue sphere
    assert after.pixel(40, 60) == before.pixel(40, 60)  # the box is untouched
    viewer.set_picked(None)
    assert np.array_equal(viewer.rerender().array, before.array)


def test_pick_highlight_follows_the_path_of_a_shared_node():
    from omnirender.viewer.picking import shape_world_matrix

    wheel = om.Node("wheel")
    wheel.add(om.Translation(0, 1, 0))
    disk = wheel.add(om.Cylinder(radius=0.5, height=0.2))
    scene = om.Node("car")
    left = scene.add(om.Node("left", [om.Translation(-2, 0, 0)]))
    right = scene.add(om.Node("right", [om.Translation(2, 0, 0)]))
    left.add(wheel)
    right.add(wheel)
    assert np.allclose(shape_world_matrix(scene, "/car/right/wheel", disk)[:3, 3], (2, 1, 0))
    assert np.allclose(shape_world_matrix(scene, "/car/left/wheel", disk)[:3, 3], (-2, 1, 0))


def moving_sphere_scene():
    scene = om.Node("scene")
    body = scene.add(om.Node("body"))
    move = body.add(om.Translation(-1.0, 0, 0))
    body.add(om.Material(diffuse=(0.9, 0.1, 0.1)))
    body.add(om.Sphere(radius=0.6))
    return scene, body, move


def red_centroid_x(img):
    return float(np.nonzero(red(img))[1].mean())


@pytest.mark.parametrize("how", ["mutate", "replace"])
def test_node_repaint_draws_the_prerendered_state(viewer, how):
    scene, body, move = moving_sphere_scene()
    viewer.add_renderable(scene)
    viewer.set_eye_to_world((0, 0, 8), (0, 0, 0), (0, 1, 0))
    first = viewer.rerender()
    x0 = red_centroid_x(first)
    if how == "mutate":
        move.offset = (1.0, 0, 0)
    else:
        body.remove(move)
        body.insert(0, om.Translation(1.0, 0, 0))
    assert np.array_equal(viewer.repaint().array, first.array)  # repaint: what was prerendered
    viewer.camera.orbit(0, 0)
    viewer.set_highlight(scene)  # even a repaint that has to traverse again draws the snapshot
    viewer.set_highlight(scene, False)
    viewer.wireframe = True
    wire = viewer.repaint()
    assert abs(red_centroid_x(wire) - x0) < 3
    viewer.wireframe = False
    after = viewer.rerender()
    assert red_centroid_x(after) > x0 + 20  # rerender shows the move


def test_text_in_a_node_keeps_depth_testing_for_its_3d_shapes(viewer):
    # a red sphere behind a blue box, plus a Text label in the same node
    scene = om.Node("scene")
    scene.add(om.Node("back", [om.Translation(0, 0, -2), om.Material(diffuse=(0.9, 0.1, 0.1)), om.Sphere(radius=0.8)]))
    scene.add(
        om.Node("front", [om.Translation(0, 0, 1), om.Material(diffuse=(0.1, 0.1, 0.9)), om.Box(size=(2.5, 2.5, 0.5))])
    )
    viewer.set_eye_to_world((0, 0, 10), (0, 0, 0), (0, 1, 0))
    viewer.set_perspective(35, 1, 50)
    viewer.add_renderable(scene)
    without = viewer.rerender()
    assert red(without).sum() == 0  # hidden by the box
    scene.add(om.Text("label", (0, 2.5, 0), 14))
    with_text = viewer.rerender()
    assert red(with_text).sum() == 0  # still hidden: only the text is drawn without depth test
    lists = viewer.render_list
    assert len(lists.opaque) == 1 and len(lists.opaque_2d) == 1
    assert not np.array_equal(with_text.array, without.array)  # the label is drawn


def test_one_translucent_shape_does_not_make_the_whole_node_transparent(viewer):
    scene = om.Node("scene")
    scene.add(om.Node("solid", [om.Material(diffuse=(0.9, 0.1, 0.1)), om.Sphere(radius=0.5)]))
    scene.add(om.Node("glass", [om.Translation(1.5, 0, 0), om.Material(diffuse=(0.1, 0.1, 0.9), opacity=0.4),
                                 om.Box(size=(1, 1, 1))]))  # fmt: skip
    viewer.add_renderable(scene)
    viewer.set_eye_to_world((0, 0, 8), (0, 0, 0), (0, 1, 0))
    img = viewer.rerender()
    lists = viewer.render_list
    assert len(lists.opaque) == 1 and len(lists.transparent) == 1
    assert red(img).sum() > 100
    # the translucent part still carries the scoped attributes above it: box at x = +1.5, bluish
    part = lists.transparent[0]
    assert part.node is scene and part.render_hints() == TRANSPARENT
    x, y = int(SIZE[0] / 2 + 1.5 * SIZE[1] / (2 * 8 * np.tan(np.radians(17.5)))), SIZE[1] // 2
    r, g, b, _ = img.pixel(x, y)
    assert b > r + 20


def test_zoom_moves_near_and_far_with_the_eye(viewer):
    viewer.add_renderable(om.Node("s", [om.Material(diffuse=(0.9, 0.1, 0.1)), om.Sphere(radius=1)]))
    viewer.set_eye_to_world((3, 2, 4), (0, 0, 0), (0, 1, 0))
    viewer.auto_fit()
    fitted = red(viewer.rerender()).sum()
    centre = (SIZE[0] // 2, SIZE[1] // 2)
    coverage = [fitted]
    for _ in range(8):  # wheel notches out: the sphere shrinks but is never cut by the far plane
        viewer.camera.zoom(1 / 0.9)
        img = viewer.repaint()
        coverage.append(red(img).sum())
        assert img.pixel(*centre)[0] > 150
    assert all(a > b > 0 for a, b in zip(coverage, coverage[1:], strict=False))
    viewer.auto_fit()
    for _ in range(8):  # notches in: the sphere grows and its front is never cut by the near plane
        viewer.camera.zoom(0.9)
        img = viewer.repaint()
        assert img.pixel(*centre)[0] > 150, viewer.camera.view_plane_distance
    assert red(img).sum() > 3 * fitted
    assert 0 < viewer.view_plane_distance < viewer.far_plane_distance


def test_open_scene_adopts_the_scene_background(viewer):
    from omnirender.viewer.window import open_scene

    scene = scene_with_sphere()
    scene["/scene/body"].add(om.Background((0.0, 0.6, 0.2)))
    open_scene(viewer, scene)
    assert viewer.background == (0.0, 0.6, 0.2, 1.0)
    img = viewer.rerender()
    assert img.pixel(0, 0)[:3] == (0, 153, 51)
    plain = Viewer(size=SIZE, samples=0)
    try:
        open_scene(plain, scene_with_sphere())  # no Background: the viewer's default stays
        assert plain.background == Viewer(size=SIZE, engine=om.Engine()).background
    finally:
        plain.close()
