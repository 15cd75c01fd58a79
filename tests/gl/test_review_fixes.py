"""Regression tests for review findings on the GL engine: blend order, segment order, resources, clipping, errors."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(96, 72), samples=0)
    yield e
    e.release()


def two_transparent_spheres(separate: bool) -> om.Node:
    """Red sphere behind, blue sphere in front, both 50% opaque and unlit (emission only), same mesh."""
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6), center=(0, 0, 0), fov=40))
    s.add(om.AmbientLight(intensity=0.0))
    for i, (color, z) in enumerate((((1, 0, 0), -0.6), ((0, 0, 1), 0.6))):
        n = s.add(om.Node(f"t{i}"))
        if separate and i:
            # a different (no-op) draw state: the two spheres cannot share one draw call
            n.add(om.gl.PolygonOffset(0.0, 0.0))
        n.add(om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), specular=(0, 0, 0), emission=color, opacity=0.5))
        n.add(om.Sphere(center=(0.35 * (1 if i else -1), 0, z), radius=0.9))
    return s


def test_transparent_instances_of_one_mesh_blend_back_to_front(engine):
    merged = engine.render(two_transparent_spheres(False), background=(1, 1, 1)).array.astype(int)
    split = engine.render(two_transparent_spheres(True), background=(1, 1, 1)).array.astype(int)
    assert np.abs(merged - split).max() <= 2
    # analytic overlap colour at the centre, where both spheres cover the pixel twice (back and front faces):
    # white, then red back and front face, then blue back and front face, each blended "over" with alpha 0.5
    c = np.array([1.0, 1.0, 1.0])
    for color in ((1, 0, 0), (1, 0, 0), (0, 0, 1), (0, 0, 1)):
        c = 0.5 * np.asarray(color, float) + 0.5 * c
    expected = np.round(c * 255)
    assert np.abs(merged[36, 48, :3] - expected).max() <= 6, (merged[36, 48], expected)


def test_plain_shapes_after_a_special_state_shape_are_drawn_after_it(engine):
    """A green box (plain), a red sphere without depth test, then a blue box in front: blue must win."""
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6)))
    x = s.add(om.Node("x"))
    x.add(om.Color(0, 1, 0))
    x.add(om.Box(size=(0.5, 0.5, 0.5), center=(-2, 0, 0)))  # same mesh as the blue box: would share its batch
    sp = s.add(om.Node("s"))
    sp.add(om.gl.DepthTest(False))
    sp.add(om.Color(1, 0, 0))
    sp.add(om.Sphere(radius=1, center=(0, 0, -1)))
    y = s.add(om.Node("y"))
    y.add(om.Color(0, 0, 1))
    y.add(om.Box(size=(1, 1, 1), center=(0, 0, 1)))
    r, g, b, _ = engine.render(s).pixel(48, 36)
    assert b > 200 and r < 50, (r, g, b)


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
def test_transparent_shapes_with_per_frame_state_keep_buffers_bounded(engine):
    """An animated clip plane through a transparent sphere and a per-frame texture / draw style leak nothing."""
    from omnirender.gl.engine.resources import live_buffers

    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 0, 4)))
    clipped = scene.add(om.Node("clipped"))
    clipped.add(om.Material(diffuse=(1, 0, 0), opacity=0.5))
    plane = clipped.add(om.ClipPlane(normal=(1, 0, 0), offset=0.0))
    clipped.add(om.Sphere(radius=0.8))
    holder = scene.add(om.Node("holder"))
    rng = np.random.default_rng(2)
    counts = []
    for frame in range(40):
        plane.offset = -0.5 + frame / 40.0
        holder.clear()
        holder.add(om.Material(diffuse=(0, 0, 1), opacity=0.5))
        holder.add(om.Texture(rng.integers(0, 255, (4, 4, 3)).astype(np.uint8)))
        holder.add(om.DrawStyle(line_width=float(frame + 1)))
        holder.add(om.Box(center=(0.5, 0, 0)))
        engine.render(scene, read_depth=False)
        counts.append((engine.live_buffers(), live_buffers(engine.ctx), engine.drawer.live_buffers()))
    assert max(c[0] for c in counts[5:]) <= counts[5][0], counts
    assert max(c[1] for c in counts[5:]) <= counts[5][1], counts
    assert max(c[2] for c in counts) <= 4, counts  # two shapes, each in the blended pass and the depth pass


def test_line_with_an_endpoint_behind_the_camera_is_clipped_not_dropped(engine):
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 0), center=(0, 0, -1), fov=60))
    n = s.add(om.Node("line"))
    n.add(om.Color(1, 1, 0))
    n.add(om.DrawStyle(line_width=3))
    n.add(om.LineSet([(0, -0.5, -5), (0, -0.5, 5)]))  # runs from in front of the camera to behind it
    img = engine.render(s)
    column = img.array[:, 46:51, :3].max(axis=1)
    drawn = np.flatnonzero((column[:, 0] > 150) & (column[:, 1] > 150))
    # from the projection of (0, -0.5, -5) down to the bottom edge (the segment's near-plane end is off-screen)
    assert len(drawn) > 20, drawn
    assert drawn.max() == 71, drawn
    assert abs(drawn.min() - 36 - 36 * 0.1 / np.tan(np.radians(30))) <= 3, drawn


class _Custom(om.Shape):
    """A shape only the test painter below knows how to draw."""

    __slots__ = ()


def _custom_scene(make_geometry) -> om.Node:
    from omnirender.core.handler import ShapePainter

    class Painter(ShapePainter):
        __slots__ = ()
        service = "gl.paint"
        target = _Custom

        def exec(self, shape, engine):
            engine.submit(make_geometry())

    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 4)))
    n = s.add(om.Node("custom"))
    n.add(Painter())
    n.add(_Custom())
    return s


TRIANGLE = np.array([(0, 0, 0), (1, 0, 0), (0, 1, 0)], np.float32)


@pytest.mark.parametrize(
    "positions, indices, message",
    [
        (TRIANGLE, np.array([0, 1, -1], np.int64), "negative"),
        (TRIANGLE, np.array([0, 1, 3], np.int64), "< number of vertices"),
        (TRIANGLE, np.array([0, 1], np.int64), "multiple of 3"),
        (TRIANGLE, np.array([0, 1, 1.5]), "whole numbers"),
        (np.array([(0, 0, np.nan), (1, 0, 0), (0, 1, 0)], np.float32), None, "not finite"),
        (np.array([(0, 0, np.inf), (1, 0, 0), (0, 1, 0)]), None, "not finite"),
        (TRIANGLE[:, :2], None, r"expected \(N, 3\)"),
    ],
)
def test_custom_painters_cannot_send_bad_geometry_to_the_driver(monkeypatch, positions, indices, message):
    from omnirender.gl.engine.geometry import Geometry

    uploads = []
    original = Geometry.upload
    monkeypatch.setattr(Geometry, "upload", lambda self, ctx: uploads.append(self.label) or original(self, ctx))
    scene = _custom_scene(lambda: Geometry("triangles", positions, indices=indices, label="custom triangle"))
    with pytest.raises(ValueError, match=message) as info:
        om.render(scene, engine="gl", size=(32, 32))
    text = str(info.value)
    assert "custom triangle" in text and "/scene/custom" in text and "fix" in text, text
    assert "custom triangle" not in uploads


def test_value_errors_from_gl_painters_name_the_node():
    def fail():
        raise ValueError("Custom: the thing is broken; fix the thing")

    with pytest.raises(ValueError, match=r"fix the thing \(in node /scene/custom\)"):
        om.render(_custom_scene(fail), engine="gl", size=(32, 32))


def test_shape_construction_errors_say_how_to_fix():
    v = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    with pytest.raises(ValueError, match="indices must be < number of vertices; fix the index array"):
        om.TriangleSet(v, [(0, 1, 5)])
    with pytest.raises(ValueError, match="indices must be >= 0; fix the index array"):
        om.TriangleSet(v, [(0, 1, -1)])
    with pytest.raises(ValueError, match="; give one row per vertex"):
        om.TriangleSet(v, colors=[(1, 0, 0), (0, 1, 0)])


@pytest.mark.parametrize("limit", ["context", 16384, 32768])
def test_oversized_texture_and_volume_raise_a_clear_error(engine, monkeypatch, limit):
    """The limits are the context's (llvmpipe allows 16384 texels per side, NVIDIA 32768): an image one texel
    wider is refused with a clear error, by the engine or, beyond what any GPU holds, by the Texture itself."""
    from omnirender.attributes.appearance import MAX_TEXTURE_SIDE

    if limit != "context":  # another driver's limit, as the engine would have read it from that context
        monkeypatch.setattr(engine, "max_texture_size", limit)
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 4)))
    n = s.add(om.Node("textured"))
    # one pixel high, one pixel wider than the GPU allows: tiny in memory, still too large
    image = np.zeros((1, engine.max_texture_size + 1, 3), np.uint8)
    if image.shape[1] > MAX_TEXTURE_SIDE:  # no GPU holds it: the declaration refuses it already
        with pytest.raises(ValueError, match=r"Texture: image is .* at most \d+ per side .*scale the image down"):
            om.Texture(image)
        image = np.zeros((1, 2, 3), np.uint8)
        monkeypatch.setattr(engine, "max_texture_size", 1)  # the engine's own check, at a limit an image exceeds
    n.add(om.Texture(image))
    n.add(om.Box())
    with pytest.raises(ValueError, match=r"Texture .*in node /scene/textured: .*resize") as info:
        engine.render(s)
    assert "GL_INVALID_VALUE" not in str(info.value)
    s.remove(n)
    assert not engine.render(s).mask.any()  # the engine stays usable (an empty scene renders)
    s.add(om.Sphere())
    assert engine.render(s).mask.any()

    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 4)))
    v = s.add(om.Node("volume"))
    v.add(om.Volume(np.zeros((engine.max_texture_size_3d + 1, 2, 2), np.float32)))
    with pytest.raises(ValueError, match=r"Volume .*in node /scene/volume: .*resize"):
        engine.render(s)


def volume_scene(eye) -> om.Node:
    """A 2 x 2 x 2 volume of uniform, half-opaque orange "fog" centred at the origin."""
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=eye, center=(0, 0, -1), fov=60, near=0.05))
    v = s.add(om.Node("volume"))
    data = np.ones((9, 9, 9), np.float32)
    v.add(om.Volume(data, spacing=0.25, transfer_function=[(0, (1, 0.5, 0, 0.5)), (1, (1, 0.5, 0, 0.5))]))
    return s


def test_camera_inside_a_volume_sees_it(engine):
    outside = engine.render(volume_scene((0, 0, 4)))
    inside = engine.render(volume_scene((0, 0, 0.5)))
    assert outside.array[36, 48, 3] > 200
    # inside, every pixel looks through fog: the volume fills the image
    assert inside.array[..., 3].min() > 100, inside.array[..., 3].min()
    r, g, b, _ = inside.array[36, 48]
    assert r > g > b
    # depth at the centre: the first significant sample is just in front of the camera, not behind it
    assert 0.05 <= inside.depth[36, 48] < 0.5


@pytest.mark.gl_needs(samples=4)
def test_multisampling_is_on_by_default():
    """om.render's default anti-aliases edges: a tilted white square on black has intermediate grey levels."""
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 5), center=(0, 0, 0), fov=40))
    s.add(om.Rotation(17, (0, 0, 1)))
    s.add(om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), specular=(0, 0, 0), emission=(1, 1, 1)))
    s.add(om.Box(size=(1.3, 1.3, 0.1)))
    default = om.render(s, engine="gl", size=(64, 64), background=(0, 0, 0)).array[..., 0]
    aliased = om.render(s, engine="gl", size=(64, 64), background=(0, 0, 0), samples=0).array[..., 0]
    assert len(np.unique(aliased)) == 2  # black and white only
    edge = (default > 10) & (default < 245)
    assert len(np.unique(default)) >= 4 and edge.sum() > 40, (np.unique(default), edge.sum())


