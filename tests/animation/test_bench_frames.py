"""The frame-rendering benchmark runs end to end (small and with GL here; the README figures use POV-Ray)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "bench" / "render_frames.py"


@pytest.mark.slow
@pytest.mark.gl
def test_render_frames_benchmark_runs():
    pytest.importorskip("distributed")
    out = subprocess.run(
        [sys.executable, str(BENCH), "--frames", "4", "--engine", "gl", "--size", "64x48"],
        capture_output=True, text=True, timeout=300, check=True,
    ).stdout  # fmt: skip
    assert "4 gl frames of the demo turntable at 64x48" in out
    for label in ("one process", "Dask, 2 workers", "2 local processes"):
        line = next(line for line in out.splitlines() if line.startswith(label))
        assert "ms/frame" in line and "overhead" in line
    assert "speed-up Dask 2 workers vs one process:" in out
