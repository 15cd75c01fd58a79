"""Loading a 1,000,000-triangle glTF file: ``om.load_gltf`` against trimesh on the same file.

The file is a bumpy sphere (positions, normals, texture coordinates, 32-bit
indices) with a textured PBR material, written by omnirender's glTF exporter
the way the README teaches (``om.export(scene, "mesh.glb")``).  Measured in
one run, best of ``--repeat``:

* ``trimesh.load(path)`` (the baseline: a mesh loader that drops most of the material),
* ``om.load_gltf(path)`` plus ``vertex_array()``/``index_array()`` of the triangle set
  (the arrays engines use), everything kept,
* ``om.MeshFile(path).parts()`` (the same importer, flattened to world coordinates).

Target (issue 14): loading is at most 1.5x trimesh's time.

Run: .venv/bin/python bench/gltf_load.py [--triangles 1000000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

import omnirender as om


def bumpy_sphere(triangles: int) -> om.TriangleSet:
    n = max(8, int(np.sqrt(triangles / 2)))
    theta, phi = np.meshgrid(np.linspace(0, np.pi, n + 1), np.linspace(0, 2 * np.pi, n + 1), indexing="ij")
    r = 1.0 + 0.05 * np.sin(7 * theta) * np.cos(9 * phi)
    v = np.stack([r * np.sin(theta) * np.cos(phi), r * np.cos(theta), r * np.sin(theta) * np.sin(phi)], -1)
    uv = np.stack([phi / (2 * np.pi), 1 - theta / np.pi], -1)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    b, c, d = a + n + 1, a + 1, a + n + 2
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([c, b, d], 1)])
    return om.TriangleSet(v.reshape(-1, 3), faces, texcoords=uv.reshape(-1, 2))


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--triangles", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    import trimesh

    mesh = bumpy_sphere(args.triangles)
    texture = om.Texture(np.random.default_rng(1).integers(0, 255, (256, 256, 3)).astype(np.uint8))
    scene = om.Node("mesh", [om.PBRMaterial(base_color_texture=texture, roughness=0.6), mesh])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "mesh.glb"
        om.export(scene, path)
        size = path.stat().st_size / 1e6

        def ours() -> None:
            root = om.load_gltf(path)
            for node in root.walk():
                for c in node.components:
                    if isinstance(c, om.TriangleSet):
                        c.vertex_array()
                        c.index_array()

        base = best(lambda: trimesh.load(path, process=False), args.repeat)
        mine = best(ours, args.repeat)
        flat = best(lambda: om.MeshFile(path).parts(), args.repeat)
    print(f"{mesh.triangle_count:,} triangles, {size:.1f} MB .glb")
    print(f"trimesh.load          {base:7.3f} s")
    print(f"om.load_gltf + arrays {mine:7.3f} s   ratio {mine / base:.2f}x (target <= 1.5x)")
    print(f"om.MeshFile.parts()   {flat:7.3f} s   ratio {flat / base:.2f}x")


if __name__ == "__main__":
    main()
