"""Mitsuba render options are checked before anything reaches Mitsuba."""

from __future__ import annotations

import pytest

import omnirender as om


@pytest.mark.mitsuba
@pytest.mark.parametrize(
    "options, message",
    [
        ({"spp": "x"}, "spp must be a whole number"),
        ({"spp": 0}, "spp must be a whole number"),
        ({"seed": "a"}, "seed must be a whole number"),
        ({"spp": float("nan")}, "spp must be a whole number"),
        ({"seed": 2**64}, r"seed must be a whole number in 0\.\.4294967295"),
        ({"global_ambient": float("nan")}, "global_ambient must be a finite number"),
        ({"size": (100000, 100000)}, "at most 16384 pixels per side"),
        ({"integrator": "magic"}, "integrator must be a Mitsuba plugin dict"),
    ],
)
def test_bad_values_are_explained(options, message):
    with pytest.raises(ValueError, match=message):
        om.render(om.Node("s", [om.Sphere()]), engine="mitsuba", **{"size": (8, 6), **options})


@pytest.mark.mitsuba
def test_unknown_options_list_the_accepted_ones():
    with pytest.raises(TypeError, match=r"unknown option\(s\) \['samples'\]; accepted: spp, quality, denoise, integ"):
        om.render(om.Node("s", [om.Sphere()]), engine="mitsuba", size=(8, 6), samples=3)
