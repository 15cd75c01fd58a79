"""Offline engines: writing a 1,000,000-triangle mesh, and render times of the agreement test scene.

POV-Ray half: the mesh (a 1001 x 501 vertex grid bent into a wave, with
normals) is written as POV-Ray ``mesh2`` through ``om.export(scene,
"mesh.pov")`` (the whole pipeline: engine traversal, SDL formatting, atomic
file write) and compared with trimesh's own OBJ export of the same mesh
(vertices, normals, faces) in the same run.  Target: SDL writing at most as
slow as trimesh's OBJ export.  Then the test scene of
``tests/test_engines_agree.py`` is rendered with POV-Ray at 640x480.

Mitsuba half: ``mitsuba_half`` below builds the same mesh as a Mitsuba mesh
(raw arrays, and through the engine) and renders the test scene; both build
times are also printed as a ratio to trimesh's OBJ export of the same run.

``--triangles N`` changes the mesh size (a grid of about N triangles, twice as
wide as deep; the exact count is printed).

Run: .venv/bin/python bench/offline_export.py [--triangles N] [--repeat N] [--no-render]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import omnirender as om

ROOT = Path(__file__).resolve().parent.parent


def wave_mesh(nx: int = 1001, nz: int = 501) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertices, normals, faces) of a grid with 2 (nx-1)(nz-1) triangles (1,000,000 by default)."""
    x, z = np.meshgrid(np.linspace(-2, 2, nx), np.linspace(-1, 1, nz))
    y = 0.1 * np.sin(4 * x) * np.cos(5 * z)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()]).astype(np.float32)
    dydx = 0.4 * np.cos(4 * x) * np.cos(5 * z)
    dydz = -0.5 * np.sin(4 * x) * np.sin(5 * z)
    normals = np.column_stack([-dydx.ravel(), np.ones(x.size), -dydz.ravel()])
    normals = (normals / np.linalg.norm(normals, axis=1, keepdims=True)).astype(np.float32)
    i = np.arange(nx * nz, dtype=np.uint32).reshape(nz, nx)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(), i[1:, :-1].ravel()
    faces = np.concatenate([np.column_stack([a, c, b]), np.column_stack([a, d, c])])
    return vertices, normals, faces


def grid_for(triangles: int) -> tuple[int, int]:
    """(nx, nz) of a wave_mesh grid with about ``triangles`` triangles, twice as wide as deep."""
    if triangles < 2:
        raise ValueError(f"--triangles must be at least 2, got {triangles}")
    rows = max(1, round((triangles / 4) ** 0.5))
    cols = max(1, round(triangles / (2 * rows)))
    return cols + 1, rows + 1


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def povray_half(vertices, normals, faces, repeat: int, render: bool) -> dict[str, float]:
    import trimesh

    scene = om.Node("bench")
    scene.add(om.Camera.look_at(eye=(0, 3, 4)))
    scene.add(om.TriangleSet(vertices=vertices, indices=faces, normals=normals))
    tm = trimesh.Trimesh(vertices=vertices, faces=faces, vertex_normals=normals, process=False)
    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        pov, obj = Path(tmp) / "mesh.pov", Path(tmp) / "mesh.obj"
        out["povray_mesh2_s"] = best_of(lambda: om.export(scene, pov), repeat)
        out["trimesh_obj_s"] = best_of(lambda: tm.export(obj), repeat)
        out["povray_mb"] = pov.stat().st_size / 1e6
        out["obj_mb"] = obj.stat().st_size / 1e6
        obj_text = obj.read_text()
        assert obj_text.count("\nf ") + obj_text.startswith("f ") == len(faces)
        assert f"face_indices {{ {len(faces)}," in pov.read_text()
    out["ratio_pov_over_obj"] = out["povray_mesh2_s"] / out["trimesh_obj_s"]
    if render:
        sys.path.insert(0, str(ROOT / "tests"))
        from test_engines_agree import make_scene

        times = []
        for _ in range(repeat):
            img = om.render(make_scene(), engine="povray", size=(640, 480), progress=False)
            times.append(img.info["render_seconds"])
        out["povray_render_640x480_s"] = min(times)
        out["povray_render_640x480_median_s"] = statistics.median(times)
    return out


