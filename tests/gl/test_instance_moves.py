"""An instance set moved through its array: what a moved frame does and does not redo (issue 22).

* A positions-only move leaves the rows' translations pending (``Batch.move_to``):
  the frame uploads the new positions and writes no row; whatever reads the
  rows later (a transform above the set moving, the camera turning, new
  colours) sees the moved positions.
* The front-to-back order of an opaque set only speeds drawing up: it is kept
  across moves (a partly culled set is culled again and the kept order
  partitioned), made again when the view changes, and amortised after
  ``drawer.RESORT_AFTER`` changes.
* Translucent instances are still drawn back to front by their moved positions.
* A positions-only move of a set in view uploads the positions and replays the
  recorded frame plan; a set that must be culled again, new colours and
  translucent sets draw the frame in full.

Every picture equals a fresh engine's.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def fresh(scene: om.Node) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        return e.render(scene).array


def swarm(n: int, seed: int = 5) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    positions = rng.uniform(-3.0, 3.0, (n, 3))
    colors = np.concatenate([rng.uniform(0.2, 1.0, (n, 3)), np.ones((n, 1))], axis=1)
    return positions, colors


@pytest.fixture
def row_writes(monkeypatch):
    """How many times translations are written into rows (``drawlist.set_translations``)."""
    from omnirender.gl.engine import drawlist

    calls = []
    original = drawlist.set_translations

    def counting(rows, world):
        calls.append(len(world))
        return original(rows, world)

    monkeypatch.setattr(drawlist, "set_translations", counting)
    return calls


def test_moved_rows_are_written_only_when_read_and_every_reader_sees_the_moves(row_writes):
    from omnirender.gl import GLEngine

    positions, colors = swarm(200)
    balls = om.InstanceSet(om.Box(size=0.3), positions, colors=colors)
    lift = om.Translation((0.0, 0.0, 0.0))
    camera = om.Camera.look_at((0, 5, 12), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), om.Node("set", [lift, balls])])
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        for step in range(3):
            positions[:, 1] += 0.2
            positions[step, 0] += 1.0
            balls.touch()
            image = e.render(scene).array
            assert e.stats["compiled"] is False  # no compile: the arrays were applied in place
            assert np.array_equal(image, fresh(scene))
        assert row_writes == [], "a moved frame that reads no row writes none"
        lift.offset = (0.5, -0.2, 0.0)  # a transform above the set: its rows are read and rewritten
        assert np.array_equal(e.render(scene).array, fresh(scene))
        positions[:, 2] -= 0.3
        balls.touch()
        e.render(scene)
        camera.eye = (4.0, 3.0, 10.0)  # another view: the set is sorted again from its rows
        assert np.array_equal(e.render(scene).array, fresh(scene))
        assert row_writes, "the rows were read after the move: its translations were written then"
        positions[:, 0] += 0.25
        balls.touch()
        e.render(scene)
        colors[:10, :3] = (0.9, 0.1, 0.1)  # new colours: the rows are made again from the arrays
        balls.touch()
        assert np.array_equal(e.render(scene).array, fresh(scene))


@pytest.fixture
def sorts(monkeypatch):
    """How many times the drawer sorts (``np.argsort`` called from ``gl/engine/drawer.py``)."""
    from omnirender.gl.engine import drawer

    calls = []
    original = np.argsort

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    class Numpy:  # the drawer's numpy, with a counting argsort
        def __getattr__(self, name):
            return counting if name == "argsort" else getattr(np, name)

    monkeypatch.setattr(drawer, "np", Numpy())
    return calls


def fresh_uncounted(scene: om.Node, sorts: list) -> np.ndarray:
    """A fresh engine's picture; its own sorts are not counted."""
    count = len(sorts)
    image = fresh(scene)
    del sorts[count:]
    return image


