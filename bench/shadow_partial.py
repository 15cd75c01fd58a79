"""Partial against full shadow-map redraws, by the share of the map a change covers (issue 22).

The 10,000-node scene of ``bench/frame_cost.py`` (a directional light, so
default shadows), 256x256: each frame moves two casters that lie at opposite
corners of a square in the light's map, so the region the partial update
redraws covers about ``share`` of the map.  The same frames are timed with
every update forced partial and forced full
(``omnirender.gl.techniques.shadows.PARTIAL_MAX``); the ratio partial / full
says where a partial update stops paying, which is how ``PARTIAL_MAX`` was
chosen.  Frames are CPU time of the process (llvmpipe's threads included);
``GALLIUM_NOOP=1`` gives the CPU side alone.

Run: ``.venv/bin/python bench/shadow_partial.py`` (``--frames N``).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from frame_cost import SIZE, node_scene  # noqa: E402

from omnirender.gl import GLEngine  # noqa: E402
from omnirender.gl.techniques import shadows  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=6, help="frames per figure (median)")
    args = parser.parse_args()
    scene, nodes, positions, _ = node_scene(10_000)
    moves = [node.items[0] for node in nodes]
    chosen = shadows.PARTIAL_MAX
    print(f"10,000 nodes, default shadows, {SIZE[0]}x{SIZE[1]}: partial against full map redraws (PARTIAL_MAX "
          f"is {chosen}), median of {args.frames} frames, CPU time of the process", flush=True)  # fmt: skip
    with GLEngine(size=SIZE, samples=0) as engine:
        engine.render(scene)
        face = engine.frame_shadows.faces[0]
        m = face.proj @ face.view
        ndc = positions @ m[:2, :3].T + m[:2, 3]  # the map's coordinates (an orthographic face)
        side = shadows.auto_resolution(SIZE)
        try:
            for share in (0.05, 0.2, 0.35, 0.5, 0.65, 0.8):
                s = share**0.5
                pair = [int(np.argmin(((ndc - corner) ** 2).sum(axis=1))) for corner in ((-s, -s), (s, s))]
                out = {}
                for mode, limit in (("partial", 1.01), ("full", 0.0)):
                    shadows.PARTIAL_MAX = limit
                    times, covered = [], []
                    for frame in range(args.frames):
                        for k in pair:
                            x, y, z = positions[k]
                            moves[k].offset = (float(x), float(y) + 0.01 * (frame % 2 + 1), float(z))
                        start = time.process_time()
                        engine.render(scene, read_depth=False)
                        times.append(time.process_time() - start)
                        covered.append(engine.stats["shadow_maps"]["pixels"] / side**2)
                    out[mode] = (statistics.median(times), statistics.median(covered))
                (partial, area), (full, _) = out["partial"], out["full"]
                print(f"  region {area:.2f} of the map: partial {partial * 1e3:.1f} ms, full {full * 1e3:.1f} ms, "
                      f"partial / full {partial / full:.2f}", flush=True)  # fmt: skip
        finally:
            shadows.PARTIAL_MAX = chosen
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
