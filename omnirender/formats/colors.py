"""Colour helpers shared by the exporters (file formats want linear colour factors)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["srgb_to_linear"]


def srgb_to_linear(c: Any) -> np.ndarray:
    """sRGB-encoded values in [0, 1] (our colours are display values) to linear ones."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, None)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
