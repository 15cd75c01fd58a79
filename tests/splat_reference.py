"""A numpy reference of 3D Gaussian splatting (Kerbl et al. 2023) for small scenes.

The equations of the paper and its reference rasteriser (``forward.cu``), one
step at a time, with no GPU and no approximation beyond float64:

1. *project*: each splat's centre through the model-view and projection
   matrices; splats whose centre is nearer than the near plane, or outside
   1.3x the view frustum in x or y, are culled (``in_frustum``);
2. *EWA*: the 3D covariance ``Sigma = R S S^T R^T`` is carried into view space
   (``W Sigma W^T`` with ``W`` the model-view's 3x3 part) and through the
   Jacobian ``J`` of the perspective projection at the centre (the centre's
   x/z and y/z clamped to 1.3 times the frustum's half-extent, as the paper
   does), giving the 2D covariance ``J W Sigma W^T J^T`` in pixels;
3. *dilate*: + 0.3 px^2 on the diagonal (the paper's low-pass filter);
4. *colour*: ``omnirender.shapes._sh.sh_colors`` seen from the eye (in the
   splats' own space);
5. *sort* by view depth and *composite front to back* per pixel:
   ``alpha = min(0.99, opacity * exp(-0.5 d^T Sigma2D^-1 d))``, skipped below
   1/255, stopping once the transmittance would drop below 1e-4; pixel
   centres are at (i + 0.5, j + 0.5) in window coordinates (y up).  A splat
   covers the pixels whose centres lie inside the square of half-side
   ``r = ceil(3 sqrt(lambda_max))`` around its mean (the paper evaluates every
   pixel of the 16x16 tiles that square touches: it differs only where a
   splat's alpha beyond 3 sigma is still above 1/255).

``render`` returns premultiplied display RGB and the accumulated alpha, top row
first (as ``om.Image.array``).  ``depth`` (eye-space distance along the view
axis, top row first, ``inf`` where nothing is: ``om.Image.depth`` of the opaque
shapes) excludes splats whose centre lies at or behind it, as the GL engine's
depth test against opaque shapes does.  ``background`` (H, W, 3)
display values are composited under the splats.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from omnirender.attributes.photometry import linear_to_srgb, srgb_to_linear
from omnirender.shapes import _sh
from omnirender.shapes.splats import quaternion_matrices

__all__ = ["render", "psnr", "project"]

#: alpha below which a splat is skipped at a pixel (1/255), and the cap on one splat's alpha
ALPHA_MIN = 1.0 / 255.0
ALPHA_MAX = 0.99
#: transmittance below which compositing stops
T_MIN = 1e-4
#: the low-pass dilation of the 2D covariance (px^2)
DILATION = 0.3


def project(
    splats: Any, model: np.ndarray, view: np.ndarray, proj: np.ndarray, size: tuple[int, int]
) -> dict[str, np.ndarray]:
    """Per splat: ``mean`` (window px), ``conic`` (inverse 2D covariance: a, b, c), ``radius`` (px), ``depth``
    (view distance), ``ndc_z``, ``color`` (display RGB), ``opacity`` and ``visible`` (not culled)."""
    a = splats.checked()
    w, h = size
    mv = view @ model
    n = len(a.positions)
    p = np.concatenate([a.positions, np.ones((n, 1))], axis=1)
    t = p @ mv.T  # view space (camera looks down -z)
    clip = t @ proj.T
    ndc = clip[:, :3] / clip[:, 3:4]
    ortho = proj[3, 3] == 1.0
    near = (proj[2, 3] / (proj[2, 2] - 1.0)) if not ortho else (proj[2, 3] + 1.0) / proj[2, 2]
    depth = -t[:, 2]
    visible = (depth > near) & (np.abs(ndc[:, 0]) <= 1.3) & (np.abs(ndc[:, 1]) <= 1.3) & (ndc[:, 2] <= 1.0)
    fx, fy = proj[0, 0] * w / 2.0, proj[1, 1] * h / 2.0
    r = quaternion_matrices(a.rotations) * a.scales[:, None, :]
    cov = r @ np.transpose(r, (0, 2, 1))
    wm = mv[:3, :3]
    cov_view = wm @ cov @ wm.T
    jac = np.zeros((n, 2, 3))
    if ortho:
        jac[:, 0, 0], jac[:, 1, 1] = fx, fy
    else:
        d = np.maximum(depth, 1e-12)
        # x/z clamped to 1.3 times the frustum's half-extent around the frustum's axis (off-axis cameras)
        cx, cy = -proj[0, 2] / proj[0, 0], -proj[1, 2] / proj[1, 1]
        limx, limy = 1.3 / proj[0, 0], 1.3 / proj[1, 1]
        tx = (np.clip(t[:, 0] / d - cx, -limx, limx) + cx) * d
        ty = (np.clip(t[:, 1] / d - cy, -limy, limy) + cy) * d
        jac[:, 0, 0] = fx / d
        jac[:, 0, 2] = fx * tx / (d * d)
        jac[:, 1, 1] = fy / d
        jac[:, 1, 2] = fy * ty / (d * d)
    cov2 = jac @ cov_view @ np.transpose(jac, (0, 2, 1))
    cov2[:, 0, 0] += DILATION
    cov2[:, 1, 1] += DILATION
    det = cov2[:, 0, 0] * cov2[:, 1, 1] - cov2[:, 0, 1] ** 2
    visible &= det > 0
    det = np.where(det > 0, det, 1.0)
    conic = np.stack([cov2[:, 1, 1] / det, -cov2[:, 0, 1] / det, cov2[:, 0, 0] / det], axis=1)
    mid = 0.5 * (cov2[:, 0, 0] + cov2[:, 1, 1])
    lam = mid + np.sqrt(np.maximum(0.1, mid * mid - det))
    radius = np.ceil(3.0 * np.sqrt(lam))
    mean = np.stack([(ndc[:, 0] + 1.0) * 0.5 * w, (ndc[:, 1] + 1.0) * 0.5 * h], axis=1)
    eye = np.linalg.inv(mv) @ np.array([0.0, 0.0, 0.0, 1.0])
    if ortho:  # every splat is seen along the view direction
        forward = np.linalg.inv(mv)[:3, :3] @ np.array([0.0, 0.0, -1.0])
        basis = _sh.sh_basis(np.repeat((forward / np.linalg.norm(forward))[None], n, axis=0), a.sh_degree)
        color = np.maximum(np.einsum("nk,nkc->nc", basis, a.sh) + 0.5, 0.0)
    else:
        color = _sh.sh_colors(a.positions, a.sh, eye[:3] / eye[3], a.sh_degree)
    return {
        "mean": mean,
        "conic": conic,
        "radius": radius,
        "depth": depth,
        "ndc_z": ndc[:, 2] * 0.5 + 0.5,
        "color": color,
        "opacity": a.opacities,
        "visible": visible,
    }


def render(
    splats: Any,
    model: np.ndarray,
    view: np.ndarray,
    proj: np.ndarray,
    size: tuple[int, int],
    depth: np.ndarray | None = None,
    background: np.ndarray | None = None,
    space: str = "display",
) -> tuple[np.ndarray, np.ndarray]:
    """``(rgb, alpha)``: (H, W, 3) display colour (premultiplied, over ``background`` when given) and (H, W) alpha.

    ``space="display"`` blends the display colours as the trainer does (the GL engine in an 8-bit target);
    ``"linear"`` decodes them (and the background) to linear light, blends there and encodes the result
    (the GL engine in a float target: post-processing, HDR).
    """
    w, h = size
    s = project(splats, model, view, proj, size)
    if space == "linear":
        s["color"] = srgb_to_linear(s["color"])
        if background is not None:
            background = srgb_to_linear(np.clip(background, 0.0, 1.0))
    order = np.argsort(s["depth"], kind="stable")  # nearest first
    order = order[s["visible"][order]]
    color = np.zeros((h, w, 3))
    trans = np.ones((h, w))
    done = np.zeros((h, w), dtype=bool)
    opaque = None if depth is None else np.asarray(depth, dtype=np.float64)[::-1]  # row 0 = bottom
    for i in order:
        mx, my = s["mean"][i]
        rad = s["radius"][i]
        x0, x1 = max(int(np.floor(mx - rad)), 0), min(int(np.ceil(mx + rad)) + 1, w)
        y0, y1 = max(int(np.floor(my - rad)), 0), min(int(np.ceil(my + rad)) + 1, h)
        if x0 >= x1 or y0 >= y1:
            continue
        xs = np.arange(x0, x1) + 0.5 - mx
        ys = np.arange(y0, y1) + 0.5 - my
        dx, dy = np.meshgrid(xs, ys)
        a, b, c = s["conic"][i]
        power = -0.5 * (a * dx * dx + c * dy * dy) - b * dx * dy
        alpha = np.minimum(ALPHA_MAX, s["opacity"][i] * np.exp(np.minimum(power, 0.0)))
        inside = (np.abs(dx) < rad) & (np.abs(dy) < rad)  # the quad the GL engine draws: pixel centres inside
        use = inside & (power <= 0.0) & (alpha >= ALPHA_MIN) & ~done[y0:y1, x0:x1]
        if opaque is not None:
            use &= s["depth"][i] < opaque[y0:y1, x0:x1]
        t = trans[y0:y1, x0:x1]
        test = t * (1.0 - alpha)
        stop = use & (test < T_MIN)
        done[y0:y1, x0:x1] |= stop
        use &= ~stop
        color[y0:y1, x0:x1] += np.where(use[..., None], (alpha * t)[..., None] * s["color"][i], 0.0)
        trans[y0:y1, x0:x1] = np.where(use, test, t)
    alpha_out = 1.0 - trans
    if background is not None:
        color = color + trans[..., None] * np.asarray(background, dtype=np.float64)[::-1]
    if space == "linear":
        color = linear_to_srgb(np.clip(color, 0.0, 1.0))
    return color[::-1], alpha_out[::-1]


def psnr(a: np.ndarray, b: np.ndarray, peak: float = 1.0) -> float:
    """Peak signal-to-noise ratio (dB) between two images of values in [0, peak]."""
    mse = float(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2))
    return float("inf") if mse == 0 else 10.0 * np.log10(peak * peak / mse)