@pytest.mark.parametrize("eye", [(0.0, 5.0, 12.0), (0.0, 1.0, 2.5)], ids=["all in view", "partly culled"])
def test_the_front_to_back_order_is_kept_across_moves_and_made_again_for_a_new_view(sorts, eye):
    from omnirender.gl import GLEngine
    from omnirender.gl.engine.drawer import RESORT_AFTER

    positions, colors = swarm(300)
    balls = om.InstanceSet(om.Box(size=0.25), positions, colors=colors)
    camera = om.Camera.look_at(eye, (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), balls])
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.drawer.sorts_instances = True  # culled and drawn front to back (a software rasteriser's way) on any GL
        e.render(scene)
        drawn = sum(p["items"] for p in e.stats["passes"] if p["name"] == "opaque")
        assert (drawn == 300) == (eye[2] == 12.0)  # the close view culls some
        assert sorts, "a set of 300 is drawn front to back"
        sorts.clear()
        for step in range(4):
            positions[:, 2] += 0.3 if step % 2 else -0.3  # moves that change the depth order
            positions[step * 11, :] = (step * 0.7 - 1.0, 0.1, 0.5)  # (apart: no coplanar faces)
            balls.touch()
            assert np.array_equal(e.render(scene).array, fresh_uncounted(scene, sorts))
        assert sorts == [], "moves keep the order made for the view (a partly culled set is only culled again)"
        camera.eye = (eye[0] + 1.0, eye[1], eye[2])
        assert np.array_equal(e.render(scene).array, fresh_uncounted(scene, sorts))
        assert sorts, "a new view: sorted again"
        sorts.clear()
        for _ in range(2 * RESORT_AFTER):
            positions[:, 0] += 0.001
            balls.touch()
            e.render(scene)
        assert 1 <= len(sorts) <= 3, "sorted again after RESORT_AFTER changes, not every frame"
        assert np.array_equal(e.render(scene).array, fresh_uncounted(scene, sorts))


def test_translucent_instances_are_drawn_back_to_front_after_they_move():
    from omnirender.gl import GLEngine

    # two overlapping translucent boxes on the view axis: which one is in front decides the blended colour
    positions = np.array([(0.0, 0.0, 0.0), (0.3, 0.2, 1.5)])
    colors = np.array([(1.0, 0.1, 0.1, 0.5), (0.1, 0.2, 1.0, 0.5)])
    boxes = om.InstanceSet(om.Box(size=1.0), positions, colors=colors)
    camera = om.Camera.look_at((0, 0, 8), (0, 0, 0), fov=30)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(0.0, 0.0, -1.0)), boxes])
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        positions[:, 2] = positions[::-1, 2]  # they swap depths: the other one is in front now
        boxes.touch()
        after = e.render(scene).array
        assert e.stats["compiled"] is False  # the positions-only path, not a compile
        assert np.array_equal(after, fresh(scene))
        assert not np.array_equal(after, before), "the blend order changed with the depths"


def test_a_set_moved_in_view_replays_the_frame_plan_and_one_that_must_be_culled_again_does_not():
    from omnirender.gl import GLEngine

    positions, colors = swarm(300)
    balls = om.InstanceSet(om.Box(size=0.25), positions, colors=colors)
    camera = om.Camera.look_at((0, 5, 12), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), balls])
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.drawer.sorts_instances = True  # culled and drawn front to back (a software rasteriser's way) on any GL
        e.render(scene)
        e.render(scene)  # recorded
        for _ in range(2):
            positions[:, 1] += 0.1
            balls.touch()
            image = e.render(scene)
            assert image.info["replayed"], e.frame_runner.not_recorded  # positions uploaded, plan replayed
            assert np.array_equal(image.array, fresh(scene))
        colors[:5, :3] = (0.1, 0.9, 0.1)  # rows made again: a frame in full
        balls.touch()
        image = e.render(scene)
        assert not image.info["replayed"] and np.array_equal(image.array, fresh(scene))
        camera.eye = (0.0, 1.0, 2.5)  # close up: some culled
        e.render(scene)
        e.render(scene)
        positions[:, 2] += 0.2
        balls.touch()
        image = e.render(scene)
        assert not image.info["replayed"], "a partly culled set is culled again: a frame in full"
        assert np.array_equal(image.array, fresh(scene))
        assert np.array_equal(e.render(scene).array, image.array)


