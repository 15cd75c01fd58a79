"""What a GL frame of Gaussian splats costs: 1,000,000 splats against 10,000, steady and with the camera moving.

The scene is built the README's way: one ``om.GaussianSplats`` of N random
splats (SH degree 3 unless ``--degree``) under a camera that either stays put
(the order of the last view is kept: no sort) or orbits a little every frame
(every frame sorts all N splats).  A frame is ``GLEngine.render`` (colour read
back, no depth); the first frames (upload, programs) are not timed.

``--cpu`` re-executes the script under Mesa's no-op driver (``GALLIUM_NOOP=1``):
every Python and driver call runs and nothing is drawn, so the figures are the
CPU side of a frame, and the ratio 1M / 10k shows whether it grows with the
splat count (issue 28's target: <= 2x with the GPU sort).  It also measures
the numpy fallback (the order sorted on the CPU, as without compute shaders)
for comparison.  Without ``--cpu`` the figures are the current driver's:
llvmpipe on a machine without a GPU (640x480 by default), a GPU's with
``--timer wall`` (``bench/gpu.sh`` runs 1920x1080).

Run: ``.venv/bin/python bench/splats.py --cpu`` and ``.venv/bin/python bench/splats.py --timer wall``.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from collections.abc import Callable

import numpy as np

import omnirender as om
from omnirender.gl import GLEngine
from omnirender.gl.engine.context import gl_renderer
from omnirender.gl.painters import splats as painter

CLOCK: list[Callable[[], float]] = [time.process_time]


def cloud(n: int, degree: int, seed: int = 0) -> om.GaussianSplats:
    """``n`` random splats in a cube of half-side 1, sized so the cloud looks alike at every count."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4)).astype(np.float32)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    size = 0.08 * (10_000 / n) ** (1 / 3)
    sh = rng.normal(0.0, 0.2, (n, (degree + 1) ** 2, 3)).astype(np.float32)
    sh[:, 0] *= 3.0
    return om.GaussianSplats(
        rng.uniform(-1, 1, (n, 3)).astype(np.float32),
        q,
        rng.uniform(0.3, 1.0, (n, 3)).astype(np.float32) * size,
        rng.uniform(0.2, 0.9, n).astype(np.float32),
        sh,
    )


def bench(n: int, degree: int, size: tuple[int, int], frames: int, moving: bool, fallback: bool = False) -> float:
    """Median time of a frame of ``n`` splats (camera orbiting when ``moving``)."""
    splats = cloud(n, degree)
    camera = om.Camera.look_at((0.0, 1.0, 4.0), (0, 0, 0), fov=45)
    scene = om.Node("scene", [camera, om.Background((0, 0, 0)), om.Node("cloud", [splats])])
    saved = painter.compute_available
    if fallback:
        painter.compute_available = lambda ctx: False
    engine = GLEngine(size=size, samples=0)
    try:
        times = []
        for i in range(frames + 2):
            if moving:
                a = 0.02 * i
                camera.eye = (4.0 * math.sin(a), 1.0, 4.0 * math.cos(a))
            t = CLOCK[0]()
            engine.render(scene)
            if i >= 2:
                times.append(CLOCK[0]() - t)
        return statistics.median(times)
    finally:
        engine.release()
        painter.compute_available = saved


def ms(t: float) -> str:
    return f"{t * 1000:.2f} ms"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cpu", action="store_true", help="re-execute under GALLIUM_NOOP=1: the CPU side only")
    parser.add_argument("--size", type=int, nargs=2, default=None, help="frame size (640 480; 256 256 with --cpu)")
    parser.add_argument("--degree", type=int, default=3, help="SH degree of the splats (default 3)")
    parser.add_argument("--frames", type=int, default=None, help="timed frames per case")
    parser.add_argument("--large", type=int, default=1_000_000, help="the large splat count (default 1,000,000)")
    parser.add_argument(
        "--timer", choices=("cpu", "wall"), default="cpu", help="CPU time of the process (default) or wall time (GPU)"
    )
    args = parser.parse_args()
    CLOCK[0] = time.process_time if args.timer == "cpu" else time.perf_counter
    if args.cpu and os.environ.get("GALLIUM_NOOP") != "1":
        env = dict(os.environ, GALLIUM_NOOP="1", GALLIUM_THREAD="0")  # as bench/frame_cost.py (docs/NOTES.md)
        argv = [a for a in sys.argv[1:] if a != "--cpu"]
        return os.spawnve(os.P_WAIT, sys.executable, [sys.executable, __file__, *argv], env)
    noop = os.environ.get("GALLIUM_NOOP") == "1"
    size = tuple(args.size) if args.size else ((256, 256) if noop else (640, 480))
    frames = args.frames or (15 if noop else 3)
    probe = GLEngine(size=(8, 8), samples=0)
    method = painter.sort_method(probe)
    probe.release()
    print(
        f"Gaussian splats, SH degree {args.degree}, {size[0]}x{size[1]}, MSAA off, median frame = render + colour "
        f"read-back, {'CPU time of the process' if args.timer == 'cpu' else 'wall time'} "
        f"({gl_renderer()}{', GALLIUM_NOOP=1: CPU side only' if noop else ''}; sort: {method})",
        flush=True,
    )
    large = args.large
    for moving in (False, True):
        what = "camera orbiting (a sort every frame)" if moving else "still camera (no sort)"
        small_t = bench(10_000, args.degree, size, frames, moving)
        large_t = bench(large, args.degree, size, frames, moving)
        target = " (issue 28 target <= 2 under GALLIUM_NOOP=1)" if noop else ""
        print(
            f"  {what}: 10,000 splats {ms(small_t)}; {large:,} splats {ms(large_t)} = {large_t / small_t:.2f}x{target}",
            flush=True,
        )
    if noop:
        small_t = bench(10_000, args.degree, size, max(3, frames // 3), True, fallback=True)
        large_t = bench(large, args.degree, size, max(3, frames // 3), True, fallback=True)
        print(
            f"  numpy fallback (no compute shaders), camera orbiting: 10,000 splats {ms(small_t)}; {large:,} "
            f"splats {ms(large_t)} = {large_t / small_t:.2f}x (the CPU sorts: it grows with the count)",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
