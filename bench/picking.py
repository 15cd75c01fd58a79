"""Picking speed on a 1,000,000-triangle mesh: acceleration-structure build and random picks.

The mesh is a bumpy sphere (a UV sphere with radial noise) built with numpy.
Measured in one run on the same mesh and the same rays:

* build time of the numpy BVH and of the Embree scene (``embreex``),
* 1,000 random picks through ``om.pick`` (a scene with one TriangleSet; the
  BVH is cached per triangle set, so picks measure traversal plus the engine),
  once per backend,
* trimesh's own pure-Python ray query, ``trimesh.ray.ray_triangle.RayMeshIntersector``
  (an r-tree of triangle boxes, needs the ``rtree`` package), one call per ray
  like a pick and, for reference, all rays in one batched call.  It is slow
  (about 0.1 s per ray here), so it runs on the first ``trimesh_rays`` rays
  (100 by default) and ``om.pick`` is timed again on exactly those rays: the
  speed ratios compare per-ray times on the same rays.

Every backend's nearest hit distances are checked against each other.
Targets (issue 3): build < 3 s, < 1 ms per pick, >= 10x faster per pick than trimesh.

Run: .venv/bin/python bench/picking.py [triangles] [picks] [trimesh_rays]
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

import omnirender as om
from omnirender.geometry.bvh import BVH, EmbreeBVH, embree_available


def bumpy_sphere(triangles: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A closed UV sphere with about ``triangles`` triangles and 2% radial noise."""
    n_lat = max(4, int(math.sqrt(triangles / 4)))
    n_lon = 2 * n_lat
    rng = np.random.default_rng(seed)
    theta = np.linspace(0, np.pi, n_lat + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    r = 1.0 + 0.02 * rng.standard_normal(th.shape)
    ring = np.stack([r * np.sin(th) * np.cos(ph), r * np.cos(th), r * np.sin(th) * np.sin(ph)], axis=-1)
    v = np.concatenate([[[0, 1, 0]], ring.reshape(-1, 3), [[0, -1, 0]]])
    rows = n_lat - 1
    idx = 1 + np.arange(rows * n_lon).reshape(rows, n_lon)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1], nxt[:-1], idx[1:], nxt[1:]
    quads = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    top = np.stack([np.zeros(n_lon, int), nxt[0], idx[0]], -1)
    bottom = np.stack([np.full(n_lon, len(v) - 1), idx[-1], nxt[-1]], -1)
    return v, np.concatenate([top, quads, bottom])


