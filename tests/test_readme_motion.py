"""The README's "Moving many objects" example runs as written and moves what it says."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).parent.parent / "README.md"


@pytest.mark.gl
def test_moving_many_objects_example_runs():
    section = README.read_text().split("### Moving many objects", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    namespace: dict = {"__name__": "__main__"}
    exec(compile(code, "README.md", "exec"), namespace)
    moves, positions = namespace["moves"], namespace["positions"]
    assert np.allclose([t.offset for t in moves], positions)
    assert namespace["image"].mask.mean() > 0.01
