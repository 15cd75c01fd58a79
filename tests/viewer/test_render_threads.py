"""Render threads on immutable snapshots: sharing by version, immutability, mirrors, latest-wins clients."""

from __future__ import annotations

import copy
import threading
import time

import numpy as np
import pytest

import omnirender as om
from omnirender.scene import SceneMirror, Snapshotter
from omnirender.viewer import RenderClient, RenderThreads


def many_nodes(n: int = 200) -> tuple[om.Node, list[om.Translation]]:
    root = om.Node("root")
    root.add(om.Camera.look_at((0, 0, 30)))
    moves = []
    for i in range(n):
        node = root.add(om.Node(f"n{i}"))
        moves.append(node.add(om.Translation(i % 20, i // 20, 0)))
        node.add(om.Sphere(radius=0.25))
    return root, moves


def test_unchanged_subtrees_are_shared_and_changed_paths_rebuilt():
    root, moves = many_nodes()
    snaps = Snapshotter(root)
    first = snaps.take()
    assert first.built == 201 and first.shared == 0
    again = snaps.take()
    assert again.root is first.root and again.built == 0  # nothing changed: the whole tree is shared
    moves[7].offset = (50, 0, 0)
    third = snaps.take()
    assert third.built == 2 and third.shared == 199  # the root and the moved node
    kids_before, kids = again.root.children, third.root.children
    assert all(kids[i] is kids_before[i] for i in range(200) if i != 7)
    assert kids[7] is not kids_before[7]
    np.testing.assert_allclose(kids[7].world[:3, 3], (50, 0, 0))
    np.testing.assert_allclose(kids_before[7].world[:3, 3], (7, 0, 0))  # the old snapshot still shows its frame
    # the component that did not change keeps its frozen copy
    assert kids[7].items[1] is kids_before[7].items[1] and kids[7].items[0] is not kids_before[7].items[0]


def test_world_transforms_and_bounds_are_resolved():
    root = om.Node("root")
    arm = root.add(om.Node("arm", [om.Translation(1, 0, 0)]))
    hand = arm.add(om.Node("hand", [om.Translation(0, 2, 0), om.Sphere(radius=0.5)]))
    hand.add(om.Box(size=(1, 1, 1), center=(0, 0, 3)))
    snap = Snapshotter(root).take()
    node = snap.root.children[0].children[0]
    np.testing.assert_allclose(node.world[:3, 3], (1, 2, 0))
    lo, hi = snap.root.bounds
    np.testing.assert_allclose(lo, (0.5, 1.5, -0.5))
    np.testing.assert_allclose(hi, (1.5, 2.5, 3.5))
    np.testing.assert_allclose(np.array(om.bounds(root)), np.array([lo, hi]))


def test_snapshots_do_not_change_with_the_scene():
    positions = np.zeros((4, 3))
    root = om.Node("root", [om.InstanceSet(om.Sphere(radius=0.1), positions)])
    snap = Snapshotter(root).take()
    frozen = snap.root.items[0]
    positions[:] = 5.0  # the application writes its array in place
    root.items[0].touch()
    assert np.all(frozen.transforms == 0.0) and not frozen.transforms.flags.writeable
    with pytest.raises(AttributeError, match="immutable"):
        snap.root.name = "other"


def test_a_mirror_renders_what_the_scene_renders_through_changes():
    scene, moves = many_nodes(60)
    snaps, mirror = Snapshotter(scene), SceneMirror()
    with om.gl.GLEngine(size=(160, 120)) as engine, om.gl.GLEngine(size=(160, 120)) as reference:
        for step in range(4):
            if step == 1:
                for t in moves[::3]:
                    t.offset = (t.offset[0], t.offset[1] + 0.5, 0)
            if step == 2:
                scene.children[5].add(om.Color((1, 0, 0)))  # a list changes
                scene.remove(scene.children[9])
            if step == 3:
                moves[0].offset = (3, 3, 3)
            mine = engine.render(mirror.apply(snaps.take())).array
            assert np.array_equal(mine, reference.render(scene).array), step
            if step == 3:
                assert mirror.rebuilt == 0 and mirror.updated == 1  # one transform updated in place


def frame_code(frame: int) -> tuple[float, float, float]:
    """An emission colour that encodes a frame number (steps of 16 levels per channel)."""
    return ((24 + 16 * (frame % 14)) / 255, (24 + 16 * (frame // 14 % 14)) / 255, 0.0)


def decode(rgb: np.ndarray) -> int:
    r, g = (int(round((float(v) - 24) / 16)) for v in rgb[:2])
    return r + 14 * g


def coded_scene(count: int = 8) -> tuple[om.Node, list[om.Material], list[om.Translation]]:
    scene = om.Node("coded", [om.Camera.orthographic((0, 0, 10), height=4), om.Background((0, 0, 0.5))])
    materials, moves = [], []
    for i in range(count):
        node = scene.add(om.Node(f"box{i}"))
        moves.append(node.add(om.Translation(-3.5 + i, 0, 0)))
        materials.append(node.add(om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), emission=frame_code(0))))
        node.add(om.Box(size=(0.6, 0.6, 0.6)))
    return scene, materials, moves


def app_frame(frame: int, materials, moves) -> None:
    """Every object encodes the frame twice: its colour and its height (all objects at the same height)."""
    y = 0.8 * np.sin(frame * 0.7)
    for material, move in zip(materials, moves, strict=True):
        material.emission = frame_code(frame)
        move.offset = (move.offset[0], y, 0)


def check_consistent(image: np.ndarray, frame: int) -> None:
    """Each box shows ``frame`` in its colour and sits at that frame's height."""
    h, w = image.shape[:2]
    expected_row = h / 2 - 0.8 * np.sin(frame * 0.7) * h / 4
    for i in range(8):
        col = int(w / 2 + (-3.5 + i) * w / (4 * w / h))
        column = image[:, col, :3].astype(int)
        rows = np.nonzero(column[:, 2] < 60)[0]  # the box (the background is blue)
        assert len(rows), (frame, i)
        assert abs(rows.mean() - expected_row) < 1.5, (frame, i, rows.mean(), expected_row)
        assert decode(column[int(rows.mean())]) == frame % 196, (frame, i, column[int(rows.mean())])


def test_every_rendered_frame_is_one_snapshot_and_clients_draw_the_same_snapshots():
    scene, materials, moves = coded_scene()
    images: dict[str, list] = {"engine": [], "viewer": []}

    def keep(name):
        def on_frame(image, snapshot):
            images[name].append((snapshot.frame, image.array.copy()))
            time.sleep(0.02)

        return on_frame

    clients = [
        RenderClient((160, 80), samples=0, on_frame=keep("engine"), name="engine"),
        RenderClient(renderer=lambda: om.Viewer(size=(160, 80), samples=0), on_frame=keep("viewer"), name="viewer"),
    ]
    with RenderThreads(scene, clients) as threads:
        for frame in range(1, 40):
            app_frame(frame, materials, moves)
            published = threads.publish()
            assert published.frame == frame
            time.sleep(0.004)
        assert all(c.wait_for(39) for c in clients), [c.error for c in clients]
    for name, made in images.items():
        frames = [f for f, _ in made]
        assert frames == sorted(set(frames)) and frames[-1] == 39, (name, frames)  # newest wins, in order
        for frame, image in made:
            check_consistent(image, frame)
    # both threads drew the final snapshot the same way
    last = {name: made[-1][1] for name, made in images.items()}
    assert np.abs(last["engine"].astype(int) - last["viewer"]).max() <= 2


def run_app(frames: int, threads: RenderThreads | None, materials, moves) -> tuple[float, float]:
    """The application loop at 60 Hz (sleeping to absolute deadlines); returns its frame rate and the
    longest ``publish`` call."""
    period = 1.0 / 60.0
    start = time.perf_counter()
    deadline = start
    longest = 0.0
    for frame in range(1, frames + 1):
        app_frame(frame, materials, moves)
        if threads is not None:
            before = time.perf_counter()
            threads.publish()
            longest = max(longest, time.perf_counter() - before)
        deadline += period
        time.sleep(max(0.0, deadline - time.perf_counter()))
    return frames / (time.perf_counter() - start), longest


def test_a_slow_renderer_never_slows_the_application_loop():
    """The loop keeps its rate within 10 % beside a renderer taking 100 ms per frame.

    Timing on a shared 2-core machine: each attempt measures the loop alone and beside the renderer
    back to back, and one attempt in three must pass; a loop that waited for the renderer would run
    at 10 Hz in all of them.  The figures are printed by bench/snapshots.py.
    """
    scene, materials, moves = coded_scene()
    frames = 45
    results = []
    for _ in range(3):
        alone, _ = run_app(frames, None, materials, moves)
        drawn: list[int] = []

        def slow(image, snapshot, drawn=drawn):  # this renderer takes at least 100 ms per frame
            drawn.append(snapshot.frame)
            time.sleep(0.1)

        client = RenderClient((160, 80), on_frame=slow, name="slow")
        with RenderThreads(scene, [client]) as threads:
            loaded, longest = run_app(frames, threads, materials, moves)
            assert client.wait_for(frames)
        # never one snapshot twice or out of order, and the last one drawn: whatever the machine's load
        assert drawn == sorted(set(drawn)) and drawn[-1] == frames
        # timing, retried with the rest: latest wins (the client skipped most snapshots), publishing never
        # waits for the 100 ms renderer, and the loop keeps its rate
        timing = {
            "skipped most": client.dropped > frames / 2 and len(drawn) < frames / 3,
            "publishing never waited": longest < 0.05,
            "rate kept": loaded >= 0.9 * min(alone, 60.0),
        }
        results.append((round(alone, 1), round(loaded, 1), round(longest, 3), client.dropped, len(drawn)))
        if all(timing.values()):
            return
    pytest.fail(
        "beside a 100 ms renderer the application loop slowed by more than 10 %, waited, or the client drew "
        f"too many snapshots in every attempt: (alone Hz, loaded Hz, longest publish s, dropped, drawn) {results}"
    )


def test_render_client_errors_reach_the_application():
    scene, _, _ = coded_scene()

    def broken():
        raise RuntimeError("no GPU today")

    client = RenderClient(renderer=broken, name="broken")
    with RenderThreads(scene, [client]) as threads:
        assert not client.wait_for(1, timeout=10)  # the thread failed making its renderer
        with pytest.raises(RuntimeError, match="render client 'broken' failed"):
            threads.publish()
    with pytest.raises(TypeError, match="RenderClient"):
        RenderThreads(scene, ["viewer"])
    with pytest.raises(TypeError, match="om.Node"):
        Snapshotter(om.Sphere())


def test_snapshots_are_cheaper_than_a_deep_copy():
    root, moves = many_nodes(2000)
    snaps = Snapshotter(root)
    snaps.take()
    moves[3].offset = (1, 1, 1)
    start = time.perf_counter()
    one = snaps.take()
    incremental = time.perf_counter() - start
    start = time.perf_counter()
    copy.deepcopy(root)
    deep = time.perf_counter() - start
    assert one.built == 2
    assert incremental < deep  # a property, not a speed target: the numbers are in bench/snapshots.py
    assert threading.active_count() >= 1


def test_world_matrices_follow_added_and_removed_transforms():
    root = om.Node("root")
    node = root.add(om.Node("n", [om.Translation(1, 0, 0)]))
    child = node.add(om.Node("child", [om.Sphere()]))
    snaps = Snapshotter(root)
    np.testing.assert_allclose(snaps.take().root.children[0].children[0].parent_world[:3, 3], (1, 0, 0))
    extra = node.insert(0, om.Translation(0, 2, 0))
    np.testing.assert_allclose(snaps.take().root.children[0].world[:3, 3], (1, 2, 0))
    node.remove(extra)
    snap = snaps.take()
    np.testing.assert_allclose(snap.root.children[0].world[:3, 3], (1, 0, 0))
    np.testing.assert_allclose(snap.root.children[0].children[0].parent_world[:3, 3], (1, 0, 0))
    assert child.version >= 0
