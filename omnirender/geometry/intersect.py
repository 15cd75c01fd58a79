"""Intersection tests: rays with boxes, triangles and analytic shapes; triangle pairs.

Everything is vectorised numpy in float64.  Analytic ray intersections work in
the shape's *local* coordinates: the caller transforms the ray by the inverse
model matrix and passes the direction unnormalised, so the ray parameter ``t``
is the same in local and world space (world distance when the world direction
has unit length).  Each analytic function returns ``(t, normals)``: every
crossing with ``t > tmin`` in increasing order and the local geometric normals
there (pointing out of solids, +y for the flat disk and rectangle).

Shape conventions (DESIGN.md): cylinder and cone are centred at the origin
with axis +y (the cone's base disk at y = -h/2, apex at y = +h/2); disk and
rectangle lie in the xz plane facing +y; ``Rectangle.size`` is (x, z) extent.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "cross",
    "safe_inverse",
    "ray_aabb",
    "ray_triangles",
    "ray_sphere",
    "ray_box",
    "ray_cylinder",
    "ray_cone",
    "ray_disk",
    "ray_rectangle",
    "triangles_intersect",
    "triangle_bounds",
    "boxes_overlap",
]

_TINY = 1e-300


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis (length 3), broadcasting; cheaper than ``np.cross`` for small arrays."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def safe_inverse(direction: np.ndarray) -> np.ndarray:
    """1/direction with zero components replaced by a huge finite value (keeps slab tests NaN-free)."""
    d = np.asarray(direction, dtype=np.float64)
    d = np.where(np.abs(d) < 1e-150, np.where(d < 0, -1e-150, 1e-150), d)
    return 1.0 / d


def ray_aabb(
    origin: np.ndarray, inv_dir: np.ndarray, lo: np.ndarray, hi: np.ndarray, tmax: float | np.ndarray = np.inf
) -> tuple[np.ndarray, np.ndarray]:
    """Slab test of ray(s) against boxes; shapes broadcast over the leading axes.

    Returns ``(hit, tnear)``; a box with NaN bounds (an empty node) is never hit.
    """
    t1 = (lo - origin) * inv_dir
    t2 = (hi - origin) * inv_dir
    tn = np.minimum(t1, t2).max(axis=-1)
    tf = np.maximum(t1, t2).min(axis=-1)
    hit = (tn <= tf) & (tf >= 0.0) & (tn <= tmax)
    return hit, tn


def ray_triangles(
    origin: np.ndarray, direction: np.ndarray, v0: np.ndarray, e1: np.ndarray, e2: np.ndarray, tmin: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Möller–Trumbore, double-sided, broadcast over leading axes.

    ``v0`` is the first vertex, ``e1 = v1 - v0``, ``e2 = v2 - v0``.
    Returns ``(hit, t, u, v)``; ``t`` is meaningful only where ``hit``.
    """
    p = cross(direction, e2)
    det = np.einsum("...i,...i->...", e1, p)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_det = 1.0 / det
        s = origin - v0
        u = np.einsum("...i,...i->...", s, p) * inv_det
        q = cross(s, e1)
        v = np.einsum("...i,...i->...", direction, q) * inv_det
        t = np.einsum("...i,...i->...", e2, q) * inv_det
    scale = np.einsum("...i,...i->...", e1, e1) * np.einsum("...i,...i->...", e2, e2)
    eps = 1e-12
    with np.errstate(invalid="ignore"):
        hit = (np.abs(det) > 1e-14 * np.sqrt(scale + _TINY)) & (u >= -eps) & (v >= -eps) & (u + v <= 1.0 + eps)
        hit &= t > tmin
    return hit, t, u, v


def _sorted(ts: list[np.ndarray], ns: list[np.ndarray], tmin: float) -> tuple[np.ndarray, np.ndarray]:
    t = np.concatenate(ts) if ts else np.zeros(0)
    n = np.concatenate(ns) if ns else np.zeros((0, 3))
    keep = np.isfinite(t) & (t > tmin)
    t, n = t[keep], n[keep]
    order = np.argsort(t, kind="stable")
    t, n = t[order], n[order]
    if len(t) > 1:  # a tangent or apex crossing found twice counts once
        keep = np.ones(len(t), dtype=bool)
        keep[1:] = np.diff(t) > 1e-12 * (1.0 + np.abs(t[1:]))
        t, n = t[keep], n[keep]
    return t, n