def random_rays(n: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Rays from a sphere of radius 4 towards random points within radius 1.3 (most hit, some miss)."""
    rng = np.random.default_rng(seed)
    o = rng.standard_normal((n, 3))
    o = 4.0 * o / np.linalg.norm(o, axis=1)[:, None]
    target = rng.uniform(-1.3, 1.3, (n, 3))
    d = target - o
    return o, d / np.linalg.norm(d, axis=1)[:, None]


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def pick_all(scene: om.Node, origins: np.ndarray, dirs: np.ndarray, backend: str) -> list:
    return [om.pick(scene, ray=(o, d), backend=backend) for o, d in zip(origins, dirs, strict=True)]


def same_hits(a: np.ndarray, b: np.ndarray) -> bool:
    """Same rays hit, at the same nearest distances (1e-6 relative)."""
    fa, fb = np.isfinite(a), np.isfinite(b)
    return bool(np.array_equal(fa, fb) and np.allclose(a[fa], b[fb], rtol=1e-6))


def nearest(hits: list) -> float:
    return hits[0].distance if hits else np.inf


def main() -> None:
    n_tri = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    n_picks = int(sys.argv[2]) if len(sys.argv) > 2 else 1000
    n_trimesh = int(sys.argv[3]) if len(sys.argv) > 3 else 100
    v, f = bumpy_sphere(n_tri)
    origins, dirs = random_rays(n_picks)
    print(f"mesh: {len(f):,} triangles, {len(v):,} vertices; {n_picks} random picks")

    # -- builds -------------------------------------------------------------
    numpy_bvh, t_build_np = timed(lambda: BVH(v, f))
    print(f"build numpy BVH : {t_build_np:7.3f} s  (depth {numpy_bvh.depth}, branching {numpy_bvh.branching})")
    t_build_em = None
    if embree_available():
        _, t_build_em = timed(lambda: EmbreeBVH(v, f))
        print(f"build Embree    : {t_build_em:7.3f} s")

    # -- picks through om.pick ------------------------------------------------
    mesh = om.TriangleSet(v, indices=f)
    scene = om.Node("scene", [mesh])
    backends = ["numpy"] + (["embree"] if embree_available() else [])
    per_pick: dict[str, float] = {}
    distances: dict[str, np.ndarray] = {}
    for backend in backends:
        # first pick builds and caches the structure (timed above); not part of the per-pick figure
        _, t_first = timed(lambda b=backend: om.pick(scene, ray=(origins[0], dirs[0]), backend=b))
        results, t = timed(lambda b=backend: pick_all(scene, origins, dirs, b))
        per_pick[backend] = t / n_picks
        distances[backend] = np.array([nearest(h) for h in results])
        hits = np.isfinite(distances[backend]).sum()
        print(
            f"om.pick [{backend:6}]: {1e3 * per_pick[backend]:7.3f} ms per pick "
            f"({hits} of {n_picks} rays hit; first pick incl. cache fill {t_first:.2f} s)"
        )
    if len(backends) == 2:
        same = same_hits(distances["numpy"], distances["embree"])
        print(f"numpy and Embree nearest hits agree on all {n_picks} rays: {same}")

    # -- trimesh ------------------------------------------------------------
    t_trimesh = t_trimesh_batch = None
    same_rays: dict[str, float] = {}  # om.pick per ray on exactly the rays trimesh is timed on
    try:
        import rtree  # noqa: F401  (trimesh's pure-Python path needs it)
        import trimesh
        from trimesh.ray.ray_triangle import RayMeshIntersector
    except ImportError as exc:
        print(f"trimesh comparison skipped: {exc}")
    else:
        tm = trimesh.Trimesh(v, f, process=False)
        intersector = RayMeshIntersector(tm)
        _, t_tree = timed(lambda: tm.triangles_tree)
        print(f"trimesh r-tree build: {t_tree:7.3f} s")
        n_trimesh = min(n_trimesh, n_picks)
        sub = slice(0, n_trimesh)  # the same rays for trimesh and for om.pick below

        def one_by_one():
            out = []
            for o, d in zip(origins[sub], dirs[sub], strict=True):
                loc, _, _ = intersector.intersects_location([o], [d], multiple_hits=True)
                out.append(np.linalg.norm(loc - o, axis=1).min() if len(loc) else np.inf)
            return np.array(out)

        tm_dist, t = timed(one_by_one)
        t_trimesh = t / n_trimesh
        _, t = timed(lambda: intersector.intersects_location(origins[sub], dirs[sub], multiple_hits=True))
        t_trimesh_batch = t / n_trimesh
        ok = same_hits(tm_dist, distances["numpy"][sub])
        print(
            f"trimesh RayMeshIntersector: {1e3 * t_trimesh:9.3f} ms per ray one call each, "
            f"{1e3 * t_trimesh_batch:9.3f} ms per ray batched (the first {n_trimesh} rays); "
            f"nearest hits agree with om.pick: {ok}"
        )
        for backend in backends:
            _, t = timed(lambda b=backend: pick_all(scene, origins[sub], dirs[sub], b))
            same_rays[backend] = t / n_trimesh
            print(
                f"same {n_trimesh} rays: om.pick [{backend:6}] {1e3 * same_rays[backend]:7.3f} ms per ray vs "
                f"trimesh {1e3 * t_trimesh:9.3f} ms per ray: {t_trimesh / same_rays[backend]:,.0f}x"
            )

    # -- summary ----------------------------------------------------------------
    print("\ntargets:")
    print(f"  build < 3 s        : numpy {t_build_np:.3f} s {'OK' if t_build_np < 3 else 'MISSED'}", end="")
    if t_build_em is not None:
        print(f", Embree {t_build_em:.3f} s {'OK' if t_build_em < 3 else 'MISSED'}", end="")
    print()
    for backend, t in per_pick.items():
        line = f"  pick [{backend:6}]     : {1e3 * t:.3f} ms {'OK' if t < 1e-3 else 'MISSED'} (< 1 ms)"
        if t_trimesh is not None:
            mine = same_rays[backend]
            ratio = t_trimesh / mine
            line += (
                f"; on the same {n_trimesh} rays {1e3 * mine:.3f} ms vs trimesh {1e3 * t_trimesh:.1f} ms per ray: "
                f"{ratio:,.0f}x faster {'OK' if ratio >= 10 else 'MISSED'} (>= 10x)"
                f", {t_trimesh_batch / mine:,.0f}x vs trimesh batched"
            )
        print(line)


if __name__ == "__main__":
    main()
