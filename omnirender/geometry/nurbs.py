"""NURBS surfaces and trimming curves: evaluation, Bézier extraction, trimmed tessellation (numpy).

Conventions: control points ``(nu, nv, 3)`` with weights ``(nu, nv)``, clamped knot vectors
(the first and last ``degree + 1`` knots equal), parameters normalised to ``[0, 1]`` in both
directions (``(u, v)``, also the texture coordinates).  Trimming curves are closed loops in that
``(u, v)`` square: a counter-clockwise loop keeps its inside, a clockwise loop cuts a hole; when every
loop is clockwise the square's own boundary is the outer loop (GLU's and OpenNURBS's convention).
Everything here is vectorised over parameters; the algorithms are Piegl & Tiller's (basis
functions A2.2, knot insertion A5.1).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "clamped_uniform_knots",
    "basis",
    "surface_points",
    "surface_normals",
    "curve_points",
    "bezier_patches",
    "trim_winding",
    "trim_kept",
    "trim_segments",
    "tessellate_surface",
    "grid_winding",
]


def clamped_uniform_knots(count: int, degree: int) -> np.ndarray:
    """The clamped uniform knot vector for ``count`` control points of ``degree``, on [0, 1]."""
    inner = np.linspace(0.0, 1.0, count - degree + 1)
    return np.concatenate([np.zeros(degree), inner, np.ones(degree)])


def basis(knots: np.ndarray, degree: int, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(span index per parameter, the ``degree + 1`` non-zero basis functions per parameter)."""
    t = np.asarray(t, np.float64)
    n = len(knots) - degree - 2  # last control point index
    span = np.searchsorted(knots, t, side="right") - 1
    span = np.clip(span, degree, n)
    left = np.zeros((len(t), degree + 1))
    right = np.zeros((len(t), degree + 1))
    out = np.zeros((len(t), degree + 1))
    out[:, 0] = 1.0
    for j in range(1, degree + 1):
        left[:, j] = t - knots[span + 1 - j]
        right[:, j] = knots[span + j] - t
        saved = np.zeros(len(t))
        for r in range(j):
            denom = right[:, r + 1] + left[:, j - r]
            temp = np.divide(out[:, r], denom, out=np.zeros(len(t)), where=denom != 0)
            out[:, r] = saved + right[:, r + 1] * temp
            saved = left[:, j - r] * temp
        out[:, j] = saved
    return span, out


def _homogeneous(points: np.ndarray, weights: np.ndarray) -> np.ndarray:
    return np.concatenate([points * weights[..., None], weights[..., None]], axis=-1)


def surface_points(points: np.ndarray, weights: np.ndarray, knots: tuple[np.ndarray, np.ndarray],
                   degrees: tuple[int, int], u: np.ndarray, v: np.ndarray) -> np.ndarray:  # fmt: skip
    """Points of the surface at parameters ``(u, v)`` (arrays of one shape, in the knot range)."""
    (ku, kv), (p, q) = knots, degrees
    shape = np.shape(u)
    u, v = np.ravel(u), np.ravel(v)
    su, nu = basis(ku, p, u)
    sv, nv = basis(kv, q, v)
    h = _homogeneous(points, weights)
    iu = su[:, None] - p + np.arange(p + 1)
    iv = sv[:, None] - q + np.arange(q + 1)
    block = h[iu[:, :, None], iv[:, None, :]]  # (N, p + 1, q + 1, 4)
    s = np.einsum("ni,nj,nijk->nk", nu, nv, block)
    return (s[:, :3] / s[:, 3:]).reshape(*shape, 3)


def surface_normals(points: np.ndarray, weights: np.ndarray, knots: tuple[np.ndarray, np.ndarray],
                    degrees: tuple[int, int], u: np.ndarray, v: np.ndarray) -> np.ndarray:  # fmt: skip
    """Unit normals (along dS/du x dS/dv) at ``(u, v)``, from central differences of the surface."""
    (ku, kv) = knots
    h = 1e-5
    lo_u, hi_u, lo_v, hi_v = ku[0], ku[-1], kv[0], kv[-1]
    u0, u1 = np.clip(u - h, lo_u, hi_u), np.clip(u + h, lo_u, hi_u)
    v0, v1 = np.clip(v - h, lo_v, hi_v), np.clip(v + h, lo_v, hi_v)
    du = surface_points(points, weights, knots, degrees, u1, v) - surface_points(points, weights, knots, degrees, u0, v)
    dv = surface_points(points, weights, knots, degrees, u, v1) - surface_points(points, weights, knots, degrees, u, v0)
    n = np.cross(du, dv)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    bad = length[..., 0] < 1e-14
    if np.any(bad):  # a pole (the derivatives vanish): the normal a little way into the surface
        mid_u, mid_v = (lo_u + hi_u) / 2.0, (lo_v + hi_v) / 2.0
        nudged = surface_normals(points, weights, knots, degrees, u + (mid_u - u) * 1e-3, v + (mid_v - v) * 1e-3)
        n = np.where(bad[..., None], nudged, n / np.where(length > 0, length, 1.0))
        return n
    return n / length


