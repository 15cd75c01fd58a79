"""Why does a steady frame with default shadows cost more on a GPU than without them? (issue 22, a GPU probe)

On an NVIDIA H200 (``bench/gpu.sh``) the 10,000-node scene of
``bench/frame_cost.py`` (256x256) took 2.83 ms per steady frame with default
shadows and 0.67 ms without, although the shadowed steady frame replays one
recorded draw (the atlas is kept, not redrawn) and its CPU side under Mesa's
no-op driver is only ~0.04 ms more.  This script splits the frame so the
figures point at a cause.  Per configuration it prints, median (min) of the
frames:

* ``wall``: ``engine.render`` (draw + glFinish + colour read-back), wall time;
* ``gpu``: a GL timer query (``ctx.query(time=True)``) around the same
  render: what the GPU spent between the frame's first and last command;
* ``draw`` / ``finish`` / ``read``: the wall time of the Python draw call
  (``engine.draw``: commands issued, nothing waited for), of ``glFinish``
  after it (the GPU catching up), and of the read-back;
* ``samples``: fragments that passed the depth test (an occlusion query), the
  fragment shading load;
* ``replayed`` and the shadow stage's report of the last frame, and why a
  frame was not recorded (if it was not);
* the same for one moved node (``Translation.offset``) per frame.

Configurations (each isolates one hypothesis, see docs/NOTES.md "shadowed
steady frame on a GPU"): shadows off; default shadows; shadows with hard
(1-tap) filtering; shadows with a 64-texel map; a light that casts no
shadows on a shadowed engine (no atlas bound, the shadow-free program);
default shadows with frame replay switched off (every frame drawn in full:
the stage keeps the atlas); default shadows with the maps redrawn in full
every frame (what the engine before the change tracker did, whose steady
frames cost the same with and without shadows on the H200); 100 nodes with
and without shadows (does the extra cost scale with the scene?).  "steady" frames follow each other;
"after" frames are the first steady frame after all 10,000 moved (what
``frame_cost.py``'s interleaved "steady" measures).

Then the top Python functions by cumulative wall time (cProfile) over the
shadowed steady frames, and the driver's KHR_debug messages (performance
warnings such as shader recompiles or pipeline stalls) counted per
configuration, when the driver gives any.

Run (on the GPU machine, repository root): ``python3 bench/shadow_probe.py``
(``--frames N``; about 30-60 s).  ``GALLIUM_NOOP=1 GALLIUM_THREAD=0`` runs it
on Mesa's no-op driver (the CPU side only).
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import ctypes
import io
import pstats
import statistics
import sys
import time
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

from frame_cost import SIZE, node_scene  # noqa: E402

import omnirender as om  # noqa: E402
from omnirender.gl import GLEngine  # noqa: E402
from omnirender.gl.engine.context import RawGL, gl_renderer  # noqa: E402
from omnirender.gl.techniques import shadows as shadow_module  # noqa: E402

N = 10_000


class DebugLog:
    """The driver's KHR_debug messages (GL 4.3 glDebugMessageCallback), counted; inert where unavailable."""

    GL_DEBUG_OUTPUT = 0x92E0
    GL_DEBUG_OUTPUT_SYNCHRONOUS = 0x8242
    GL_DONT_CARE = 0x1100
    TYPES = {0x824C: "error", 0x824D: "deprecated", 0x824E: "undefined", 0x824F: "portability",
             0x8250: "performance", 0x8251: "other", 0x8268: "marker"}  # fmt: skip

    def __init__(self) -> None:
        self.counts: Counter[str] = Counter()
        self.available = False
        self._callback: Any = None
        lib = RawGL()._lib if RawGL().available else None
        if lib is None:
            return
        try:
            proto = ctypes.CFUNCTYPE(None, ctypes.c_uint, ctypes.c_uint, ctypes.c_uint, ctypes.c_uint, ctypes.c_int,
                                     ctypes.c_char_p, ctypes.c_void_p)  # fmt: skip
            self._callback = proto(self._message)
            self._set = lib.glDebugMessageCallback
            self._set.argtypes, self._set.restype = [proto, ctypes.c_void_p], None
            control = lib.glDebugMessageControl
            u = ctypes.c_uint
            control.argtypes = [u, u, u, ctypes.c_int, ctypes.c_void_p, ctypes.c_ubyte]
            control.restype = None
            self._control = control
            self._enable = lib.glEnable
            self._enable.argtypes, self._enable.restype = [ctypes.c_uint], None
            self.available = True
        except (AttributeError, OSError):
            self.available = False

    def _message(self, source: int, kind: int, ident: int, severity: int, length: int, text: bytes, user: Any) -> None:
        message = (text or b"").decode("utf-8", "replace").strip().replace("\n", " ")
        self.counts[f"[{self.TYPES.get(kind, hex(kind))} #{ident}] {message[:160]}"] += 1

    def install(self) -> None:
        """Ask the current context for every message, delivered while the call that caused it runs."""
        if not self.available:
            return
        try:
            self._enable(self.GL_DEBUG_OUTPUT)
            self._enable(self.GL_DEBUG_OUTPUT_SYNCHRONOUS)
            self._control(self.GL_DONT_CARE, self.GL_DONT_CARE, self.GL_DONT_CARE, 0, None, 1)
            self._set(self._callback, None)
        except Exception as error:  # noqa: BLE001 - a probe reports what it could not do
            print(f"  (KHR_debug unavailable: {error})")
            self.available = False

    def take(self) -> Counter[str]:
        out, self.counts = self.counts, Counter()
        return out


