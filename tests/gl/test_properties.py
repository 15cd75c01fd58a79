"""Measurable properties of GL renders: colour at known pixels, depth, determinism, validation, resources."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(96, 72))
    yield e
    e.release()


def red_sphere_blue_box() -> om.Node:
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 5), center=(0, 0, 0), fov=40))
    s.add(om.PointLight(position=(3, 3, 5)))
    a = s.add(om.Node("sphere"))
    a.add(om.Color(1, 0, 0))
    a.add(om.Sphere(radius=0.8))
    b = s.add(om.Node("box"))
    b.add(om.Translation(0.5, 0, -1))
    b.add(om.Color(0, 0, 1))
    b.add(om.Box(size=(2, 2, 0.5)))
    return s


def test_red_sphere_in_front_of_blue_box(engine):
    img = engine.render(red_sphere_blue_box())
    r, g, b, a = img.pixel(48, 36)
    assert r > 150 and g < 40 and b < 40 and a == 255
    # the box shows to the right of the sphere
    r, g, b, _ = img.pixel(48 + 17, 36)
    assert b > 100 and r < 40


def test_depth_at_centre_is_analytic_distance(engine):
    img = engine.render(red_sphere_blue_box())
    assert img.depth is not None and img.depth.dtype == np.float32
    assert img.depth[36, 48] == pytest.approx(5.0 - 0.8, rel=0.01)
    assert np.isinf(img.depth[0, 0])
    assert img.mask[36, 48] and not img.mask[0, 0]


def test_two_identical_renders_are_byte_identical(engine):
    scene = red_sphere_blue_box()
    a = engine.render(scene)
    b = engine.render(scene)
    assert a.array.tobytes() == b.array.tobytes()
    c = om.render(scene, engine="gl", size=(96, 72))
    assert c.array.tobytes() == a.array.tobytes()


def test_out_of_range_indices_raise_naming_node(engine):
    from omnirender.gl.engine.geometry import validate_mesh

    with pytest.raises(ValueError, match="out of range"):
        validate_mesh(np.zeros((3, 3), np.float32), np.array([0, 1, 3], np.uint32), "TriangleSet", "/scene/bad")
    with pytest.raises(ValueError, match="not finite"):
        validate_mesh(np.array([[0, 0, np.nan]], np.float32), None, "TriangleSet", "/scene/bad")


def test_bad_size_raises():
    from omnirender.gl import GLEngine

    with pytest.raises(ValueError, match="positive"):
        GLEngine(size=(0, 10))
    with pytest.raises(ValueError, match="maximum"):
        GLEngine(size=(10**6, 10))


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
def test_replacing_a_mesh_every_frame_keeps_buffers_bounded(engine):
    from omnirender.gl.engine.resources import live_buffers

    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 0, 4)))
    holder = scene.add(om.Node("holder"))
    counts = []
    rng = np.random.default_rng(1)
    for _frame in range(40):
        holder.clear()
        v = rng.normal(size=(30, 3)).astype(np.float32)
        holder.add(om.TriangleSet(v, np.arange(30).reshape(10, 3)))
        engine.render(scene, read_depth=False)
        counts.append((engine.live_buffers(), live_buffers(engine.ctx)))
    assert max(c[0] for c in counts[5:]) == counts[5][0], counts
    # and counted independently: moderngl Buffer objects alive in the process
    assert max(c[1] for c in counts[5:]) <= counts[5][1], counts


def test_unchanged_scene_is_replayed_without_compiling(engine):
    scene = red_sphere_blue_box()
    engine.render(scene)
    assert engine.stats["compiled"]
    engine.render(scene)
    assert not engine.stats["compiled"]


def test_changing_one_child_updates_only_its_instance(engine):
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 0, 30)))
    moves = []
    for i in range(50):
        n = scene.add(om.Node(f"c{i}"))
        moves.append(n.add(om.Translation(i % 10 - 5, i // 10 - 2, 0)))
        n.add(om.Color(i / 50, 0.5, 0.5))
        n.add(om.Box(size=(0.5, 0.5, 0.5)))
    engine.render(scene)
    assert engine.stats["batches"] == 1 and engine.stats["draw_calls"] == 1
    moves[7].offset = (0, 0, 3)
    img = engine.render(scene)
    assert engine.stats["incremental"] == 1
    assert img.depth.min() == pytest.approx(30 - 3 - 0.25, rel=0.01)


def test_bad_geometry_through_the_engine_names_the_node(engine):
    scene = om.Node("scene")
    bad = scene.add(om.Node("bad"))
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    mesh = bad.add(om.TriangleSet(v.copy(), [(0, 1, 2)]))
    engine.render(scene)
    arr = np.array(mesh.vertices, dtype=np.float32)
    arr[1, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        mesh.vertices = arr
    # the engine itself refuses non-finite data even if it reaches a painter
    from omnirender.gl.engine.geometry import validate_mesh

    with pytest.raises(ValueError, match=r"/scene/bad.*vertex 1"):
        validate_mesh(arr, None, "TriangleSet", "/scene/bad")
    # the engine is still usable after an error
    assert engine.render(red_sphere_blue_box()).mask.any()


def test_error_during_compile_leaves_engine_usable(engine):
    from omnirender.core.handler import ShapePainter

    class Boom(ShapePainter):
        __slots__ = ()
        service = "gl.paint"
        target = om.Sphere

        def exec(self, shape, engine):
            raise RuntimeError("boom")

    scene = red_sphere_blue_box()
    scene.insert(0, Boom())
    with pytest.raises(RuntimeError, match="boom"):
        engine.render(scene)
    assert engine.render(red_sphere_blue_box()).pixel(48, 36)[0] > 150


def test_default_camera_fits_the_scene(engine):
    scene = om.Node("scene")
    scene.add(om.Translation(10, 5, -3))
    scene.add(om.Sphere(radius=2))
    img = engine.render(scene)
    ys, xs = np.nonzero(img.mask)
    assert img.mask[36, 48]  # centred
    assert xs.min() > 0 and xs.max() < 95 and ys.min() > 0 and ys.max() < 71  # fully visible
    assert (ys.max() - ys.min()) > 36  # and large


def test_image_conventions(engine):
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 0, 5)))
    scene.add(om.Color(1, 1, 1))
    scene.add(om.Sphere(center=(0, 1.2, 0), radius=0.3))  # above the centre
    img = engine.render(scene, background=(0, 0, 0, 0))
    assert img.array.shape == (72, 96, 4) and img.array.dtype == np.uint8
    ys, _ = np.nonzero(img.mask)
    assert ys.mean() < 36  # top row first
    assert img.pixel(0, 0)[3] == 0  # transparent background
    assert img.engine == "gl"


def test_micro_program_on_the_engine(engine):
    """DESIGN.md's engine-level example: push, eval, pop, then draw what was evaluated."""
    mat = om.Material(diffuse=(1, 0.4, 0.6))
    rot = om.Rotation(30, (1, 0, 0))
    torus = om.Torus(major_radius=1, minor_radius=0.3)
    engine.push(mat)
    engine.push(rot)
    engine.eval(torus)
    engine.pop(rot.category)
    engine.pop(mat.category)
    img = engine.render()
    assert img.mask.sum() > 500
    r, g, b, _ = img.array[img.mask].max(axis=0)
    assert r > g and r > b
    assert engine.context.is_empty()


