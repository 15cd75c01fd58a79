"""Bounding-volume hierarchies over triangles for ray queries and box queries.

:class:`BVH` is pure numpy.  Build: triangles are sorted along a Morton
(Z-order) curve of their centroids, cut into equal leaves, and grouped into a
*complete* tree of branching factor ``B`` (default 8) stored level by level as
flat ``(lo, hi)`` arrays: node ``j`` of level ``k`` has the children
``j*B .. j*B+B-1`` on level ``k+1``.  Every level's bounds come from one
vectorised reduction of the level below, so building a million triangles takes
a fraction of a second.  A wide, shallow tree suits numpy: traversal handles
the whole frontier of nodes of one level with a handful of array operations,
whether it holds one ray's nodes or (ray, node) pairs of a batch.

:class:`EmbreeBVH` offers the same queries through Intel Embree (``embreex``)
when it is importable; exact distances are recomputed in float64 from the
triangles Embree reports, so both paths agree.  :func:`bvh_for` caches one
structure per (triangle set, version).
"""

from __future__ import annotations

import math
import weakref
from typing import Any

import numpy as np

from .intersect import ray_triangles, safe_inverse

__all__ = ["BVH", "EmbreeBVH", "RayHits", "build_bvh", "bvh_for", "embree_available"]


class RayHits:
    """Crossings of one ray with a triangle mesh, nearest first: ``t``, ``triangle``, ``u``, ``v``."""

    __slots__ = ("t", "triangle", "u", "v")

    def __init__(self, t: np.ndarray, triangle: np.ndarray, u: np.ndarray, v: np.ndarray) -> None:
        self.t, self.triangle, self.u, self.v = t, triangle, u, v

    def __len__(self) -> int:
        return len(self.t)

    @classmethod
    def empty(cls) -> RayHits:
        return cls(np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0))


def _morton(points: np.ndarray) -> np.ndarray:
    """30-bit Morton codes of points quantised to a 1024^3 grid over their (cubic) bounding box."""
    lo = points.min(axis=0)
    extent = float((points.max(axis=0) - lo).max())
    scale = 1023.0 / extent if extent > 0 else 0.0
    q = np.clip(((points - lo) * scale).astype(np.uint64), 0, 1023)

    def spread(x: np.ndarray) -> np.ndarray:
        x = (x | (x << np.uint64(16))) & np.uint64(0x030000FF)
        x = (x | (x << np.uint64(8))) & np.uint64(0x0300F00F)
        x = (x | (x << np.uint64(4))) & np.uint64(0x030C30C3)
        x = (x | (x << np.uint64(2))) & np.uint64(0x09249249)
        return x

    return (spread(q[:, 0]) << np.uint64(2)) | (spread(q[:, 1]) << np.uint64(1)) | spread(q[:, 2])


def _check_mesh(vertices: Any, indices: Any) -> tuple[np.ndarray, np.ndarray]:
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(indices)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"BVH: vertices must have shape (N, 3), got {v.shape}")
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"BVH: indices must have shape (M, 3), got {f.shape}")
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        raise ValueError(f"BVH: indices must lie in [0, {len(v)}), got range [{f.min()}, {f.max()}]")
    if not np.all(np.isfinite(v)):
        raise ValueError("BVH: vertices must be finite")
    return v, f.astype(np.int64, copy=False)