def checker_quad(mipmap: bool, board: np.ndarray | None = None) -> om.Node:
    """A 100x100 one-texel checker (or ``board``) on a quad about 16 pixels wide: heavily minified."""
    if board is None:
        board = ((np.indices((100, 100)).sum(axis=0) % 2) * 255).astype(np.uint8)
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 12), center=(0, 0, 0), fov=40))
    s.add(om.AmbientLight(intensity=1.0))
    n = s.add(om.Node("quad"))
    n.add(om.Texture(np.stack([board] * 3, axis=-1), filter="nearest", mipmap=mipmap))
    n.add(om.Color(1, 1, 1))
    n.add(
        om.TriangleSet(
            [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)],
            [(0, 1, 2), (0, 2, 3)],
            texcoords=[(0, 0), (1, 0), (1, 1), (0, 1)],
        )
    )
    return s


def test_mipmaps_average_a_minified_checker(engine):
    with_mips = engine.render(checker_quad(True)).array[30:42, 42:54, 0].astype(float)
    without = engine.render(checker_quad(False)).array[30:42, 42:54, 0].astype(float)
    # mipmapped: an even grey; without mipmaps: texels picked at random, black and white
    assert with_mips.std() < 12, with_mips.std()
    assert without.std() > 3 * with_mips.std() + 20, (without.std(), with_mips.std())
    # sRGB-correct averaging: half black, half white texels give the grey of 50% light (sRGB 188), the same as
    # a uniform texture of that grey -- not the darker grey of averaging the encoded values 0 and 255
    grey = engine.render(checker_quad(True, np.full((100, 100), 188, np.uint8))).array[30:42, 42:54, 0]
    assert abs(with_mips.mean() - grey.mean()) <= 4, (with_mips.mean(), grey.mean())