def test_transparent_shapes_are_sorted_back_to_front(engine):
    def scene(order):
        s = om.Node("scene")
        s.add(om.Camera.look_at(eye=(0, 0, 6)))
        specs = [((1, 0, 0), -1.0), ((0, 1, 0), 0.0), ((0, 0, 1), 1.0)]
        for i in order:
            color, z = specs[i]
            n = s.add(om.Node(f"s{i}"))
            n.add(om.Material(diffuse=color, opacity=0.5))
            n.add(om.Sphere(center=(0.2 * z, 0, z), radius=0.6))
        return s

    a = engine.render(scene([0, 1, 2])).array
    b = engine.render(scene([2, 1, 0])).array
    c = engine.render(scene([1, 2, 0])).array
    assert np.abs(a.astype(int) - b.astype(int)).max() <= 1
    assert np.abs(a.astype(int) - c.astype(int)).max() <= 1
    # the nearest (blue) sphere dominates the centre
    r, g, bl, _ = a[36, 48]
    assert bl > r and bl > g


def test_clip_planes_and_fog_apply_to_lines_and_points(engine):
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 6)))
    s.add(om.ClipPlane(normal=(1, 0, 0), offset=0.0))
    s.add(om.Fog(color=(0.5, 0.5, 0.5), start=2, end=10))
    s.add(om.DrawStyle(line_width=3, point_size=6))
    s.add(om.Polyline([(-2, -1, 0), (2, 1, 0)]))
    s.add(om.PointSet(np.random.default_rng(0).normal(size=(50, 3))))
    s.add(om.DrawStyle(mode="points", point_size=3))
    s.add(om.Torus())
    img = engine.render(s)
    assert img.mask[:, 50:].sum() > 50
    assert img.mask[:, :46].sum() == 0  # everything with x < 0 is clipped


