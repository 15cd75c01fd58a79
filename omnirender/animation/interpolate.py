"""Keyframe interpolation: step, linear and cubic, for vectors and for unit quaternions.

Pure numpy, no scene graph.  ``times`` are strictly increasing seconds,
``values`` an (n, d) array.  Before the first key the first value holds, after
the last key the last one (clamping, as glTF does).  Cubic interpolation is a
Hermite spline: with ``tangents`` ``(in, out)`` given (glTF's CUBICSPLINE keys,
in units per second), else Catmull-Rom tangents from the neighbouring keys
(one-sided at the ends), so the curve passes through every key with a
continuous first derivative.  Quaternions (w, x, y, z) use spherical linear
interpolation along the shorter arc for ``linear``, and for ``cubic`` the
normalised Hermite curve of the sign-aligned keys (glTF's rule).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["INTERPOLATIONS", "interpolate", "slerp", "catmull_rom_tangents", "align_quaternions"]

#: The interpolation modes a keyframe track accepts.
INTERPOLATIONS = ("step", "linear", "cubic")


def _segment(times: np.ndarray, t: float) -> tuple[int, float] | None:
    """(k, u): ``t`` lies in [times[k], times[k+1]) at fraction u; None when it is outside the keys."""
    if t <= times[0] or len(times) == 1:
        return None
    if t >= times[-1]:
        return None
    k = int(np.searchsorted(times, t, side="right")) - 1
    return k, (t - times[k]) / (times[k + 1] - times[k])


def slerp(q0: np.ndarray, q1: np.ndarray, u: float) -> np.ndarray:
    """Spherical linear interpolation between unit quaternions along the shorter arc."""
    q0 = np.asarray(q0, np.float64)
    q1 = np.asarray(q1, np.float64)
    dot = float(np.dot(q0, q1))
    if dot < 0.0:  # q and -q are the same rotation: take the short way round
        q1, dot = -q1, -dot
    if dot > 0.9995:  # nearly equal: linear interpolation is exact enough and avoids 0/0
        q = q0 + u * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = math.acos(min(1.0, dot))
    s = math.sin(theta)
    return (math.sin((1.0 - u) * theta) * q0 + math.sin(u * theta) * q1) / s


def align_quaternions(values: np.ndarray) -> np.ndarray:
    """Flip signs so that consecutive quaternions lie in the same hemisphere (no detours in cubic curves)."""
    out = np.array(values, np.float64)
    for k in range(1, len(out)):
        if np.dot(out[k - 1], out[k]) < 0.0:
            out[k] = -out[k]
    return out


def catmull_rom_tangents(times: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Tangents (units per second) at every key: central differences, one-sided at the ends."""
    n = len(times)
    tangents = np.zeros_like(values, dtype=np.float64)
    if n < 2:
        return tangents
    tangents[0] = (values[1] - values[0]) / (times[1] - times[0])
    tangents[-1] = (values[-1] - values[-2]) / (times[-1] - times[-2])
    if n > 2:
        tangents[1:-1] = (values[2:] - values[:-2]) / (times[2:] - times[:-2])[:, None]
    return tangents


def interpolate(
    times: np.ndarray,
    values: np.ndarray,
    t: float,
    mode: str = "linear",
    *,
    quaternion: bool = False,
    tangents: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """The value of the track (``times``, ``values``) at time ``t`` (see the module docs)."""
    where = _segment(times, t)
    if where is None:
        return np.array(values[0] if t <= times[0] else values[-1], np.float64)
    k, u = where
    if mode == "step":
        return np.array(values[k], np.float64)
    if mode == "linear":
        if quaternion:
            return slerp(values[k], values[k + 1], u)
        return (1.0 - u) * values[k] + u * values[k + 1]
    if mode != "cubic":
        raise ValueError(f"interpolation must be one of {INTERPOLATIONS}, got {mode!r}")
    v = align_quaternions(values) if quaternion and tangents is None else values
    if tangents is None:
        out_tangents = in_tangents = catmull_rom_tangents(times, v)
    else:
        in_tangents, out_tangents = tangents
    dt = times[k + 1] - times[k]
    u2, u3 = u * u, u * u * u
    h00, h10 = 2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u
    h01, h11 = -2 * u3 + 3 * u2, u3 - u2
    p = h00 * v[k] + h10 * dt * out_tangents[k] + h01 * v[k + 1] + h11 * dt * in_tangents[k + 1]
    if quaternion:
        n = np.linalg.norm(p)
        return p / n if n > 0 else np.array(values[k], np.float64)
    return p
