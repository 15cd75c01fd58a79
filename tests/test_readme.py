"""The README's "Ten lines" example runs as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).parent.parent / "README.md"


def _block(heading: str) -> str:
    text = README.read_text()
    section = text.split(heading, 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
@pytest.mark.mitsuba
def test_ten_lines_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    exec(compile(_block("## Ten lines"), "README.md", "exec"), {})
    for name in ("gl.png", "pov.png", "mitsuba.png", "scene.glb"):
        assert (tmp_path / name).stat().st_size > 1000, name
    assert "/scene/body" in capsys.readouterr().out