class BVH:
    """A complete B-ary bounding-volume hierarchy over triangles, in flat numpy arrays."""

    backend = "numpy"

    def __init__(self, vertices: Any, indices: Any, branching: int = 8, leaf_size: int = 8) -> None:
        v, f = _check_mesh(vertices, indices)
        if branching < 2 or leaf_size < 1:
            raise ValueError(f"BVH: need branching >= 2 and leaf_size >= 1, got {branching}, {leaf_size}")
        n = len(f)
        self.count = n
        self.branching = b = int(branching)
        if n:
            centroids = v[f[:, 0]] + v[f[:, 1]] + v[f[:, 2]]
            order = np.argsort(_morton(centroids), kind="stable")
            tri = v[f[order]]
        else:
            order = np.zeros(0, dtype=np.int64)
            tri = np.zeros((0, 3, 3))
        #: original triangle index of each sorted triangle
        self.order = order
        self.v0 = np.ascontiguousarray(tri[:, 0])
        self.e1 = tri[:, 1] - self.v0
        self.e2 = tri[:, 2] - self.v0
        self.tri_lo = np.minimum(np.minimum(tri[:, 0], tri[:, 1]), tri[:, 2])
        self.tri_hi = np.maximum(np.maximum(tri[:, 0], tri[:, 1]), tri[:, 2])
        depth = max(0, math.ceil(math.log(max(n, 1) / leaf_size, b) - 1e-9)) if n > leaf_size else 0
        leaves = b**depth
        self.leaf_size = ls = max(1, -(-n // leaves))
        self.depth = depth
        pad = leaves * ls - n
        lo = np.concatenate([self.tri_lo, np.full((pad, 3), np.nan)]).reshape(leaves, ls, 3)
        hi = np.concatenate([self.tri_hi, np.full((pad, 3), np.nan)]).reshape(leaves, ls, 3)
        levels_lo = [_reduce(np.fmin, lo)]
        levels_hi = [_reduce(np.fmax, hi)]
        for _ in range(depth):
            levels_lo.append(_reduce(np.fmin, levels_lo[-1].reshape(-1, b, 3)))
            levels_hi.append(_reduce(np.fmax, levels_hi[-1].reshape(-1, b, 3)))
        #: per level (root first): node bounds; empty nodes have NaN bounds and are never hit
        self.lo = levels_lo[::-1]
        self.hi = levels_hi[::-1]
        #: per level: (n, 6) = [lo | hi], one gather per level during single-ray traversal
        self.boxes = [
            np.ascontiguousarray(np.concatenate([lo, hi], axis=1)) for lo, hi in zip(self.lo, self.hi, strict=True)
        ]

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(min, max) of all triangles, or None when empty."""
        if self.count == 0:
            return None
        return self.lo[0][0].copy(), self.hi[0][0].copy()

    # -- one ray ----------------------------------------------------------
    def _leaf_triangles(self, leaves: np.ndarray) -> np.ndarray:
        ls = self.leaf_size
        tris = (leaves[:, None] * ls + np.arange(ls)).ravel()
        return tris[tris < self.count]

    def candidates(self, origin: np.ndarray, direction: np.ndarray, tmax: float = np.inf) -> np.ndarray:
        """Sorted-triangle indices in the leaves the ray passes through."""
        if self.count == 0:
            return np.zeros(0, dtype=np.int64)
        inv = safe_inverse(direction)
        # slab test with the near/far planes chosen by the direction's signs (no min/max per node)
        neg = (inv < 0).astype(np.int64) * 3
        near = np.arange(3) + neg
        far = np.arange(3) + 3 - neg
        o_inv = origin * inv
        b = self.branching
        offsets = np.arange(b)
        nodes = np.zeros(1, dtype=np.int64)
        boxes = self.boxes
        for level in range(self.depth + 1):
            box = boxes[level][nodes]
            tn = (box[:, near] * inv - o_inv).max(axis=1)
            tf = (box[:, far] * inv - o_inv).min(axis=1)
            nodes = nodes[(tn <= tf) & (tf >= 0.0) & (tn <= tmax)]
            if not nodes.size:
                return nodes
            if level < self.depth:
                nodes = (nodes[:, None] * b + offsets).ravel()
        return self._leaf_triangles(nodes)

    def intersect(self, origin: Any, direction: Any, tmax: float = np.inf, tmin: float = 0.0) -> RayHits:
        """Every crossing of the ray ``origin + t * direction`` (tmin < t <= tmax), nearest first.

        ``t`` is in units of ``direction``'s length.  Crossings on shared edges
        are reported once.
        """
        o = np.asarray(origin, dtype=np.float64)
        d = np.asarray(direction, dtype=np.float64)
        tris = self.candidates(o, d, tmax)
        if not tris.size:
            return RayHits.empty()
        hit, t, u, v = ray_triangles(o, d, self.v0[tris], self.e1[tris], self.e2[tris], tmin)
        hit &= t <= tmax
        return _dedupe(t[hit], self.order[tris[hit]], u[hit], v[hit])

    # -- many rays --------------------------------------------------------
    def intersect_rays(
        self, origins: Any, directions: Any, chunk: int = 2048
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Nearest crossing per ray: ``(t, triangle, u, v)`` with ``inf`` / ``-1`` for misses."""
        o = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        r = len(o)
        best_t = np.full(r, np.inf)
        best_tri = np.full(r, -1, dtype=np.int64)
        best_u = np.zeros(r)
        best_v = np.zeros(r)
        if self.count == 0:
            return best_t, best_tri, best_u, best_v
        inv = safe_inverse(d)
        b = self.branching
        ls = self.leaf_size
        for start in range(0, r, chunk):
            rays = np.arange(start, min(start + chunk, r))
            nodes = np.zeros(len(rays), dtype=np.int64)
            for level in range(self.depth + 1):
                hit, _ = ray_aabb_level(o[rays], inv[rays], self.lo[level][nodes], self.hi[level][nodes], np.inf)
                rays, nodes = rays[hit], nodes[hit]
                if level < self.depth:
                    rays = np.repeat(rays, b)
                    nodes = (nodes[:, None] * b + np.arange(b)).ravel()
            rays = np.repeat(rays, ls)
            tris = (nodes[:, None] * ls + np.arange(ls)).ravel()
            ok = tris < self.count
            rays, tris = rays[ok], tris[ok]
            hit, t, u, v = ray_triangles(o[rays], d[rays], self.v0[tris], self.e1[tris], self.e2[tris])
            rays, tris, t, u, v = rays[hit], tris[hit], t[hit], u[hit], v[hit]
            if not len(rays):
                continue
            order = np.lexsort((t, rays))
            rays, tris, t, u, v = rays[order], tris[order], t[order], u[order], v[order]
            first = np.ones(len(rays), dtype=bool)
            first[1:] = rays[1:] != rays[:-1]
            sel = rays[first]
            best_t[sel] = t[first]
            best_tri[sel] = self.order[tris[first]]
            best_u[sel] = u[first]
            best_v[sel] = v[first]
        return best_t, best_tri, best_u, best_v

    # -- boxes ------------------------------------------------------------
    def query_boxes(self, lo: Any, hi: Any, chunk: int = 4096) -> tuple[np.ndarray, np.ndarray]:
        """Pairs (box index, original triangle index) whose AABBs overlap (touching counts)."""
        qlo = np.asarray(lo, dtype=np.float64).reshape(-1, 3)
        qhi = np.asarray(hi, dtype=np.float64).reshape(-1, 3)
        out_q, out_t = [], []
        if self.count == 0 or not len(qlo):
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        b = self.branching
        ls = self.leaf_size
        for start in range(0, len(qlo), chunk):
            qs = np.arange(start, min(start + chunk, len(qlo)))
            nodes = np.zeros(len(qs), dtype=np.int64)
            for level in range(self.depth + 1):
                nlo, nhi = self.lo[level][nodes], self.hi[level][nodes]
                ok = (nlo <= qhi[qs]) & (qlo[qs] <= nhi)
                hit = ok[:, 0] & ok[:, 1] & ok[:, 2]
                qs, nodes = qs[hit], nodes[hit]
                if level < self.depth:
                    qs = np.repeat(qs, b)
                    nodes = (nodes[:, None] * b + np.arange(b)).ravel()
            qs = np.repeat(qs, ls)
            tris = (nodes[:, None] * ls + np.arange(ls)).ravel()
            ok = tris < self.count
            qs, tris = qs[ok], tris[ok]
            ok = (self.tri_lo[tris] <= qhi[qs]) & (qlo[qs] <= self.tri_hi[tris])
            hit = ok[:, 0] & ok[:, 1] & ok[:, 2]
            out_q.append(qs[hit])
            out_t.append(self.order[tris[hit]])
        return np.concatenate(out_q), np.concatenate(out_t)


def _reduce(op: np.ufunc, a: np.ndarray) -> np.ndarray:
    """``op`` folded over axis 1 of (n, k, 3) with elementwise calls (much faster than ``reduce`` for small k)."""
    out = a[:, 0].copy()
    for i in range(1, a.shape[1]):
        op(out, a[:, i], out=out)
    return out


def ray_aabb_level(
    origin: np.ndarray, inv_dir: np.ndarray, lo: np.ndarray, hi: np.ndarray, tmax: float
) -> tuple[np.ndarray, np.ndarray]:
    """Slab test used during traversal (NaN bounds never hit)."""
    t1 = (lo - origin) * inv_dir
    t2 = (hi - origin) * inv_dir
    tn = np.minimum(t1, t2).max(axis=-1)
    tf = np.maximum(t1, t2).min(axis=-1)
    return (tn <= tf) & (tf >= 0.0) & (tn <= tmax), tn


def _dedupe(t: np.ndarray, tri: np.ndarray, u: np.ndarray, v: np.ndarray) -> RayHits:
    order = np.argsort(t, kind="stable")
    t, tri, u, v = t[order], tri[order], u[order], v[order]
    if len(t) > 1:
        keep = np.ones(len(t), dtype=bool)
        keep[1:] = np.diff(t) > 1e-9 * (1.0 + np.abs(t[1:]))
        t, tri, u, v = t[keep], tri[keep], u[keep], v[keep]
    return RayHits(t, tri, u, v)


# -- Embree ---------------------------------------------------------------------


def embree_available() -> bool:
    """Whether ``embreex`` (Intel Embree) can be imported."""
    try:
        import embreex.mesh_construction  # noqa: F401
        import embreex.rtcore_scene  # noqa: F401
    except Exception:
        return False
    return True


class EmbreeBVH:
    """The same queries as :class:`BVH`, through Intel Embree (``embreex``).

    Embree finds the triangles (in float32); distances and barycentrics are
    recomputed in float64 so results match the numpy path.
    """

    backend = "embree"

    def __init__(self, vertices: Any, indices: Any) -> None:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        v, f = _check_mesh(vertices, indices)
        self.count = len(f)
        self._v = v
        self._f = f
        self._scale = float(np.ptp(v, axis=0).max()) if len(v) else 1.0
        self._scene = rtcore_scene.EmbreeScene()
        if self.count:
            self._mesh = TriangleMesh(self._scene, v.astype(np.float32), f.astype(np.int32))

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        if self.count == 0:
            return None
        used = self._v[np.unique(self._f)]
        return used.min(axis=0), used.max(axis=0)

    def _exact(self, o: np.ndarray, d: np.ndarray, tri: np.ndarray):
        v0 = self._v[self._f[tri, 0]]
        e1 = self._v[self._f[tri, 1]] - v0
        e2 = self._v[self._f[tri, 2]] - v0
        return ray_triangles(o, d, v0, e1, e2, -np.inf)

    def intersect(self, origin: Any, direction: Any, tmax: float = np.inf, tmin: float = 0.0) -> RayHits:
        """Every crossing with tmin < t <= tmax, nearest first (Embree shot repeatedly past each hit)."""
        if self.count == 0:
            return RayHits.empty()
        o = np.asarray(origin, dtype=np.float64)
        d = np.asarray(direction, dtype=np.float64)
        length = float(np.linalg.norm(d))
        unit = d / length
        step = 1e-6 * max(self._scale, 1e-12)
        start = max(tmin, 0.0) * length
        tmax_world = tmax * length
        direction32 = unit.astype(np.float32)[None]
        prims: list[int] = []
        seen: set[int] = set()
        for _ in range(100000):
            res = self._scene.run((o + unit * start).astype(np.float32)[None], direction32, output=1)
            prim = int(res["primID"][0])
            if prim < 0:
                break
            reached = start + float(res["tfar"][0])
            if reached > tmax_world + step:
                break
            if prim not in seen:
                seen.add(prim)
                prims.append(prim)
            start = max(reached, start) + step
        if not prims:
            return RayHits.empty()
        tri = np.array(prims, dtype=np.int64)
        ok, t, u, v = self._exact(o, d, tri)
        ok &= (t > tmin) & (t <= tmax)
        return _dedupe(t[ok], tri[ok], u[ok], v[ok])

    def intersect_rays(self, origins: Any, directions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Nearest crossing per ray: ``(t, triangle, u, v)`` with ``inf`` / ``-1`` for misses."""
        o = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        r = len(o)
        t = np.full(r, np.inf)
        tri = np.full(r, -1, dtype=np.int64)
        u = np.zeros(r)
        v = np.zeros(r)
        if self.count == 0 or r == 0:
            return t, tri, u, v
        lengths = np.linalg.norm(d, axis=1)
        unit = d / lengths[:, None]
        prim = np.asarray(self._scene.run(o.astype(np.float32), unit.astype(np.float32)), dtype=np.int64)
        hit = prim >= 0
        _, th, uh, vh = self._exact(o[hit], d[hit], prim[hit])
        t[hit], tri[hit], u[hit], v[hit] = th, prim[hit], uh, vh
        return t, tri, u, v


def build_bvh(vertices: Any, indices: Any, backend: str = "auto") -> BVH | EmbreeBVH:
    """An acceleration structure: ``backend`` "numpy", "embree", or "auto" (Embree when importable)."""
    if backend not in ("auto", "numpy", "embree"):
        raise ValueError(f"build_bvh: backend must be 'auto', 'numpy' or 'embree', got {backend!r}")
    if backend == "embree" or (backend == "auto" and embree_available()):
        return EmbreeBVH(vertices, indices)
    return BVH(vertices, indices)


_cache: weakref.WeakKeyDictionary[Any, dict[str, tuple[int, Any]]] = weakref.WeakKeyDictionary()


def bvh_for(shape: Any, backend: str = "auto") -> BVH | EmbreeBVH:
    """The cached acceleration structure of a triangle set (rebuilt when its ``version`` changes)."""
    if backend == "auto":
        backend = "embree" if embree_available() else "numpy"
    entry = _cache.get(shape)
    if entry is None:
        entry = {}
        _cache[shape] = entry
    found = entry.get(backend)
    version = getattr(shape, "version", 0)
    if found is not None and found[0] == version:
        return found[1]
    bvh = build_bvh(shape.vertex_array(), shape.index_array(), backend)
    entry[backend] = (version, bvh)
    return bvh