# ---------------------------------------------------------------------------
# MITSUBA HALF — owned by the Mitsuba adapter's author; fill in below.
# Should time building the same (vertices, normals, faces) mesh as a Mitsuba
# mesh and, when ``render`` is True, the Mitsuba render of
# test_engines_agree.make_scene() at 640x480.  Return {name: seconds}.
# ---------------------------------------------------------------------------
MITSUBA_SPP = 64


def mitsuba_half(vertices, normals, faces, repeat: int, render: bool) -> dict[str, float]:
    """Mitsuba mesh building (raw arrays, and through the engine) and the test scene's render time.

    ``mitsuba_build_mesh_s``: ``omnirender.mitsuba.mesh.build_mesh`` (an ``mi.Mesh`` filled via
    ``mi.traverse``, no files); ``mitsuba_engine_mesh_s``: the whole pipeline from a scene with the
    TriangleSet to the loaded ``mi.Scene`` (traversal, BSDF, mesh, sensor).  The render is the
    agreement test scene at 640x480, ``MITSUBA_SPP`` samples per pixel, ``scalar_rgb``, once.
    """
    ok, why = om.mitsuba.available()
    if not ok:
        print(f"mitsuba half skipped: {why}")
        return {}
    from omnirender.mitsuba.mesh import build_mesh

    out: dict[str, float] = {}
    built = []
    out["mitsuba_build_mesh_s"] = best_of(
        lambda: built.append(build_mesh("bench", vertices, faces, normals=normals)), repeat
    )
    assert built[-1].face_count() == len(faces) and built[-1].vertex_count() == len(vertices)
    built.clear()
    scene = om.Node("bench")
    scene.add(om.Camera.look_at(eye=(0, 3, 4)))
    scene.add(om.TriangleSet(vertices=vertices, indices=faces, normals=normals))

    def through_engine() -> None:
        engine = om.mitsuba.MitsubaEngine((640, 480))
        engine.run(scene)
        engine.load()

    out["mitsuba_engine_mesh_s"] = best_of(through_engine, repeat)
    if render:
        sys.path.insert(0, str(ROOT / "tests"))
        from test_engines_agree import make_scene

        img = om.render(make_scene(), engine="mitsuba", size=(640, 480), spp=MITSUBA_SPP, progress=False)
        out[f"mitsuba_render_640x480_spp{MITSUBA_SPP}_s"] = img.info["render_seconds"]
        out["mitsuba_coverage_pass_s"] = img.info["coverage_seconds"]
    return out


def main(argv: list[str] | None = None) -> dict[str, float]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--triangles", type=int, default=1_000_000, help="mesh size (default 1,000,000)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-render", action="store_true")
    args = parser.parse_args(argv)
    try:
        nx, nz = grid_for(args.triangles)
    except ValueError as exc:
        parser.error(str(exc))
    vertices, normals, faces = wave_mesh(nx, nz)
    print(f"mesh: {len(vertices)} vertices, {len(faces)} triangles")
    results = povray_half(vertices, normals, faces, args.repeat, not args.no_render)
    results.update(mitsuba_half(vertices, normals, faces, args.repeat, not args.no_render))
    obj = results.get("trimesh_obj_s")
    for name in ("mitsuba_build_mesh_s", "mitsuba_engine_mesh_s"):
        if obj and name in results:  # the Mitsuba mesh build against the same trimesh OBJ export
            results[f"ratio_{name[:-2]}_over_obj"] = results[name] / obj
    for key, value in results.items():
        print(f"{key:34s} {value:10.3f}")
    if "ratio_pov_over_obj" in results:
        verdict = "met" if results["ratio_pov_over_obj"] <= 1.0 else "NOT met"
        print(f"target (POV-Ray SDL at most as slow as trimesh OBJ): {verdict}")
    return results


if __name__ == "__main__":
    main()
