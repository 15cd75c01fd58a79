"""Tiled rendering: seams, agreement with the untiled image, and memory of wide and huge renders.

Run: .venv/bin/python bench/tiles.py [--compare WxH] [--tile N] [--wide WxH] [--poster WxH] [--effects]

* ``--compare 4000x3000 --tile 1024``: the demo scene (with SSAO and FXAA when
  ``--effects``) rendered whole and as tiles; prints the largest difference per
  channel, how many pixels differ by more than 2/255, and how far the worst
  ones lie from a tile seam (0 means the seams themselves differ).
* ``--wide 24000x1000``: a render beyond the GL framebuffer limit (tiled on its
  own) in a child process; prints its peak resident memory (VmHWM, reset through
  /proc/self/clear_refs just before the render) above the resident memory before
  the render, and that minus the image (colour and depth).
* ``--poster 20000x20000``: ``om.render_to_file`` streaming a poster into a PNG; peak memory likewise.
The baseline of every ratio is measured in the same run.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

import numpy as np


def _size(text: str) -> tuple[int, int]:
    w, h = text.lower().split("x")
    return int(w), int(h)


def _scene(effects: bool):
    import omnirender as om
    from omnirender.demo import demo_scene

    scene = demo_scene()
    if effects:  # the README's post-processing chain, less the effects that look at the whole image
        return om.Node("root", [om.gl.PostProcess([om.gl.SSAO(radius=0.5), om.gl.FXAA()]), scene])
    return scene


def compare(size: tuple[int, int], tile: int, effects: bool, margin: int | None = None) -> None:
    import omnirender as om

    scene = _scene(effects)
    t0 = time.perf_counter()
    whole = om.render(scene, size=size)
    t1 = time.perf_counter()
    if margin is None:
        tiled = om.render(scene, size=size, tile=tile)
    else:
        from omnirender.tiling import render_tiled

        tiled = render_tiled(scene, "gl", size, tile, margin=margin)
    t2 = time.perf_counter()
    diff = np.abs(whole.array.astype(np.int16) - tiled.array.astype(np.int16))
    worst = diff.max(axis=2)
    bad = np.argwhere(worst > 2)
    w, h = size
    print(f"{w}x{h}, tiles of {tile}, margin {tiled.info['margin']} ({tiled.info['tiles']} tiles, "
          f"effects={'SSAO+FXAA' if effects else 'none'})")  # fmt: skip
    print(f"  untiled {t1 - t0:.1f} s, tiled {t2 - t1:.1f} s: ratio {(t2 - t1) / (t1 - t0):.2f}x")
    print(f"  largest difference per channel: {diff.reshape(-1, 4).max(axis=0).tolist()} (of 255)")
    print(f"  pixels differing by more than 2/255: {len(bad)} of {w * h:,} ({len(bad) / (w * h):.2e})")
    if len(bad):
        edges_x = np.arange(0, w, tile)
        edges_y = h - np.arange(0, h, tile)
        dist = np.minimum(
            np.abs(bad[:, 1:2] - edges_x[None, :]).min(axis=1), np.abs(bad[:, 0:1] - edges_y[None, :]).min(axis=1)
        )
        print(f"  their distance to the nearest seam: min {dist.min()} px, median {int(np.median(dist))} px")
    seam_cols = [x for x in range(tile, w, tile)]
    seam = max((int(diff[:, x - 1 : x + 1].max()) for x in seam_cols), default=0)
    print(f"  largest difference in the two pixel columns at each vertical seam: {seam}")


CHILD = r"""
import json, sys, time
import numpy as np
import omnirender as om
from omnirender.demo import demo_scene

def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024

mode, w, h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
scene = demo_scene()
om.render(scene, size=(64, 48))  # the GL context, shaders and imports: not the render's memory
with open("/proc/self/clear_refs", "w") as fh:
    fh.write("5")  # the peak (VmHWM) starts again from the current resident size
base = status("VmRSS:")
t = time.perf_counter()
if mode == "wide":
    img = om.render(scene, size=(w, h))
    image_bytes = img.array.nbytes + (img.depth.nbytes if img.depth is not None else 0)
    tiles = img.info.get("tiles")
else:
    om.render_to_file(scene, sys.argv[4], size=(w, h))
    image_bytes, tiles = 0, None
peak = status("VmHWM:")
print(json.dumps({"seconds": time.perf_counter() - t, "base": base, "peak": peak, "image": image_bytes,
                  "tiles": tiles}))
"""


def memory(mode: str, size: tuple[int, int], out: str) -> None:
    w, h = size
    args = [sys.executable, "-c", CHILD, mode, str(w), str(h)] + ([out] if mode == "poster" else [])
    result = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout.splitlines()[-1])
    above = result["peak"] - result["base"]
    mib = 1 << 20
    print(f"{mode} {w}x{h}: {result['seconds']:.1f} s, tiles {result['tiles']}")
    print(f"  peak resident memory above the process's before the render: {above / mib:.0f} MiB")
    print(f"  of which the image (colour + depth): {result['image'] / mib:.0f} MiB; beyond it: "
          f"{(above - result['image']) / mib:.0f} MiB (target: < 1024 MiB)")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--compare", type=_size, default=(4000, 3000))
    parser.add_argument("--tile", type=int, default=1024)
    parser.add_argument("--effects", action="store_true", help="add SSAO and FXAA to the scene")
    parser.add_argument("--wide", type=_size, default=(24000, 1000))
    parser.add_argument("--poster", type=_size, default=None)
    parser.add_argument("--out", default="/tmp/omnirender-poster.png")
    parser.add_argument("--skip-compare", action="store_true")
    parser.add_argument("--margin", type=int, default=None, help="guard band of the tiles (default: the tiler's)")
    args = parser.parse_args()
    if not args.skip_compare:
        compare(args.compare, args.tile, args.effects, args.margin)
    memory("wide", args.wide, args.out)
    if args.poster:
        memory("poster", args.poster, args.out)


if __name__ == "__main__":
    main()
