"""Property-based fuzzing of the loaders (a bounded number of examples; the long campaign is tools/fuzz.py).

Each example mutates a valid glTF, GLB, OBJ (+MTL), PLY, STL, OFF or scene
file (truncation, random bytes, interesting integers in counts, offsets,
strides and indices, JSON values replaced, keys deleted, nesting added) with
the mutations of :mod:`tools.fuzz`, and asserts: a clear error (ValueError or
OSError), or a graph with finite bounds (the unmutated seeds are rendered); never another exception,
never more than 10 seconds.  Run ``python -m tools.fuzz --examples 100000``
for the long campaign.
"""

from __future__ import annotations

import signal
import sys
import tempfile
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root, for tools/

from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import omnirender as om  # noqa: E402
from tools import fuzz  # noqa: E402

EXAMPLES = 15


def _hang(signum, frame):
    raise fuzz.Hang("a loader ran for more than 10 s")


@pytest.mark.parametrize("loader", fuzz.LOADERS)
def test_seeds_are_valid_files(loader, tmp_path):
    """Unmutated, every seed loads (so the mutations start from files the loaders accept)."""
    import random

    files = fuzz.mutate(loader, random.Random(0), mutations=False)
    assert fuzz.check(files, tmp_path) == "loaded"
    graph = fuzz.load(tmp_path, next(iter(files)))
    if om.engines()["gl"][0]:  # and renders: something covers the middle of the image
        image = om.render(om.Node("s", [graph]), size=(48, 32), background=(0, 0, 0))
        assert image.array[8:24, 12:36, :3].max() > 0


@pytest.mark.parametrize("loader", fuzz.LOADERS)
@settings(
    max_examples=EXAMPLES, deadline=None, database=None, derandomize=True, suppress_health_check=list(HealthCheck)
)
@given(rnd=st.randoms(use_true_random=False))
def test_a_mutated_file_gives_a_clear_error_or_loads(loader, rnd):
    files = fuzz.mutate(loader, rnd)
    previous = signal.signal(signal.SIGALRM, _hang)
    signal.setitimer(signal.ITIMER_REAL, 10.0)
    try:
        with tempfile.TemporaryDirectory() as folder:
            fuzz.check(files, Path(folder))  # a clear error, or loaded with finite bounds
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
