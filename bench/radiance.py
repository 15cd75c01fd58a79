"""The Radiance engine: mesh export, picture and analysis times, against baselines measured in the same run.

1. A 1,000,000-triangle mesh (the wave grid of ``offline_export.py``) written with
   ``om.export(scene, "mesh.rad")`` (traversal, OBJ formatting, ``obj2mesh``,
   atomic files), against trimesh's own OBJ export of the same mesh.
2. The agreement test scene (``tests/test_engines_agree.py``) and the demo scene
   rendered at 320x240 with Radiance, against POV-Ray (one thread each, as rpict
   has one) on the same scenes.
3. Accuracy of the analysis: irradiance from an isotropic point light against
   I cos(theta) / d^2 at 60 points, and the illuminance under a uniform sky against
   179 pi L (both also checked by tests/radiance/test_radiance_analysis.py).
4. Irradiance at 10,000 points under a point light and a sky (one interreflection,
   1024 ambient divisions) with one and two rtrace processes.

Run: .venv/bin/python bench/radiance.py [--triangles N] [--repeat N]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

import omnirender as om

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from offline_export import best_of, grid_for, wave_mesh  # noqa: E402
from test_engines_agree import make_scene  # noqa: E402

from omnirender.demo import demo_scene  # noqa: E402


def mesh_export(triangles: int, repeat: int) -> None:
    vertices, normals, faces = wave_mesh(*grid_for(triangles))
    scene = om.Node("mesh", [om.TriangleSet(vertices=vertices, indices=faces, normals=normals)])
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, vertex_normals=normals, process=False)
    with tempfile.TemporaryDirectory() as tmp:
        ours = best_of(lambda: om.export(scene, Path(tmp) / "mesh.rad"), repeat)
        theirs = best_of(lambda: mesh.export(Path(tmp) / "mesh.obj"), repeat)
    print(f"mesh of {len(faces):,} triangles: .rad + .rtm {ours:.2f} s, trimesh OBJ {theirs:.2f} s, "
          f"ratio {ours / theirs:.2f}")  # fmt: skip


def pictures(repeat: int) -> None:
    for label, scene in (("agreement scene", make_scene()), ("demo scene", demo_scene())):
        om.render(scene, engine="radiance", size=(32, 24))  # warm up (mesh file import, first process)
        rad = best_of(lambda s=scene: om.render(s, engine="radiance", size=(320, 240), progress=False), repeat)
        pov = best_of(lambda s=scene: om.render(s, engine="povray", size=(320, 240), threads=1, progress=False), repeat)
        print(f"{label} at 320x240: Radiance {rad:.2f} s, POV-Ray {pov:.2f} s, ratio {rad / pov:.2f}")


def analysis(repeat: int) -> None:
    room = om.Node("room", [om.PointLight(position=(0, 3, 0), intensity=10, constant=0, quadratic=1)])
    room.add(om.radiance.Sky(intensity=20))
    room.add(om.radiance.Options(ab=1, ad=1024, as_=0, aa=0))
    room.add(om.Node("floor", [om.Color(0.5, 0.5, 0.5), om.Rectangle(size=(20, 20))]))
    rng = np.random.default_rng(1)
    points = np.column_stack([rng.uniform(-9, 9, 10000), np.full(10000, 0.01), rng.uniform(-9, 9, 10000)])
    up = np.tile([0.0, 1.0, 0.0], (len(points), 1))
    one = best_of(lambda: om.radiance.irradiance(room, points, up), repeat)
    two = best_of(lambda: om.radiance.irradiance(room, points, up, processes=2), repeat)
    print(f"irradiance at {len(points):,} points (ab 1, ad 1024): 1 process {one:.2f} s, 2 processes {two:.2f} s, "
          f"speed-up {one / two:.2f}")  # fmt: skip


def accuracy() -> None:
    rng = np.random.default_rng(7)
    light_at = np.array([0.3, 2.5, -0.2])
    scene = om.Node("ground", [om.PointLight(position=light_at, intensity=3, constant=0, quadratic=1)])
    scene.add(om.Node("floor", [om.Color(0.5, 0.5, 0.5), om.Rectangle(size=(40, 40))]))
    points = np.column_stack([rng.uniform(-6, 6, 60), np.full(60, 1e-3), rng.uniform(-6, 6, 60)])
    tilt = np.radians(rng.uniform(-70, 70, 60))
    normals = np.column_stack([np.sin(tilt), np.cos(tilt), np.zeros(60)])
    to_light = light_at - points
    d = np.linalg.norm(to_light, axis=1)
    expected = 3 * np.pi * np.maximum(np.sum(to_light * normals, axis=1) / d, 0) / d**2
    measured = om.radiance.irradiance(scene, points, normals)[:, 0]
    lit = expected > 1e-9
    error = np.abs(measured[lit] / expected[lit] - 1)
    print(f"point light, {lit.sum()} lit points: irradiance error vs I cos/d^2 max {error.max():.4%}, "
          f"mean {error.mean():.4%}")  # fmt: skip
    sky = om.Node("open", [om.radiance.Sky(intensity=25), om.radiance.Options(ab=1)])
    sky.add(om.Node("floor", [om.Color(0.5, 0.5, 0.5), om.Rectangle(size=(40, 40))]))
    lux = om.radiance.illuminance(sky, points, np.tile([0.0, 1.0, 0.0], (60, 1)))
    error = np.abs(lux / (179 * np.pi * 25) - 1)
    print(f"uniform sky, 60 points: illuminance error vs 179 pi L max {error.max():.4%}")


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
    accuracy()
    analysis(args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
