"""``om.GaussianSplats`` in Radiance: refused, with the engines that render them.

Radiance has no primitive whose opacity falls off inside the object: its
translucent materials (``trans``, ``glass``, ``mixfunc`` with ``void``) are
surfaces, it has no ellipsoid (``xform`` scales uniformly only, so each of a
splat's shells would be a tessellated mesh of its own), and its irradiance
caching is built for lit surfaces, not the self-lit, view-dependent colours
of a splat cloud.  Rather than an approximation whose error we cannot bound,
the Radiance engine refuses splats with an error naming the node, the engines
that draw them (``"gl"``: the reference rasteriser's method; ``"mitsuba"`` and
``"povray"``: nested translucent ellipsoid shells) and how to keep them out of
a Radiance render (a group mask).
"""

from __future__ import annotations

from typing import Any

from ..core import ShapePainter, default_for
from ..shapes import GaussianSplats
from . import rad
from .engine import RadianceEngine

__all__ = ["GaussianSplatsRefusal"]


@default_for(RadianceEngine)
class GaussianSplatsRefusal(ShapePainter):
    """Raise :class:`~omnirender.radiance.rad.RadError` (a ValueError) for splats (see the module docs)."""

    __slots__ = ()
    service = RadianceEngine.service
    target = GaussianSplats

    def exec(self, shape: Any, engine: RadianceEngine) -> None:
        raise rad.RadError(
            f"{engine.owner()}: om.GaussianSplats cannot be rendered by Radiance (it has no translucent volumetric "
            "primitive and no ellipsoid; see omnirender.radiance.splats); render the scene with engine='gl' (the "
            "splat rasteriser), 'mitsuba' or 'povray' (translucent ellipsoid shells), or keep the splats out of the "
            "Radiance render with a group mask (put them in a node with groups={'splats'} and render with "
            "mask='!splats')"
        )
