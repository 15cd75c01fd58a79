"""``GaussianSplats``: a 3D Gaussian splatting scene (Kerbl et al. 2023) as one shape.

Each splat ``i`` is an anisotropic 3D Gaussian: centre ``positions[i]``,
covariance ``Sigma = R S S^T R^T`` from the unit quaternion ``rotations[i]``
(``(w, x, y, z)``, the reference trainer's ``rot_0..3`` order) and the standard
deviations ``scales[i]`` along its rotated axes, a peak opacity
``opacities[i]`` in [0, 1] and a view-dependent colour given by spherical
harmonics ``sh[i]`` ``(K, 3)``, K = (sh_degree+1)^2 (see :mod:`._sh`, the one
implementation of the colour rule).

Like ``om.InstanceSet`` the shape holds the application's arrays *by
reference*: write them in place and call ``splats.touch()``; assign one array
(same length) through its property, or several at once (any new length) with
:meth:`GaussianSplats.update`.  The arrays are checked when the shape is made,
on assignment and when an engine reads them (:meth:`GaussianSplats.checked`,
cached per version): shapes, finite values, scales > 0, opacities in [0, 1],
quaternions of unit length within 1e-3.  Errors name the first bad row.

Values are the trainer's *linear* parameters (scales, not log-scales;
opacities, not logits); file readers convert.  Picking reports the splat's
index as ``Hit.primitive`` (also readable as ``Hit.splat``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ..core.component import Shape
from . import _sh

__all__ = ["GaussianSplats", "SplatArrays", "quaternion_matrices", "SH_C0", "SH_C1", "SH_C2", "SH_C3"]

#: The colour rule's SH constants (``_sh.C0`` ... ``_sh.C3``), public for engines that write them into shaders.
SH_C0, SH_C1, SH_C2, SH_C3 = _sh.C0, _sh.C1, _sh.C2, _sh.C3

#: How far from 1 a quaternion's length may be (the trainer stores unnormalised ones: readers normalise).
QUATERNION_TOLERANCE = 1e-3

_NAMES = ("positions", "rotations", "scales", "opacities", "sh")


class SplatArrays(NamedTuple):
    """The checked arrays of a ``GaussianSplats`` (float64 views or copies of the application's arrays)."""

    positions: np.ndarray  # (N, 3)
    rotations: np.ndarray  # (N, 4) unit quaternions (w, x, y, z)
    scales: np.ndarray  # (N, 3) > 0
    opacities: np.ndarray  # (N,) in [0, 1]
    sh: np.ndarray  # (N, K, 3)
    sh_degree: int


def _array(value: Any) -> Any:
    """The array behind ``value``: numpy arrays as they are (no copy), ``om.data`` sequences through ``.array()``."""
    if hasattr(value, "array") and not isinstance(value, np.ndarray):
        return value.array()
    return value


def quaternion_matrices(q: np.ndarray) -> np.ndarray:
    """``(N, 3, 3)`` rotation matrices of unit quaternions ``q`` ``(N, 4)`` in (w, x, y, z) order."""
    q = np.asarray(q, dtype=np.float64).reshape(-1, 4)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    r = np.empty((len(q), 3, 3))
    r[:, 0, 0] = 1 - 2 * (y * y + z * z)
    r[:, 0, 1] = 2 * (x * y - w * z)
    r[:, 0, 2] = 2 * (x * z + w * y)
    r[:, 1, 0] = 2 * (x * y + w * z)
    r[:, 1, 1] = 1 - 2 * (x * x + z * z)
    r[:, 1, 2] = 2 * (y * z - w * x)
    r[:, 2, 0] = 2 * (x * z - w * y)
    r[:, 2, 1] = 2 * (y * z + w * x)
    r[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return r


class GaussianSplats(Shape):
    """N anisotropic 3D Gaussians with opacities and spherical-harmonics colours (3D Gaussian splatting).

    ``positions`` ``(N, 3)`` centres in the shape's local space; ``rotations``
    ``(N, 4)`` unit quaternions (w, x, y, z); ``scales`` ``(N, 3)`` standard
    deviations (> 0, linear); ``opacities`` ``(N,)`` in [0, 1]; ``sh``
    ``(N, K, 3)`` spherical-harmonics coefficients per colour channel
    (coefficient 0 is the DC term), K = (sh_degree+1)^2; ``sh_degree`` 0..3,
    inferred from K when None.  The arrays are held by reference (no copy).

    The colour of a splat seen from ``eye`` is ``max(0.5 + SH(dir) . sh, 0)``
    (:func:`omnirender.shapes._sh.sh_colors`), a display (sRGB-encoded)
    colour as the trainer fitted it.
    """

    #: No default simplifier on purpose (a mesh cannot stand for semi-transparent Gaussians): engines
    #: without a splat painter refuse the shape with this hint in their ``NoHandlerError``.
    no_handler_hint = (
        "om.GaussianSplats has no mesh simplification: it needs an engine with a splat painter; "
        "docs/DESIGN.md, 'Gaussian splats', lists the engines that draw it"
    )

    __slots__ = ("_positions", "_rotations", "_scales", "_opacities", "_sh", "_sh_degree", "_checked")
    _transient = {"_checked": lambda: None}

    def __init__(
        self,
        positions: Any,
        rotations: Any,
        scales: Any,
        opacities: Any,
        sh: Any,
        sh_degree: int | None = None,
    ) -> None:
        super().__init__()
        for name, value in zip(_NAMES, (positions, rotations, scales, opacities, sh), strict=True):
            object.__setattr__(self, "_" + name, value)
        object.__setattr__(self, "_sh_degree", _degree_argument(sh_degree))
        object.__setattr__(self, "_checked", None)
        self.checked()

    # -- parameters -------------------------------------------------------------------
    @property
    def positions(self) -> Any:
        """The ``(N, 3)`` centres (the application's own array)."""
        return self._positions

    @positions.setter
    def positions(self, value: Any) -> None:
        self._assign(positions=value)

    @property
    def rotations(self) -> Any:
        """The ``(N, 4)`` unit quaternions (w, x, y, z)."""
        return self._rotations

    @rotations.setter
    def rotations(self, value: Any) -> None:
        self._assign(rotations=value)

    @property
    def scales(self) -> Any:
        """The ``(N, 3)`` standard deviations along the rotated axes (linear, > 0)."""
        return self._scales

    @scales.setter
    def scales(self, value: Any) -> None:
        self._assign(scales=value)

    @property
    def opacities(self) -> Any:
        """The ``(N,)`` peak opacities in [0, 1]."""
        return self._opacities

    @opacities.setter
    def opacities(self, value: Any) -> None:
        self._assign(opacities=value)

    @property
    def sh(self) -> Any:
        """The ``(N, K, 3)`` spherical-harmonics coefficients."""
        return self._sh

    @sh.setter
    def sh(self, value: Any) -> None:
        self._assign(sh=value)

    @property
    def sh_degree(self) -> int:
        """The SH degree used (0..3): the one given, else the one the coefficient count implies."""
        return self.checked().sh_degree

    @sh_degree.setter
    def sh_degree(self, value: int | None) -> None:
        self._assign(sh_degree=_degree_argument(value))

    def update(self, **arrays: Any) -> None:
        """Replace several arrays at once (e.g. all five with a new length), checked together, one change."""
        unknown = sorted(set(arrays) - set(_NAMES) - {"sh_degree"})
        if unknown:
            raise TypeError(f"GaussianSplats.update: unknown parameter(s) {unknown}; use {list(_NAMES)} or sh_degree")
        if "sh_degree" in arrays:
            arrays["sh_degree"] = _degree_argument(arrays["sh_degree"])
        self._assign(**arrays)

    def _assign(self, **arrays: Any) -> None:
        old = {name: object.__getattribute__(self, "_" + name) for name in arrays}
        for name, value in arrays.items():
            object.__setattr__(self, "_" + name, value)
        object.__setattr__(self, "_checked", None)
        try:
            self.checked()
        except ValueError as exc:
            for name, value in old.items():
                object.__setattr__(self, "_" + name, value)
            object.__setattr__(self, "_checked", None)
            if len(arrays) == 1 and "length" in str(exc):
                raise ValueError(f"{exc}; to change the number of splats, assign all arrays with update()") from None
            raise
        self.touch()

    def parameters(self) -> dict[str, Any]:
        return {
            "positions": self._positions,
            "rotations": self._rotations,
            "scales": self._scales,
            "opacities": self._opacities,
            "sh": self._sh,
            "sh_degree": self._sh_degree,
        }

    @property
    def count(self) -> int:
        """The number of splats N."""
        return len(self.checked().positions)

    def __len__(self) -> int:
        return self.count

    def touch(self) -> None:
        """Mark the splats as changed (after writing their arrays in place): engines re-read and re-check them."""
        object.__setattr__(self, "_checked", None)
        super().touch()

    # -- the arrays, checked ------------------------------------------------------------
    def checked(self) -> SplatArrays:
        """The arrays as float64 (views where they already are), checked; cached until the next change.

        Raises ValueError naming the array and its first bad row.
        """
        found = self._checked
        if found is not None and found[0] == self._version:
            return found[1]
        arrays = _check(*(_array(object.__getattribute__(self, "_" + n)) for n in _NAMES), self._sh_degree)
        object.__setattr__(self, "_checked", (self._version, arrays))
        return arrays

    def validate(self) -> None:
        """Check the arrays now (ValueError naming the first bad row); engines call it through :meth:`checked`."""
        object.__setattr__(self, "_checked", None)
        self.checked()

    def rotation_matrices(self) -> np.ndarray:
        """``(N, 3, 3)`` rotation matrices of the splats' quaternions."""
        return quaternion_matrices(self.checked().rotations)

    def covariances(self) -> np.ndarray:
        """``(N, 3, 3)`` covariance matrices ``Sigma = R S S^T R^T`` in the shape's local space."""
        a = self.checked()
        m = self.rotation_matrices() * a.scales[:, None, :]  # R S
        return m @ np.transpose(m, (0, 2, 1))

    def colors(self, eye: Any) -> np.ndarray:
        """``(N, 3)`` display colours seen from ``eye`` (a point in the shape's local space), by :mod:`._sh`."""
        a = self.checked()
        return _sh.sh_colors(a.positions, a.sh, np.asarray(eye, dtype=np.float64), a.sh_degree)

    def bounds(self, sigma: float = 3.0) -> tuple[np.ndarray, np.ndarray] | None:
        """Axis-aligned ``(lo, hi)`` box of the ``sigma``-sigma ellipsoids in local space; None with no splats.

        The half extent of an ellipsoid along axis j is ``sigma * sqrt(Sigma_jj)``.
        """
        a = self.checked()
        if not len(a.positions):
            return None
        m = self.rotation_matrices() * a.scales[:, None, :]
        half = float(sigma) * np.sqrt(np.einsum("nij,nij->ni", m, m))
        return (a.positions - half).min(axis=0), (a.positions + half).max(axis=0)


def _degree_argument(value: Any) -> int | None:
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or not 0 <= int(value) <= 3:
        raise ValueError(f"GaussianSplats: sh_degree must be 0, 1, 2 or 3 (or None to infer it), got {value!r}")
    return int(value)


def _numeric(name: str, value: Any) -> np.ndarray:
    try:
        a = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged lists
        raise ValueError(f"GaussianSplats: {name} must be a numeric array, got {type(value).__name__}: {exc}") from None
    if a.dtype.kind not in "biuf":
        raise ValueError(f"GaussianSplats: {name} must hold numbers, got dtype {a.dtype}; pass a float array")
    return a.astype(np.float64, copy=False)


def _first_bad(mask: np.ndarray) -> int:
    return int(np.argmax(mask))


def _check_rows(name: str, a: np.ndarray) -> None:
    rows = a.reshape(len(a), int(np.prod(a.shape[1:], dtype=np.int64)))
    finite = np.isfinite(rows).all(axis=1)
    if not finite.all():
        bad = _first_bad(~finite)
        raise ValueError(
            f"GaussianSplats: {name} of splat {bad} are not finite: {rows[bad].tolist()}; write finite numbers"
        )


def _check(positions: Any, rotations: Any, scales: Any, opacities: Any, sh: Any, sh_degree: int | None) -> SplatArrays:
    p = _numeric("positions", positions)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"GaussianSplats: positions must have shape (N, 3), got {p.shape}")
    n = len(p)
    q = _numeric("rotations", rotations)
    s = _numeric("scales", scales)
    o = _numeric("opacities", opacities)
    c = _numeric("sh", sh)
    for name, a, want in (("rotations", q, (n, 4)), ("scales", s, (n, 3)), ("opacities", o, (n,))):
        if a.shape != want:
            what = "length" if a.ndim == len(want) and a.shape[1:] == want[1:] else "shape"
            raise ValueError(
                f"GaussianSplats: {name} must have shape {want} (one row per position), got {a.shape} (wrong {what})"
            )
    if c.ndim == 2 and c.shape[1] == 3:  # (N, 3): the DC term only
        c = c.reshape(len(c), 1, 3)
    if c.ndim != 3 or c.shape[2] != 3:
        raise ValueError(
            f"GaussianSplats: sh must have shape (N, K, 3) (K = (sh_degree+1)^2 coefficients per RGB channel), "
            f"got {c.shape}"
        )
    if len(c) != n:
        raise ValueError(f"GaussianSplats: sh must have one row per position ({n}), got {len(c)} (wrong length)")
    k = c.shape[1]
    implied = _sh.degree_for(k)
    if sh_degree is None:
        if implied is None:
            raise ValueError(
                f"GaussianSplats: sh has {k} coefficients per channel; SH degrees 0..3 need 1, 4, 9 or 16 "
                "((degree+1)^2)"
            )
        degree = implied
    else:
        degree = sh_degree
        if k != _sh.coefficient_count(degree):
            raise ValueError(
                f"GaussianSplats: sh_degree={degree} needs {_sh.coefficient_count(degree)} coefficients per channel "
                f"((degree+1)^2), sh has {k}; pass sh of shape (N, {_sh.coefficient_count(degree)}, 3) or "
                f"sh_degree={implied}"
                if implied is not None
                else f"GaussianSplats: sh_degree={degree} needs {_sh.coefficient_count(degree)} coefficients per "
                f"channel ((degree+1)^2), sh has {k}"
            )
    for name, a in (("positions", p), ("rotations", q), ("scales", s), ("opacities", o), ("sh", c)):
        _check_rows(name, a)
    if n:
        bad_scale = (s <= 0).any(axis=1)
        if bad_scale.any():
            i = _first_bad(bad_scale)
            raise ValueError(
                f"GaussianSplats: scales of splat {i} are {s[i].tolist()}; scales are standard deviations and must "
                "be > 0 (linear, not log: a trainer's .ply stores log-scales, use np.exp)"
            )
        bad_opacity = (o < 0) | (o > 1)
        if bad_opacity.any():
            i = _first_bad(bad_opacity)
            raise ValueError(
                f"GaussianSplats: the opacity of splat {i} is {o[i]}; opacities must be in [0, 1] (not logits: a "
                "trainer's .ply stores logits, use 1 / (1 + np.exp(-x)))"
            )
        length = np.sqrt(np.einsum("ij,ij->i", q, q))
        bad_q = np.abs(length - 1.0) > QUATERNION_TOLERANCE
        if bad_q.any():
            i = _first_bad(bad_q)
            raise ValueError(
                f"GaussianSplats: the rotation quaternion of splat {i} is {q[i].tolist()} of length {length[i]:.6g}; "
                "quaternions must be unit length (within 1e-3): normalise them, q / np.linalg.norm(q, axis=1, "
                "keepdims=True)"
            )
    return SplatArrays(p, q, s, o, c, degree)
