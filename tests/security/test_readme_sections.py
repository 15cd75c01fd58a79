"""The README's sections on untrusted files and on tiled rendering run as written."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"


def _block(heading: str) -> str:
    section = README.read_text().split(heading, 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_untrusted_files_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    exec(compile(_block("## Untrusted files"), "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "leads outside the file's folder" in out and "trusted=True" in out
    assert "dropped" in out and "never downloads" in out and "strict:" in out


def test_tiled_rendering_example_runs(tmp_path, monkeypatch):
    from PIL import Image

    monkeypatch.chdir(tmp_path)
    exec(compile(_block("## Posters: tiled rendering"), "README.md", "exec"), {})
    with Image.open(tmp_path / "tiled.png") as a, Image.open(tmp_path / "poster.png") as b:
        assert a.size == (800, 600) and b.size == (1000, 600)
