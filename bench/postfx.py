"""The cost of each post-processing effect at 640x480, as a ratio to the frame without effects.

The demo scene (``omnirender.demo.demo_scene``) is rendered by one ``GLEngine(size=(640, 480), samples=0)``
per configuration, the way the README teaches: ``om.Node("root", [om.gl.PostProcess([...]), scene])``.
Configurations: no chain (the baseline), an empty chain (the linear half-float scene target and the output
pass: what any chain costs), each effect alone, and the README's chain (SSAO + bloom + tone mapping + FXAA).
Each frame is drawn and read back (``engine.render``); configurations take turns frame by frame and the
median frame time is printed with its ratio to the baseline measured in the same run, and the GPU time of
the effect's own passes (timer queries: llvmpipe's time, less disturbed by other processes than the wall clock).

Run: ``.venv/bin/python bench/postfx.py`` (``--frames N``, default 10; ``--pipeline deferred``).
"""

from __future__ import annotations

import argparse
import statistics
import time

import omnirender as om
from omnirender.demo import demo_scene
from omnirender.gl import GLEngine

SIZE = (640, 480)
#: the passes every chain has (the rest of a frame's top-level passes are its effects')
CHAIN_PASSES = {"scene", "resolve", "composite", "transparent", "output", "overlay"}


def configurations() -> dict[str, list | None]:
    """Name -> the chain's effects (None: no chain)."""
    return {
        "no chain (baseline)": None,
        "empty chain": [],
        "FXAA": [om.gl.FXAA()],
        "ToneMap aces": [om.gl.ToneMap("aces")],
        "ToneMap auto exposure": [om.gl.ToneMap("reinhard", auto_exposure=True)],
        "Bloom (5 levels)": [om.gl.Bloom()],
        "SSAO (16 samples)": [om.gl.SSAO()],
        "DepthFog": [om.gl.DepthFog(start=2, end=20)],
        "Vignette": [om.gl.Vignette()],
        "LightShafts (64 samples)": [om.gl.LightShafts()],
        "DepthOfField (32 taps)": [om.gl.DepthOfField(focus=7, range=4)],
        "ColorGrading (16^3)": [om.gl.ColorGrading()],
        "SSAO + Bloom + ToneMap + FXAA": [om.gl.SSAO(), om.gl.Bloom(), om.gl.ToneMap("aces"), om.gl.FXAA()],
    }


def scene(effects: list | None) -> om.Node:
    if effects is None:
        return demo_scene()
    return om.Node("root", [om.gl.PostProcess(effects), demo_scene()])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10)
    parser.add_argument("--pipeline", choices=("forward", "deferred"), default="forward")
    args = parser.parse_args()
    runs = {}
    for name, effects in configurations().items():
        engine = GLEngine(size=SIZE, samples=0, pipeline=args.pipeline, timing=True)
        root = scene(effects)
        engine.render(root)  # compile, upload, build programs and targets
        runs[name] = (engine, root, [], [])
    for _ in range(args.frames):
        for engine, root, times, gpu in runs.values():
            start = time.perf_counter()
            engine.render(root)
            times.append(time.perf_counter() - start)
            gpu.append(sum(p["gpu_ms"] for p in engine.stats["passes"] if "/" not in p["name"]
                           and p["name"] not in CHAIN_PASSES))  # fmt: skip
    base = statistics.median(runs["no chain (baseline)"][2])
    print(f"post-processing at {SIZE[0]}x{SIZE[1]}, {args.pipeline} pipeline, median of {args.frames} frames "
          "(render + read-back):")  # fmt: skip
    empty = statistics.median(runs["empty chain"][2])
    for name, (engine, _, times, gpu) in runs.items():
        ms = statistics.median(times)
        extra = ""
        if not name.startswith(("no chain", "empty")):
            over, own = 1e3 * (ms - empty), statistics.median(gpu)
            extra = f"   {over:+6.1f} ms over the empty chain; its passes {own:6.1f} ms GPU"
        print(f"  {name:32s} {1e3 * ms:8.2f} ms   x{ms / base:5.2f} of the frame without effects{extra}")
        engine.release()


if __name__ == "__main__":
    main()
