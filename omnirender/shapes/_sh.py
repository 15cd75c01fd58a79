"""Real spherical harmonics up to degree 3: THE colour rule of ``om.GaussianSplats`` (numpy, vectorised).

The constants and the basis order are the reference rasteriser's (Kerbl et
al. 2023, ``forward.cu`` ``computeColorFromSH``); the GL splat shader
(``omnirender/gl/painters/splats_glsl.py``) mirrors this module constant for
constant, and every other engine (numpy reference, Mitsuba, POV-Ray,
Radiance, exporters) calls :func:`sh_colors`.

``rgb = max(0.5 + sum_k Y_k(dir) * sh[k], 0)`` per channel, with ``dir`` the
unit vector from the eye to the splat's centre in the splat's own (object)
space.  The result is a *display* (sRGB-encoded) colour, as the trainer fitted
it; engines that work in linear light decode it with the sRGB transfer
function (see ``docs/DESIGN.md``, "Gaussian splats").
"""

from __future__ import annotations

import numpy as np

__all__ = ["C0", "C1", "C2", "C3", "coefficient_count", "degree_for", "sh_basis", "sh_colors"]

#: degree 0 (the DC term): 1 / (2 sqrt(pi))
C0 = 0.28209479177387814
#: degree 1
C1 = 0.4886025119029199
#: degree 2, basis functions 4..8
C2 = (1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792, 0.5462742152960396)
#: degree 3, basis functions 9..15
C3 = (
    -0.5900435899266435,
    2.890611442640554,
    -0.4570457994644658,
    0.3731763325901154,
    -0.4570457994644658,
    1.445305721320277,
    -0.5900435899266435,
)


def coefficient_count(degree: int) -> int:
    """K = (degree + 1)^2 coefficients per channel."""
    return (int(degree) + 1) ** 2


def degree_for(count: int) -> int | None:
    """The degree whose coefficient count is ``count`` (1, 4, 9, 16), or None."""
    for degree in range(4):
        if coefficient_count(degree) == count:
            return degree
    return None


def sh_basis(directions: np.ndarray, degree: int) -> np.ndarray:
    """``(N, K)`` values of the K = (degree+1)^2 basis functions at unit ``directions`` ``(N, 3)``.

    The signs and order are the reference rasteriser's (``-C1*y, +C1*z, -C1*x``...).
    """
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    n = len(d)
    out = np.empty((n, coefficient_count(degree)))
    out[:, 0] = C0
    if degree < 1:
        return out
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    out[:, 1] = -C1 * y
    out[:, 2] = C1 * z
    out[:, 3] = -C1 * x
    if degree < 2:
        return out
    xx, yy, zz = x * x, y * y, z * z
    xy, yz, xz = x * y, y * z, x * z
    out[:, 4] = C2[0] * xy
    out[:, 5] = C2[1] * yz
    out[:, 6] = C2[2] * (2.0 * zz - xx - yy)
    out[:, 7] = C2[3] * xz
    out[:, 8] = C2[4] * (xx - yy)
    if degree < 3:
        return out
    out[:, 9] = C3[0] * y * (3.0 * xx - yy)
    out[:, 10] = C3[1] * xy * z
    out[:, 11] = C3[2] * y * (4.0 * zz - xx - yy)
    out[:, 12] = C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy)
    out[:, 13] = C3[4] * x * (4.0 * zz - xx - yy)
    out[:, 14] = C3[5] * z * (xx - yy)
    out[:, 15] = C3[6] * x * (xx - 3.0 * yy)
    return out


def sh_colors(positions: np.ndarray, sh: np.ndarray, eye: np.ndarray, degree: int | None = None) -> np.ndarray:
    """``(N, 3)`` display colours of splats at ``positions`` with coefficients ``sh`` ``(N, K, 3)`` seen from ``eye``.

    ``eye`` and ``positions`` are in the same (the splats' object) space; a
    splat at the eye gets the direction (0, 0, 1) (any unit vector would do: it
    is not visible).  ``degree`` defaults to the one K implies; a smaller one
    uses only the first (degree+1)^2 coefficients.
    """
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    c = np.asarray(sh, dtype=np.float64)
    k = c.shape[1]
    deg = degree_for(k) if degree is None else int(degree)
    if deg is None or coefficient_count(deg) > k:
        raise ValueError(f"sh_colors: {k} coefficients per channel do not make an SH degree 0..3 (1, 4, 9 or 16)")
    d = p - np.asarray(eye, dtype=np.float64).reshape(1, 3)
    length = np.linalg.norm(d, axis=1, keepdims=True)
    d = np.where(length > 0, d / np.where(length > 0, length, 1.0), np.array([0.0, 0.0, 1.0]))
    basis = sh_basis(d, deg)
    rgb = np.einsum("nk,nkc->nc", basis, c[:, : basis.shape[1], :]) + 0.5
    return np.maximum(rgb, 0.0)