@pytest.mark.parametrize("sorted_", [True, False], ids=["front to back", "row order"])
@pytest.mark.parametrize("options", [{"shadows": True}, {"pipeline": "deferred", "shadows": True}], ids=str)
def test_moves_between_splices_and_transform_moves_match_a_fresh_engine(options, sorted_):
    """Pending translations meet every other path: shadow maps (bounds read every frame), the deferred
    pipeline, a transform above the set moving, a node added (a splice) between moves; drawn front to back
    or in row order (a GPU's way), against a fresh engine drawing front to back."""
    from omnirender.gl import GLEngine

    positions, colors = swarm(200, seed=2)
    balls = om.InstanceSet(om.Box(size=0.3), positions, colors=colors)
    lift = om.Translation((0.0, 0.0, 0.0))
    floor = om.Node("floor", [om.Box(size=(12, 0.1, 12), center=(0, -3.5, 0))])
    camera = om.Camera.look_at((0, 5, 12), (0, 0, 0), fov=45)
    scene = om.Node(
        "scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), floor, om.Node("s", [lift, balls])]
    )
    with GLEngine(size=SIZE, samples=0, **options) as e:
        e.drawer.sorts_instances = sorted_
        e.render(scene)
        for step in range(5):
            positions[:, 1] += 0.1
            positions[step] += 0.5
            balls.touch()
            if step == 2:
                lift.offset = (0.3, 0.0, 0.1)
            if step == 3:
                scene.add(om.Node("extra", [om.Translation((1.0, 1.0, 1.0)), om.Sphere(radius=0.4)]))
            image = e.render(scene).array
            with GLEngine(size=SIZE, samples=0, **options) as f:
                assert np.array_equal(image, f.render(scene).array), step


# -- the GPU's row order, touches naming arrays, bad positions, tiny sets ------------------------------------
POLICIES = ["front to back", "row order"]


def engine_for(policy: str, **options):
    """A GL engine drawing opaque instance sets front to back (a software rasteriser's way) or in row order (a
    GPU's, :func:`~omnirender.gl.engine.drawer.sorts_instances`), whatever the machine's GL is."""
    from omnirender.gl import GLEngine

    e = GLEngine(size=SIZE, samples=0, shadows=False, **options)
    e.drawer.sorts_instances = policy == "front to back"
    return e


@pytest.mark.parametrize("policy", POLICIES)
def test_a_touch_naming_the_transforms_keeps_the_colours_and_one_naming_the_colours_draws_them(policy):
    positions, colors = swarm(300)
    balls = om.InstanceSet(om.Box(size=0.25), positions, colors=colors)
    camera = om.Camera.look_at((0, 5, 12), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), balls])
    with engine_for(policy) as e:
        e.render(scene)
        e.render(scene)
        positions[:, 1] += 0.1
        balls.touch("transforms")
        image = e.render(scene)
        assert image.info["replayed"] and not e.stats["compiled"]
        assert np.array_equal(image.array, fresh(scene))
        # colours written with the positions, the touch naming both: drawn
        colors[:40, :3] = (0.9, 0.2, 0.1)
        positions[:, 0] += 0.1
        balls.touch("transforms", "colors")
        assert np.array_equal(e.render(scene).array, fresh(scene))
        # two touches before a frame: a plain one (the colours may have changed), then a named one
        colors[40:80, :3] = (0.1, 0.2, 0.9)
        balls.touch()
        positions[:, 2] += 0.1
        balls.touch("transforms")
        assert np.array_equal(e.render(scene).array, fresh(scene))
        # a new colour array assigned, then a touch naming the transforms only
        balls.colors = np.concatenate([colors[:, :3][::-1], colors[:, 3:]], axis=1)
        positions[:, 1] -= 0.1
        balls.touch("transforms")
        assert np.array_equal(e.render(scene).array, fresh(scene))
        # a plain touch that wrote no colour: compared, found equal, the positions-only path again
        positions[:, 1] += 0.05
        balls.touch()
        image = e.render(scene)
        assert image.info["replayed"] and np.array_equal(image.array, fresh(scene))


