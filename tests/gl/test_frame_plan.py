"""The frame plan: a steady frame is recorded once and replayed while nothing changed (gl/engine/plan.py).

Every test changes one thing between two replayed frames and compares the
next frame with a fresh engine's picture of the changed scene: the replay
must stop exactly when the change tracker says something changed.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.gl import GLEngine

pytestmark = pytest.mark.gl

SIZE = (64, 48)


def scene() -> tuple[om.Node, dict[str, om.Component]]:
    """Boxes with materials of their own, a directional and a point light, a camera: several draws and programs."""
    parts: dict[str, om.Component] = {}
    s = om.Node("scene")
    parts["camera"] = s.add(om.Camera.look_at(eye=(0.5, 1.0, 7.0)))
    parts["light"] = s.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0), color=(1.0, 1.0, 1.0)))
    parts["lamp"] = s.add(om.PointLight(position=(2.0, 2.0, 3.0), color=(0.4, 0.4, 0.3)))
    for i in range(4):
        node = s.add(om.Node(f"b{i}"))
        parts[f"move{i}"] = node.add(om.Translation(1.3 * i - 2.0, 0.2 * i, 0.0))
        parts[f"material{i}"] = node.add(om.Material(diffuse=(0.3 + 0.2 * i, 0.8 - 0.15 * i, 0.4)))
        node.add(om.Box(size=0.9) if i % 2 else om.Sphere(radius=0.5))
    return s, parts


def fresh(root: om.Node, **kwargs) -> np.ndarray:
    with GLEngine(size=kwargs.pop("size", SIZE), samples=0, shadows=False) as e:
        return e.render(root, read_depth=False, **kwargs).array


def steady(engine: GLEngine, root: om.Node, **kwargs) -> np.ndarray:
    """Render until a frame is a replay; its picture."""
    engine.render(root, read_depth=False, **kwargs)
    engine.render(root, read_depth=False, **kwargs)
    image = engine.render(root, read_depth=False, **kwargs)
    assert engine.stats["replayed"], engine.frame_runner.not_recorded
    return image.array


@pytest.fixture
def engine():
    e = GLEngine(size=SIZE, samples=0, shadows=False)
    yield e
    e.release()


def test_a_steady_frame_is_replayed_and_draws_the_same(engine):
    root, _ = scene()
    first = engine.render(root, read_depth=False)
    assert not first.info["replayed"]
    replayed = steady(engine, root)
    assert np.array_equal(replayed, first.array)
    assert np.array_equal(replayed, fresh(root))
    # what the frame reports is the recorded frame's
    assert engine.stats["draw_calls"] == first.info["draw_calls"] > 1
    assert [p["name"] for p in engine.stats["passes"]] == [p["name"] for p in first.info["passes"]]
    assert engine.stats["passes"] is not first.info["passes"]
    # depth is read back from the replayed frame too
    image = engine.render(root)
    assert image.info["replayed"] and np.isfinite(image.depth).any()


CHANGES = {
    "camera moved": lambda root, p: setattr(p["camera"], "eye", (1.5, 0.5, 6.0)),
    "light colour": lambda root, p: setattr(p["light"], "color", (1.0, 0.2, 0.2)),
    "light switched off": lambda root, p: setattr(p["lamp"], "enabled", False),
    "node moved": lambda root, p: setattr(p["move1"], "offset", (0.0, -1.0, 0.5)),
    "material changed": lambda root, p: setattr(p["material2"], "diffuse", (0.1, 0.2, 0.9)),
    "node added": lambda root, p: root.add(
        om.Node("new", [om.Translation(0, 1.2, 0), om.Color(1, 1, 0), om.Box(size=0.5)])
    ),  # fmt: skip
    "node removed": lambda root, p: root.remove(root.child("b3")),
    "background attribute": lambda root, p: root.add(om.Background((0.2, 0.3, 0.4))),
}


@pytest.mark.parametrize("change", list(CHANGES))
def test_a_change_between_replayed_frames_is_drawn(engine, change):
    root, parts = scene()
    before = steady(engine, root)
    CHANGES[change](root, parts)
    image = engine.render(root, read_depth=False)
    # a node moved in place is replayed with its rows uploaded first (FrameRunner.rows_moved); others in full
    assert image.info["replayed"] == (change == "node moved")
    expected = fresh(root)
    assert not np.array_equal(expected, before), "the change shows in the picture"
    assert np.array_equal(image.array, expected)
    assert np.array_equal(steady(engine, root), expected)  # and the changed frame is replayed in turn


def test_resize_mask_background_and_technique_between_replayed_frames(engine):
    root, _ = scene()
    steady(engine, root)
    engine.size = (40, 40)
    image = engine.render(root, read_depth=False)
    assert not image.info["replayed"] and image.array.shape[:2] == (40, 40)
    assert np.array_equal(image.array, fresh(root, size=(40, 40)))
    assert np.array_equal(steady(engine, root), fresh(root, size=(40, 40)))
    engine.size = SIZE
    # a background given to render
    image = engine.render(root, read_depth=False, background=(0.5, 0.0, 0.5))
    assert not image.info["replayed"]
    assert np.array_equal(image.array, fresh(root, background=(0.5, 0.0, 0.5)))
    # a mask: the nodes it leaves out are not drawn
    root.child("b1").groups = ["hidden"]
    steady(engine, root)
    masked = engine.render(root, read_depth=False, mask="!hidden")
    assert not masked.info["replayed"]
    assert np.array_equal(masked.array, fresh(root, mask="!hidden"))
    assert np.array_equal(steady(engine, root, mask="!hidden"), fresh(root, mask="!hidden"))
    # another engine technique: a wireframe-free pass list of the application's is not replayed
    steady(engine, root)

    class Flat(om.gl.Forward):
        def prepare_pass(self, e):
            e.set_pass(om.gl.Pass(self.PASSES[e.current_pass].name, shader=om.gl.Shader(flat_color=(0, 1, 0, 1))))

    engine.technique = Flat()
    flat = engine.render(root, read_depth=False)
    again = engine.render(root, read_depth=False)
    assert not again.info["replayed"] and "Flat" in (engine.frame_runner.not_recorded or "")
    assert np.array_equal(flat.array, again.array)
    assert (flat.array[..., 1] == 255).any() and not np.array_equal(flat.array, fresh(root))


def test_frames_of_two_engines_sharing_programs(engine):
    """The programs keep the uniforms their last frame wrote: a replay after another engine's frame writes all."""
    root, _ = scene()
    other_root, parts = scene()
    parts["camera"].eye = (-2.0, 2.0, 6.0)
    parts["light"].color = (0.3, 1.0, 0.3)
    with GLEngine(size=SIZE, samples=0, shadows=False, context=engine.ctx, programs=engine.programs) as other:
        a, b = fresh(root), fresh(other_root)
        assert not np.array_equal(a, b)
        for _ in range(4):
            assert np.array_equal(engine.render(root, read_depth=False).array, a)
            assert np.array_equal(other.render(other_root, read_depth=False).array, b)
        assert engine.stats["replayed"] and other.stats["replayed"]


