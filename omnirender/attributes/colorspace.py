"""sRGB and linear colour values: the one implementation every engine uses.

Scene colours (``Color``, materials, lights, backgrounds, vertex colours,
textures) are display values, sRGB-encoded as in every image editor; lighting
and blending in linear light need them decoded (IEC 61966-2-1).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["srgb_to_linear", "linear_to_srgb", "linear_rgb"]


def srgb_to_linear(c: Any) -> np.ndarray:
    """sRGB-encoded values in [0, 1] (any shape) to linear light."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: Any) -> np.ndarray:
    """Linear values (clipped to [0, 1]) to sRGB encoding."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def _channel(c: float) -> float:
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def linear_rgb(rgb: Any) -> tuple[float, float, float]:
    """The first three values of an sRGB colour as a linear (r, g, b) tuple of Python floats (no numpy: fast)."""
    r, g, b = rgb[:3]
    return (_channel(float(r)), _channel(float(g)), _channel(float(b)))