def test_light_switch_with_a_light_list_is_selective(engine):
    red = om.DirectionalLight(direction=(0, 0, -1), color=(1, 0, 0))
    blue = om.DirectionalLight(direction=(0, 0, -1), color=(0, 0, 1))

    def centre(switch):
        s = om.Node("scene")
        s.add(om.Camera.look_at(eye=(0, 0, 5)))
        s.add(red)
        s.add(blue)
        n = s.add(om.Node("lit"))
        if switch is not None:
            n.add(switch)
        n.add(om.Material(ambient=(0, 0, 0), diffuse=(1, 1, 1), specular=(0, 0, 0)))
        n.add(om.Sphere())
        return engine.render(s).pixel(48, 36)[:3]

    both = centre(None)
    only_blue = centre(om.LightSwitch(on=False, lights=[red]))
    only_red = centre(om.LightSwitch(on=True, lights=[red]))
    assert both[0] > 200 and both[2] > 200, both
    assert only_blue[0] < 10 and only_blue[2] > 200, only_blue
    assert only_red[0] > 200 and only_red[2] < 10, only_red


def test_wireframe_reference_scene_shows_edges_not_a_surface(engine):
    from .scenes import wireframe

    def bluish(img):
        a = img.array[..., :3].astype(int)
        return int(((a[..., 2] > a[..., 0] + 60) & (a[..., 2] > 150)).sum())

    wire = bluish(engine.render(wireframe()))
    filled_scene = wireframe()
    filled_scene.child("wire").remove(filled_scene.child("wire").components[0])  # drop the DrawStyle
    filled = bluish(engine.render(filled_scene))
    assert 0 < wire < 0.6 * filled, (wire, filled)
