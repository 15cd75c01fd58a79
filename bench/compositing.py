"""Renderer trees: frame times at 640x480 against the plain GL render of the same scene (issue 13).

The scene is the textured light-field test scene (a box, a sphere, a ground
slab; diffuse textures), built as users write it.  One GL engine draws, in
the same run:

* baseline: the scene graph itself (``engine.render(scene)``);
* the scene through a ``SceneRenderer`` in a ``DepthGroup`` (the tree's
  overhead: a second engine drawing into the frame);
* the same in an offscreen ``DepthGroup`` (one offscreen target, one merge);
* a ``ShadowGroup`` (2048 x 2048 shadow map, offscreen children, shading pass);
* an ``OcclusionGroup`` with the sphere as its child;
* a ``DepthPeelGroup`` of the scene (at most 8 layers, a pass of the scene and a composite each; it stops at
  the first empty layer);
* a ``DistanceGroup`` colouring the scene by its distance to the sphere (two offscreen children, one pass);
* the ``LightFieldRenderer`` of a light field captured from 20 cameras on a
  sphere cap, from three novel views, with its PSNR on the foreground against
  the GL render of the real scene.

A frame is draw + read-back; the first frame of each (compile, uploads) is
not timed; each tree and its baseline are timed in alternation.
Run: ``.venv/bin/python bench/compositing.py`` (``--frames N``).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import omnirender as om
from omnirender.gl import GLEngine

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.compositing.scenes import capture_cameras, novel_cameras, textured_scene  # noqa: E402

C = om.compositing
SIZE = (640, 480)


def timed(engine: GLEngine, scene: om.Node, frames: int) -> float:
    """Median milliseconds of a frame (the first frame, which compiles and uploads, is not timed)."""
    engine.render(scene)
    times = []
    for _ in range(frames):
        t = time.perf_counter()
        engine.render(scene)
        times.append(time.perf_counter() - t)
    return statistics.median(times) * 1e3


def against_baseline(engine: GLEngine, scene: om.Node, baseline: om.Node, frames: int) -> tuple[float, float]:
    """(ms of ``scene``, ms of ``baseline``), measured in alternation so that a busy machine slows both alike."""
    mine, base = [], []
    for _ in range(frames):
        mine.append(timed(engine, scene, 1))
        base.append(timed(engine, baseline, 1))
    return statistics.median(mine), statistics.median(base)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=5)
    args = parser.parse_args()
    scene = textured_scene()
    camera = novel_cameras()[1]
    sphere = om.Node("sphere", [om.Color(0.2, 0.5, 1.0), om.Sphere(center=(-0.6, 0, 0.2), radius=0.72)])
    light = om.PointLight(position=(3, 6, 4))
    trees = {
        "SceneRenderer in a DepthGroup": C.DepthGroup([C.SceneRenderer(scene)]),
        "offscreen DepthGroup": C.DepthGroup([C.SceneRenderer(scene)], offscreen=True),
        "ShadowGroup (2048^2 map)": C.ShadowGroup(light, [C.SceneRenderer(scene)]),
        "OcclusionGroup": C.DepthGroup([C.SceneRenderer(scene), C.OcclusionGroup([C.SceneRenderer(sphere)])]),
        "DepthPeelGroup (8 layers)": C.DepthGroup([C.DepthPeelGroup([C.SceneRenderer(scene)])]),
        "DistanceGroup": C.DepthGroup([C.DistanceGroup([C.SceneRenderer(scene), C.SceneRenderer(sphere)])]),
    }
    with GLEngine(size=SIZE) as engine:
        baseline = om.Node.transient([camera, scene])
        print(f"{'baseline: the scene graph':36s} {timed(engine, baseline, args.frames):8.1f} ms/frame")
        for name, tree in trees.items():
            ms, base = against_baseline(engine, tree.as_scene("gl", SIZE, camera), baseline, args.frames)
            print(f"{name:36s} {ms:8.1f} ms/frame   {ms / base:5.2f}x baseline")
        t = time.perf_counter()
        lf = C.capture_light_field(scene, capture_cameras(20), size=SIZE)
        print(f"capture of 20 views at 640x480: {time.perf_counter() - t:.2f} s")
        renderer = C.LightFieldRenderer(lf)
        for i, view in enumerate(novel_cameras()):
            reference = engine.render(om.Node.transient([view, scene]), background=(0, 0, 0, 1))
            tree = renderer.as_scene("gl", SIZE, view)
            ms, base = against_baseline(engine, tree, om.Node.transient([view, scene]), args.frames)
            image = engine.render(tree, background=(0, 0, 0, 1))
            foreground = np.isfinite(reference.depth)
            error = (image.array[..., :3].astype(float) - reference.array[..., :3].astype(float))[foreground]
            psnr = 10 * np.log10(255**2 / (error**2).mean())
            mesh = renderer.stats["mesh_ms"]
            print(f"light field, novel view {i}: {ms:8.1f} ms/frame   {ms / base:5.2f}x baseline   "
                  f"(screen mesh + blending field on the CPU {mesh:.1f} ms)   PSNR {psnr:.1f} dB")  # fmt: skip


if __name__ == "__main__":
    main()
