"""Cost of shadows in the GL engine on the demo scene (issue 10).

The demo scene (``omnirender demo``: floor, knot mesh, torus, sphere, two
point lights) at 640x480 with 4x multisampling, built the way the README
teaches, rendered frame after frame by one ``GLEngine`` (render + read-back):

* baseline: ``GLEngine(shadows=False)``;
* shadow maps, both lights (the default), maps redrawn every frame (the
  torus turns a little each frame, so the casters change);
* the same with only one light casting shadows, for the cost per light;
* shadow maps on a static scene (the maps of the last frame are reused);
* stencil shadow volumes (``om.gl.ShadowVolumes`` at the top of the scene).

Every figure is the median frame time and its ratio to the baseline measured
in the same run; the issue asks for at most 2x with shadow maps.  The pass
report of one frame gives the GPU time of the map passes (timer queries).

Run: ``.venv/bin/python bench/shadows.py`` (``--frames N``, default 12).
"""

from __future__ import annotations

import argparse
import statistics
import time

import omnirender as om
from omnirender.demo import demo_scene
from omnirender.gl import GLEngine

SIZE = (640, 480)


def scene(casting: tuple[int, ...] = (0, 1), volumes: bool = False) -> tuple[om.Node, om.Rotation]:
    """The demo scene with shadows from the lights numbered in ``casting``; the torus's rotation to animate."""
    s = demo_scene()
    lights = [c for c in s["/lights"].items if isinstance(c, om.LightSource)]
    for i, light in enumerate(lights):
        light.casts_shadows = i in casting
    turn = om.Rotation(0, (0, 1, 0))
    s["/torus"].insert(0, turn)
    if volumes:
        return om.Node("root", [om.gl.ShadowVolumes(), s]), turn
    return s, turn


def measure(configs: dict[str, tuple[GLEngine, om.Node, om.Rotation | None]], n: int) -> dict[str, float]:
    """Median seconds per frame (render + read-back) of every configuration over ``n`` frames.

    The configurations take turns frame by frame, so a change in the machine's
    load (other processes) affects them alike; two warm-up rounds come first.
    """
    times: dict[str, list[float]] = {name: [] for name in configs}
    for k in range(n + 2):
        for name, (engine, root, turn) in configs.items():
            if turn is not None:
                turn.angle = 3.0 * k
            start = time.perf_counter()
            engine.render(root)
            if k >= 2:
                times[name].append(time.perf_counter() - start)
    return {name: statistics.median(t) for name, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=16)
    args = parser.parse_args()
    configs: dict[str, tuple[GLEngine, om.Node, om.Rotation | None]] = {}
    configs["no shadows (baseline)"] = (GLEngine(size=SIZE, samples=4, shadows=False), *scene())
    for label, casting in (("both lights", (0, 1)), ("light 1 only", (0,)), ("light 2 only", (1,))):
        configs[f"shadow maps, {label}, maps redrawn every frame"] = (GLEngine(size=SIZE, samples=4), *scene(casting))
    configs["shadow maps, both lights, static scene"] = (GLEngine(size=SIZE, samples=4), scene()[0], None)
    configs["shadow volumes, both lights"] = (GLEngine(size=SIZE, samples=4), *scene(volumes=True))
    try:
        result = measure(configs, args.frames)
    finally:
        for engine, _, _ in configs.values():
            engine.release()
    base = result["no shadows (baseline)"]
    print(f"demo scene {SIZE[0]}x{SIZE[1]}, 4x MSAA, median of {args.frames} frames (render + read-back), "
          "configurations interleaved")  # fmt: skip
    for label, seconds in result.items():
        print(f"  {label:58s} {seconds * 1000:7.1f} ms  {seconds / base:5.2f}x")
    both, one, two = (result[f"shadow maps, {x}, maps redrawn every frame"] for x in
                      ("both lights", "light 1 only", "light 2 only"))  # fmt: skip
    print(f"  per light: light 1 +{(one - base) * 1000:.1f} ms, light 2 +{(two - base) * 1000:.1f} ms "
          f"(both: +{(both - base) * 1000:.1f} ms)")  # fmt: skip
    with GLEngine(size=SIZE, samples=4, timing=True) as engine:
        root, _ = scene()
        engine.render(root)
        maps = [p for p in engine.stats["passes"] if p["name"].startswith("shadow-map")]
        gpu = sum(p["gpu_ms"] for p in maps)
        print(f"  one frame's {len(maps)} shadow-map faces (cube faces that see casters): {gpu:.1f} ms GPU time")


if __name__ == "__main__":
    main()
