"""Positions-only changes rewrite only the translation columns of a batch's GPU content (issue 22).

A batch keeps ``packed``, the content of its GPU buffer; when only
translations moved since the last upload (an instance set's positions, a
touched ``om.TranslationArray``, a setter loop over most translations), the
upload writes just those columns into it and sends the range, without
packing every field of the rows again (``drawer._pack`` is not called).  Any
other change (colours, a material, rows added) packs the rows as before.
Every frame equals a fresh engine's, including after the camera moves (the
batch is sorted again and its mirror made again).
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


@pytest.fixture
def packs(monkeypatch):
    from omnirender.gl.engine import drawer

    calls: list[int] = []
    original = drawer._pack

    def counting(rows, order, columns):
        calls.append(len(rows) if order is None else len(order))
        return original(rows, order, columns)

    monkeypatch.setattr(drawer, "_pack", counting)
    return calls


def test_instance_positions_rewrite_only_translations_and_match_a_fresh_engine(packs):
    from omnirender.gl import GLEngine

    n = 300  # a sorted batch (more than drawer.SORT_MIN)
    rng = np.random.default_rng(5)
    positions = rng.uniform(-3, 3, (n, 3))
    colors = np.concatenate([rng.uniform(0.2, 1.0, (n, 3)), np.ones((n, 1))], axis=1)
    balls = om.InstanceSet(om.Box(size=0.25), positions, colors=colors)
    camera = om.Camera.look_at((0, 5, 12), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), balls])
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        for step in range(3):
            positions[:, 1] += 0.15
            positions[step * 7, 2] -= 1.0
            balls.touch()
            packs.clear()
            image = e.render(scene).array
            assert not packs, "positions only: no row packed again"
            assert (image != image[0, 0]).any(axis=2).mean() > 0.02
            assert np.array_equal(image, fresh(scene))
        colors[:20, :3] = (1.0, 0.1, 0.1)  # colours changed: the rows are packed again
        balls.touch()
        packs.clear()
        assert np.array_equal(e.render(scene).array, fresh(scene)) and packs
        camera.eye = (1.0, 4.0, 12.5)  # another view: sorted again, the mirror made again
        e.render(scene)
        positions[:, 0] += 0.2
        balls.touch()
        packs.clear()
        image = e.render(scene).array
        assert not packs and np.array_equal(image, fresh(scene))


def test_a_translation_array_and_a_setter_loop_rewrite_only_translations(packs):
    from omnirender.gl import GLEngine

    n = 120
    i = np.arange(n)
    positions = np.stack([(i % 12 - 5.5) * 0.7, (i // 12 - 4.5) * 0.6, 0.2 * (i % 3)], axis=1)
    moves = om.TranslationArray(positions)
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 14), (0, 0, 0), fov=45)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.35)
    for k in range(n):
        scene.add(om.Node(f"b{k}", [moves[k], om.Material(diffuse=(0.2 + 0.006 * k, 0.6, 0.4)), box]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        positions[:, 1] += 0.1
        moves.touch()
        packs.clear()
        image = e.render(scene).array
        assert not packs and np.array_equal(image, fresh(scene))
        for step in range(2):  # the plan's own map is made on the second such frame (the first: general path)
            for t, row in zip(moves, positions - (0.0, 0.25 * (step + 1), 0.0), strict=True):
                t.offset = row
            packs.clear()
            image = e.render(scene).array
            packed = list(packs)  # (the fresh engine below packs its own rows)
            assert np.array_equal(image, fresh(scene))
        assert not packed
        scene.child("b7").remove(scene.child("b7").items[1])  # a material replaced: that row packed again
        scene.child("b7").insert(1, om.Material(diffuse=(1.0, 0.0, 0.0)))
        positions[:, 0] -= 0.1
        moves.touch()
        assert np.array_equal(e.render(scene).array, fresh(scene))
        positions[:, 0] += 0.3
        moves.touch()
        packs.clear()
        image = e.render(scene).array
        assert np.array_equal(image, fresh(scene))


@pytest.fixture
def writes(monkeypatch):
    """(bytes, offset) of every GPU buffer write, in order."""
    import moderngl

    calls: list[tuple[int, int]] = []
    original = moderngl.Buffer.write

    def counting(self, data, offset=0):
        calls.append((memoryview(data).nbytes, offset))
        return original(self, data, offset)

    monkeypatch.setattr(moderngl.Buffer, "write", counting)
    return calls


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_instance_positions_upload_only_the_positions_buffer(writes, dtype):
    """A positions-only change of a set in view writes the (N, 3) float32 translations (their own buffer) and
    nothing else; the pictures equal a fresh engine's (default shadows on), culled or not."""
    from omnirender.gl import GLEngine

    n = 300
    rng = np.random.default_rng(7)
    positions = rng.uniform(-3, 3, (n, 3)).astype(dtype)
    colors = np.concatenate([rng.uniform(0.2, 1.0, (n, 3)), np.ones((n, 1))], axis=1)
    balls = om.InstanceSet(om.Box(size=0.25), positions, colors=colors)
    camera = om.Camera.look_at((0, 5, 12), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), balls])
    with GLEngine(size=SIZE, samples=0) as e:
        e.drawer.sorts_instances = True  # culled and drawn front to back (a software rasteriser's way) on any GL
        e.render(scene)
        for step in range(2):
            positions[:, 1] += 0.1
            positions[step * 7, 0] -= 0.5
            balls.touch()
            writes.clear()
            image = e.render(scene).array
            # one write of the N float32 triples per batch drawing the set (the shadow map's and the view's)
            assert writes and all(w == (n * 12, 0) for w in writes), "positions only: the positions alone"
            assert np.array_equal(image, fresh_shadowed(scene))
        camera.eye = (0.0, 1.0, 2.5)  # close up: some instances culled, the rest drawn first
        e.render(scene)
        drawn = sum(p["items"] for p in e.stats["passes"] if p["name"] == "opaque")
        assert 0 < drawn < n
        positions[:, 2] += 0.05
        balls.touch()
        image = e.render(scene).array  # a partly culled set is culled again when it moves (rows re-ordered)
        assert np.array_equal(image, fresh_shadowed(scene))
        colors[:20, :3] = (1.0, 0.1, 0.1)  # colours changed: the rows are written again (once per change)
        balls.touch()
        writes.clear()
        image = e.render(scene).array
        assert any(size > n * 12 for size, _ in writes)
        assert np.array_equal(image, fresh_shadowed(scene))


def fresh_shadowed(scene: om.Node) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0) as e:
        return e.render(scene).array
