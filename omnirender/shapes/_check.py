"""Validation helpers shared by the shape declarations.

Every helper raises ValueError naming the shape class and the parameter, so a
bad input is reported where it is made (construction or assignment), never
when an engine first draws the shape.
"""

from __future__ import annotations

import operator
from typing import Any

import numpy as np

from ..core.limits import MAX_MAGNITUDE, MIN_MAGNITUDE, as_float, check_array_magnitude
from ..data import as_array


def scalar(owner: str, name: str, value: Any, *, positive: bool = False, nonnegative: bool = False) -> float:
    """``value`` as a finite float within the magnitude limit (``omnirender.core.limits``); optionally > 0 or >= 0."""
    v = as_float(owner, name, value)
    if positive and v <= 0.0:
        raise ValueError(f"{owner}: {name} must be > 0, got {v}")
    if positive and v < MIN_MAGNITUDE:
        raise ValueError(f"{owner}: {name} must be at least {MIN_MAGNITUDE:.0e}, got {v}")
    if nonnegative and v < 0.0:
        raise ValueError(f"{owner}: {name} must be >= 0, got {v}")
    return v


def integer(owner: str, name: str, value: Any, minimum: int = 0) -> int:
    """``value`` as an int >= ``minimum``."""
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{owner}: {name} must be an integer, got {value!r}")
    try:
        n = operator.index(value)
    except TypeError:
        raise ValueError(f"{owner}: {name} must be an integer, got {value!r}") from None
    if n < minimum:
        raise ValueError(f"{owner}: {name} must be >= {minimum}, got {n}")
    return n


def vector(owner: str, name: str, value: Any, size: int, *, positive: bool = False) -> tuple[float, ...]:
    """``value`` as a tuple of ``size`` finite floats (a single number is broadcast when ``positive``)."""
    if isinstance(value, (str, bytes, bool, np.bool_)):
        raise ValueError(f"{owner}: {name} must be {size} numbers, got {value!r:.60}")
    try:
        arr = np.array(value, dtype=np.float64)
    except OverflowError:
        raise ValueError(f"{owner}: {name} must be {size} numbers of at most {MAX_MAGNITUDE:.0e}") from None
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: {name} must be {size} numbers, got {value!r:.60}") from None
    if arr.ndim > 1:
        raise ValueError(
            f"{owner}: {name} must be a flat list of {size} numbers, got a nested list of shape {arr.shape} "
            f"({value!r:.60}); pass e.g. {name}=(1, 2, 3)"
        )
    arr = arr.reshape(-1)
    if positive and arr.size == 1:
        arr = np.repeat(arr, size)
    if arr.shape != (size,):
        raise ValueError(f"{owner}: {name} must be {size} numbers, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{owner}: {name} must be finite, got {value!r}")
    check_array_magnitude(owner, name, arr)
    if positive and np.any(arr < MIN_MAGNITUDE):
        raise ValueError(
            f"{owner}: {name} must be > 0 (at least {MIN_MAGNITUDE:.0e}) in every component, got {tuple(arr.tolist())}"
        )
    return tuple(float(c) for c in arr)


def float_array(
    owner: str,
    name: str,
    value: Any,
    widths: tuple[int, ...],
    *,
    count: int | None = None,
    minimum: int = 0,
) -> np.ndarray:
    """``value`` (a data sequence or array-like) as a read-only (N, w) float32 array.

    ``widths`` lists the accepted row widths; ``count`` the required N (e.g. one
    per vertex); ``minimum`` the least N.  Non-finite entries are rejected.
    """
    a = as_array(value, None, name=f"{owner}: {name}")
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{owner}: {name} must hold numbers, got dtype {a.dtype}; pass a numeric array")
    if a.ndim == 1 and len(widths) == 1 and widths[0] > 1 and a.size % widths[0] == 0 and a.size > 0:
        a = a.reshape(-1, widths[0])
    if widths == (1,) and a.ndim == 1:
        a = a.reshape(-1, 1)
    if a.ndim != 2 or a.shape[1] not in widths:
        want = " or ".join(f"(N, {w})" for w in widths)
        raise ValueError(f"{owner}: {name} must have shape {want}, got {a.shape}; fix the array's shape")
    if count is not None and a.shape[0] != count:
        raise ValueError(
            f"{owner}: {name} must have one row per vertex ({count}), got {a.shape[0]}; give one row per vertex"
        )
    if a.shape[0] < minimum:
        raise ValueError(f"{owner}: {name} needs at least {minimum} rows, got {a.shape[0]}; add rows")
    if a.dtype.kind == "f" and a.size and not np.all(np.isfinite(a)):
        bad = int(np.argwhere(~np.isfinite(a))[0][0])
        raise ValueError(f"{owner}: {name} must be finite (row {bad} is {a[bad].tolist()}); fix or drop that row")
    check_array_magnitude(owner, name, a if a.dtype.kind == "f" else a.astype(np.float64))
    out = np.ascontiguousarray(a, dtype=np.float32)
    if out is a:
        out = out.copy()
    out.setflags(write=False)
    return out


