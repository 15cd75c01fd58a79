"""Loading USD stages: a 1,000,000-triangle mesh against usd-core's own read, and a 100,000-instance PointInstancer.

Both stages are written with usd-core (``.usdc``, the binary crate format most
pipelines ship).  Measured in one run, best of ``--repeat``:

* baseline: ``Usd.Stage.Open`` and the mesh's points, face vertex counts and
  indices read into numpy (``np.asarray`` of the Vt arrays) -- what usd-core
  itself needs before anything can be drawn;
* ``om.load_usd(path)`` plus ``vertex_array()``/``index_array()`` of the
  triangle set (n-gons fan-triangulated with numpy, primvars read), the ratio
  against the baseline; target (issue 27): at most 1.5x;
* ``om.load_usd`` of the 100,000-instance PointInstancer (target: at most 0.5 s)
  and one GL frame of it: the draw calls it takes (one instanced batch: the
  same number as for 10 instances).

Run: .venv/bin/python bench/usd.py [--triangles 1000000] [--instances 100000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

import omnirender as om


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def write_mesh(path: Path, triangles: int) -> None:
    """A bumpy grid of quads (two triangles each) with vertex normals and st, as one UsdGeomMesh."""
    from pxr import Sdf, Usd, UsdGeom, Vt

    n = max(2, int(np.sqrt(triangles / 2)))
    x, z = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1))
    y = 0.05 * np.sin(9 * x) * np.cos(7 * z)
    points = np.stack([x, y, z], -1).reshape(-1, 3).astype(np.float32)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    quads = np.stack([a, a + n + 1, a + n + 2, a + 1], 1).astype(np.int32)
    stage = Usd.Stage.CreateNew(str(path))
    mesh = UsdGeom.Mesh.Define(stage, "/Terrain")
    mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(points))
    mesh.GetFaceVertexCountsAttr().Set(Vt.IntArray.FromNumpy(np.full(len(quads), 4, np.int32)))
    mesh.GetFaceVertexIndicesAttr().Set(Vt.IntArray.FromNumpy(quads.reshape(-1)))
    mesh.GetSubdivisionSchemeAttr().Set("none")
    normals = np.tile(np.array([0, 1, 0], np.float32), (len(points), 1))
    mesh.GetNormalsAttr().Set(Vt.Vec3fArray.FromNumpy(normals))
    mesh.SetNormalsInterpolation("vertex")
    st = UsdGeom.PrimvarsAPI(mesh.GetPrim()).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, "vertex")
    st.Set(Vt.Vec2fArray.FromNumpy(np.ascontiguousarray((points[:, [0, 2]] + 1) / 2)))
    stage.GetRootLayer().Save()


def write_instancer(path: Path, count: int) -> None:
    from pxr import Gf, Usd, UsdGeom, Vt

    stage = Usd.Stage.CreateNew(str(path))
    cam = UsdGeom.Camera.Define(stage, "/Camera")
    cam.AddTranslateOp().Set(Gf.Vec3d(0, 60, 160))
    cam.AddRotateXOp().Set(-20.0)
    instancer = UsdGeom.PointInstancer.Define(stage, "/Crowd")
    box = UsdGeom.Cube.Define(stage, "/Crowd/Prototypes/Box")
    box.GetSizeAttr().Set(0.5)
    instancer.CreatePrototypesRel().SetTargets([box.GetPath()])
    side = int(np.ceil(np.sqrt(count)))
    grid = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:count]
    positions = np.zeros((count, 3), np.float32)
    positions[:, [0, 2]] = (grid - side / 2).astype(np.float32)
    instancer.CreateProtoIndicesAttr(Vt.IntArray.FromNumpy(np.zeros(count, np.int32)))
    instancer.CreatePositionsAttr(Vt.Vec3fArray.FromNumpy(positions))
    angles = np.linspace(0, np.pi, count, dtype=np.float32)
    quats = np.stack([np.zeros(count), np.sin(angles / 2), np.zeros(count), np.cos(angles / 2)], 1)  # (i, j, k, r)
    instancer.CreateOrientationsAttr(Vt.QuathArray.FromNumpy(quats.astype(np.float16)))
    instancer.CreateScalesAttr(Vt.Vec3fArray.FromNumpy(np.ones((count, 3), np.float32)))
    stage.GetRootLayer().Save()


def baseline(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Terrain"))
    return (
        np.asarray(mesh.GetPointsAttr().Get()),
        np.asarray(mesh.GetFaceVertexCountsAttr().Get()),
        np.asarray(mesh.GetFaceVertexIndicesAttr().Get()),
    )


def load(path: Path) -> tuple[np.ndarray, np.ndarray]:
    root = om.load_usd(path)
    (ts,) = [c for c in root["/Terrain"].components if isinstance(c, om.TriangleSet)]
    return ts.vertex_array(), ts.index_array()


def draw_calls(path: Path) -> int:
    from omnirender.gl import GLEngine

    engine = GLEngine(size=(320, 240), samples=0, shadows=False)
    try:
        engine.render(om.load_usd(path), read_depth=False)
        return int(engine.stats["draw_calls"])
    finally:
        engine.release()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--triangles", type=int, default=1_000_000)
    parser.add_argument("--instances", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        mesh_path, crowd_path, few_path = Path(tmp) / "mesh.usdc", Path(tmp) / "crowd.usdc", Path(tmp) / "few.usdc"
        write_mesh(mesh_path, args.triangles)
        write_instancer(crowd_path, args.instances)
        write_instancer(few_path, 10)
        vertices, indices = load(mesh_path)
        base = best(lambda: baseline(mesh_path), args.repeat)
        mine = best(lambda: load(mesh_path), args.repeat)
        print(f"mesh: {len(indices):,} triangles, {len(vertices):,} vertices")
        print(f"usd-core read into numpy  {base:7.3f} s   (baseline)")
        print(f"om.load_usd + arrays      {mine:7.3f} s   ratio {mine / base:.2f}x (target <= 1.5x)")
        crowd = best(lambda: om.load_usd(crowd_path), args.repeat)
        print(f"PointInstancer of {args.instances:,}: om.load_usd {crowd:.3f} s (target <= 0.5 s)")
        try:
            many, few = draw_calls(crowd_path), draw_calls(few_path)
        except Exception as exc:  # no GL here
            print(f"GL draw calls not measured: {type(exc).__name__}: {exc}")
        else:
            print(
                f"GL draw calls per frame: {many} for {args.instances:,} instances, {few} for 10 (one instanced batch)"
            )


if __name__ == "__main__":
    main()
