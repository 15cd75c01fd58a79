"""Frames of an animation on a 2-worker local Dask cluster versus one process.

The demo scene (``omnirender demo``) as a turntable, built the way the README
teaches (``om.turntable(scene, seconds)``), rendered with POV-Ray at 320x240:
24 frames (``--frames``) by ``om.render_frames`` in this one process
(``workers=0``, the baseline), then on a local Dask cluster of 2 worker
processes with 1 thread each (``workers=cluster``), and on the local process
pool (``workers=2``) for comparison.  POV-Ray itself uses every core in every
run (its default); ``--threads 1`` limits it to one thread per frame.

Printed: wall time per run, the speed-up against the baseline of the same
run, the cluster's start-up time, and the per-frame overhead of distributing
= (wall time x workers - the seconds the workers spent on frames) / frames,
i.e. scheduling, shipping and idle time per frame.  Issue 16 asks for a
speed-up of at least 1.6x on this 2-core machine.

Run: .venv/bin/python bench/render_frames.py [--frames 24] [--size 320x240] [--engine povray] [--threads N]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import omnirender as om
from omnirender.demo import demo_scene


def run(label: str, scene: om.Node, args: argparse.Namespace, out: Path, workers, options: dict) -> float:
    start = time.perf_counter()
    report = om.render_frames(
        scene, f"0-{args.frames - 1}", engine=args.engine, size=args.size, out=out / label / "%03d.png",
        workers=workers, progress=False, **options,
    )  # fmt: skip
    wall = time.perf_counter() - start
    busy = sum(report.render_seconds.values())
    count = len(report.written)
    n = {"one process": 1}.get(label, 2)
    overhead = (wall * n - busy) / count
    print(
        f"{label:22s} {wall:7.2f} s   {wall / count * 1000:7.1f} ms/frame   worker time {busy / count * 1000:7.1f} "
        f"ms/frame   overhead {overhead * 1000:6.1f} ms/frame",
        flush=True,
    )
    return wall


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=24)
    parser.add_argument("--size", default="320x240")
    parser.add_argument("--engine", default="povray")
    parser.add_argument("--threads", type=int, default=None, help="POV-Ray threads per frame (default: all cores)")
    args = parser.parse_args()
    args.size = tuple(int(v) for v in args.size.split("x"))
    options = {"threads": args.threads} if args.threads and args.engine == "povray" else {}
    ok, why = om.engines()[args.engine]
    if not ok:
        print(f"{args.engine} unavailable: {why}")
        return 1
    scene = demo_scene()
    om.turntable(scene, seconds=args.frames / 24.0, fps=24)
    print(f"{args.frames} {args.engine} frames of the demo turntable at {args.size[0]}x{args.size[1]}"
          f"{f', POV-Ray threads {args.threads}' if options else ''}")  # fmt: skip
    from omnirender.animation.dask import local_cluster

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        base = run("one process", scene, args, out, 0, options)
        start = time.perf_counter()
        with local_cluster(workers=2, threads=1) as cluster:
            started = time.perf_counter() - start
            print(f"{'(Dask cluster start)':22s} {started:7.2f} s")
            dask = run("Dask, 2 workers", scene, args, out, cluster, options)
        pool = run("2 local processes", scene, args, out, 2, options)
    print(f"speed-up Dask 2 workers vs one process: {base / dask:.2f}x (issue 16 target: >= 1.6x)")
    print(f"speed-up 2 local processes vs one process: {base / pool:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