def test_gl_state_changed_between_frames_does_not_reach_a_replay(engine):
    root, _ = scene()
    expected = steady(engine, root)
    with engine.current():
        ctx = engine.ctx
        ctx.enable(ctx.BLEND)
        ctx.blend_func = ctx.ONE, ctx.ONE
        ctx.depth_func = ">="
        ctx.enable(ctx.CULL_FACE)
        ctx.cull_face = "front"
    image = engine.render(root, read_depth=False)
    assert image.info["replayed"]
    assert np.array_equal(image.array, expected)


def test_frames_that_are_not_recorded(engine):
    """Transparent items and a camera given to draw() run the full frame every time, correctly."""
    root, parts = scene()
    root.child("b2").insert(2, om.Material(diffuse=(0.2, 0.9, 0.2), opacity=0.5))
    first = engine.render(root, read_depth=False)
    second = engine.render(root, read_depth=False)
    assert not second.info["replayed"] and "transparent" in engine.frame_runner.not_recorded
    assert np.array_equal(first.array, second.array)
    assert np.array_equal(second.array, fresh(root))
    steady_root, parts = scene()
    steady(engine, steady_root)
    camera = om.Camera.look_at(eye=(0.0, 4.0, 6.0))
    with engine.current():
        engine.draw(camera=camera)
        assert not engine.stats["replayed"]
        seen = engine.read(read_depth=False)
    engine.render(steady_root, read_depth=False)  # the scene's own camera again
    reference = root_with_camera(steady_root, camera)
    assert np.array_equal(seen.array, fresh(reference))


