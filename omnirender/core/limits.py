"""How large a number may be: finite is not enough.

A radius of ``1e308`` is finite, yet every engine draws nothing with it, and
``1e39`` overflows the GPU's float32.  Coordinates, sizes, offsets, scale
factors, matrix entries and camera distances are therefore limited to
:data:`MAX_MAGNITUDE` in absolute value (and non-zero sizes and scale factors
to at least :data:`MIN_MAGNITUDE`): float32 holds about 3.4e38, so products of
two such values (a matrix times a point, a squared distance) still fit.  The
accumulated model matrix obeys the same limit (a deep stack of ``Scaling(10)``
overflows long before any single one does); it is checked where the matrix is
composed.  One rule, used by every component and by the context.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["MAX_MAGNITUDE", "MIN_MAGNITUDE", "check_magnitude", "check_array_magnitude", "as_float"]

#: Largest absolute value of a coordinate, size, offset, scale factor or matrix entry.
MAX_MAGNITUDE = 1e15
#: Smallest absolute value of a non-zero size or scale factor (its inverse must stay below MAX_MAGNITUDE).
MIN_MAGNITUDE = 1.0 / MAX_MAGNITUDE


def _limit_text() -> str:
    return f"at most {MAX_MAGNITUDE:.0e} in magnitude (larger values overflow the engines' float32 arithmetic)"


def as_float(owner: str, name: str, value: Any) -> float:
    """``float(value)`` with ValueError (not OverflowError or TypeError) naming ``owner``/``name``.

    Refuses booleans and strings, non-finite numbers, and magnitudes above
    :data:`MAX_MAGNITUDE` (an integer of 400 digits is refused here, not
    reported by Python as an overflow).
    """
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise ValueError(f"{owner}: {name} must be a number, got {value!r:.60}")
    try:
        x = float(value)
    except OverflowError:
        raise ValueError(
            f"{owner}: {name} must be {_limit_text()}, got an integer of {len(str(value))} digits"
        ) from None
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: {name} must be a number, got {value!r:.60}") from None
    if not math.isfinite(x):
        raise ValueError(f"{owner}: {name} must be finite, got {value!r:.60}")
    return check_magnitude(owner, name, x)


def check_magnitude(owner: str, name: str, x: float) -> float:
    """``x`` when ``abs(x) <= MAX_MAGNITUDE``, else ValueError naming ``owner``/``name``."""
    if not abs(x) <= MAX_MAGNITUDE:
        raise ValueError(f"{owner}: {name} must be {_limit_text()}, got {x!r}")
    return x


def check_array_magnitude(owner: str, name: str, arr: np.ndarray) -> np.ndarray:
    """``arr`` (finite numbers) when every entry is within :data:`MAX_MAGNITUDE`, else ValueError (first bad row)."""
    if arr.size and arr.dtype.kind == "f":
        big = np.abs(arr) > MAX_MAGNITUDE
        if big.any():
            where = np.argwhere(big)[0]
            row = int(where[0])
            shown = arr[row].tolist() if arr.ndim > 1 else float(arr[row])
            raise ValueError(f"{owner}: {name} must be {_limit_text()} (row {row} is {shown}); rescale the data")
    return arr