def index_array(owner: str, name: str, value: Any, width: int, vertex_count: int) -> np.ndarray:
    """``value`` as a read-only (K, width) uint32 array of indices < ``vertex_count``."""
    a = as_array(value, None, name=f"{owner}: {name}")
    if a.size == 0:
        raise ValueError(f"{owner}: {name} is empty; give at least one primitive (or indices=None for all vertices)")
    if a.dtype.kind == "f":
        if not np.all(np.isfinite(a)) or not np.all(a == np.round(a)):
            raise ValueError(f"{owner}: {name} must be integers; fix the index array")
    elif a.dtype.kind not in "iu":
        raise ValueError(f"{owner}: {name} must be integers, got dtype {a.dtype}; fix the index array")
    if a.ndim == 1:
        if a.size % width:
            raise ValueError(f"{owner}: {name} length {a.size} is not a multiple of {width}; fix the index array")
        a = a.reshape(-1, width)
    if a.ndim != 2 or a.shape[1] != width:
        raise ValueError(f"{owner}: {name} must have shape (K, {width}), got {a.shape}; fix the index array")
    lo, hi = int(a.min()), int(a.max())
    if lo < 0:
        raise ValueError(
            f"{owner}: {name} has index {lo} out of range for {vertex_count} vertices (valid: 0..{vertex_count - 1}): "
            "indices must be >= 0; fix the index array"
        )
    if hi >= vertex_count:
        raise ValueError(
            f"{owner}: {name} has index {hi} out of range for {vertex_count} vertices (valid: 0..{vertex_count - 1}): "
            "indices must be < number of vertices; fix the index array"
        )
    out = np.ascontiguousarray(a, dtype=np.uint32)
    if out is a:
        out = out.copy()
    out.setflags(write=False)
    return out


def colors(owner: str, name: str, value: Any, count: int) -> np.ndarray | None:
    """Per-vertex colours as (count, 4) float32 RGBA in [0, 1]; a single RGB(A) colour is broadcast."""
    if value is None:
        return None
    a = as_array(value, None, name=f"{owner}: {name}")
    if a.ndim == 1 and a.shape[0] in (3, 4):
        a = np.broadcast_to(a, (count, a.shape[0]))
    c = float_array(owner, name, a, (3, 4), count=count)
    if c.size and (c.min() < 0.0 or c.max() > 1.0):
        bad = int(np.argwhere((c < 0.0) | (c > 1.0))[0][0])
        raise ValueError(
            f"{owner}: {name} must be in [0, 1] (row {bad} is {c[bad].tolist()}); colours are fractions, "
            "divide 0-255 values by 255"
        )
    if c.shape[1] == 3:
        c = np.concatenate([c, np.ones((count, 1), np.float32)], axis=1)
        c.setflags(write=False)
    return c


def normals(owner: str, name: str, value: Any, count: int) -> np.ndarray:
    """Per-vertex normals as a read-only (count, 3) float32 array of unit vectors; zero-length ones are refused."""
    n = float_array(owner, name, value, (3,), count=count)
    length = np.sqrt(np.einsum("ij,ij->i", n, n, dtype=np.float64))  # float64 sums, no float64 copies of n
    if length.size and length.min() < 1e-12:
        bad = int(np.argmin(length))
        raise ValueError(
            f"{owner}: {name} must have non-zero length (row {bad} is {n[bad].tolist()}); give a direction, "
            "or normals=None to compute smooth normals"
        )
    out = n * (1.0 / length).astype(np.float32)[:, None] if n.dtype == np.float32 else (n / length[:, None])
    out = out.astype(np.float32, copy=False)
    out.setflags(write=False)
    return out
