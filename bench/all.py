"""Run every benchmark in this folder, one after the other.

Run: .venv/bin/python bench/all.py [--quick]
Each script prints its own figures and ratios against a baseline measured in
the same run (plain Python loop, hand-written moderngl, trimesh).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

SCRIPTS = {
    "traversal.py": [],
    "picking.py": [],
    "gl_objects.py": [],
    "dynamic.py": [],
    "frame_cost.py": ["--cpu"],
    "frame_plan.py": ["--cpu"],
    "shadows.py": [],
    "offline_export.py": ["--repeat", "1"],
    "render_frames.py": [],
    "radiance.py": ["--repeat", "1"],
    "gltf_load.py": [],
    "gltf_instances.py": [],
    "usd.py": [],
    "compositing.py": [],
    "deferred.py": [],
    "postfx.py": [],
    "soak.py": [],
    "snapshots.py": [],
    "mitsuba_preview.py": [],
    "splats.py": ["--cpu"],
}
QUICK = {
    "gl_objects.py": ["--quick"],
    "dynamic.py": ["--quick"],
    "frame_cost.py": ["--cpu", "--quick"],
    "frame_plan.py": ["--cpu", "--frames", "60"],
    "shadows.py": ["--frames", "6"],
    "offline_export.py": ["--repeat", "1", "--triangles", "200000"],
    "render_frames.py": ["--frames", "8"],
    "radiance.py": ["--repeat", "1", "--triangles", "200000"],
    "gltf_load.py": ["--triangles", "200000", "--repeat", "1"],
    "gltf_instances.py": ["--instances", "2000", "--repeat", "1"],
    "usd.py": ["--triangles", "200000", "--instances", "10000", "--repeat", "1"],
    "compositing.py": ["--frames", "2"],
    "deferred.py": ["--frames", "3"],
    "postfx.py": ["--frames", "3"],
    "soak.py": ["--quick"],
    "snapshots.py": ["--quick"],
    "mitsuba_preview.py": ["--repeat", "1"],
    "splats.py": ["--cpu", "--large", "200000", "--frames", "5"],
}


def main() -> int:
    quick = "--quick" in sys.argv[1:]
    here = Path(__file__).parent
    failed = 0
    for name, args in SCRIPTS.items():
        args = QUICK.get(name, args) if quick else args
        print(f"\n=== {name} {' '.join(args)}", flush=True)
        failed += subprocess.run([sys.executable, str(here / name), *args]).returncode != 0
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
