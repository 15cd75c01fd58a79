"""Regular-grid shapes: heightfields (terrain) and volumes (3D scalar fields).

Placement conventions (local coordinates, +y up):

* ``Heightfield(heights (R, C), spacing=(dx, dz))``: sample ``heights[i, j]`` sits at
  ``x = (j - (C - 1) / 2) * dx``, ``y = heights[i, j]``, ``z = (i - (R - 1) / 2) * dz``:
  columns run along +x, rows along +z, the grid is centred on the y axis and its
  surface faces +y.
* ``Volume(data (D, H, W) indexed [z, y, x], spacing=(sx, sy, sz))``: voxel
  ``data[k, j, i]`` sits at ``((i - (W - 1) / 2) * sx, (j - (H - 1) / 2) * sy, (k - (D - 1) / 2) * sz)``:
  the volume is centred at the origin and spans ``bounds()`` = +-((W-1) sx, (H-1) sy, (D-1) sz) / 2.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from ..data import as_array
from . import _check
from .base import DeclaredShape, parameter

__all__ = ["Heightfield", "Volume", "TransferFunction"]


class Heightfield(DeclaredShape):
    """A terrain grid of ``heights`` (R, C), R and C >= 2, sample spacing ``(dx, dz)`` (> 0; one number for both).

    See the module docstring for the placement.  Simplifies to a TriangleSet
    (two triangles per cell, normals from the surface, texcoords (u, v) in [0, 1]
    along x and z).
    """

    __slots__ = ("_heights", "_spacing")
    _params = ("heights", "spacing")
    heights = parameter("heights", "(R, C) heights, R, C >= 2.")
    spacing = parameter("spacing", "(dx, dz) sample spacing, > 0.")

    def __init__(self, heights: Any, spacing: float | Sequence[float] = (1.0, 1.0)) -> None:
        super().__init__(heights=heights, spacing=spacing)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        name = "Heightfield"
        h = as_array(p["heights"], None, name=f"{name}: heights")
        if h.dtype.kind not in "biuf":
            raise ValueError(f"{name}: heights must be numbers, got dtype {h.dtype}")
        if h.ndim != 2 or h.shape[0] < 2 or h.shape[1] < 2:
            raise ValueError(f"{name}: heights must be a 2D grid of at least 2 x 2 samples, got shape {h.shape}")
        h = np.array(h, dtype=np.float32)
        if not np.all(np.isfinite(h)):
            raise ValueError(f"{name}: heights must be finite")
        h.setflags(write=False)
        p["spacing"] = _check.vector(name, "spacing", p["spacing"], 2, positive=True)
        return p, {"heights": h}

    def height_array(self) -> np.ndarray:
        """(R, C) float32 heights, read-only."""
        return self._cached("heights")

    @property
    def grid_shape(self) -> tuple[int, int]:
        """(rows, columns)."""
        return self.height_array().shape

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Local (min, max) corners."""
        h = self.height_array()
        rows, cols = h.shape
        dx, dz = self._spacing
        hx, hz = (cols - 1) * dx / 2.0, (rows - 1) * dz / 2.0
        return np.array([-hx, float(h.min()), -hz]), np.array([hx, float(h.max()), hz])


class TransferFunction:
    """Maps scalar values to RGBA: control points ``(value, (r, g, b, a))``, linearly interpolated.

    Values below the first point take its colour, above the last the last one's.
    Data only (a list of points), so scene files store it as plain numbers.
    """

    __slots__ = ("_values", "_colors")

    def __init__(self, points: Iterable[tuple[float, Sequence[float]]]) -> None:
        pts = list(points) if not isinstance(points, TransferFunction) else points.points
        if not pts:
            raise ValueError("TransferFunction: needs at least one control point (value, (r, g, b, a))")
        values, colors = [], []
        for k, item in enumerate(pts):
            try:
                value, color = item
            except (TypeError, ValueError):
                raise ValueError(
                    f"TransferFunction: control point {k} must be (value, (r, g, b, a)), got {item!r}"
                ) from None
            values.append(_check.scalar("TransferFunction", f"value of point {k}", value))
            c = _check.vector("TransferFunction", f"colour of point {k}", color, len(np.ravel(color)))
            if len(c) == 3:
                c = (*c, 1.0)
            if len(c) != 4:
                raise ValueError(f"TransferFunction: colour of point {k} must be RGB or RGBA, got {color!r}")
            colors.append(c)
        order = np.argsort(values, kind="stable")
        v = np.array(values, dtype=np.float64)[order]
        c = np.array(colors, dtype=np.float64)[order]
        v.setflags(write=False)
        c.setflags(write=False)
        self._values = v
        self._colors = c

    @classmethod
    def ramp(cls, low: float, high: float, color: Sequence[float] = (1.0, 1.0, 1.0)) -> TransferFunction:
        """``color`` with alpha rising linearly from 0 at ``low`` to 1 at ``high``."""
        r, g, b = color[:3]
        if high <= low:
            high = low + 1.0
        return cls([(low, (r, g, b, 0.0)), (high, (r, g, b, 1.0))])

    @property
    def points(self) -> list[tuple[float, tuple[float, float, float, float]]]:
        """The control points as plain data."""
        return [(float(v), tuple(float(x) for x in c)) for v, c in zip(self._values, self._colors, strict=True)]

    @property
    def range(self) -> tuple[float, float]:
        """(first, last) control value."""
        return float(self._values[0]), float(self._values[-1])

    def lookup(self, values: Any) -> np.ndarray:
        """RGBA float32 of shape ``values.shape + (4,)``."""
        x = np.asarray(values, dtype=np.float64)
        out = np.empty(x.shape + (4,), dtype=np.float32)
        for ch in range(4):
            out[..., ch] = np.interp(x, self._values, self._colors[:, ch])
        return out

    def table(self, n: int = 256) -> np.ndarray:
        """(n, 4) float32 RGBA sampled evenly from the first to the last control value (a 1D texture)."""
        n = _check.integer("TransferFunction", "n", n, minimum=2)
        lo, hi = self.range
        return self.lookup(np.linspace(lo, hi, n))

    def iso_level(self) -> float:
        """A sensible isosurface level: the lowest value where alpha reaches half its maximum."""
        alpha = self._colors[:, 3]
        peak = float(alpha.max())
        if peak <= 0.0:
            return float(self._values.mean())
        half = 0.5 * peak
        k = int(np.argmax(alpha >= half))
        if k == 0:
            return float(self._values[0])
        a0, a1 = alpha[k - 1], alpha[k]
        v0, v1 = self._values[k - 1], self._values[k]
        t = 0.0 if a1 == a0 else (half - a0) / (a1 - a0)
        return float(v0 + t * (v1 - v0))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TransferFunction):
            return NotImplemented
        return np.array_equal(self._values, other._values) and np.array_equal(self._colors, other._colors)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"TransferFunction({self.points!r})"


