"""Colour comparisons of rendered pixels with a stated tolerance (never exact equality of rasterised values).

OpenGL converts a float colour to an 8-bit channel by ``round(f * 255)``, but allows implementations
their own precision in the conversion and in the arithmetic before it: a value exactly between two
levels (0.1 * 255 = 25.5, 0.5 * 255 = 127.5) comes out as 25 or 26 (127 or 128) depending on the driver,
and blending or filtering may add another unit.  :data:`CHANNEL_TOLERANCE` is that one level.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: 8-bit levels two conforming drivers may differ by for the same colour (see the module docstring).
CHANNEL_TOLERANCE = 1


def assert_rgb(pixel: Sequence[float], expected: Sequence[float], tolerance: float = CHANNEL_TOLERANCE) -> None:
    """Assert that the RGB of ``pixel`` is within ``tolerance`` levels of ``expected`` in every channel."""
    got = np.asarray(pixel, dtype=float)[:3]
    want = np.asarray(expected, dtype=float)[:3]
    assert np.abs(got - want).max() <= tolerance, (
        f"colour {tuple(int(v) for v in got)} differs from {tuple(want.tolist())} by more than {tolerance}"
    )
