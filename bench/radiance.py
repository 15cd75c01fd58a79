"""The Radiance engine: mesh export, picture and analysis times, against baselines measured in the same run.

1. A 1,000,000-triangle mesh (the wave grid of ``offline_export.py``) written with
   ``om.export(scene, "mesh.rad")`` (traversal, OBJ formatting, ``obj2mesh``,
   atomic files), against trimesh's own OBJ export of the same mesh.
2. The agreement test scene (``tests/test_engines_agree.py``) and the demo scene
   rendered at 320x240 with Radiance, against POV-Ray (one thread each, as rpict
   has one) on the same scenes.
3. Irradiance at 10,000 points under a point light and a sky (one interreflection,
   1024 ambient divisions) with one and two rtrace processes.

Run: .venv/bin/python bench/radiance.py [--triangles N] [--repeat N]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import omnirender as om

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from offline_export import wave_mesh  # noqa: E402
from test_engines_agree import make_scene  # noqa: E402

from omnirender.demo import demo_scene  # noqa: E402


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def mesh_export(triangles: int, repeat: int) -> None:
    nz = max(2, int(round((triangles / 4) ** 0.5)) + 1)
    vertices, normals, faces = wave_mesh(2 * nz - 1, nz)
    scene = om.Node("mesh", [om.TriangleSet(vertices=vertices, indices=faces, normals=normals)])
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, vertex_normals=normals, process=False)
    with tempfile.TemporaryDirectory() as tmp:
        ours = best(lambda: om.export(scene, Path(tmp) / "mesh.rad"), repeat)
        theirs = best(lambda: mesh.export(Path(tmp) / "mesh.obj"), repeat)
    print(f"mesh of {len(faces):,} triangles: .rad + .rtm {ours:.2f} s, trimesh OBJ {theirs:.2f} s, "
          f"ratio {ours / theirs:.2f}")  # fmt: skip


def pictures(repeat: int) -> None:
    for label, scene in (("agreement scene", make_scene()), ("demo scene", demo_scene())):
        om.render(scene, engine="radiance", size=(32, 24))  # warm up (mesh file import, first process)
        rad = best(lambda s=scene: om.render(s, engine="radiance", size=(320, 240), progress=False), repeat)
        pov = best(lambda s=scene: om.render(s, engine="povray", size=(320, 240), threads=1, progress=False), repeat)
        print(f"{label} at 320x240: Radiance {rad:.2f} s, POV-Ray {pov:.2f} s, ratio {rad / pov:.2f}")


def analysis(repeat: int) -> None:
    room = om.Node("room", [om.PointLight(position=(0, 3, 0), intensity=10, constant=0, quadratic=1)])
    room.add(om.radiance.Sky(intensity=20))
    room.add(om.radiance.Options(ab=1, ad=1024, as_=0, aa=0))
    room.add(om.Node("floor", [om.Color(0.5, 0.5, 0.5), om.Rectangle(size=(20, 20))]))
    rng = np.random.default_rng(1)
    points = np.column_stack([rng.uniform(-9, 9, 10000), np.full(10000, 0.01), rng.uniform(-9, 9, 10000)])
    up = np.tile([0.0, 1.0, 0.0], (len(points), 1))
    one = best(lambda: om.radiance.irradiance(room, points, up), repeat)
    two = best(lambda: om.radiance.irradiance(room, points, up, processes=2), repeat)
    print(f"irradiance at {len(points):,} points (ab 1, ad 1024): 1 process {one:.2f} s, 2 processes {two:.2f} s, "
          f"speed-up {one / two:.2f}")  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--triangles", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    ok, why = om.engines()["radiance"]
    if not ok:
        print(f"Radiance unavailable: {why}")
        return 1
    print(why)
    mesh_export(args.triangles, args.repeat)
    pictures(args.repeat)
    analysis(args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