def curve_points(points: np.ndarray, weights: np.ndarray, knots: np.ndarray, degree: int, t: np.ndarray) -> np.ndarray:
    """Points of a rational curve (control points ``(n, d)``) at parameters ``t``."""
    span, n = basis(knots, degree, t)
    h = np.concatenate([points * weights[:, None], weights[:, None]], axis=1)
    idx = span[:, None] - degree + np.arange(degree + 1)
    s = np.einsum("ni,nik->nk", n, h[idx])
    return s[:, :-1] / s[:, -1:]


def _insert(h: np.ndarray, knots: np.ndarray, degree: int, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Insert knot ``t`` once into the curves along axis 0 of ``h`` (homogeneous control points)."""
    k = int(np.searchsorted(knots, t, side="right") - 1)
    n = h.shape[0]
    out = np.empty((n + 1, *h.shape[1:]))
    out[: k - degree + 1] = h[: k - degree + 1]
    out[k + 1 :] = h[k:]
    for i in range(k - degree + 1, k + 1):
        a = (t - knots[i]) / (knots[i + degree] - knots[i])
        out[i] = a * h[i] + (1.0 - a) * h[i - 1]
    return out, np.insert(knots, k + 1, t)


def _to_bezier(h: np.ndarray, knots: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Insert every interior knot up to multiplicity ``degree``: consecutive Bézier segments along axis 0."""
    inner = np.unique(knots[degree + 1 : -degree - 1])
    for t in inner:
        for _ in range(degree - int(np.sum(knots == t))):
            h, knots = _insert(h, knots, degree, float(t))
    return h, np.unique(knots)


def bezier_patches(points: np.ndarray, weights: np.ndarray, knots: tuple[np.ndarray, np.ndarray],
                   degrees: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The surface as rational Bézier patches: (patches (k, p + 1, q + 1, 4) homogeneous control points,
    domains (k, 4) as (u0, u1, v0, v1) in the knot range)."""
    (ku, kv), (p, q) = knots, degrees
    h = _homogeneous(points, weights)
    h, breaks_u = _to_bezier(h, ku, p)
    h, breaks_v = _to_bezier(np.swapaxes(h, 0, 1), kv, q)
    h = np.swapaxes(h, 0, 1)
    patches, domains = [], []
    for i in range(len(breaks_u) - 1):
        for j in range(len(breaks_v) - 1):
            patches.append(h[i * p : i * p + p + 1, j * q : j * q + q + 1])
            domains.append((breaks_u[i], breaks_u[i + 1], breaks_v[j], breaks_v[j + 1]))
    return np.array(patches), np.array(domains, np.float64)


# -- trimming -----------------------------------------------------------------------------------------------
def trim_segments(loops: list[np.ndarray]) -> tuple[np.ndarray, float]:
    """All loops' edges as (n, 4) (x0, y0, x1, y1) and the winding the square's boundary adds (1 when every
    loop is clockwise: they are holes in the whole surface; else 0)."""
    segments = []
    outer = 1.0
    for loop in loops:
        a = np.asarray(loop, np.float64)
        b = np.roll(a, -1, axis=0)
        segments.append(np.hstack([a, b]))
        area = 0.5 * float(np.sum(a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]))
        if area > 0.0:
            outer = 0.0
    return (np.vstack(segments) if segments else np.zeros((0, 4))), outer


def trim_winding(uv: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Winding numbers of points ``uv`` (N, 2) about the loops' edges ``segments`` (Sunday's crossing rule)."""
    x, y = uv[:, :1], uv[:, 1:2]
    x0, y0, x1, y1 = (segments[None, :, k] for k in range(4))
    cross = (x1 - x0) * (y - y0) - (x - x0) * (y1 - y0)
    up = (y0 <= y) & (y1 > y) & (cross > 0)
    down = (y0 > y) & (y1 <= y) & (cross < 0)
    return up.sum(axis=1) - down.sum(axis=1)


def trim_kept(uv: np.ndarray, loops: list[np.ndarray]) -> np.ndarray:
    """Whether each point ``uv`` (N, 2) of the parameter square is kept by the trimming loops."""
    if not loops:
        return np.ones(len(uv), bool)
    segments, outer = trim_segments(loops)
    return _winding_chunked(np.asarray(uv, np.float64), segments) + outer > 0


def grid_winding(xs: np.ndarray, ys: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Winding numbers (len(xs), len(ys)) of the grid points ``(xs[i], ys[j])``: :func:`trim_winding`'s rule
    row by row (an edge crossing row ``y`` at ``x_c`` counts for the points with ``x < x_c``), in
    O(rows x edges + points) instead of O(points x edges)."""
    x0, y0, x1, y1 = segments.T
    out = np.zeros((len(xs), len(ys)), np.int64)
    for j, y in enumerate(ys):
        up = (y0 <= y) & (y1 > y)
        down = (y0 > y) & (y1 <= y)
        hit = up | down
        if not hit.any():
            continue
        xc = x0[hit] + (y - y0[hit]) * (x1[hit] - x0[hit]) / (y1[hit] - y0[hit])
        w = np.where(up[hit], 1, -1)
        order = np.argsort(xc)
        xc, w = xc[order], w[order]
        suffix = np.concatenate([np.cumsum(w[::-1])[::-1], [0]])  # sum of the weights from k on
        out[:, j] = suffix[np.searchsorted(xc, xs, side="right")]
    return out


def tessellate_surface(points: np.ndarray, weights: np.ndarray, knots: tuple[np.ndarray, np.ndarray],
                       degrees: tuple[int, int], segments: tuple[int, int],
                       loops: list[np.ndarray] | None = None) -> dict[str, Any]:  # fmt: skip
    """A triangle mesh of the surface: a ``segments`` grid in (u, v), cut along the trimming loops.

    Triangles the loops cross are cut where the boundary crosses their edges (found by bisection on the
    exact inside test, so the cut lies on the loops to within 1e-4 of the square); the new vertices are
    points of the surface.  Returns ``vertices``, ``normals``, ``texcoords`` (normalised (u, v)) and
    ``indices``.
    """
    (ku, kv) = knots
    nu, nv = segments
    s, t = np.meshgrid(np.linspace(0.0, 1.0, nu + 1), np.linspace(0.0, 1.0, nv + 1), indexing="ij")
    uv = np.column_stack([s.ravel(), t.ravel()])
    k = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    a, b, c, d = k[:-1, :-1].ravel(), k[1:, :-1].ravel(), k[1:, 1:].ravel(), k[:-1, 1:].ravel()
    tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    if loops:
        segs, outer = trim_segments(loops)
        kept = (grid_winding(s[:, 0], t[0], segs) + outer > 0).ravel()
        uv, tris = _cut(uv, tris, kept, segs, outer)
        used, tris = np.unique(tris, return_inverse=True)  # the vertices cut away go
        uv, tris = uv[used], tris.reshape(-1, 3)
    su = ku[0] + uv[:, 0] * (ku[-1] - ku[0])
    sv = kv[0] + uv[:, 1] * (kv[-1] - kv[0])
    vertices = surface_points(points, weights, knots, degrees, su, sv)
    normals = surface_normals(points, weights, knots, degrees, su, sv)
    return {"vertices": vertices, "normals": normals, "texcoords": uv, "indices": tris.astype(np.int64)}


def _cut(uv: np.ndarray, tris: np.ndarray, kept_points: np.ndarray, segs: np.ndarray,
         outer: float) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Marching triangles on the inside test (``kept_points`` per vertex): keep the kept part of every triangle."""
    inside = kept_points[tris]
    count = inside.sum(axis=1)
    mixed = tris[(count == 1) | (count == 2)]
    flags = inside[(count == 1) | (count == 2)]
    one = flags.sum(axis=1) == 1
    # rotate each mixed triangle so that its odd corner (the one kept, or the one cut away) comes first
    r = np.where(one, np.argmax(flags, axis=1), np.argmin(flags, axis=1))
    rows = np.arange(len(mixed))[:, None]
    a, b, c = (mixed[rows, (r[:, None] + k) % 3][:, 0] for k in range(3))
    # the edges the loops cross, once each, and where (bisection on the exact inside test, all at once)
    pairs = np.concatenate([np.stack([a, b], 1), np.stack([a, c], 1)])
    keys, inverse = np.unique(np.sort(pairs, axis=1), axis=0, return_inverse=True)
    lo_first = kept_points[keys[:, 0]]
    lo = np.where(lo_first[:, None], uv[keys[:, 0]], uv[keys[:, 1]])  # kept end
    hi = np.where(lo_first[:, None], uv[keys[:, 1]], uv[keys[:, 0]])  # cut-away end
    for _ in range(20):
        mid = (lo + hi) / 2.0
        keep = (_winding_chunked(mid, segs) + outer > 0)[:, None]
        lo, hi = np.where(keep, mid, lo), np.where(keep, hi, mid)
    crossing = len(uv) + inverse.reshape(2, -1)  # vertex index of each triangle's (a, b) and (a, c) crossing
    ab, ac = crossing[0], crossing[1]
    small = np.stack([a, ab, ac], 1)[one]  # one corner kept: a smaller triangle
    quads = ~one  # two kept: a quad, two triangles
    quad = np.concatenate([np.stack([ab, b, c], 1)[quads], np.stack([ab, c, ac], 1)[quads]])
    kept = np.vstack([tris[count == 3], small, quad]).astype(np.int64)
    return np.vstack([uv, (lo + hi) / 2.0]), kept


def _winding_chunked(uv: np.ndarray, segments: np.ndarray) -> np.ndarray:
    chunk = max(1, 2**21 // max(1, len(segments)))
    return np.concatenate(
        [trim_winding(uv[i : i + chunk], segments) for i in range(0, len(uv), chunk)] or [np.zeros(0, int)]
    )
