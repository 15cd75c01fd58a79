"""NURBS surfaces with optional trimming curves.

``NURBSSurface(control_points, weights=None, knots_u=None, knots_v=None, degree_u=3, degree_v=3, trim=())``:
``control_points`` is an ``(nu, nv, 3)`` grid (``nu > degree_u``, ``nv > degree_v``), ``weights``
``(nu, nv)`` positive numbers (None: 1, a polynomial surface), knot vectors clamped and non-decreasing
(None: clamped uniform).  ``trim`` is a list of closed loops in the normalised parameter square
``[0, 1]^2`` (the surface's (u, v), which are also its texture coordinates): each an ``(n, 2)``
polyline or a :class:`TrimCurve`; counter-clockwise loops keep their inside, clockwise loops cut
holes, and when all are clockwise the square's boundary is the outer loop.

Every engine reaches it through its simplifier (a trimmed triangle mesh at the Tessellation
level); the GL engine tessellates it on the GPU, POV-Ray writes untrimmed polynomial bicubic
patches natively.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core import RenderingComponent
from ..core.limits import check_array_magnitude
from ..geometry import nurbs
from . import _check
from .base import DeclaredShape, parameter

__all__ = ["NURBSSurface", "TrimCurve"]

_MAX_DEGREE = 7
#: The most points all trimming loops of a surface may have together (each is tested against every pixel).
MAX_TRIM_POINTS = 8192


def _numbers(owner: str, name: str, value: Any) -> np.ndarray:
    """``value`` as a float64 array of finite numbers of bounded magnitude, or a clear error."""
    try:
        a = np.asarray(value, np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{owner}: {name} must be numbers, got {value!r:.60}") from None
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{owner}: {name} must be finite numbers; fix or drop the NaN/infinite entries")
    return check_array_magnitude(owner, name, a)


def _knots(owner: str, name: str, value: Any, count: int, degree: int) -> np.ndarray:
    if value is None:
        return nurbs.clamped_uniform_knots(count, degree)
    knots = _numbers(owner, name, value).ravel()
    if knots.shape != (count + degree + 1,):
        raise ValueError(f"{owner}: {name} must be {count + degree + 1} finite numbers (control points + degree + 1), "
                         f"got {np.size(value)}")  # fmt: skip
    if np.any(np.diff(knots) < 0) or knots[-1] <= knots[0]:
        raise ValueError(f"{owner}: {name} must be non-decreasing and span a range, got {knots.tolist()}")
    if np.any(knots[: degree + 1] != knots[0]) or np.any(knots[-degree - 1 :] != knots[-1]):
        raise ValueError(f"{owner}: {name} must be clamped: the first and the last {degree + 1} knots equal")
    if np.any(np.unique(knots[1:-1], return_counts=True)[1] > degree):
        raise ValueError(f"{owner}: {name}: an inner knot repeats more than the degree ({degree}) times")
    return knots


class TrimCurve(RenderingComponent):
    """A closed trimming loop given as a NURBS curve in the parameter square (2D control points).

    ``TrimCurve(points, weights=None, knots=None, degree=2)``; :meth:`polyline` samples it (``segments``
    points) for the engines, which trim along the polyline.  A component (not a shape: it is only ever a
    value of :attr:`NURBSSurface.trim`) so that scene files store it by name like any other.
    """

    __slots__ = ("_points", "_weights", "_knots", "_degree")

    def __init__(self, points: Any, weights: Any = None, knots: Any = None, degree: int = 2) -> None:
        super().__init__()
        owner = "TrimCurve"
        pts = _numbers(owner, "points", points)
        degree = _check.integer(owner, "degree", degree, 1)
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) <= degree:
            raise ValueError(f"{owner}: points must be (n, 2) finite numbers with n > degree, got {pts.shape}")
        w = np.ones(len(pts)) if weights is None else _numbers(owner, "weights", weights).ravel()
        if w.shape != (len(pts),) or not np.all(w > 0):
            raise ValueError(f"{owner}: weights must be {len(pts)} positive numbers")
        k = _knots(owner, "knots", knots, len(pts), degree)
        for name, value in (("_points", pts), ("_weights", w), ("_knots", k), ("_degree", degree)):
            object.__setattr__(self, name, value)

    points = property(lambda self: self._points, doc="(n, 2) control points in the (u, v) square.")
    weights = property(lambda self: self._weights, doc="(n,) positive weights.")
    knots = property(lambda self: self._knots, doc="the clamped knot vector (n + degree + 1).")
    degree = property(lambda self: self._degree, doc="the curve's degree.")

    def parameters(self) -> dict[str, Any]:
        """Constructor keyword arguments that rebuild the curve."""
        return {"points": self._points, "weights": self._weights, "knots": self._knots, "degree": self._degree}

    def polyline(self, segments: int = 128) -> np.ndarray:
        """``segments`` points along the curve (the last one, equal to the first on a closed curve, dropped)."""
        t = np.linspace(self.knots[0], self.knots[-1], segments + 1)
        return nurbs.curve_points(self.points, self.weights, self.knots, self.degree, t)[:-1]

    def __repr__(self) -> str:
        return f"TrimCurve({len(self.points)} points, degree {self.degree})"


class NURBSSurface(DeclaredShape):
    """A (trimmed) NURBS surface; see the module docstring for the parameters."""

    __slots__ = ("_control_points", "_weights", "_knots_u", "_knots_v", "_degree_u", "_degree_v", "_trim")
    _params = ("control_points", "weights", "knots_u", "knots_v", "degree_u", "degree_v", "trim")
    control_points = parameter("control_points", "(nu, nv, 3) control points.")
    weights = parameter("weights", "(nu, nv) positive weights, or None (all 1).")
    knots_u = parameter("knots_u", "clamped knot vector along u (nu + degree_u + 1), or None (uniform).")
    knots_v = parameter("knots_v", "clamped knot vector along v, or None (uniform).")
    degree_u = parameter("degree_u", "degree along u (1..7).")
    degree_v = parameter("degree_v", "degree along v (1..7).")
    trim = parameter("trim", "closed loops in the (u, v) square: (n, 2) polylines or TrimCurves.")

    def __init__(
        self,
        control_points: Any,
        weights: Any = None,
        knots_u: Any = None,
        knots_v: Any = None,
        degree_u: int = 3,
        degree_v: int = 3,
        trim: Sequence[Any] = (),
    ) -> None:
        super().__init__(control_points=control_points, weights=weights, knots_u=knots_u, knots_v=knots_v,
                         degree_u=degree_u, degree_v=degree_v, trim=trim)  # fmt: skip

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        owner = "NURBSSurface"
        cp = _numbers(owner, "control_points", p["control_points"])
        if cp.ndim != 3 or cp.shape[2] != 3:
            raise ValueError(f"{owner}: control_points must be an (nu, nv, 3) grid of finite numbers, got {cp.shape}")
        du = _check.integer(owner, "degree_u", p["degree_u"], 1)
        dv = _check.integer(owner, "degree_v", p["degree_v"], 1)
        if du > _MAX_DEGREE or dv > _MAX_DEGREE:
            raise ValueError(f"{owner}: degrees above {_MAX_DEGREE} are not supported, got ({du}, {dv})")
        nu, nv = cp.shape[:2]
        if nu <= du or nv <= dv:
            raise ValueError(f"{owner}: a degree ({du}, {dv}) surface needs more than ({du}, {dv}) control points "
                             f"per direction, got {nu} x {nv}")  # fmt: skip
        if p["weights"] is None:
            w = np.ones((nu, nv))
        else:
            w = _numbers(owner, "weights", p["weights"])
            if w.shape != (nu, nv) or not np.all(w > 0):
                raise ValueError(f"{owner}: weights must be ({nu}, {nv}) positive numbers, got shape {w.shape}")
        ku = _knots(owner, "knots_u", p["knots_u"], nu, du)
        kv = _knots(owner, "knots_v", p["knots_v"], nv, dv)
        loops = []
        for i, loop in enumerate(p["trim"] or ()):
            if isinstance(loop, TrimCurve):
                line = loop.polyline()
            else:
                line = _numbers(owner, f"trim loop {i}", loop)
                if line.ndim != 2 or line.shape[1] != 2 or len(line) < 3:
                    raise ValueError(f"{owner}: trim loop {i} must be an (n, 2) polyline (n >= 3) or a TrimCurve")
                if np.allclose(line[0], line[-1]):
                    line = line[:-1]
            loops.append(line)
        edges = sum(len(loop) for loop in loops)
        if edges > MAX_TRIM_POINTS:
            raise ValueError(f"{owner}: the trimming loops have {edges} points in all, more than {MAX_TRIM_POINTS}; "
                             "sample them more coarsely")  # fmt: skip
        p["trim"] = tuple(p["trim"] or ())
        for value in (cp, w, ku, kv):
            value.setflags(write=False)
        derived = {"points": cp, "w": w, "ku": ku, "kv": kv, "loops": loops}
        return {**p, "degree_u": du, "degree_v": dv}, derived

    # -- what engines read -----------------------------------------------------------------------
    def point_array(self) -> np.ndarray:
        """(nu, nv, 3) control points."""
        return self._cached("points")

    def weight_array(self) -> np.ndarray:
        """(nu, nv) weights."""
        return self._cached("w")

    def knot_vectors(self) -> tuple[np.ndarray, np.ndarray]:
        """(knots along u, knots along v)."""
        return self._cached("ku"), self._cached("kv")

    @property
    def degrees(self) -> tuple[int, int]:
        return int(self._degree_u), int(self._degree_v)

    def trim_loops(self) -> list[np.ndarray]:
        """The trimming loops as (n, 2) polylines in the normalised parameter square."""
        return self._cached("loops")

    @property
    def rational(self) -> bool:
        """Whether the weights differ (a rational surface); with equal weights it is a polynomial one."""
        w = self.weight_array()
        return bool(np.ptp(w) > 1e-12 * np.abs(w).max())

    def evaluate(self, u: Any, v: Any) -> np.ndarray:
        """Surface points at normalised parameters ``(u, v)`` in [0, 1]."""
        ku, kv = self.knot_vectors()
        u = ku[0] + np.asarray(u, np.float64) * (ku[-1] - ku[0])
        v = kv[0] + np.asarray(v, np.float64) * (kv[-1] - kv[0])
        return nurbs.surface_points(self.point_array(), self.weight_array(), (ku, kv), self.degrees, u, v)

    def bezier_patches(self) -> tuple[np.ndarray, np.ndarray]:
        """Rational Bézier patches (k, p + 1, q + 1, 4) and their domains (k, 4) in the normalised square."""

        def compute() -> tuple[np.ndarray, np.ndarray]:
            ku, kv = self.knot_vectors()
            patches, domains = nurbs.bezier_patches(self.point_array(), self.weight_array(), (ku, kv), self.degrees)
            domains[:, :2] = (domains[:, :2] - ku[0]) / (ku[-1] - ku[0])
            domains[:, 2:] = (domains[:, 2:] - kv[0]) / (kv[-1] - kv[0])
            return patches, domains

        return self._cached("bezier", compute)

    def tessellate(self, segments: tuple[int, int]) -> dict[str, Any]:
        """A trimmed triangle mesh with ``segments`` grid cells along u and v (see ``geometry.nurbs``)."""
        return nurbs.tessellate_surface(self.point_array(), self.weight_array(), self.knot_vectors(), self.degrees,
                                        segments, self.trim_loops())  # fmt: skip

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Local (min, max): the control points' box, which holds the surface (convex hull property)."""
        cp = self.point_array().reshape(-1, 3)
        return cp.min(axis=0), cp.max(axis=0)
