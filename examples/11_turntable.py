"""Example 7: a turntable animation, previewed with OpenGL and finished with POV-Ray.

The demo scene goes on a turntable (``om.turntable``: the camera and the
lights orbit the scene, so it looks as if the scene turned in front of them).
The GL engine renders the preview frames in this process in a fraction of a
second; POV-Ray renders the final frames on local worker processes (or on a
Dask cluster: pass ``--scheduler tcp://host:8786``).  Both become MP4 files,
and the final frames also a GIF.  Frames already on disk are kept, so an
interrupted run resumes where it stopped.

    python examples/11_turntable.py [OUTPUT_FOLDER] [--seconds 3] [--fps 12] [--size 320x240]

Like every script that starts worker processes, its work runs under ``if __name__ == "__main__":``
(worker processes import the script; the guard keeps them from rendering it again).
"""

from __future__ import annotations

import argparse
import time

from _common import output_dir

import omnirender as om
from omnirender.demo import demo_scene


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", help="output folder (default examples/output)")
    parser.add_argument("--seconds", type=float, default=3.0, help="length of one turn")
    parser.add_argument("--fps", type=float, default=12.0)
    parser.add_argument("--size", default="320x240")
    parser.add_argument("--workers", type=int, default=None, help="POV-Ray worker processes (default: one per core)")
    parser.add_argument("--scheduler", help="a Dask scheduler address for the POV-Ray frames")
    args = parser.parse_args()
    out = output_dir()
    size = tuple(int(v) for v in args.size.split("x"))

    scene = demo_scene()
    om.turntable(scene, seconds=args.seconds, fps=args.fps)  # adds an om.Animation to the scene

    start = time.perf_counter()
    preview = om.render_frames(scene, engine="gl", size=size, out=out / "11-frames-gl" / "%04d.png", workers=0)
    om.video(preview, out / "11-turntable-gl.mp4", fps=args.fps)
    print(f"GL preview: {preview.summary()} -> 11-turntable-gl.mp4 ({time.perf_counter() - start:.1f} s)")

    start = time.perf_counter()
    final = om.render_frames(
        scene, engine="povray", size=size, out=out / "11-frames-povray" / "%04d.png",
        workers=args.scheduler or args.workers, antialias=True,
    )  # fmt: skip
    om.video(final, out / "11-turntable-povray.mp4", fps=args.fps)
    om.video(final, out / "11-turntable.gif", fps=args.fps)
    seconds = time.perf_counter() - start
    print(f"POV-Ray final: {final.summary()} -> 11-turntable-povray.mp4, 11-turntable.gif ({seconds:.1f} s)")


if __name__ == "__main__":
    main()
