"""Checks for the options of the render functions (``om.render(..., **options)``), shared by every engine.

Each check raises ValueError naming the engine and the option, says what is
accepted, and runs before anything is computed or allocated: a timeout of
NaN is not "no timeout", a seed of 2**64 is not passed on to a library that
reports it in its own words, and an image larger than an engine can hold is
refused with the limit in the message (engines declare their limits as data).
Like :mod:`omnirender.image` and :mod:`omnirender.fileio`, this module
imports only numpy and may be used by every adapter.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

__all__ = [
    "check_timeout",
    "check_integer",
    "check_real",
    "check_image_size",
    "SizeLimits",
    "did_you_mean",
    "options_hint",
]


def did_you_mean(name: Any, choices: Any) -> str:
    """``"; did you mean 'spp'?"`` when ``name`` is close to one of ``choices``, else ``""``."""
    import difflib

    close = difflib.get_close_matches(str(name), [str(c) for c in choices], n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


def options_hint(unknown: Any, accepted: Any) -> str:
    """``"; did you mean 'spp' for 'sp'?"`` for each unknown option close to an accepted one, else ``""``."""
    import difflib

    accepted = [str(a) for a in accepted]
    pairs = []
    for name in sorted(str(u) for u in unknown):
        close = difflib.get_close_matches(name, accepted, n=1, cutoff=0.6)
        if close:
            pairs.append(f"{close[0]!r} for {name!r}")
    return f"; did you mean {' and '.join(pairs)}?" if pairs else ""


def _is_bool_or_text(value: Any) -> bool:
    return isinstance(value, (bool, str, bytes)) or type(value).__name__ == "bool_"


def check_timeout(owner: str, timeout: Any) -> float | None:
    """``timeout`` seconds as a float > 0, or None (no limit); NaN, infinity, strings and booleans are refused."""
    if timeout is None:
        return None
    if _is_bool_or_text(timeout) or not isinstance(timeout, numbers.Real):
        raise ValueError(f"{owner}: timeout must be a number of seconds > 0 or None (no limit), got {timeout!r:.60}")
    value = float(timeout)
    if not (value > 0 and math.isfinite(value)):
        raise ValueError(
            f"{owner}: timeout must be a finite number of seconds > 0, or None for no limit; got {timeout!r}"
        )
    return value


def check_integer(owner: str, name: str, value: Any, minimum: int, maximum: int) -> int:
    """``value`` as an int in [minimum, maximum] (a float with an integral value is accepted)."""
    if _is_bool_or_text(value) or not isinstance(value, numbers.Real):
        raise ValueError(f"{owner}: {name} must be a whole number in {minimum}..{maximum}, got {value!r:.60}")
    if isinstance(value, numbers.Integral):
        n = int(value)
    else:
        x = float(value)
        if not math.isfinite(x) or x != math.floor(x):
            raise ValueError(f"{owner}: {name} must be a whole number in {minimum}..{maximum}, got {value!r}")
        n = int(x)
    if not minimum <= n <= maximum:
        raise ValueError(f"{owner}: {name} must be a whole number in {minimum}..{maximum}, got {value!r}")
    return n


def check_real(owner: str, name: str, value: Any, minimum: float, maximum: float) -> float:
    """``value`` as a finite float in [minimum, maximum]."""
    if _is_bool_or_text(value) or not isinstance(value, numbers.Real):
        raise ValueError(f"{owner}: {name} must be a number in [{minimum:g}, {maximum:g}], got {value!r:.60}")
    x = float(value)
    if not (minimum <= x <= maximum):  # NaN fails
        raise ValueError(f"{owner}: {name} must be a finite number in [{minimum:g}, {maximum:g}], got {value!r}")
    return x


class SizeLimits:
    """The largest image an engine renders: ``max_side`` pixels per side, ``max_pixels`` in all."""

    __slots__ = ("max_side", "max_pixels", "why")

    def __init__(self, max_side: int, max_pixels: int, why: str) -> None:
        self.max_side = max_side
        self.max_pixels = max_pixels
        self.why = why


def check_image_size(owner: str, size: Any, limits: SizeLimits | None = None) -> tuple[int, int]:
    """``size`` as ``(width, height)`` positive ints within ``limits``; ValueError naming the limit otherwise."""
    try:
        values = list(size)
    except TypeError:
        raise ValueError(f"{owner}: size must be (width, height) in whole pixels, got {size!r:.60}") from None
    if len(values) != 2 or any(_is_bool_or_text(v) or not isinstance(v, numbers.Real) for v in values):
        raise ValueError(f"{owner}: size must be (width, height) in whole pixels, got {size!r:.60}")
    floats = [float(v) for v in values]
    if not all(math.isfinite(v) and v == math.floor(v) for v in floats):
        raise ValueError(f"{owner}: size must be (width, height) in whole pixels, got {size!r}")
    w, h = (int(v) for v in floats)
    if w <= 0 or h <= 0:
        raise ValueError(f"{owner}: size must be positive, got {w}x{h}")
    if limits is not None and (w > limits.max_side or h > limits.max_side or w * h > limits.max_pixels):
        raise ValueError(
            f"{owner}: size {w}x{h} ({w * h:,} pixels) is more than this engine renders: at most "
            f"{limits.max_side} pixels per side and {limits.max_pixels:,} pixels in all ({limits.why}); "
            "render a smaller image, or tiles of it"
        )
    return w, h
