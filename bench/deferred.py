"""Forward against deferred shading with many small lights (issue 11).

A floor with 1,000 objects on it (spheres, boxes and tori in a grid, each with
its own colour), lit by N small point lights just above the floor (quadratic
attenuation, reach about one grid cell, no shadows) and a dim ambient light,
built the way the README teaches and rendered at 640x480 with 4x
multisampling, frame after frame, by one ``GLEngine`` per configuration
(render + read-back):

* forward: ``GLEngine()``, up to its limit of 32 lights;
* deferred: ``GLEngine(pipeline="deferred")`` for N = 8, 32, 128, 512, 2048.

Printed: the median frame time of every configuration, the ratio deferred /
forward at 8 and 32 lights (the issue asks for deferred no slower at 32), the
ratio deferred(N) / deferred(8) (at most 3x at 512: cost follows lit pixels,
not lights x pixels) and the G-buffer + L-buffer memory (per frame size and at
1920x1080 for this Phong-only scene).  Configurations take turns frame by frame.

Run: ``.venv/bin/python bench/deferred.py`` (``--frames N``, default 8; ``--samples S``, default 4).
"""

from __future__ import annotations

import argparse

import numpy as np
from shadows import measure  # the same interleaved frame timing (bench/shadows.py)

import omnirender as om
from omnirender.gl import GLEngine
from omnirender.gl.deferred import BufferLayout

SIZE = (640, 480)
GRID = 32  # 32 x 32 = 1024 objects
SPACING = 1.25


def scene(lights: int, seed: int = 7) -> om.Node:
    """The floor, the objects and ``lights`` small point lights."""
    rng = np.random.default_rng(seed)
    half = GRID * SPACING / 2.0
    root = om.Node("scene")
    root.add(om.Camera.look_at(eye=(0, 14, 26), center=(0, 0, 2), fov=50))
    root.add(om.AmbientLight(intensity=0.15))
    floor = root.add(om.Node("floor"))
    floor.add(om.Material(diffuse=(0.7, 0.7, 0.72), specular=(0.2, 0.2, 0.2), shininess=20))
    floor.add(om.Box(size=(2 * half + 2, 0.2, 2 * half + 2), center=(0, -0.1, 0)))
    objects = root.add(om.Node("objects"))
    shapes = (om.Sphere(radius=0.4), om.Box(size=0.7), om.Torus(major_radius=0.35, minor_radius=0.12))
    for i in range(GRID):
        for j in range(GRID):
            x, z = -half + (i + 0.5) * SPACING, -half + (j + 0.5) * SPACING
            color = tuple(float(c) for c in rng.uniform(0.25, 0.95, 3))
            objects.add(om.Node(f"o{i}_{j}", [om.Translation(x, 0.4, z), om.Material(diffuse=color, specular=(0.4,) * 3,
                                                                                     shininess=30),
                                             shapes[(i + j) % 3]]))  # fmt: skip
    group = root.add(om.Node("lights"))
    for _k in range(lights):
        x, z = rng.uniform(-half, half, 2)
        color = tuple(float(c) for c in rng.uniform(0.3, 1.0, 3))
        group.add(om.PointLight(position=(x, 0.6, z), color=color, intensity=1.0, quadratic=60.0, threshold=1 / 128,
                                casts_shadows=False))  # fmt: skip
    return root


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--samples", type=int, default=4)
    args = parser.parse_args()
    counts = (8, 32, 128, 512, 2048)
    configs: dict[str, tuple[GLEngine, om.Node, None]] = {}
    for n in counts:
        if n <= 32:
            configs[f"forward, {n} lights"] = (GLEngine(size=SIZE, samples=args.samples), scene(n), None)
        deferred_engine = GLEngine(size=SIZE, samples=args.samples, pipeline="deferred")
        configs[f"deferred, {n} lights"] = (deferred_engine, scene(n), None)
    try:
        result = measure(configs, args.frames)
        deferred = configs["deferred, 8 lights"][0].pipeline
        print(f"{GRID * GRID} objects on a floor, {SIZE[0]}x{SIZE[1]}, {args.samples}x multisampling, "
              f"median of {args.frames} frames (render + read-back)")  # fmt: skip
        for name, seconds in result.items():
            print(f"  {name:<24} {seconds * 1000:8.1f} ms")
        for n in (8, 32):
            ratio = result[f"deferred, {n} lights"] / result[f"forward, {n} lights"]
            print(f"  deferred / forward at {n} lights: {ratio:.2f}x")
        base = result["deferred, 8 lights"]
        for n in counts[1:]:
            print(f"  deferred {n} lights / deferred 8 lights: {result[f'deferred, {n} lights'] / base:.2f}x")
        print(f"  G-buffer + L-buffer: {deferred.memory() / 2**20:.1f} MiB at {SIZE[0]}x{SIZE[1]} "
              f"({args.samples} samples); {deferred.memory((1920, 1080), 0) / 2**20:.1f} MiB at 1920x1080 "
              "without multisampling")  # fmt: skip
        compact = BufferLayout(deferred.layout.models, light_format="r11g11b10f")
        print(f"  with om.gl.Deferred(light_format='r11g11b10f'): {compact.memory((1920, 1080)) / 2**20:.1f} MiB "
              "at 1920x1080 (guacamole: about 81 MiB; target at most 32 MiB)")  # fmt: skip
        print(deferred.describe((1920, 1080)))
    finally:
        for engine, _, _ in configs.values():
            engine.release()


if __name__ == "__main__":
    main()
