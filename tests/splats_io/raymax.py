"""A ray-traced numpy model of Gaussian splats for the shell engines' tests: each splat covers a pixel by its
Gaussian's peak along the pixel's ray (``opacity * exp(-b^2 / 2)``, ``b`` the ray's Mahalanobis distance from
the centre, cut off at 3), blended back to front in linear light by the centres' eye depth.

This is the model POV-Ray's and Mitsuba's nested shells approximate (``omnirender.geometry.splat_shells``); the
rasteriser's projected 2D Gaussian equals it for orthographic views and, for perspective ones, to the affine
approximation's accuracy.
"""

from __future__ import annotations

import numpy as np

import omnirender as om
from omnirender.attributes.photometry import linear_to_srgb, srgb_to_linear
from omnirender.techniques import pixel_ray


def render_raymax(splats: om.GaussianSplats, camera: om.Camera, size: tuple[int, int]) -> np.ndarray:
    """(H, W, 4) float RGBA in [0, 1] (sRGB-encoded colour, straight alpha) of ``splats`` (world = local space)."""
    w, h = size
    a = splats.checked()
    view = camera.view_matrix()
    eye = np.linalg.inv(view)[:3, 3]
    colors = srgb_to_linear(np.maximum(splats.colors(eye), 0.0))
    order = np.argsort((a.positions @ view[:3, :3].T + view[:3, 3])[:, 2])  # farthest (most negative z) first
    r = splats.rotation_matrices()
    out = np.zeros((h, w, 4))
    for y in range(h):
        for x in range(w):
            o, d = pixel_ray(camera, None, (x, y), size)
            ou = np.einsum("nji,nj->ni", r, o - a.positions) / a.scales
            du = np.einsum("nji,j->ni", r, d) / a.scales
            t = -np.einsum("ni,ni->n", ou, du) / np.einsum("ni,ni->n", du, du)
            b2 = np.einsum("ni,ni->n", ou + t[:, None] * du, ou + t[:, None] * du)
            alpha = np.where((b2 < 9.0) & (t > 0), a.opacities * np.exp(-0.5 * b2), 0.0)
            rgb, cover = np.zeros(3), 0.0
            for i in order:
                if alpha[i] > 0.0:
                    rgb = alpha[i] * colors[i] + (1.0 - alpha[i]) * rgb
                    cover = alpha[i] + (1.0 - alpha[i]) * cover
            out[y, x, :3] = linear_to_srgb(rgb / cover) if cover > 0 else 0.0
            out[y, x, 3] = cover
    return out


def cloud(n: int = 40, degree: int = 0, seed: int = 3) -> om.GaussianSplats:
    """A small random cloud around the origin (radius about 1) of splats 0.05..0.3 across."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    k = (degree + 1) ** 2
    sh = rng.normal(scale=0.15, size=(n, k, 3))
    sh[:, 0, :] = (rng.uniform(0.1, 0.9, (n, 3)) - 0.5) / 0.28209479177387814
    return om.GaussianSplats(
        (rng.normal(size=(n, 3)) * 0.5).astype(np.float32),
        q.astype(np.float32),
        (np.exp(rng.normal(size=(n, 3)) * 0.3) * 0.12).astype(np.float32),
        rng.uniform(0.3, 1.0, n).astype(np.float32),
        sh.astype(np.float32),
    )