@pytest.mark.parametrize("policy", POLICIES)
def test_overlapping_translucent_and_opaque_instances_after_many_moves_match_a_fresh_sort(policy):
    from omnirender.gl.engine.drawer import RESORT_AFTER

    rng = np.random.default_rng(11)
    n = 90
    # translucent boxes crowded along the view axis (each one's blend depends on which are in front) and an
    # opaque set interleaved with them
    glass = rng.uniform((-0.8, -0.6, -4.0), (0.8, 0.6, 4.0), (n, 3))
    tint = np.concatenate([rng.uniform(0.1, 1.0, (n, 3)), np.full((n, 1), 0.45)], axis=1)
    solid = rng.uniform((-2.5, -1.5, -4.0), (2.5, 1.5, 4.0), (n, 3))
    glass_set = om.InstanceSet(om.Box(size=0.6), glass, colors=tint)
    solid_set = om.InstanceSet(om.Box(size=0.35), solid, colors=np.full((n, 3), 0.7))
    camera = om.Camera.look_at((0.5, 0.8, 10), (0, 0, 0), fov=40)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.3, -0.5, -1.0)), glass_set, solid_set])
    with engine_for(policy) as e:
        e.render(scene)
        for step in range(RESORT_AFTER + 7):
            glass[:, 2] = glass[rng.permutation(n), 2]  # the depth order shuffled: another blend order
            solid[:, 2] = solid[rng.permutation(n), 2]
            glass_set.touch("transforms")
            solid_set.touch("transforms")
            image = e.render(scene).array
            if step % 20 == 0:
                assert np.array_equal(image, fresh(scene)), step
        assert np.array_equal(image, fresh(scene))


@pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning")
@pytest.mark.filterwarnings("ignore:invalid value encountered in dot:RuntimeWarning")
@pytest.mark.parametrize("value", [np.nan, np.inf, 1e39], ids=["nan", "inf", "beyond float32"])
@pytest.mark.parametrize("names", [(), ("transforms",)], ids=["touch()", "touch('transforms')"])
def test_a_bad_position_is_refused_naming_the_instance_and_the_node(value, names):
    positions, colors = swarm(120)
    balls = om.InstanceSet(om.Box(size=0.25), positions, colors=colors)
    camera = om.Camera.look_at((0, 5, 12), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), om.Node("swarm", [balls])])
    with engine_for("row order") as e:
        e.render(scene)
        positions[17, 1] = value
        balls.touch(*names)
        with pytest.raises(ValueError, match=r"instance 17 .*\(in node /scene/swarm\)"):
            e.render(scene)
        positions[17, 1] = 0.5  # fixed: drawn again
        balls.touch(*names)
        assert np.array_equal(e.render(scene).array, fresh(scene))


@pytest.mark.parametrize("policy", POLICIES)
@pytest.mark.parametrize("n", [0, 1, 2])
def test_sets_of_no_one_or_two_instances_move(policy, n):
    positions, colors = swarm(n, seed=n)
    balls = om.InstanceSet(om.Sphere(radius=0.8), positions, colors=colors)
    camera = om.Camera.look_at((0, 2, 9), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), balls])
    with engine_for(policy) as e:
        e.render(scene)
        for step in range(3):
            positions += (0.3, -0.2, 0.1)
            balls.touch("transforms")
            assert np.array_equal(e.render(scene).array, fresh(scene)), step
        balls.colors = None  # colours taken away (the shape was captured under the instances' colours)
        m = 1 - min(n, 1)
        balls.transforms = np.zeros((m, 3))  # one instance where there were none, or none
        assert np.array_equal(e.render(scene).array, fresh(scene))
        balls.colors = np.full((m, 3), (0.9, 0.3, 0.2))  # and given again
        assert np.array_equal(e.render(scene).array, fresh(scene))


def test_in_row_order_a_partly_culled_set_is_neither_culled_nor_sorted_and_its_moves_replay(sorts):
    positions, colors = swarm(300)
    balls = om.InstanceSet(om.Box(size=0.25), positions, colors=colors)
    camera = om.Camera.look_at((0.0, 1.0, 2.5), (0, 0, 0), fov=45)  # close up: some instances out of view
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), balls])
    with engine_for("row order") as e:
        e.render(scene)
        e.render(scene)
        assert sum(p["items"] for p in e.stats["passes"] if p["name"] == "opaque") == 300, "all of them drawn"
        for _ in range(3):
            positions[:, 2] += 0.2
            balls.touch("transforms")
            image = e.render(scene)
            assert image.info["replayed"], e.frame_runner.not_recorded
            assert np.array_equal(image.array, fresh_uncounted(scene, sorts))
        camera.eye = (0.5, 1.0, 2.5)  # another view: still row order
        assert np.array_equal(e.render(scene).array, fresh_uncounted(scene, sorts))
        assert sorts == [], "row order: nothing sorted"


