"""Analytic reference masks: rays through pixel centres with the GL camera matrices."""

from __future__ import annotations

import math

import numpy as np


def pixel_rays(camera, size, camera_world=None):
    """(origins, directions) in world space, (H, W, 3) each, through pixel centres (row 0 at the top)."""
    w, h = size
    view = camera.view_matrix()
    if camera_world is not None:
        view = view @ np.linalg.inv(camera_world)
    inv = np.linalg.inv(view)
    xs = ((np.arange(w) + 0.5) / w) * 2.0 - 1.0
    ys = 1.0 - ((np.arange(h) + 0.5) / h) * 2.0
    x, y = np.meshgrid(xs, ys)
    aspect = w / h
    if camera.is_orthographic:
        half = camera.height / 2.0
        o = np.stack([x * half * aspect, y * half, np.zeros_like(x)], axis=-1)
        d = np.broadcast_to(np.array([0.0, 0.0, -1.0]), o.shape)
    else:
        t = math.tan(math.radians(camera.fov) / 2.0)
        d = np.stack([x * t * aspect, y * t, -np.ones_like(x)], axis=-1)
        o = np.zeros_like(d)
    origins = o @ inv[:3, :3].T + inv[:3, 3]
    dirs = d @ inv[:3, :3].T
    dirs = dirs / np.linalg.norm(dirs, axis=-1, keepdims=True)
    return origins, dirs


def sphere_mask(origins, dirs, center, radius):
    oc = origins - np.asarray(center, dtype=np.float64)
    b = np.sum(oc * dirs, axis=-1)
    c = np.sum(oc * oc, axis=-1) - radius * radius
    disc = b * b - c
    t = -b + np.sqrt(np.maximum(disc, 0.0))
    return (disc >= 0.0) & (t > 0.0)


def box_mask(origins, dirs, lo, hi):
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / dirs
        t1 = (np.asarray(lo) - origins) * inv
        t2 = (np.asarray(hi) - origins) * inv
    tmin = np.nanmax(np.minimum(t1, t2), axis=-1)
    tmax = np.nanmin(np.maximum(t1, t2), axis=-1)
    return (tmax >= tmin) & (tmax > 0.0)
