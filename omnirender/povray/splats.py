"""``om.GaussianSplats`` in POV-Ray: nested translucent ellipsoid shells, an approximation.

POV-Ray has no Gaussian primitive.  Each splat becomes :data:`LAYERS`
concentric ellipsoids (``sphere`` under the splat's matrix) at the Mahalanobis
radii of :func:`~omnirender.geometry.splat_shells.shell_layers`, self-lit
(``emission 1``, no diffuse, no ambient, ``no_shadow``) in the splat's colour
for the camera's eye (its spherical harmonics evaluated once per splat, as
the rasteriser does) and with ``transmit`` set so that the shells crossed
(entry and exit) let through what the Gaussian lets through: POV-Ray blends
the layers exactly in depth order.  The alpha profile is a staircase of
``LAYERS`` steps; the error against the splat rasteriser is measured in
``tests/splats`` and docs/NOTES.md.  ``max_trace_level`` is raised to 256 so
that rays pass many shells.
"""

from __future__ import annotations

import numpy as np

from ..core import ShapePainter, default_for
from ..geometry.splat_shells import local_eye, shell_layers, splat_matrices
from ..shapes import GaussianSplats
from . import sdl
from .appearance import srgb_to_linear
from .engine import POVRayEngine

__all__ = ["GaussianSplatsPainter", "LAYERS"]

#: Shells per splat.
LAYERS = 6
#: Trace depth the scene needs (each shell is crossed twice).
TRACE_LEVEL = 256


@default_for(POVRayEngine)
class GaussianSplatsPainter(ShapePainter):
    """``GaussianSplats`` -> ``LAYERS`` translucent self-lit ellipsoids per splat (see the module docs)."""

    __slots__ = ()
    service = "pov.paint"
    target = GaussianSplats

    def exec(self, shape: GaussianSplats, engine: POVRayEngine) -> None:
        n = shape.count
        if n == 0:
            return
        model = engine.model_matrix()
        colors = srgb_to_linear(np.maximum(shape.colors(local_eye(engine.view_matrix(), model)), 0.0))
        radii, alphas = shell_layers(shape.opacities, LAYERS, crossings=2)
        keep = np.asarray(shape.opacities, np.float64).reshape(n) > 1.0 / 512.0
        if "max_trace_level" not in "".join(o for o in engine.objects if isinstance(o, str)):
            engine.objects.append(f"global_settings {{ max_trace_level {TRACE_LEVEL} }}\n")
        for layer, radius in enumerate(radii):
            matrices = model @ splat_matrices(shape.positions, shape.rotation_matrices(), shape.scales, radius)
            for i in np.nonzero(keep)[0]:
                rgb = colors[i]
                texture = (
                    f"pigment {{ {sdl.color(rgb, transmit=1.0 - float(alphas[i, layer]))} }} "
                    "finish { emission 1 diffuse 0 ambient 0 specular 0 phong 0 }"
                )
                engine.emit("sphere { 0, 1 no_shadow }", texture, matrix=matrices[i])