def test_the_instance_cull_keeps_exactly_the_spheres_meeting_the_frustum():
    """``drawer.cull_spheres`` (column by column) against the plain per-instance computation."""
    from omnirender.gl.engine.drawer import cull_spheres

    rng = np.random.default_rng(3)
    camera = om.Camera.look_at((3, 4, 10), (0, 0, 0), fov=45)
    clip = camera.projection_matrix(1.3) @ camera.view_matrix()
    planes = [clip[3] + clip[i // 2] * (1 if i % 2 == 0 else -1) for i in range(6)]
    n = 400
    m = np.zeros((n, 4, 4))
    m[:, :3, :3] = rng.normal(size=(n, 3, 3))  # rotations, shears, mirrors, scales
    m[: n // 2, :3, :3] = np.eye(3) * rng.uniform(0.2, 2.0, (n // 2, 1, 1))  # positions with uniform scales
    m[:, :3, 3] = rng.uniform(-15, 15, (n, 3))
    m[:, 3, 3] = 1.0
    bounds = (np.array([-0.5, -0.2, 0.1]), np.array([0.7, 0.4, 0.3]))
    center = np.append((bounds[0] + bounds[1]) / 2, 1.0)
    radius = np.linalg.norm(bounds[1] - bounds[0]) / 2
    rows = m.transpose(0, 2, 1).reshape(n, 16).astype(np.float32)  # as the rows hold them: M transposed
    expected = []
    for i in range(n):
        mi = rows[i].reshape(4, 4).T.astype(np.float64)
        c, scale = mi @ center, max(np.linalg.norm(mi[:3, k]) for k in range(3))
        expected.append(all(p @ c / np.linalg.norm(p[:3]) > -radius * scale for p in planes))
    visible = cull_spheres(rows, bounds, clip)
    assert 0 < sum(expected) < n
    assert visible is not None and visible.tolist() == expected
    assert cull_spheres(rows[np.array(expected)], bounds, clip) is None, "all of them in view: None"


@pytest.mark.parametrize("policy", POLICIES)
@pytest.mark.parametrize("center", [(0.0, 0.0, 0.0), (0.4, 0.0, 0.2)], ids=["centred", "shifted shape"])
def test_a_set_with_scales_and_a_mask_moves_its_positions_alone_while_they_are_not_written(policy, center):
    """The README's swarm (radii, an alive mask, colours): ``touch("transforms")`` moves the visible instances'
    rows without making them again; a touch naming the scales or the mask (or a plain one) makes them again."""
    positions, colors = swarm(240, seed=9)
    radii = np.random.default_rng(9).uniform(0.1, 0.3, 240)
    alive = np.ones(240, bool)
    alive[::7] = False
    balls = om.InstanceSet(om.Box(size=1.0, center=center), positions, colors=colors, scales=radii, visible=alive)
    camera = om.Camera.look_at((0, 5, 12), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), balls])
    with engine_for(policy) as e:
        e.render(scene)
        e.render(scene)
        for step in range(3):
            positions[:, 1] += 0.15
            positions[step * 7] += 0.4  # a hidden one moves too
            balls.touch("transforms")
            image = e.render(scene)
            assert not e.stats["compiled"]
            assert image.info["replayed"] == (center == (0.0, 0.0, 0.0)), "positions alone: uploaded, replayed"
            assert np.array_equal(image.array, fresh(scene)), step
        alive[::7] = True  # the mask written (as many hidden, others): rows made again for the visible ones
        alive[1::7] = False
        assert (~alive).sum() == 35
        positions[:, 0] -= 0.1
        balls.touch("transforms", "visible")
        assert np.array_equal(e.render(scene).array, fresh(scene))
        radii *= 1.5  # the scales written
        balls.touch("scales")
        assert np.array_equal(e.render(scene).array, fresh(scene))
        positions[:, 2] += 0.2
        balls.touch("transforms")
        image = e.render(scene)
        assert np.array_equal(image.array, fresh(scene))
        # plain touches: the scales and the mask are compared with the rows' copies
        positions[:, 2] -= 0.2
        balls.touch()
        image = e.render(scene)
        assert image.info["replayed"] == (center == (0.0, 0.0, 0.0)), "unchanged scales and mask: positions alone"
        assert np.array_equal(image.array, fresh(scene))
        alive[1::7] = True  # as many hidden, others again, in place
        alive[2::7] = False
        balls.touch()
        assert np.array_equal(e.render(scene).array, fresh(scene))
        radii[:10] *= 0.5
        balls.touch()
        assert np.array_equal(e.render(scene).array, fresh(scene))
