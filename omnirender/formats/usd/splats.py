"""``om.GaussianSplats`` in OpenUSD: the ``ParticleField3DGaussianSplat`` prim of ``UsdVol`` (written and read).

The schema (OpenUSD 26.03+, in the ``usd-core`` wheel) applies the particle
field's attribute schemas:

================================================  =========================================================
``positions`` (point3f[])                          centres in the prim's space (its transform applies)
``orientations`` (quatf[])                         unit quaternions; Gf stores (real, i, j, k) = (w, x, y, z)
``scales`` (float3[])                              linear standard deviations (not log, unlike PLY files)
``opacities`` (float[])                            opacities in [0, 1] (not logits)
``radiance:sphericalHarmonicsDegree`` (int)        0..3
``radiance:sphericalHarmonicsCoefficients``        (degree+1)^2 float3 per particle, particle by particle,
                                                   in the trainer's coefficient order (``sh[:, k]``)
================================================  =========================================================

The ``*h`` half-precision variants are read when the float ones are absent.
USD gives no colour space for the coefficients; omnirender reads and writes
them as the reference trainer trains them (display-referred sRGB, the 0.5
bias of the DC term applied at evaluation), the convention of
``KHR_gaussian_splatting``'s ``srgb_rec709_display``.  The writer also sets
``extent`` (the 3-sigma ellipsoids' box) and ``primvars:displayColor`` (the
linear DC colour per particle, for viewers that show a particle field as
points).  As the schema says, an attribute shorter than ``positions`` is
ignored (its default applies: no rotation, unit scale, opaque, grey); longer
ones are truncated.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...core import ShapePainter, default_for
from ...shapes import GaussianSplats
from .writer import USDEngine

__all__ = ["GaussianSplatsWriter", "read_splats", "TYPE_NAME"]

TYPE_NAME = "ParticleField3DGaussianSplat"
_C0 = 0.28209479177387814


@default_for(USDEngine)
class GaussianSplatsWriter(ShapePainter):
    """``GaussianSplats`` -> a ``ParticleField3DGaussianSplat`` prim (see the module docs)."""

    __slots__ = ()
    service = USDEngine.service
    target = GaussianSplats

    def exec(self, shape: GaussianSplats, engine: USDEngine) -> None:
        from pxr import UsdVol, Vt

        from ...geometry.ellipsoids import ellipsoid_bounds
        from ..colors import srgb_to_linear

        field = engine.gprim(UsdVol.ParticleField3DGaussianSplat, "GaussianSplats")
        if field is None:
            return
        n = shape.count
        p = np.ascontiguousarray(shape.positions, np.float32).reshape(n, 3)
        q = np.ascontiguousarray(shape.rotations, np.float32).reshape(n, 4)
        s = np.ascontiguousarray(shape.scales, np.float32).reshape(n, 3)
        o = np.ascontiguousarray(shape.opacities, np.float32).reshape(n)
        sh = np.ascontiguousarray(shape.sh, np.float32)
        field.CreatePositionsAttr(Vt.Vec3fArray.FromNumpy(p))
        field.CreateOrientationsAttr(Vt.QuatfArray.FromNumpy(np.ascontiguousarray(q[:, [1, 2, 3, 0]])))
        field.CreateScalesAttr(Vt.Vec3fArray.FromNumpy(s))
        field.CreateOpacitiesAttr(Vt.FloatArray.FromNumpy(o))
        field.CreateRadianceSphericalHarmonicsDegreeAttr(int(shape.sh_degree))
        field.CreateRadianceSphericalHarmonicsCoefficientsAttr(
            Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(sh.reshape(-1, 3)))
        )
        if n:
            lo, hi = ellipsoid_bounds(p, shape.rotation_matrices(), s, None, 3.0)
            field.CreateExtentAttr(Vt.Vec3fArray([tuple(map(float, lo)), tuple(map(float, hi))]))
        dc = np.clip(0.5 + _C0 * sh[:, 0, :].astype(np.float64), 0.0, 1.0)
        field.CreateDisplayColorPrimvar("vertex").Set(
            Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(srgb_to_linear(dc), np.float32))
        )


def _array(prim: Any, name: str, time: Any, width: int) -> np.ndarray | None:
    """The float attribute ``name`` (or its half twin ``name + 'h'``) as an (M, width) float64 array, or None."""
    for attr_name in (name, name + "h"):
        attr = prim.GetAttribute(attr_name)
        if attr and attr.HasAuthoredValue():
            value = attr.Get(time)
            if value is None:
                continue
            a = np.asarray(value, np.float64)
            return a.reshape(-1, width) if width > 1 else a.reshape(-1, 1)
    return None


def read_splats(prim: Any, time: Any, warn: Any) -> GaussianSplats | None:
    """The ``om.GaussianSplats`` of a ``ParticleField3DGaussianSplat`` prim (None when it has no positions)."""
    from .reader import _quaternions

    where = str(prim.GetPath())
    positions = _array(prim, "positions", time, 3)
    if positions is None or not len(positions):
        return None
    n = len(positions)

    def per_particle(name: str, width: int, default: np.ndarray) -> np.ndarray:
        a = _array(prim, name, time, width)
        if a is None:
            return np.repeat(default[None, :], n, axis=0)
        if len(a) < n:
            warn(f"{where}: {name} holds {len(a)} values for {n} particles; ignored (the schema's default applies)")
            return np.repeat(default[None, :], n, axis=0)
        return a[:n]

    attr = prim.GetAttribute("orientations") or prim.GetAttribute("orientationsh")
    if attr and attr.HasAuthoredValue() and len(attr.Get(time) or []) >= n:
        q = _quaternions(attr.Get(time))[:n]
    else:
        if attr and attr.HasAuthoredValue():
            warn(f"{where}: orientations holds fewer values than positions; ignored (no rotation)")
        q = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    length = np.linalg.norm(q, axis=1)
    if not (length > 1e-12).all():
        raise ValueError(f"load_usd: {where}: orientation {int(np.argmin(length > 1e-12))} is the zero quaternion")
    q = q / length[:, None]
    scales = per_particle("scales", 3, np.ones(3))
    opacities = per_particle("opacities", 1, np.ones(1)).reshape(n)
    degree_attr = prim.GetAttribute("radiance:sphericalHarmonicsDegree")
    degree = int(degree_attr.Get(time)) if degree_attr and degree_attr.Get(time) is not None else 3
    if not 0 <= degree <= 3:
        raise ValueError(f"load_usd: {where}: radiance:sphericalHarmonicsDegree is {degree}; omnirender reads 0..3")
    k = (degree + 1) ** 2
    coefficients = _array(prim, "radiance:sphericalHarmonicsCoefficients", time, 3)
    if coefficients is None or len(coefficients) < n * k:
        if coefficients is not None:
            warn(
                f"{where}: radiance:sphericalHarmonicsCoefficients holds {len(coefficients)} values, "
                f"{n * k} needed for degree {degree}; ignored (grey, as the schema says)"
            )
        sh = np.zeros((n, 1, 3))
    else:
        sh = coefficients[: n * k].reshape(n, k, 3)
    try:
        return GaussianSplats(
            positions.astype(np.float32),
            q.astype(np.float32),
            scales.astype(np.float32),
            opacities.astype(np.float32),
            sh.astype(np.float32),
        )
    except ValueError as exc:
        raise ValueError(f"load_usd: {where}: {exc}") from None
