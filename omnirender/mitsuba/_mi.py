"""Importing Mitsuba safely: the ``scalar_rgb`` variant only.

On these machines selecting an ``llvm_*`` variant aborts the whole process, so
this adapter never does it; ``scalar_rgb`` is always present in the pip wheels.
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np

__all__ = ["VARIANT", "mitsuba", "available", "transform"]

VARIANT = "scalar_rgb"
_lock = threading.Lock()
_module: Any = None


def mitsuba() -> Any:
    """The ``mitsuba`` module with the ``scalar_rgb`` variant selected (imported on first use)."""
    global _module
    if _module is not None:
        return _module
    with _lock:
        if _module is None:
            try:
                import mitsuba as mi
            except ImportError as exc:
                raise RuntimeError(
                    f"the Mitsuba engine needs the mitsuba package: pip install 'omnirender[mitsuba]' ({exc})"
                ) from None
            if VARIANT not in mi.variants():
                raise RuntimeError(f"mitsuba {mi.__version__} has no {VARIANT!r} variant (it has {mi.variants()})")
            if mi.variant() != VARIANT:
                mi.set_variant(VARIANT)
            _module = mi
    return _module


def available() -> tuple[bool, str]:
    """(True, version) when Mitsuba imports and offers ``scalar_rgb``, else (False, reason)."""
    try:
        mi = mitsuba()
    except Exception as exc:
        return False, str(exc)
    return True, f"Mitsuba {mi.__version__} ({VARIANT})"


def transform(matrix: np.ndarray) -> Any:
    """A 4x4 numpy matrix as ``mi.ScalarTransform4f``."""
    mi = mitsuba()
    return mi.ScalarTransform4f(np.asarray(matrix, dtype=np.float64).tolist())
