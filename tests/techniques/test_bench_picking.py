"""The picking benchmark runs end to end on a small mesh and its backends agree."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "bench" / "picking.py"


@pytest.mark.slow
def test_picking_benchmark_runs_and_backends_agree():
    out = subprocess.run(
        [sys.executable, str(BENCH), "20000", "100", "5"], capture_output=True, text=True, timeout=300, check=True
    ).stdout
    assert "build numpy BVH" in out and "om.pick [numpy ]" in out
    if "om.pick [embree]" in out:
        assert "agree on all 100 rays: True" in out
    if "trimesh RayMeshIntersector" in out:
        assert "nearest hits agree with om.pick: True" in out
        assert "same 5 rays: om.pick [numpy ]" in out  # both timed on the same rays