class Volume(DeclaredShape):
    """A 3D scalar grid ``data`` (D, H, W) indexed ``[z, y, x]``, each dimension >= 2.

    ``spacing`` = (sx, sy, sz) voxel spacing along x, y, z (> 0; one number for
    all); see the module docstring for the placement (centred at the origin).
    ``transfer_function`` maps values to RGBA: a :class:`TransferFunction` or its
    control points ``[(value, (r, g, b, a)), ...]``; None means a white ramp from
    the data minimum (transparent) to the maximum (opaque).  ``iso`` is the level
    of the isosurface that engines without volume rendering show (via the
    marching-cubes simplifier); None means the transfer function's
    ``iso_level()``.  ``parameters()`` returns the transfer function as its
    control points (plain data).
    """

    __slots__ = ("_data", "_spacing", "_transfer_function", "_iso")
    _params = ("data", "spacing", "transfer_function", "iso")
    data = parameter("data", "(D, H, W) scalar grid indexed [z, y, x].")
    spacing = parameter("spacing", "(sx, sy, sz) voxel spacing, > 0.")
    transfer_function = parameter("transfer_function", "TransferFunction mapping values to RGBA.")
    iso = parameter("iso", "Isosurface level or None for the transfer function's.")

    def __init__(
        self,
        data: Any,
        spacing: float | Sequence[float] = (1.0, 1.0, 1.0),
        transfer_function: TransferFunction | Iterable[tuple[float, Sequence[float]]] | None = None,
        iso: float | None = None,
    ) -> None:
        super().__init__(data=data, spacing=spacing, transfer_function=transfer_function, iso=iso)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        name = "Volume"
        d = self._reuse("data", p["data"], "data", _volume_data)
        p["spacing"] = _check.vector(name, "spacing", p["spacing"], 3, positive=True)
        tf = p["transfer_function"]
        if tf is None:
            tf = TransferFunction.ramp(float(d.min()), float(d.max()))
        elif not isinstance(tf, TransferFunction):
            tf = TransferFunction(tf)
        p["transfer_function"] = tf
        if p["iso"] is not None:
            p["iso"] = _check.scalar(name, "iso", p["iso"])
        return p, {"data": d}

    def data_array(self) -> np.ndarray:
        """(D, H, W) float32 data, read-only."""
        return self._cached("data")

    def parameters(self) -> dict[str, Any]:
        params = super().parameters()
        params["transfer_function"] = self._transfer_function.points
        return params

    def iso_level(self) -> float:
        """The isosurface level in use: ``iso`` or the transfer function's default."""
        return self._iso if self._iso is not None else self._transfer_function.iso_level()

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Local (min, max) corners of the box the voxel centres span."""
        d, h, w = self.data_array().shape
        half = np.array([(w - 1), (h - 1), (d - 1)], dtype=np.float64) * np.array(self._spacing) / 2.0
        return -half, half


def _volume_data(value: Any) -> np.ndarray:
    name = "Volume"
    d = as_array(value, None, name=f"{name}: data")
    if d.dtype.kind not in "biuf":
        raise ValueError(f"{name}: data must be numbers, got dtype {d.dtype}")
    if d.ndim != 3 or min(d.shape) < 2:
        raise ValueError(f"{name}: data must be a 3D grid (D, H, W) with every size >= 2, got shape {d.shape}")
    d = np.array(d, dtype=np.float32)
    if not np.all(np.isfinite(d)):
        raise ValueError(f"{name}: data must be finite")
    d.setflags(write=False)
    return d
