"""Steady frames with the frame plan on and off (issue 22: the fixed per-frame cost of a frame that changed nothing).

Two engines on the same scene, one replaying its recorded frame plan
(``gl/engine/plan.py``), the other drawing every frame in full
(``engine.frame_runner.replay = False``), frames interleaved so that load
changes hit both alike; hand-instanced moderngl drawing the same 100 cubes in
the first engine's context is the baseline of the first line.  Scenes: 100
cubes (``bench/gl_objects.py``), 10,000 cubes as users write them (a shared
``om.TriangleSet``, an ``om.Matrix`` and an ``om.Material`` each), and the
10,000 nodes of ``bench/frame_cost.py`` with shadows off and with default
shadows.  A frame is ``GLEngine.render`` (colour read back, no depth), timed in
CPU time of the process.

Run: ``.venv/bin/python bench/frame_plan.py --cpu`` (re-executes itself under
``GALLIUM_NOOP=1``: the CPU side, what a real GPU leaves; ``--frames N``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from frame_cost import node_scene  # noqa: E402
from gl_objects import HandWritten, cube_data, omni_scene, user_scene  # noqa: E402
from gl_objects import camera_for as cube_camera  # noqa: E402

from omnirender.gl import GLEngine  # noqa: E402

SIZE = (256, 256)


def compare(label: str, scene, shadows: bool, frames: int, hand_data=None) -> None:
    times: dict[str, list[float]] = {"on": [], "off": [], "hand": []}
    with GLEngine(size=SIZE, samples=0, shadows=shadows) as on, GLEngine(size=SIZE, samples=0, shadows=shadows) as off:
        off.frame_runner.replay = False
        for engine in (on, off):
            engine.render(scene, read_depth=False)
            engine.render(scene, read_depth=False)
        hand = None
        if hand_data is not None:
            with on.current():
                hand = HandWritten(on.ctx, SIZE, *hand_data)
                hand.instanced()
        for _ in range(frames):
            for name, engine in (("on", on), ("off", off)):
                t = time.process_time()
                engine.render(scene, read_depth=False)
                times[name].append(time.process_time() - t)
            if hand is not None:
                with on.current():
                    t = time.process_time()
                    hand.instanced()
                    times["hand"].append(time.process_time() - t)
        replayed = on.stats["replayed"]
    on_ms, off_ms = (statistics.median(times[k]) * 1e3 for k in ("on", "off"))
    line = f"{label}: plan on {on_ms:.3f} ms, off {off_ms:.3f} ms = {off_ms / on_ms:.2f}x"
    if times["hand"]:
        hand_ms = statistics.median(times["hand"]) * 1e3
        line += f"; on = {on_ms / hand_ms:.2f}x hand-instanced moderngl ({hand_ms:.3f} ms, target <= 4 on the CPU side)"
    print(line + ("" if replayed else " (NOT replayed)"), flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cpu", action="store_true", help="re-execute under GALLIUM_NOOP=1: the CPU side only")
    parser.add_argument("--frames", type=int, default=200)
    args = parser.parse_args()
    if args.cpu and os.environ.get("GALLIUM_NOOP") != "1":
        env = dict(os.environ, GALLIUM_NOOP="1", GALLIUM_THREAD="0")  # (see bench/frame_cost.py)
        argv = [a for a in sys.argv[1:] if a != "--cpu"]
        return os.spawnve(os.P_WAIT, sys.executable, [sys.executable, __file__, *argv], env)
    noop = " (GALLIUM_NOOP=1: CPU side only)" if os.environ.get("GALLIUM_NOOP") == "1" else ""
    print(
        f"steady frames, {SIZE[0]}x{SIZE[1]}, MSAA off, median CPU time of render + colour read-back{noop}", flush=True
    )
    mats, colors = cube_data(100)
    camera = cube_camera(100)
    compare("100 cubes", omni_scene(mats, colors, camera)[0], False, args.frames, (mats, colors, camera))
    mats, colors = cube_data(10_000)
    compare("10,000 cubes as users write them", user_scene(mats, colors, cube_camera(10_000)), False, args.frames // 2)
    scene = node_scene(10_000)[0]
    compare("10,000 nodes, shadows off", scene, False, args.frames // 2)
    compare("10,000 nodes, default shadows", scene, True, args.frames // 2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