def _quadratic(a: float, b: float, c: float) -> np.ndarray:
    """Real roots of a t^2 + b t + c (numerically stable), possibly empty."""
    if abs(a) < 1e-300:
        if abs(b) < 1e-300:
            return np.zeros(0)
        return np.array([-c / b])
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return np.zeros(0)
    sq = np.sqrt(disc)
    q = -0.5 * (b + np.copysign(sq, b))
    if q == 0.0:
        return np.array([0.0, 0.0])
    r = np.array([q / a, c / q])
    return np.sort(r)


def ray_sphere(
    o: np.ndarray, d: np.ndarray, center=(0.0, 0.0, 0.0), radius: float = 1.0, tmin: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Crossings of the ray o + t d with a sphere."""
    c = np.asarray(center, dtype=np.float64)
    oc = o - c
    roots = _quadratic(float(d @ d), 2.0 * float(d @ oc), float(oc @ oc) - radius * radius)
    pts = o + roots[:, None] * d
    return _sorted([roots], [(pts - c) / radius], tmin)


def ray_box(
    o: np.ndarray, d: np.ndarray, center=(0.0, 0.0, 0.0), size=(1.0, 1.0, 1.0), tmin: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Crossings with an axis-aligned box of ``size`` around ``center`` (entry and exit)."""
    c = np.asarray(center, dtype=np.float64)
    h = 0.5 * np.asarray(size, dtype=np.float64)
    inv = safe_inverse(d)
    t1 = (c - h - o) * inv
    t2 = (c + h - o) * inv
    tlo = np.minimum(t1, t2)
    thi = np.maximum(t1, t2)
    i_in = int(np.argmax(tlo))
    i_out = int(np.argmin(thi))
    tn, tf = tlo[i_in], thi[i_out]
    if tn > tf:
        return np.zeros(0), np.zeros((0, 3))
    n_in = np.zeros(3)
    n_in[i_in] = -np.sign(d[i_in]) or -1.0
    n_out = np.zeros(3)
    n_out[i_out] = np.sign(d[i_out]) or 1.0
    return _sorted([np.array([tn, tf])], [np.array([n_in, n_out])], tmin)


def _plane_y(o: np.ndarray, d: np.ndarray, y: float) -> tuple[float, np.ndarray]:
    if abs(d[1]) < 1e-300:
        return np.inf, o
    t = (y - o[1]) / d[1]
    return t, o + t * d


def ray_cylinder(
    o: np.ndarray, d: np.ndarray, radius: float = 1.0, height: float = 2.0, tmin: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Crossings with a capped cylinder around +y centred at the origin."""
    h2 = 0.5 * height
    ts, ns = [], []
    roots = _quadratic(d[0] ** 2 + d[2] ** 2, 2.0 * (o[0] * d[0] + o[2] * d[2]), o[0] ** 2 + o[2] ** 2 - radius**2)
    for t in roots:
        p = o + t * d
        if abs(p[1]) <= h2:
            ts.append(t)
            ns.append(np.array([p[0] / radius, 0.0, p[2] / radius]))
    for y, sign in ((h2, 1.0), (-h2, -1.0)):
        t, p = _plane_y(o, d, y)
        if np.isfinite(t) and p[0] ** 2 + p[2] ** 2 <= radius**2:
            ts.append(t)
            ns.append(np.array([0.0, sign, 0.0]))
    return _sorted([np.array(ts)], [np.array(ns).reshape(-1, 3)], tmin)


def ray_cone(
    o: np.ndarray, d: np.ndarray, radius: float = 1.0, height: float = 2.0, tmin: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Crossings with a capped cone: base disk at y = -h/2, apex at y = +h/2."""
    h2 = 0.5 * height
    k2 = (radius / height) ** 2
    yo = h2 - o[1]  # distance below the apex, along -y
    a = d[0] ** 2 + d[2] ** 2 - k2 * d[1] ** 2
    b = 2.0 * (o[0] * d[0] + o[2] * d[2] + k2 * yo * d[1])
    c = o[0] ** 2 + o[2] ** 2 - k2 * yo * yo
    ts, ns = [], []
    for t in _quadratic(a, b, c):
        p = o + t * d
        below = h2 - p[1]
        if 0.0 <= below <= height:
            n = np.array([p[0], k2 * below, p[2]])
            ln = np.linalg.norm(n)
            ts.append(t)
            ns.append(n / ln if ln > 0 else np.array([0.0, 1.0, 0.0]))
    t, p = _plane_y(o, d, -h2)
    if np.isfinite(t) and p[0] ** 2 + p[2] ** 2 <= radius**2:
        ts.append(t)
        ns.append(np.array([0.0, -1.0, 0.0]))
    return _sorted([np.array(ts)], [np.array(ns).reshape(-1, 3)], tmin)


def ray_disk(o: np.ndarray, d: np.ndarray, radius: float = 1.0, tmin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Crossing with a disk in the xz plane centred at the origin (normal +y)."""
    t, p = _plane_y(o, d, 0.0)
    if np.isfinite(t) and p[0] ** 2 + p[2] ** 2 <= radius**2:
        return _sorted([np.array([t])], [np.array([[0.0, 1.0, 0.0]])], tmin)
    return np.zeros(0), np.zeros((0, 3))


def ray_rectangle(o: np.ndarray, d: np.ndarray, size=(1.0, 1.0), tmin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Crossing with a rectangle in the xz plane centred at the origin; ``size`` = (x extent, z extent)."""
    t, p = _plane_y(o, d, 0.0)
    if np.isfinite(t) and abs(p[0]) <= 0.5 * size[0] and abs(p[2]) <= 0.5 * size[1]:
        return _sorted([np.array([t])], [np.array([[0.0, 1.0, 0.0]])], tmin)
    return np.zeros(0), np.zeros((0, 3))


# -- triangles against triangles ------------------------------------------------


def triangle_bounds(tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-triangle AABBs of (K, 3, 3) triangles (elementwise: much faster than a reduce over 3)."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    return np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)


def boxes_overlap(lo_a: np.ndarray, hi_a: np.ndarray, lo_b: np.ndarray, hi_b: np.ndarray, eps: float = 0.0):
    """Whether AABBs overlap (touching counts), broadcast over leading axes."""
    ok = (lo_a <= hi_b + eps) & (lo_b <= hi_a + eps)
    return ok[..., 0] & ok[..., 1] & ok[..., 2]


def triangles_intersect(a: np.ndarray, b: np.ndarray, eps: float | None = None) -> np.ndarray:
    """Whether triangle pairs ``a[k]`` and ``b[k]`` (each (K, 3, 3)) intersect or touch.

    Separating-axis test with 17 candidate axes: both normals, the nine edge
    cross products and, for the coplanar case, the six in-plane edge normals.
    A pair is disjoint when some axis separates their projections by more than
    ``eps`` (default: 1e-9 of the pair's size), so touching triangles collide.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape != b.shape or a.ndim != 3 or a.shape[1:] != (3, 3):
        raise ValueError(f"triangles_intersect: need two (K, 3, 3) arrays of equal shape, got {a.shape} and {b.shape}")
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    ea = np.roll(a, -1, axis=1) - a  # (K, 3 edges, 3)
    eb = np.roll(b, -1, axis=1) - b
    na = np.cross(ea[:, 0], ea[:, 1])
    nb = np.cross(eb[:, 0], eb[:, 1])
    edge_cross = np.cross(ea[:, :, None, :], eb[:, None, :, :]).reshape(len(a), 9, 3)
    in_a = np.cross(na[:, None, :], ea)
    in_b = np.cross(nb[:, None, :], eb)
    axes = np.concatenate([na[:, None], nb[:, None], edge_cross, in_a, in_b], axis=1)  # (K, 17, 3)
    length = np.linalg.norm(axes, axis=2, keepdims=True)
    extent = np.maximum(np.ptp(np.concatenate([a, b], axis=1), axis=1).max(axis=1), 1e-300)
    # axes shorter than this are degenerate (parallel edges): they separate nothing
    usable = length[..., 0] > 1e-12 * extent[:, None] ** 2
    axes = np.where(usable[..., None], axes / np.where(length > 0, length, 1.0), 0.0)
    pa = np.einsum("kvi,kai->kav", a, axes)
    pb = np.einsum("kvi,kai->kav", b, axes)
    tol = (1e-9 * extent)[:, None] if eps is None else eps
    separated = (pa.max(axis=2) < pb.min(axis=2) - tol) | (pb.max(axis=2) < pa.min(axis=2) - tol)
    return ~np.any(separated & usable, axis=1)
