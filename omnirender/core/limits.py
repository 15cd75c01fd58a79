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

**Decoded data from files** is bounded here too, in one place, because a file
can claim more than it holds: a 0.9 MB PNG can decode to 30000x30000 pixels
(3.6 GB), a PLY header can announce four billion vertices, a glTF node can be
its own grandchild.  Loaders check what a file *claims* before they allocate:

=========================  ==========================================================
:data:`MAX_IMAGE_SIDE`     width or height of a decoded image (texture, glTF image)
:data:`MAX_IMAGE_PIXELS`   width x height of a decoded image (decompression bombs)
:data:`MAX_DECODED_BYTES`  bytes of one decoded array (an image, a buffer, an accessor)
:data:`MAX_VERTICES`       vertices of one mesh (glTF accessor, OBJ, PLY, STL, OFF)
:data:`MAX_INDICES`        indices of one mesh (three per triangle)
:data:`MAX_NESTING`        depth of a node hierarchy or nested document in a file
=========================  ==========================================================

A file beyond a limit raises :class:`ResourceLimitError` (a ValueError) naming
the file, what it claimed and the limit.  The limits are module attributes read
at every check: an application that trusts its files may raise one
(``omnirender.core.limits.MAX_IMAGE_PIXELS = 2**30``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = [
    "MAX_MAGNITUDE",
    "MIN_MAGNITUDE",
    "check_magnitude",
    "check_array_magnitude",
    "as_float",
    "MAX_IMAGE_SIDE",
    "MAX_IMAGE_PIXELS",
    "MAX_DECODED_BYTES",
    "MAX_VERTICES",
    "MAX_INDICES",
    "MAX_NESTING",
    "MAX_PIXEL_SIZE",
    "ResourceLimitError",
    "check_image_size",
    "check_count",
    "check_bytes",
    "check_nesting",
]

#: Largest absolute value of a coordinate, size, offset, scale factor or matrix entry.
MAX_MAGNITUDE = 1e15
#: Smallest absolute value of a non-zero size or scale factor (its inverse must stay below MAX_MAGNITUDE).
MIN_MAGNITUDE = 1.0 / MAX_MAGNITUDE

#: Largest width or height of an image decoded from a file (GPUs hold at most 16384..32768 texels a side).
MAX_IMAGE_SIDE = 32768
#: Largest width x height of an image decoded from a file: 2**27 pixels, 512 MiB as RGBA bytes.
MAX_IMAGE_PIXELS = 2**27
#: Largest size in bytes of one array decoded from a file (an image, a glTF buffer or accessor): 2 GiB.
MAX_DECODED_BYTES = 2**31
#: Most vertices of one mesh read from a file.
MAX_VERTICES = 2**28
#: Most vertex indices of one mesh read from a file (three per triangle).
MAX_INDICES = 3 * 2**28
#: Largest point size or line width in pixels (``DrawStyle``); engines clamp further to what the driver supports.
MAX_PIXEL_SIZE = 4096.0
#: Deepest nesting of a node hierarchy (glTF nodes) or of a document (scene files) read from a file.
MAX_NESTING = 256


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


# -- decoded data from files --------------------------------------------------------
class ResourceLimitError(ValueError):
    """A file claims more data than :mod:`omnirender.core.limits` allows (see the module docs)."""

    def __init__(self, source: str, message: str, limit_name: str) -> None:
        self.source = source
        self.limit_name = limit_name
        super().__init__(
            f"{source}: {message}; a file this large is refused so that a malicious one cannot exhaust memory "
            f"(if you trust it, raise omnirender.core.limits.{limit_name})"
        )


def check_image_size(source: str, what: str, width: int, height: int) -> None:
    """Refuse an image of ``width`` x ``height`` beyond :data:`MAX_IMAGE_SIDE` / :data:`MAX_IMAGE_PIXELS`.

    Call it with the size an image file's header announces, before decoding.
    """
    if width > MAX_IMAGE_SIDE or height > MAX_IMAGE_SIDE:
        raise ResourceLimitError(
            source, f"{what} is {width}x{height} pixels, more than {MAX_IMAGE_SIDE} a side", "MAX_IMAGE_SIDE"
        )
    if width * height > MAX_IMAGE_PIXELS:
        raise ResourceLimitError(
            source,
            f"{what} is {width}x{height} = {width * height:,} pixels, more than {MAX_IMAGE_PIXELS:,} "
            "(a decompression bomb?)",
            "MAX_IMAGE_PIXELS",
        )
    if width * height * 4 > MAX_DECODED_BYTES:
        raise ResourceLimitError(source, f"{what} would decode to {width * height * 4:,} bytes", "MAX_DECODED_BYTES")


_COUNT_LIMITS = {"vertices": "MAX_VERTICES", "indices": "MAX_INDICES"}


def check_count(source: str, what: str, count: int, kind: str = "vertices") -> int:
    """``count`` when it is within the limit of ``kind`` (``"vertices"`` or ``"indices"``), else ResourceLimitError."""
    name = _COUNT_LIMITS[kind]
    limit = globals()[name]
    if count > limit:
        raise ResourceLimitError(source, f"{what} holds {count:,} {kind}, more than {limit:,}", name)
    return count


def check_bytes(source: str, what: str, nbytes: int) -> int:
    """``nbytes`` when one decoded array of that size is within :data:`MAX_DECODED_BYTES`, else ResourceLimitError."""
    if nbytes > MAX_DECODED_BYTES:
        raise ResourceLimitError(
            source, f"{what} would decode to {nbytes:,} bytes, more than {MAX_DECODED_BYTES:,}", "MAX_DECODED_BYTES"
        )
    return nbytes


def check_nesting(source: str, what: str, depth: int) -> int:
    """``depth`` when it is within :data:`MAX_NESTING`, else ResourceLimitError."""
    if depth > MAX_NESTING:
        raise ResourceLimitError(
            source, f"{what} is nested more than {MAX_NESTING} levels deep (or is its own ancestor)", "MAX_NESTING"
        )
    return depth