def median_min(values: list[float]) -> str:
    if not values:
        return "-"
    return f"{statistics.median(values) * 1e3:.3f} ({min(values) * 1e3:.3f})"


@contextlib.contextmanager
def default_settings(**settings: Any) -> Iterator[None]:
    """The default ShadowMaps of a frame (no ShadowMaps in the scene) with ``settings`` for the block."""
    saved = shadow_module._DEFAULT
    shadow_module._DEFAULT = om.gl.ShadowMaps(**settings)
    try:
        yield
    finally:
        shadow_module._DEFAULT = saved


def measure(label: str, n: int, shadows: bool, frames: int, log: DebugLog, *, replay: bool = True,
            light_shadows: bool = True, profile: bool = False, redraw_maps: bool = False) -> None:  # fmt: skip
    """Print one configuration's figures (see the module's docstring); ``redraw_maps``: the shadow stage forgets
    its atlas before every frame, so every frame draws the maps in full (what the engine before the change
    tracker did; such a frame is not recorded)."""
    scene, nodes, positions, _ = node_scene(n)
    if not light_shadows:
        light = scene.items[1]
        light.casts_shadows = False
    moves = [node.items[0] for node in nodes]
    with GLEngine(size=SIZE, samples=0, shadows=shadows) as engine:
        engine.frame_runner.replay = replay
        ctx = engine.ctx
        with engine.current():
            log.install()
            time_query = ctx.query(time=True)
            sample_query = ctx.query(samples=True)
        log.take()
        stage = next((st for st in engine.stages if isinstance(st, shadow_module.ShadowMapStage)), None)
        forget = stage._forget if redraw_maps and stage is not None else (lambda: 0)  # (a probe's reach inside)

        def render() -> None:
            forget()
            engine.render(scene, read_depth=False)

        for _ in range(3):
            render()
        warm = log.take()

        def frame(out: dict[str, list[float]], prefix: str) -> None:
            with engine.current():
                with time_query:
                    t = time.perf_counter()
                    render()
                    wall = time.perf_counter() - t
            out[prefix + "wall"].append(wall)
            out[prefix + "gpu"].append(time_query.elapsed * 1e-9)

        def split(out: dict[str, list[float]]) -> None:
            engine.compile(scene)
            forget()
            t0 = time.perf_counter()
            with engine.current():
                with sample_query:
                    engine.draw()
                t1 = time.perf_counter()
                engine.raw.glFinish()
            t2 = time.perf_counter()
            engine.read(read_depth=False)
            t3 = time.perf_counter()
            out["draw"].append(t1 - t0)
            out["finish"].append(t2 - t1)
            out["read"].append(t3 - t2)
            out["samples"].append(float(sample_query.samples))

        out: dict[str, list[float]] = {k: [] for k in ("wall", "gpu", "draw", "finish", "read", "samples",
                                                       "after_wall", "after_gpu", "one_wall", "one_gpu")}  # fmt: skip
        for _ in range(frames):
            frame(out, "")
        for _ in range(frames):
            split(out)
        steady_stats = dict(engine.stats)
        not_recorded = engine.frame_runner.not_recorded
        profiler = cProfile.Profile() if profile else None
        if profiler is not None:
            profiler.enable()
            for _ in range(4 * frames):
                render()
            profiler.disable()
        moving = positions.copy()
        for k in range(frames):
            j = (k * 7919) % n
            x, y, z = positions[j]
            moves[j].offset = (float(x), float(y) + 0.01 * (k + 1), float(z))
            frame(out, "one_")
        one_stats = dict(engine.stats)
        for _ in range(max(2, frames // 3)):
            moving[:, 1] += 0.01
            for t, row in zip(moves, moving, strict=True):
                t.offset = row
            render()
            frame(out, "after_")
        messages = log.take()
    maps = {k: v for k, v in steady_stats.get("shadow_maps", {}).items() if k != "regions"}
    one_maps = {k: v for k, v in one_stats.get("shadow_maps", {}).items() if k != "regions"}
    print(f"\n--- {label}")
    print(f"  steady: wall {median_min(out['wall'])} ms, gpu {median_min(out['gpu'])} ms; "
          f"draw {median_min(out['draw'])} + finish {median_min(out['finish'])} + read {median_min(out['read'])} ms; "
          f"samples passed {statistics.median(out['samples']):.0f}")  # fmt: skip
    print(f"    replayed={steady_stats.get('replayed')} draw_calls={steady_stats.get('draw_calls')} "
          f"not_recorded={not_recorded!r} shadow stage (last frame drawn)={maps}")  # fmt: skip
    print(f"  first steady after all {n} moved: wall {median_min(out['after_wall'])} ms, "
          f"gpu {median_min(out['after_gpu'])} ms")  # fmt: skip
    print(f"  one moved: wall {median_min(out['one_wall'])} ms, gpu {median_min(out['one_gpu'])} ms; "
          f"replayed={one_stats.get('replayed')} shadow stage={one_maps}")  # fmt: skip
    if log.available:
        for name, found in (("warm-up", warm), ("measured", messages)):
            if found:
                print(f"  driver messages ({name}): " + "; ".join(f"{c}x {m}" for m, c in found.most_common(6)))
    if profiler is not None:
        text = io.StringIO()
        stats = pstats.Stats(profiler, stream=text)
        stats.sort_stats("cumulative").print_stats(25)
        print(f"  cProfile of {4 * frames} steady frames ({label}), top 25 by cumulative wall time:")
        lines = text.getvalue().splitlines()
        start = next((i for i, line in enumerate(lines) if "ncalls" in line), 0)
        print("\n".join("    " + line for line in lines[start:] if line.strip()))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=15, help="frames per figure")
    parser.add_argument("--quick", action="store_true", help="the first three configurations only")
    args = parser.parse_args()
    started = time.perf_counter()
    print(f"shadow probe: {N} nodes (bench/frame_cost.py's scene), {SIZE[0]}x{SIZE[1]}, MSAA off; "
          f"GL renderer: {gl_renderer()}; times in ms, median (min)", flush=True)  # fmt: skip
    log = DebugLog()
    f = args.frames
    configurations: list[tuple[str, Callable[[], None]]] = [
        ("shadows off", lambda: measure("shadows off", N, False, f, log)),
        (
            "default shadows",
            lambda: measure("default shadows (PCF tent 3x3, auto resolution)", N, True, f, log, profile=True),
        ),
        (
            "light casts no shadows",
            lambda: measure(
                "shadows on, the light casts_shadows=False (no atlas bound)", N, True, f, log, light_shadows=False
            ),
        ),
    ]
    if not args.quick:
        configurations += [
            ("hard", lambda: _with(dict(softness=0.0), "default shadows, hard (1 texelFetch per light)", N, f, log)),
            ("small map", lambda: _with(dict(resolution=64), "default shadows, a 64x64 map", N, f, log)),
            (
                "no replay",
                lambda: measure(
                    "default shadows, frame replay off (every frame drawn in full)", N, True, f, log, replay=False
                ),
            ),
            (
                "maps redrawn",
                lambda: measure(
                    "default shadows, the maps redrawn in full every frame (as before the change tracker)",
                    N,
                    True,
                    f,
                    log,
                    redraw_maps=True,
                ),  # fmt: skip
            ),
            ("100 off", lambda: measure("100 nodes, shadows off", 100, False, f, log)),
            ("100 on", lambda: measure("100 nodes, default shadows", 100, True, f, log)),
        ]
    for name, run in configurations:
        try:
            run()
        except Exception as error:  # noqa: BLE001 - one configuration failing leaves the others' figures
            print(f"\n--- {name}: failed: {type(error).__name__}: {error}")
        sys.stdout.flush()
    print(f"\nshadow probe: done in {time.perf_counter() - started:.1f} s")
    return 0


def _with(settings: dict[str, Any], label: str, n: int, frames: int, log: DebugLog) -> None:
    with default_settings(**settings):
        measure(label, n, True, frames, log)


if __name__ == "__main__":
    sys.exit(main())
