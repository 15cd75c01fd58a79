"""Unstructured lumigraph rendering on the CPU side: the screen mesh and the blending field of one frame.

Per frame, for the view being drawn (Buehler et al., "Unstructured Lumigraph
Rendering", 2001):

1. **screen mesh**: a regular grid of vertices in the image, aligned with the
   view (one vertex every ``cell`` pixels);
2. **depth correction**: the depth maps of the views most relevant to this
   view (their cameras seeing the light field's centre from the closest
   directions) give a depth buffer of this view (the GL renderer draws them as
   meshes, :func:`warp_depth` splats them on the CPU), and each vertex takes
   the nearest surface found around it; vertices where no view saw anything
   are *invalid* and get a heuristic depth from the light field's bounding box
   (the middle of the ray's stretch inside it);
3. triangles whose vertices are all invalid are removed, so only the part
   connected to valid vertices is kept (the renderer fades the result out
   towards the borders of the cameras' images, where the light field ends);
4. **blending field**: per vertex and camera a penalty -- the angle between
   the camera's ray and this view's ray through the vertex's surface point,
   plus a resolution penalty for cameras farther from it than the eye;
   infinite where the camera does not see the point (outside its image, or
   hidden behind a nearer surface of its depth map) -- and the weights of the
   ``k`` best cameras, ``(1 - p / p_k) / p`` with ``p_k`` the ``k``-th smallest
   penalty, normalised to sum 1.  A camera through which the ray passes exactly
   gets all the weight (epipole consistency).

The GPU part (:mod:`.renderer`) draws the mesh once per camera with its
weights and projective texturing, additively.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .data import LightField

__all__ = [
    "ScreenMesh",
    "screen_mesh",
    "blending_weights",
    "unproject",
    "relevant_views",
    "warp_depth",
    "eye_of",
]

#: Depth-map visibility test: a point is hidden in a view when the view saw a surface this much nearer (relative).
VISIBILITY_TOLERANCE = 0.03
_EPS = 1e-4


@dataclass
class ScreenMesh:
    """One frame's mesh: world ``positions`` (V, 3), ``valid`` (V,) vertices with depth data, ``triangles``
    (T, 3) kept, ``weights`` (N cameras, V) of the blending field, ``grid`` (columns, rows)."""

    positions: np.ndarray
    valid: np.ndarray
    triangles: np.ndarray
    weights: np.ndarray
    grid: tuple[int, int]


def unproject(
    view: np.ndarray, proj: np.ndarray, size: tuple[int, int], pixels: np.ndarray, distance: np.ndarray
) -> np.ndarray:
    """World points at eye ``distance`` (along the view axis) behind image ``pixels`` (x, y from the top left)."""
    w, h = size
    ndc_x = pixels[:, 0] / w * 2.0 - 1.0
    ndc_y = 1.0 - pixels[:, 1] / h * 2.0
    z = np.asarray(distance, dtype=np.float64)
    if abs(proj[3, 3] - 1.0) < 1e-9:  # orthographic
        x = (ndc_x - proj[0, 3]) / proj[0, 0]
        y = (ndc_y - proj[1, 3]) / proj[1, 1]
    else:
        x = z * (ndc_x + proj[0, 2]) / proj[0, 0]
        y = z * (ndc_y + proj[1, 2]) / proj[1, 1]
    eye = np.stack([x, y, -z, np.ones_like(z)], axis=1)
    return (eye @ np.linalg.inv(view).T)[:, :3]


def eye_of(view: np.ndarray, proj: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """(eye position, direction towards the viewer, orthographic) of a view."""
    inv = np.linalg.inv(view)
    ortho = abs(proj[3, 3] - 1.0) < 1e-9
    return inv[:3, 3], inv[:3, 2] / np.linalg.norm(inv[:3, 2]), ortho


def relevant_views(lf: LightField, eye: np.ndarray, toward_viewer: np.ndarray, ortho: bool, count: int) -> np.ndarray:
    """Indices of the ``count`` views whose cameras see the light field's centre from the closest directions."""
    lo, hi = lf.bounds
    center = (lo + hi) / 2.0
    to_eye = toward_viewer if ortho else eye - center
    to_eye = to_eye / max(np.linalg.norm(to_eye), 1e-12)
    to_cams = lf.centers - center
    to_cams /= np.maximum(np.linalg.norm(to_cams, axis=1, keepdims=True), 1e-12)
    order = np.argsort(-(to_cams @ to_eye), kind="stable")
    return order[: max(1, min(count, len(lf)))]