def test_orthographic_depth_resize_and_single_shapes():
    from omnirender.gl import GLEngine

    with GLEngine(size=(40, 30)) as e:
        s = om.Node("scene")
        s.add(om.Camera.orthographic(eye=(0, 0, 5), height=3))
        s.add(om.Sphere(radius=0.8))
        img = e.render(s)
        assert img.depth[15, 20] == pytest.approx(4.2, rel=0.01)
        e.size = (80, 60)
        img = e.render(s)
        assert img.array.shape == (60, 80, 4) and img.depth[30, 40] == pytest.approx(4.2, rel=0.01)
        assert e.render(om.Box()).mask.any()  # a lone shape renders with the auto-fit camera
        assert e.render([om.Color(1, 0, 0), om.Sphere()]).pixel(40, 30)[0] > 100


def test_native_shapes_instance_and_follow_tessellation(engine):
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 3, 12)))
    for i in range(20):
        n = s.add(om.Node(f"c{i}"))
        n.add(om.Translation(i % 5 - 2, 0, i // 5 - 2))
        n.add(om.Color(i / 20, 0.5, 0.5))
        n.add(om.Cone(radius=0.3, height=0.6 + i * 0.01))
    coarse = s.add(om.Node("coarse"))
    coarse.add(om.Tessellation(0))
    coarse.add(om.Sphere(center=(0, 2, 0), radius=0.5))
    engine.render(s)
    labels = sorted((b.geometry.label, len(b.items)) for b in engine.batches)
    assert labels == [("unit cone", 20), ("unit sphere", 1)]
    sphere = [b for b in engine.batches if b.geometry.label == "unit sphere"][0]
    assert sphere.geometry.count < engine.unit_geometry("sphere").count  # level 0 is coarser than the default


def test_draw_items_know_their_node_and_clip_planes_are_limited(engine):
    scene = red_sphere_blue_box()
    engine.compile(scene)
    assert sorted(item.path for item in engine.draw_items) == ["/scene/box", "/scene/sphere"]
    s = om.Node("scene")
    deep = s.add(om.Node("deep"))
    for i in range(7):
        deep.add(om.ClipPlane(normal=(1, 0, i * 0.1), offset=-5))
    deep.add(om.Sphere())
    with pytest.raises(ValueError, match=r"/scene/deep.*at most 6 clip planes"):
        engine.render(s)


def test_wrapping_an_existing_context():
    import moderngl

    from omnirender.gl import GLEngine

    ctx = moderngl.create_standalone_context(backend="egl", require=330)
    try:
        e = GLEngine(size=(32, 24), context=ctx)
        s = om.Node("scene")
        s.add(om.Color(1, 0, 0))
        s.add(om.Sphere())
        assert e.render(s).pixel(16, 12)[0] > 200
        e.release()
        assert ctx.info["GL_VERSION"]  # the engine leaves a context it did not create alive
    finally:
        ctx.release()


def test_textures_of_replaced_attributes_are_released(engine):
    image = np.zeros((4, 4, 3), np.uint8)
    scene = om.Node("scene")
    holder = scene.add(om.Node("holder"))
    for _ in range(5):
        holder.clear()
        holder.add(om.Texture(image.copy()))
        holder.add(om.Box())
        engine.render(scene, read_depth=False)
        assert engine.drawer.texture_count() == 1


def test_transparent_shape_over_transparent_background_keeps_its_opacity(engine):
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=(0, 0, 5)))
    s.add(om.Material(diffuse=(1, 0, 0), opacity=0.4))
    s.add(om.Rotation(90, (1, 0, 0)))
    s.add(om.Rectangle(size=(3, 3)))  # one surface: alpha 0.4
    s.add(om.Box(size=(1, 1, 1), center=(0, 0, 0)))  # two more surfaces at the centre
    img = engine.render(s, background=(0, 0, 0, 0))
    assert img.pixel(25, 36)[3] == pytest.approx(0.4 * 255, abs=2)
    assert img.pixel(48, 36)[3] == pytest.approx((1 - 0.6**3) * 255, abs=3)
