"""Immutable snapshots for render threads (issue 12): what a snapshot costs, and the application loop's rate.

All figures come from one run, as ratios against a baseline measured in the
same run:

* snapshots of a 10,000-node scene built as the README teaches (a node per
  ball: ``Translation``, ``Material``, a ``Sphere``): nothing changed, one
  node moved, every node moved, against ``copy.deepcopy`` of the scene (the
  naive way to hand a render thread a consistent copy); best of ``--repeat``;
* a 60 Hz application loop moving 200 objects and publishing a snapshot per
  frame to render clients (one or two taking 100 ms per frame; one drawing
  every snapshot it can), against the same loop with no clients: frame rates
  and their ratio, the frames the clients drew and dropped.

Run: ``.venv/bin/python bench/snapshots.py`` (``--quick`` for 2,000 nodes).
"""

from __future__ import annotations

import argparse
import copy
import time

import omnirender as om
from omnirender.scene import Snapshotter
from omnirender.viewer import RenderClient, RenderThreads


def scene(count: int) -> tuple[om.Node, list[om.Translation]]:
    root = om.Node("balls", [om.Camera.look_at((50, 50, 200), (50, 50, 0)), om.PointLight(position=(50, 50, 100))])
    moves = []
    for i in range(count):
        ball = root.add(om.Node(f"ball{i}"))
        moves.append(ball.add(om.Translation(i % 100, i // 100, 0)))
        ball.add(om.Material(diffuse=(0.8, 0.3 + 0.5 * (i % 2), 0.2)))
        ball.add(om.Sphere(radius=0.4))
    return root, moves


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def snapshot_costs(count: int, repeat: int) -> None:
    root, moves = scene(count)
    snaps = Snapshotter(root)
    snaps.take()
    deep = best(lambda: copy.deepcopy(root), repeat)
    unchanged = best(snaps.take, repeat)
    step = [0]

    def one() -> None:
        step[0] += 1
        moves[count // 2].offset = (step[0] % 7, 0, 0)
        snaps.take()

    def every() -> None:
        step[0] += 1
        for t in moves:
            t.offset = (t.offset[0], t.offset[1], step[0] % 5)
        snaps.take()

    changed_one = best(one, repeat)
    changed_all = best(every, repeat)
    print(f"snapshot of {count:,} nodes (best of {repeat}); baseline copy.deepcopy: {deep * 1e3:.1f} ms")
    for label, value in (("nothing changed", unchanged), ("one node moved", changed_one),
                         ("every node moved", changed_all)):  # fmt: skip
        print(f"  {label:18s} {value * 1e3:9.3f} ms   {value / deep:8.4f}x deepcopy")


def app_rates(seconds: float) -> None:
    root, moves = scene(200)
    frames = int(60 * seconds)

    def loop(threads: RenderThreads | None) -> float:
        period, start = 1.0 / 60.0, time.perf_counter()
        deadline = start
        for f in range(frames):
            for t in moves:
                t.offset = (t.offset[0], t.offset[1], (f % 30) * 0.1)
            if threads is not None:
                threads.publish()
            deadline += period
            time.sleep(max(0.0, deadline - time.perf_counter()))
        return frames / (time.perf_counter() - start)

    def slow(name: str) -> RenderClient:  # a renderer that takes (its drawing plus) 100 ms per frame
        return RenderClient((320, 240), on_frame=lambda image, snap: time.sleep(0.1), name=name)

    alone = loop(None)
    print(f"application loop at 60 Hz, {frames} frames, 200 moving objects; alone: {alone:.1f} Hz")
    for label, clients in (
        ("one renderer taking 100 ms per frame", [slow("slow")]),
        ("two renderers taking 100 ms per frame", [slow("slow 1"), slow("slow 2")]),
        ("one renderer drawing every snapshot (as fast as it can)", [RenderClient((320, 240), name="eager")]),
    ):
        with RenderThreads(root, clients) as threads:
            loaded = loop(threads)
            for client in clients:
                client.wait_for(frames)
        drawn = ", ".join(f"{c.name!r} drew {c.frames} and dropped {c.dropped}" for c in clients)
        print(f"  {label}: {loaded:.1f} Hz ({loaded / alone:.3f}x alone); {drawn}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    snapshot_costs(2000 if args.quick else 10000, args.repeat)
    app_rates(1.5 if args.quick else 4.0)


if __name__ == "__main__":
    main()
