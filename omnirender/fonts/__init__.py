"""Fonts shipped with omnirender, so text has the same glyphs and pixel sizes on every machine.

``DejaVuSans.ttf`` is DejaVu Sans 2.37 under the Bitstream Vera licence (DejaVu's changes are in
the public domain); the licence is ``LICENSE.DejaVu`` next to it.  Engines that draw text load it
with :func:`font_file` instead of searching the system's fonts, whose presence (and whose fallback,
a fixed-size bitmap font that ignores the requested size) differs between machines.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["font_file", "DEFAULT_FONT"]

#: The font text is drawn with.
DEFAULT_FONT = "DejaVuSans.ttf"


def font_file(name: str = DEFAULT_FONT) -> Path:
    """The path of the shipped font ``name`` (FileNotFoundError naming the fix when the file is missing)."""
    path = Path(__file__).resolve().parent / name
    if not path.is_file():
        raise FileNotFoundError(
            f"omnirender.fonts: {path} is missing; reinstall omnirender (the font is package data of omnirender/fonts)"
        )
    return path
