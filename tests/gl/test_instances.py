"""Instance sets in the GL engine: the same pictures as nodes, updated in place, checked arrays, culling, picking."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)
BLACK = (0, 0, 0)


def fresh(scene: om.Node, size: tuple[int, int] = SIZE) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=size, samples=0) as e:
        return e.render(scene, background=BLACK).array


def swarm(n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    positions = np.stack([np.arange(n) % 8 - 3.5, np.full(n, 0.5), np.arange(n) // 8 - 2.0], axis=1)
    positions += rng.normal(0.0, 0.1, (n, 3))
    colors = np.concatenate([rng.uniform(0.2, 1.0, (n, 3)), np.ones((n, 1))], axis=1)
    return positions, colors


def stage(*items: object, floor: bool = True) -> om.Node:
    scene = om.Node("scene", [om.Camera.look_at((0, 6, 12), (0, 0, 0), fov=40), om.PointLight(position=(3, 8, 4))])
    if floor:
        box = om.Box(size=(12, 0.1, 12), center=(0, -1, 0))
        scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.8)), box]))
    scene.add(om.Node("swarm", list(items)))
    return scene


def test_an_instance_set_draws_exactly_what_the_same_nodes_draw():
    positions, colors = swarm()
    ball = om.Sphere(radius=0.3)
    nodes = stage()
    for i, (p, c) in enumerate(zip(positions, colors, strict=True)):
        nodes["/scene/swarm"].add(om.Node(f"b{i}", [om.Translation(*p), om.Color(*c), ball]))
    instanced = stage(om.InstanceSet(ball, positions, colors=colors))
    image = fresh(instanced)
    assert np.array_equal(image, fresh(nodes))  # shadows and all
    assert (image[..., :3].sum(axis=2) > 0).mean() > 0.3


def test_arrays_written_in_place_update_without_a_compile_and_match_a_fresh_engine():
    from omnirender.gl import GLEngine

    positions, colors = swarm()
    instances = om.InstanceSet(om.Sphere(radius=0.3), positions, colors=colors)
    scene = stage(om.Translation(0.0, 0.0, 0.0), instances)
    rng = np.random.default_rng(5)
    with GLEngine(size=SIZE, samples=0) as e:
        first = e.render(scene, background=BLACK).array
        for _ in range(3):
            positions += rng.normal(0.0, 0.15, positions.shape)  # the application's own array
            colors[::5, :3] = rng.uniform(0.2, 1.0, (len(colors[::5]), 3))
            instances.touch()
            image = e.render(scene, background=BLACK)
            assert e.stats["compiled"] is False and e.stats["incremental"] == 1
            assert np.array_equal(image.array, fresh(scene))
        assert not np.array_equal(image.array, first)
        scene["/scene/swarm"].components[0].offset = (0.5, 0.0, -0.5)  # the transform above the set
        image = e.render(scene, background=BLACK)
        assert e.stats["compiled"] is False
        assert np.array_equal(image.array, fresh(scene))


def test_an_instance_becoming_translucent_goes_through_the_compile():
    from omnirender.gl import GLEngine

    positions, colors = swarm(16)
    instances = om.InstanceSet(om.Box(size=0.5), positions, colors=colors)
    scene = stage(instances)
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene, background=BLACK)
        colors[4, 3] = 0.4  # drawn in the transparent pass now
        instances.touch()
        image = e.render(scene, background=BLACK)
        assert e.stats["compiled"] is True
        assert np.array_equal(image.array, fresh(scene))


def _side_coverage(image: np.ndarray) -> tuple[float, float]:
    lit = image[..., :3].sum(axis=2) > 0
    half = image.shape[1] // 2
    return float(lit[:, :half].mean()), float(lit[:, half:].mean())


def test_removed_and_hidden_instances_disappear():
    from omnirender.gl import GLEngine

    positions = np.array([(-2.5, 0.0, 0.0), (2.5, 0.0, 0.0)])
    instances = om.InstanceSet(om.Box(size=1.5), positions)
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 8), (0, 0, 0), fov=50), om.Node("pair", [instances])])
    with GLEngine(size=SIZE, samples=0) as e:
        left, right = _side_coverage(e.render(scene, background=BLACK).array)
        assert left > 0.05 and right > 0.05
        instances.transforms = positions[:1]  # the right-hand box removed
        image = e.render(scene, background=BLACK).array
        assert _side_coverage(image)[1] == 0.0 and _side_coverage(image)[0] == pytest.approx(left)
        assert np.array_equal(image, fresh(scene))
        instances.transforms = positions
        instances.visible = np.array([False, True])  # hidden, not removed
        image = e.render(scene, background=BLACK).array
        assert _side_coverage(image)[0] == 0.0 and _side_coverage(image)[1] == pytest.approx(right)
        assert np.array_equal(image, fresh(scene))


@pytest.mark.parametrize(
    ("arrays", "message"),
    [
        ({"transforms": np.zeros((4, 2))}, "transforms must be (N, 4, 4) matrices or (N, 3) positions"),
        ({"transforms": np.array([[0, 0, 0]] * 3 + [[0, np.nan, 0]], float)}, "instance 3 are not finite"),
        ({"transforms": np.stack([np.eye(4), np.eye(4), np.diag([1.0, 0.0, 1.0, 1.0])])}, "instance 2 is singular"),
        ({"transforms": np.zeros((3, 3)), "scales": np.array([1.0, 0.0, 2.0])}, "scales of instance 1 are zero"),
        ({"transforms": np.zeros((3, 3)), "scales": np.ones((2,))}, "scales must be (3,) or (3, 3)"),
        ({"transforms": np.zeros((3, 3)), "colors": np.ones((3, 2))}, "colors must be (3, 3) or (3, 4)"),
        ({"transforms": np.zeros((3, 3)), "colors": [(1, 0, 0), (1.5, 0, 0), (0, 0, 1)]}, "colours of instance 1"),
        ({"transforms": np.zeros((3, 3)), "visible": np.ones(4, bool)}, "visible must have shape (3,)"),
    ],
)
def test_bad_arrays_are_refused_naming_the_instance(arrays, message):
    with pytest.raises(ValueError, match=r"InstanceSet: .*") as info:
        om.InstanceSet(om.Box(), **arrays)
    assert message in str(info.value)


def test_an_array_spoiled_in_place_is_refused_when_drawn_with_its_node_path():
    positions = np.zeros((5, 3))
    instances = om.InstanceSet(om.Box(), positions)
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 10)), om.Node("swarm", [instances])])
    om.render(scene, engine="gl", size=(16, 16))
    positions[3, 1] = np.inf
    instances.touch()
    with pytest.raises(ValueError, match=r"instance 3 are not finite.*visible=.*/scene/swarm"):
        om.render(scene, engine="gl", size=(16, 16))


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
def test_an_array_of_another_length_resizes_the_buffer():
    from omnirender.gl import GLEngine

    rng = np.random.default_rng(9)
    instances = om.InstanceSet(om.Sphere(radius=0.2), rng.uniform(-3, 3, (10, 3)))
    scene = stage(instances)
    with GLEngine(size=SIZE, samples=0) as e:
        for n in (10, 200, 5, 300, 0, 40):
            instances.transforms = rng.uniform(-3, 3, (n, 3))
            image = e.render(scene, background=BLACK)
            assert np.array_equal(image.array, fresh(scene))
            (batch,) = [b for b in e.batches if b.items[0].source is instances]
            assert len(batch.rows) == n and batch.capacity >= n


@pytest.mark.slow
def test_gpu_memory_stays_bounded_over_ten_thousand_frames_of_resizing():
    """llvmpipe keeps buffers in process memory: the resident set is the GPU memory here."""
    from omnirender.gl import GLEngine

    def resident_mb() -> float:
        with open("/proc/self/statm") as fh:
            import os

            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6

    rng = np.random.default_rng(11)
    instances = om.InstanceSet(om.Box(size=0.1), rng.uniform(-1, 1, (1, 3)))
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 4)), om.Node("swarm", [instances])])
    with GLEngine(size=(24, 24), samples=0, shadows=False) as e:
        settled = None
        for frame in range(10_000):
            instances.transforms = rng.uniform(-1, 1, (int(rng.integers(0, 400)), 3))
            e.render(scene, read_depth=False)
            if frame == 1_000:
                settled = resident_mb()
        grown = resident_mb() - settled
        assert all(b.capacity <= 400 for b in e.batches)
    assert grown < 25.0, f"resident memory grew by {grown:.1f} MB over 9,000 frames"


def test_culling_leaves_the_picture_unchanged_and_culled_instances_come_back(monkeypatch):
    """Big batches draw only what their bounding spheres show; moving culled instances into view shows them."""
    from omnirender.gl import GLEngine
    from omnirender.gl.engine import drawer

    rng = np.random.default_rng(2)
    positions = rng.uniform(-12, 12, (600, 3))
    instances = om.InstanceSet(om.Sphere(radius=0.4), positions)
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 6), (0, 0, 0), fov=40), om.Node("swarm", [instances])])
    with GLEngine(size=SIZE, samples=0) as e:
        e.drawer.sorts_instances = True  # culled (a software rasteriser's way) on any GL
        culled = e.render(scene, background=BLACK).array
        drawn = sum(p["items"] for p in e.stats["passes"] if p["name"] == "opaque")
        assert 0 < drawn < 300  # most of the 600 are outside the view
        positions *= 0.25  # everything moves towards the view axis: culled ones come in
        instances.touch()
        moved = e.render(scene, background=BLACK).array
        assert sum(p["items"] for p in e.stats["passes"] if p["name"] == "opaque") > drawn
    monkeypatch.setattr(drawer, "SORT_MIN", 10**9)  # neither sorted nor culled
    assert np.array_equal(moved, fresh(scene))
    positions *= 4.0
    instances.touch()
    assert np.array_equal(culled, fresh(scene))


def test_culling_applies_to_plain_nodes_too(monkeypatch):
    from omnirender.gl import GLEngine
    from omnirender.gl.engine import drawer

    rng = np.random.default_rng(4)
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 6), (0, 0, 0), fov=40)])
    ball = om.Sphere(radius=0.4)
    moves = []
    for i, p in enumerate(rng.uniform(-12, 12, (300, 3))):
        moves.append(om.Translation(*p))
        scene.add(om.Node(f"b{i}", [moves[-1], ball]))
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene, background=BLACK)
        assert sum(p["items"] for p in e.stats["passes"] if p["name"] == "opaque") < 150
        for t in moves:
            t.offset = tuple(0.25 * c for c in t.offset)
        moved = e.render(scene, background=BLACK).array
        assert e.stats["compiled"] is False
    monkeypatch.setattr(drawer, "SORT_MIN", 10**9)
    assert np.array_equal(moved, fresh(scene))


def test_picking_reports_the_instance_index():
    positions = np.array([(x, 0.0, 0.0) for x in (-3.0, -1.0, 1.0, 3.0)])
    instances = om.InstanceSet(om.Box(size=1.0), positions)
    camera = om.Camera.look_at((0, 0, 10), (0, 0, 0), fov=40)
    scene = om.Node("scene", [camera, om.Node("row", [instances])])
    size = (200, 100)
    for index, x in enumerate(positions[:, 0]):
        clip = camera.projection_matrix(size[0] / size[1]) @ camera.view_matrix() @ np.array([x, 0.0, 0.5, 1.0])
        px = (clip[0] / clip[3] * 0.5 + 0.5) * size[0]
        hits = om.pick(scene, pixel=(px, size[1] / 2), size=size, camera=camera)
        assert hits and hits[0].instance == index
        assert hits[0].shape is instances and hits[0].path == "/scene/row"


def test_parts_with_their_own_material_keep_it_as_in_every_other_engine():
    """Instance colours act as an om.Color before the shape: a mesh file's own material wins over them."""
    from pathlib import Path

    mesh = om.MeshFile(Path(__file__).resolve().parents[1] / "data_files" / "cube.obj")
    positions, colors = swarm(6)
    instanced = stage(om.InstanceSet(mesh, positions, colors=colors, scales=np.full(6, 0.8)), floor=False)
    nodes = stage(floor=False)
    for i, (p, c) in enumerate(zip(positions, colors, strict=True)):
        nodes["/scene/swarm"].add(om.Node(f"b{i}", [om.Translation(*p), om.Scaling(0.8), om.Color(*c), mesh]))
    image = fresh(instanced)
    assert np.array_equal(image, fresh(nodes))
    lit = image[..., :3][image[..., :3].sum(axis=2) > 0].astype(int)
    # the file's red plus white highlights (green = blue everywhere), not the instances' colours
    assert len(lit) > 200 and (lit[:, 1] == lit[:, 2]).all() and (lit[:, 0] > lit[:, 1]).mean() > 0.9