def root_with_camera(root: om.Node, camera: om.Camera) -> om.Node:
    items = [camera if isinstance(item, om.Camera) else item for item in root.items]
    return om.Node("scene", items)


def test_a_user_stage_is_not_replayed_unless_it_says_so(engine):
    root, _ = scene()
    drawn = []

    class Counting(om.gl.FrameStage):
        name = "counting"

        def draw(self, frame, root):
            drawn.append(1)
            return 0

    engine.add_stage(Counting(), after="technique")
    for _ in range(3):
        engine.render(root, read_depth=False)
    assert len(drawn) == 3 and not engine.stats["replayed"]
    engine.remove_stage("counting")
    steady(engine, root)


def test_instance_sets_and_translation_arrays_moved_between_replayed_frames(engine):
    positions = np.array([[-1.5, 0.0, 0.0], [0.0, 0.5, 0.0], [1.5, -0.5, 0.0]])
    instances = om.InstanceSet(
        om.Box(size=0.6), positions, colors=np.array([[1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 1, 1.0]])
    )
    bound = np.array([[-1.0, 1.2, 0.0], [1.0, 1.2, 0.0]])
    offsets = om.TranslationArray(bound)
    root = om.Node("scene", [om.Camera.look_at(eye=(0, 0, 7)), om.DirectionalLight(direction=(-0.3, -0.5, -1.0)),
                             instances])  # fmt: skip
    for i in range(2):
        root.add(om.Node(f"t{i}", [offsets[i], om.Color(1, 1, 0), om.Sphere(radius=0.3)]))
    before = steady(engine, root)
    positions[1] = (0.3, -1.0, 0.5)  # the application's array, written in place
    instances.touch()
    moved = engine.render(root, read_depth=False)
    # positions only: uploaded to the set's translations, then the plan replayed (FrameRunner.rows_moved)
    assert moved.info["replayed"] and not np.array_equal(moved.array, before)
    assert np.array_equal(moved.array, fresh(root))
    steady(engine, root)
    bound[0] = (-2.0, -1.2, 0.0)  # the bound array, written in place
    offsets.touch()
    image = engine.render(root, read_depth=False)
    assert image.info["replayed"]  # rows moved in place: uploaded, then the plan replayed (FrameRunner.rows_moved)
    assert np.array_equal(image.array, fresh(root))
    assert np.array_equal(steady(engine, root), image.array)


def test_default_shadows_replay_a_kept_atlas_and_redraw_after_a_change():
    """A frame whose shadow maps were all kept is replayed (atlas bound, shadow uniforms written); a moved caster
    redraws its region in a full frame, and the picture equals a fresh engine's."""
    root, parts = scene()
    root.add(om.Node("floor", [om.Translation(0, -1.0, 0), om.Color(0.9, 0.9, 0.9), om.Box(size=(8.0, 0.1, 8.0))]))

    def fresh_shadowed() -> np.ndarray:
        with GLEngine(size=SIZE, samples=0) as e:
            return e.render(root, read_depth=False).array

    with GLEngine(size=SIZE, samples=0) as engine:
        before = steady(engine, root)
        assert engine.stats["shadow_maps"]["kept"] > 0
        assert engine.frame_shadows is not None
        assert np.array_equal(before, fresh_shadowed())
        parts["move2"].offset = (0.4, 0.8, 0.6)
        moved = engine.render(root, read_depth=False)
        assert not moved.info["replayed"]
        assert np.array_equal(moved.array, fresh_shadowed())
        assert np.array_equal(steady(engine, root), moved.array)
        parts["light"].direction = (0.5, -0.7, -0.6)  # the light turns: every face drawn again
        turned = engine.render(root, read_depth=False)
        assert not turned.info["replayed"] and not np.array_equal(turned.array, moved.array)
        assert np.array_equal(turned.array, fresh_shadowed())


