"""Text is drawn at the requested pixel size on any machine: the package ships its font.

A machine without DejaVu installed used to get Pillow's fixed-size bitmap font: 32-pixel text had a
cap height of 8 pixels instead of 23.  The test hides every font outside the package.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender.fonts import DEFAULT_FONT, font_file

pytestmark = pytest.mark.gl

#: DejaVu Sans's cap height: 1493 font units of 2048 per em
CAP_HEIGHT = 1493 / 2048


def cap_height(size: float) -> int:
    """Rows covered by "HEH" drawn at ``size`` pixels (a fresh engine: atlases are kept per engine)."""
    from omnirender.gl import GLEngine

    engine = GLEngine(size=(200, 100), samples=0)
    try:
        image = engine.render(om.Node("s", [om.Color(1, 1, 1), om.Text("HEH", position=(0, 0, 0), size=size)]))
    finally:
        engine.release()
    rows = np.nonzero((image.array[..., :3].max(axis=2) > 127).any(axis=1))[0]
    assert rows.size, "no text was drawn"
    return int(rows.max() - rows.min() + 1)


def hide_system_fonts(monkeypatch) -> None:
    """Make every font file outside omnirender's package unreadable, as on a machine without DejaVu."""
    from PIL import ImageFont

    real = ImageFont.truetype
    shipped = font_file().parent

    def truetype(font=None, *args, **kwargs):
        if isinstance(font, (str, Path)) and Path(font).resolve().parent != shipped:
            raise OSError("cannot open resource")
        return real(font, *args, **kwargs)

    monkeypatch.setattr(ImageFont, "truetype", truetype)


def test_32_pixel_text_has_the_same_cap_height_without_system_fonts(monkeypatch):
    installed = cap_height(32)
    hide_system_fonts(monkeypatch)
    hidden = cap_height(32)
    assert abs(hidden - installed) <= 1, f"cap height {installed} px with the system's fonts, {hidden} px without"
    assert abs(hidden - CAP_HEIGHT * 32) <= 1, f"32-px text has a cap height of {hidden} px, not {CAP_HEIGHT * 32:.1f}"


@pytest.mark.parametrize("size", [12, 20, 48])
def test_text_follows_the_requested_size(monkeypatch, size):
    hide_system_fonts(monkeypatch)
    assert abs(cap_height(size) - CAP_HEIGHT * size) <= 1


def test_the_font_and_its_licence_are_package_data():
    path = font_file()
    assert path.name == DEFAULT_FONT and path.stat().st_size > 100_000
    licence = (path.parent / "LICENSE.DejaVu").read_text(encoding="utf-8")
    assert "Bitstream" in licence and "Permission is hereby granted" in licence
    pyproject = (Path(__file__).resolve().parents[2] / "pyproject.toml").read_text(encoding="utf-8")
    assert '"fonts/*.ttf"' in pyproject and '"fonts/LICENSE.*"' in pyproject