def warp_depth(
    lf: LightField, views: np.ndarray, view: np.ndarray, proj: np.ndarray, size: tuple[int, int], step: int = 2
) -> np.ndarray:
    """(H, W) eye distances of this view's nearest surfaces, splatted from the depth maps of ``views``.

    Every ``step``-th depth sample becomes a point; pixels no point falls on are
    filled with the nearest surface around them (a 3 x 3 minimum).  The GL
    renderer draws the depth maps as meshes instead; this is the CPU form.
    """
    w, h = size
    buffer = np.full(h * w, np.inf)
    clip_from_world = proj @ view
    for i in views:
        pts = lf.points(int(i), step)
        if not len(pts):
            continue
        clip = pts @ clip_from_world[:3, :3].T + clip_from_world[:3, 3]
        wcl = pts @ clip_from_world[3, :3] + clip_from_world[3, 3]
        distance = -(pts @ view[2, :3] + view[2, 3])
        ok = (wcl > 1e-9) & (distance > 0)
        x = (clip[ok, 0] / wcl[ok] * 0.5 + 0.5) * w
        y = (0.5 - clip[ok, 1] / wcl[ok] * 0.5) * h
        inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
        np.minimum.at(buffer, y[inside].astype(np.int64) * w + x[inside].astype(np.int64), distance[ok][inside])
    buffer = buffer.reshape(h, w)
    return np.where(np.isfinite(buffer), buffer, _min_filter(buffer, 1))


def _min_filter(a: np.ndarray, radius: int) -> np.ndarray:
    """Minimum over a (2 radius + 1)^2 neighbourhood (inf outside)."""
    padded = np.pad(a, radius, constant_values=np.inf)
    out = np.full_like(a, np.inf)
    h, w = a.shape
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            out = np.minimum(out, padded[dy : dy + h, dx : dx + w])
    return out


def _box_depth(
    bounds: tuple[np.ndarray, np.ndarray], eye: np.ndarray, rays: np.ndarray, axis: np.ndarray
) -> np.ndarray:
    """Heuristic eye distances: the middle of each ray's stretch inside the box (its centre's where rays miss it).

    ``eye`` is the rays' common origin (3,) or one origin per ray (N, 3) on the eye plane.
    """
    lo, hi = bounds
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / rays
        t0 = (lo - eye) * inv
        t1 = (hi - eye) * inv
    t_near = np.nanmax(np.minimum(t0, t1), axis=1)
    t_far = np.nanmin(np.maximum(t0, t1), axis=1)
    hit = (t_far >= np.maximum(t_near, 0.0)) & np.isfinite(t_near) & np.isfinite(t_far)
    t = np.where(hit, (np.maximum(t_near, 0.0) + t_far) / 2.0, np.nan)
    along = rays @ axis  # eye distance per unit of t
    center = ((lo + hi) / 2.0 - eye) @ axis
    depth = np.where(hit, t * along, center)
    return np.maximum(depth, 1e-6)


def blending_weights(
    lf: LightField,
    points: np.ndarray,
    eye: np.ndarray,
    toward_viewer: np.ndarray,
    ortho: bool,
    k: int = 4,
    resolution_weight: float = 0.2,
    check: np.ndarray | None = None,
) -> np.ndarray:
    """(N cameras, V) normalised blending weights of world ``points`` seen from ``eye`` (see the module docstring).

    ``check`` (V,) bool marks the points whose visibility is tested against the
    depth maps (points with depth data; heuristic points are not).
    """
    n, v = len(lf), len(points)
    penalty = np.full((n, v), np.inf)
    if ortho:
        to_eye = np.broadcast_to(toward_viewer, points.shape)
        eye_dist = None
    else:
        to_eye = eye - points
        eye_dist = np.linalg.norm(to_eye, axis=1)
        to_eye = to_eye / np.maximum(eye_dist, 1e-12)[:, None]
    for i, view in enumerate(lf.views):
        rot, t = view.view[:3, :3], view.view[:3, 3]
        local = points @ rot.T + t
        z = -local[:, 2]
        fx, fy, cx, cy = view.intrinsics
        w, h = view.size
        with np.errstate(divide="ignore", invalid="ignore"):
            px = cx + fx * local[:, 0] / z
            py = cy - fy * local[:, 1] / z
        seen = (z > 1e-9) & (px >= 0) & (px < w) & (py >= 0) & (py < h)
        if check is not None:
            ix = np.clip(np.nan_to_num(px, nan=0.0), 0, w - 1).astype(np.int64)
            iy = np.clip(np.nan_to_num(py, nan=0.0), 0, h - 1).astype(np.int64)
            surface = view.depth[iy, ix]
            hidden = check & (surface < z * (1.0 - VISIBILITY_TOLERANCE))
            seen &= ~hidden
        to_cam = view.center - points
        cam_dist = np.linalg.norm(to_cam, axis=1)
        cos = np.einsum("ij,ij->i", to_cam / np.maximum(cam_dist, 1e-12)[:, None], to_eye)
        angle = np.arccos(np.clip(cos, -1.0, 1.0))
        if eye_dist is not None:
            angle = angle + resolution_weight * np.maximum(0.0, cam_dist - eye_dist) / np.maximum(eye_dist, 1e-12)
        penalty[i] = np.where(seen, angle, np.inf)
    k = max(1, min(k, n))
    finite = np.isfinite(penalty)
    count = finite.sum(axis=0)
    sorted_p = np.sort(penalty, axis=0)
    kth = sorted_p[min(k, n) - 1] if k < n else np.full(v, np.inf)
    # fewer than k cameras see a point: all of them share it (threshold just above the worst of them)
    worst = np.where(count > 0, sorted_p[np.maximum(count - 1, 0), np.arange(v)], 0.0)
    threshold = np.where(count >= k, kth, worst * 1.5 + 1e-3)
    threshold = np.where(np.isfinite(threshold), threshold, worst * 1.5 + 1e-3)
    with np.errstate(divide="ignore", invalid="ignore"):
        raw = np.where(penalty < threshold, (1.0 - penalty / threshold) / np.maximum(penalty, _EPS), 0.0)
    raw[~finite] = 0.0
    total = raw.sum(axis=0)
    return np.where(total > 0, raw / np.where(total > 0, total, 1.0), 0.0).astype(np.float32)


