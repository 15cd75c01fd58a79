"""The colour tolerance of tests/pixels.py: one 8-bit level, the rounding two conforming drivers may differ by."""

from __future__ import annotations

import pytest
from pixels import assert_rgb


def test_a_value_between_two_levels_may_round_either_way():
    for driver_value in (25, 26):  # 0.1 * 255 = 25.5: llvmpipe writes 26, NVIDIA 25
        assert_rgb((driver_value,) * 3, (25.5,) * 3)


def test_a_colour_two_levels_off_is_a_difference():
    with pytest.raises(AssertionError, match="differs from"):
        assert_rgb((24, 26, 26), (25.5,) * 3)
    with pytest.raises(AssertionError):
        assert_rgb((255, 125, 0), (255, 127.5, 0), tolerance=0.5)
