"""Gaussian splats as nested translucent ellipsoid shells: the approximation of engines without a splat primitive.

A ray through a 3D Gaussian splat (opacity ``a``) whose closest approach to
the centre is ``b`` standard deviations (Mahalanobis distance) is covered by
``a * exp(-b^2 / 2)``: the peak of the Gaussian along the ray, which is what
the rasteriser's projected 2D Gaussian gives (exactly for orthographic views,
to the affine approximation's accuracy for perspective ones), cut off at 3
standard deviations.  A ray tracer without volumetric primitives (POV-Ray,
Mitsuba's ``scalar_rgb`` path tracer) can reproduce that profile with
``layers`` concentric ellipsoid shells at Mahalanobis radii ``r_1 < ... <
r_m = 3``, each a translucent surface of the splat's colour: a ray passing
between ``r_(j-1)`` and ``r_j`` crosses the shells ``j..m`` (``crossings``
times each: 2 where the ray tracer sees entry and exit, 1 where back faces
are culled), so its transmittance is ``prod (1 - alpha_i)^crossings``.

:func:`shell_layers` picks the radii at equal steps up to the cut-off and
the shells' alphas so that, in each ring, the transmittance equals
``1 - a * g_j`` where ``g_j`` is the ring's area-weighted mean of
``exp(-b^2 / 2)``: the covered "alpha mass" of each ring is the splat's, and
the approximation is a staircase of ``layers`` steps in ``b``.  Its error
against the splat rasteriser is measured in the tests and docs/NOTES.md.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["shell_layers", "local_eye", "splat_matrices", "CUTOFF"]

#: The splat kernel's cut-off (standard deviations): the outermost shell.
CUTOFF = 3.0


def shell_layers(opacities: Any, layers: int = 4, crossings: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """``(radii (layers,), alphas (N, layers))``: the shells of splats of ``opacities`` (see the module docs).

    ``radii`` are Mahalanobis radii (multiply the splat's standard deviations),
    innermost first; ``alphas[:, i]`` is the opacity of one crossing of shell
    ``i``.
    """
    if layers < 1:
        raise ValueError(f"shell_layers: layers must be at least 1, got {layers}")
    if crossings not in (1, 2):
        raise ValueError(f"shell_layers: crossings must be 1 or 2, got {crossings}")
    a = np.clip(np.asarray(opacities, np.float64).reshape(-1), 0.0, 1.0 - 1e-6)
    # radii at equal steps up to the cut-off (a smaller staircase error than equal steps of the Gaussian's
    # mass: 11.5 % against 13.5 % of the covered mass for 8 layers)
    radii = CUTOFF * np.arange(layers + 1) / layers
    levels = np.exp(-0.5 * radii * radii)
    inner, outer = radii[:-1], radii[1:]
    mean = (levels[:-1] - levels[1:]) / (0.5 * (outer**2 - inner**2))  # area-weighted mean of exp(-b^2/2)
    depth = -np.log1p(-a[:, None] * mean[None, :])  # -ln T in each ring, innermost ring deepest
    per_shell = depth - np.concatenate([depth[:, 1:], np.zeros((len(a), 1))], axis=1)
    alphas = 1.0 - np.exp(-np.maximum(per_shell, 0.0) / crossings)
    return outer, alphas


def local_eye(view: np.ndarray | None, model: np.ndarray) -> np.ndarray:
    """The camera's eye in a shape's local coordinates (``view``: world to eye, None for the default camera).

    The splats' view-dependent colour (``GaussianSplats.colors(eye)``) is
    evaluated for this eye in engines that cannot evaluate it per ray.
    """
    eye_world = np.array([0.0, 0.0, 5.0, 1.0]) if view is None else np.linalg.inv(view) @ np.array([0, 0, 0, 1.0])
    local = np.linalg.solve(np.asarray(model, np.float64), eye_world)
    return local[:3] / local[3]


def splat_matrices(positions: Any, rotations: Any, scales: Any, radius: float) -> np.ndarray:
    """(N, 4, 4) matrices taking the unit sphere to each splat's ellipsoid at Mahalanobis ``radius``.

    ``rotations`` are (N, 3, 3) matrices (``GaussianSplats.rotation_matrices()``).
    """
    p = np.asarray(positions, np.float64).reshape(-1, 3)
    m = np.zeros((len(p), 4, 4))
    m[:, :3, :3] = np.asarray(rotations, np.float64) * (radius * np.asarray(scales, np.float64).reshape(-1, 1, 3))
    m[:, :3, 3] = p
    m[:, 3, 3] = 1.0
    return m
