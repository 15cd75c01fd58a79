"""The analysis engines on ``om.GaussianSplats``: bounds and picking through the splats' 3-sigma ellipsoids.

A splat's extent is its ellipsoid at :data:`SPLAT_SIGMA` standard deviations
(the support of the rasteriser's kernel, and of ``KHR_gaussian_splatting``'s
ellipse kernel): ``om.bounds`` is the exact box of those ellipsoids, and
``om.pick`` reports each crossing of the ray with one of them (entry and
exit), with the splat's index in ``Hit.primitive`` (also ``Hit.splat``).  Collisions are not computed for
splats (a cloud of Gaussians has no surface; ``om.collisions`` leaves them
out, see :mod:`omnirender.techniques.collision`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.handler import RayIntersector, default_for
from ..geometry.ellipsoids import ellipsoid_bounds, ray_ellipsoids
from ..shapes import GaussianSplats
from .bounds import BoundsEngine, BoundsHandler
from .picking import PickEngine

__all__ = ["SPLAT_SIGMA", "GaussianSplatsBounds", "GaussianSplatsIntersector"]

#: The confidence (standard deviations) of a splat's ellipsoid in bounds and picking.
SPLAT_SIGMA = 3.0


def _arrays(shape: GaussianSplats) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    checked = shape.checked()
    return checked.positions, shape.rotation_matrices(), checked.scales


@default_for(BoundsEngine)
class GaussianSplatsBounds(BoundsHandler):
    """The world box of the splats' 3-sigma ellipsoids (exact under any affine transform)."""

    __slots__ = ()
    target = GaussianSplats

    def exec(self, shape: GaussianSplats, engine: BoundsEngine) -> None:
        engine.include(ellipsoid_bounds(*_arrays(shape), engine.model_matrix(), SPLAT_SIGMA))


@default_for(PickEngine)
class GaussianSplatsIntersector(RayIntersector):
    """Every crossing of the ray with a splat's 3-sigma ellipsoid; ``Hit.splat`` is the splat's index."""

    __slots__ = ()
    target = GaussianSplats

    def exec(self, shape: Any, engine: PickEngine) -> None:
        o, d, _ = engine.local_ray()
        t, which, normals = ray_ellipsoids(o, d, *_arrays(shape), SPLAT_SIGMA)
        if len(t):
            engine.report(t, normals, which, shape)
