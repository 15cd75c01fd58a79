"""Polygon triangulation: convex fans and ear clipping for simple concave polygons."""

from __future__ import annotations

import numpy as np

__all__ = ["newell_normal", "triangulate_polygon", "project_to_plane", "best_fit_plane", "crossing_edges"]


def newell_normal(points: np.ndarray) -> np.ndarray:
    """The (unnormalised) normal of a closed 3D outline by Newell's method; its length is twice the area."""
    p = np.asarray(points, dtype=np.float64)
    q = np.roll(p, -1, axis=0)
    return np.array(
        [
            np.sum((p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2])),
            np.sum((p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0])),
            np.sum((p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1])),
        ]
    )


def project_to_plane(points: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(N, 2) coordinates of ``points`` in a right-handed basis (u, v) of the plane with ``normal``.

    An outline counter-clockwise about ``normal`` stays counter-clockwise in (u, v).
    """
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    p = np.asarray(points, dtype=np.float64)
    return np.stack([p @ u, p @ v], axis=1)


def best_fit_plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(centroid, unit normal, max distance of a point from the plane) of the least-squares plane of 3D points."""
    p = np.asarray(points, dtype=np.float64)
    centroid = p.mean(axis=0)
    _, _, vt = np.linalg.svd(p - centroid, full_matrices=False)
    normal = vt[-1]
    return centroid, normal, float(np.max(np.abs((p - centroid) @ normal)))


def crossing_edges(q: np.ndarray, limit: int = 2000) -> tuple[int, int] | None:
    """The first pair of non-adjacent edges of a closed 2D outline that properly cross, or None.

    Edge i runs from point i to point i + 1.  Touching (a vertex on another
    edge) does not count.  Outlines longer than ``limit`` are not checked
    (the test is quadratic) and give None.
    """
    q = np.asarray(q, dtype=np.float64)
    n = len(q)
    if n < 4 or n > limit:
        return None
    a, b = q, np.roll(q, -1, axis=0)
    scale = float(np.max(np.ptp(q, axis=0))) or 1.0
    eps = 1e-12 * scale * scale
    for i in range(n - 2):
        j = np.arange(i + 2, n if i else n - 1)  # not adjacent to i (edge n-1 touches edge 0)
        if not len(j):
            continue
        c, d = a[j], b[j]
        d1 = _cross2(a[i], b[i], c)
        d2 = _cross2(a[i], b[i], d)
        d3 = _cross2(c, d, a[i])
        d4 = _cross2(c, d, b[i])
        hit = (((d1 > eps) & (d2 < -eps)) | ((d1 < -eps) & (d2 > eps))) & (
            ((d3 > eps) & (d4 < -eps)) | ((d3 < -eps) & (d4 > eps))
        )
        if np.any(hit):
            return i, int(j[np.argmax(hit)])
    return None


def _cross2(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])


def triangulate_polygon(points: np.ndarray, *, owner: str = "Polygon") -> np.ndarray:
    """(N - 2, 3) uint32 triangles of a planar outline, with the outline's winding.

    2D (N, 2) or 3D (N, 3) points.  Convex outlines become a fan; simple concave
    ones are ear-clipped.  A self-intersecting outline still yields N - 2
    triangles (clipping the best available corner when no true ear exists) but
    they may overlap.  A degenerate outline (zero area) raises ValueError.
    """
    p = np.asarray(points, dtype=np.float64)
    n = len(p)
    if n < 3:
        raise ValueError(f"{owner}: a polygon needs at least 3 vertices, got {n}")
    if p.shape[1] == 3:
        normal = newell_normal(p)
        area2 = float(np.linalg.norm(normal))
        scale = float(np.max(np.ptp(p, axis=0))) or 1.0
        if area2 <= 1e-12 * scale * scale:
            raise ValueError(f"{owner}: the polygon has zero area (collinear or repeated vertices)")
        q = project_to_plane(p, normal)  # counter-clockwise in the plane by construction
        flip = False
    else:
        q = p
        signed = 0.5 * float(np.sum(_cross2(np.zeros(2), q, np.roll(q, -1, axis=0))))
        scale = float(np.max(np.ptp(q, axis=0))) or 1.0
        if abs(signed) <= 1e-12 * scale * scale:
            raise ValueError(f"{owner}: the polygon has zero area (collinear or repeated vertices)")
        flip = signed < 0
        if flip:
            q = q[::-1]
    tris = _ear_clip(q)
    if flip:  # map back to the original order and winding
        tris = (n - 1 - tris)[:, ::-1]
    out = np.ascontiguousarray(tris, dtype=np.uint32)
    out.setflags(write=False)
    return out


def _ear_clip(q: np.ndarray) -> np.ndarray:
    """Triangles of a counter-clockwise 2D outline."""
    n = len(q)
    prev = np.roll(q, 1, axis=0)
    nxt = np.roll(q, -1, axis=0)
    if np.all(_cross2(prev, q, nxt) >= 0):  # convex: a fan
        i = np.arange(1, n - 1)
        return np.stack([np.zeros(n - 2, dtype=np.int64), i, i + 1], axis=1)
    scale = float(np.max(np.ptp(q, axis=0))) or 1.0
    eps = 1e-12 * scale * scale
    remaining = list(range(n))
    out = []
    guard = 0
    while len(remaining) > 3:
        m = len(remaining)
        idx = np.array(remaining)
        pts = q[idx]
        a = np.roll(pts, 1, axis=0)
        c = np.roll(pts, -1, axis=0)
        convex = _cross2(a, pts, c) > eps
        clipped = False
        for k in np.flatnonzero(convex):
            ia, ib, ic = remaining[(k - 1) % m], remaining[k], remaining[(k + 1) % m]
            others = np.ones(m, dtype=bool)
            others[[(k - 1) % m, k, (k + 1) % m]] = False
            o = pts[others]
            # Exclude vertices coincident with the ear's corners (touching outlines).
            ta, tb, tc = q[ia], q[ib], q[ic]
            inside = (_cross2(ta, tb, o) >= -eps) & (_cross2(tb, tc, o) >= -eps) & (_cross2(tc, ta, o) >= -eps)
            if not np.any(inside):
                out.append((ia, ib, ic))
                del remaining[k]
                clipped = True
                break
        if not clipped:
            # No ear (numerical trouble or a self-intersecting outline): clip the most convex corner.
            k = int(np.argmax(_cross2(a, pts, c)))
            out.append((remaining[(k - 1) % m], remaining[k], remaining[(k + 1) % m]))
            del remaining[k]
        guard += 1
        if guard > 4 * n:  # pragma: no cover - cannot happen, every round removes a vertex
            break
    out.append(tuple(remaining))
    return np.array(out, dtype=np.int64)