def test_textures_lines_points_clip_planes_and_fog_replay_and_follow_changes(engine):
    """Draws that bind textures, write viewport, clip-plane and fog uniforms are replayed as recorded."""
    rng = np.random.default_rng(3)
    image = rng.integers(0, 255, (8, 8, 3), dtype=np.uint8)
    texture = om.Texture(image, filter="nearest", mipmap=False)
    root = om.Node("scene", [om.Camera.look_at(eye=(0.3, 0.8, 6.0)), om.DirectionalLight(direction=(-0.3, -0.5, -1))])
    root.add(om.Node("textured", [om.Translation(-1.2, 0, 0), texture, om.Box(size=1.2)]))
    clipped = root.add(om.Node("clipped", [om.Translation(1.2, 0, 0), om.ClipPlane(normal=(0, -1, 0), offset=0.2),
                                           om.Color(0.2, 0.6, 1.0), om.Sphere(radius=0.7)]))  # fmt: skip
    fog = om.Fog(color=(0.6, 0.6, 0.7), start=4.0, end=12.0)
    root.add(om.Node("far", [fog, om.Translation(0, 0, -4), om.Color(1, 0.5, 0), om.Box(size=2.0)]))
    root.add(om.Node("lines", [om.Color(0, 1, 0), om.LineSet(np.array([[-2.0, -1.3, 0], [2.0, -1.3, 0]]))]))
    root.add(om.Node("points", [om.Color(1, 0, 1), om.PointSet(np.array([[-1.5, 1.4, 0], [0, 1.5, 0], [1.5, 1.4, 0]]),
                                                                sizes=[6.0, 6.0, 6.0])]))  # fmt: skip
    first = engine.render(root, read_depth=False)
    replayed = steady(engine, root)
    assert np.array_equal(replayed, first.array)
    assert np.array_equal(replayed, fresh(root))
    texture.image = 255 - image  # a new image
    changed = engine.render(root, read_depth=False)
    assert not changed.info["replayed"] and not np.array_equal(changed.array, replayed)
    assert np.array_equal(changed.array, fresh(root))
    clipped.items[1].offset = -0.3  # the clip plane moves
    fog.end = 6.0
    again = engine.render(root, read_depth=False)
    assert not again.info["replayed"]
    assert np.array_equal(again.array, fresh(root))
    assert np.array_equal(steady(engine, root), again.array)


def test_colour_read_rows_top_down_in_the_driver_is_the_same_picture():
    """Where the driver reads rows top-down itself (Mesa's GL_MESA_pack_invert) the image is the one the
    flipping copy gives, oriented like the depth (read bottom-up and flipped), and GL's pack state is back at
    its default afterwards (a plain moderngl read is bottom-up)."""
    root = om.Node("scene")
    root.add(om.Camera.look_at(eye=(0.0, 0.0, 6.0)))
    root.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    corner = root.add(om.Node("corner"))
    corner.add(om.Translation(-1.2, 0.9, 0.0))
    corner.add(om.Box(size=0.8))
    with GLEngine(size=SIZE, samples=0, shadows=False) as engine:
        image = engine.render(root)
        covered = np.isfinite(image.depth)
        assert covered[: SIZE[1] // 2, : SIZE[0] // 2].any() and not covered[SIZE[1] // 2 :].any()  # top-left
        background = image.array[-1, -1]
        assert np.array_equal((image.array != background).any(axis=2), covered)
        with engine.current():
            plain = np.frombuffer(engine.framebuffer.read(components=4, alignment=1), np.uint8)
        assert np.array_equal(plain.reshape(SIZE[1], SIZE[0], 4)[::-1], image.array)
        if "GL_MESA_pack_invert" not in engine.ctx.extensions:  # a driver without it (NVIDIA): the copy only
            assert not engine._reads_top_down
            other = image
        else:
            engine._reads_top_down = not engine._reads_top_down  # the other way
            other = engine.render(root)
        assert np.array_equal(other.array, image.array)
        for array in (image.array, other.array):  # the image's own array, C order, as before
            assert array.flags.c_contiguous and array.flags.owndata