def screen_mesh(
    lf: LightField,
    view: np.ndarray,
    proj: np.ndarray,
    size: tuple[int, int],
    depth: np.ndarray,
    cell: int = 8,
    k: int = 4,
) -> ScreenMesh:
    """The screen mesh, its depths, fade and blending field for a frame of ``size`` seen by ``view``/``proj``.

    ``depth`` (H, W) holds the eye distances of the surfaces the relevant
    views' depth maps put in this view (inf: none), e.g. from :func:`warp_depth`.
    """
    w, h = size
    cols, rows = max(1, math.ceil(w / cell)), max(1, math.ceil(h / cell))
    gx = np.minimum(np.arange(cols + 1) * cell, w).astype(np.float64)
    gy = np.minimum(np.arange(rows + 1) * cell, h).astype(np.float64)
    px, py = np.meshgrid(gx, gy)
    pixels = np.stack([px.ravel(), py.ravel()], axis=1)
    eye, toward_viewer, ortho = eye_of(view, proj)
    near = _min_filter(np.asarray(depth, dtype=np.float64), 1)
    bx = np.clip(pixels[:, 0].astype(np.int64), 0, w - 1)
    by = np.clip(pixels[:, 1].astype(np.int64), 0, h - 1)
    vertex_depth = near[by, bx]
    valid = np.isfinite(vertex_depth)
    if not valid.all():
        axis = -toward_viewer
        if ortho:  # parallel rays from the eye plane
            origins = unproject(view, proj, size, pixels[~valid], np.zeros((~valid).sum()))
            guess = _box_depth(lf.bounds, origins, np.broadcast_to(axis, origins.shape), axis)
        else:
            far_points = unproject(view, proj, size, pixels[~valid], np.ones((~valid).sum()))
            guess = _box_depth(lf.bounds, eye, far_points - eye, axis)
        vertex_depth = vertex_depth.copy()
        vertex_depth[~valid] = guess
    positions = unproject(view, proj, size, pixels, vertex_depth)
    # two triangles per cell; keep those touching a valid vertex
    i = np.arange(rows)[:, None] * (cols + 1) + np.arange(cols)[None, :]
    a, b, c, d = i.ravel(), i.ravel() + 1, i.ravel() + cols + 1, i.ravel() + cols + 2
    triangles = np.concatenate([np.stack([a, c, b], 1), np.stack([b, c, d], 1)])
    triangles = triangles[valid[triangles].any(axis=1)]
    used = np.zeros(len(positions), bool)
    used[triangles.ravel()] = True
    weights = np.zeros((len(lf), len(positions)), np.float32)
    if used.any():
        weights[:, used] = blending_weights(lf, positions[used], eye, toward_viewer, ortho, k, check=valid[used])
    return ScreenMesh(
        positions=positions.astype(np.float32),
        valid=valid,
        triangles=triangles.astype(np.uint32),
        weights=weights,
        grid=(cols, rows),
    )
