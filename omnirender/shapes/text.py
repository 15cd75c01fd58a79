"""Text: a 2D label anchored at a 3D point."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from . import _check
from .base import DeclaredShape, parameter

__all__ = ["Text"]


class Text(DeclaredShape):
    """A screen-aligned label ``string`` whose lower-left corner is at the projection of ``position``.

    ``size`` is the text height in pixels (> 0).  Render hints mark it
    two-dimensional (``"2d"``): viewers draw it after the 3D scene, and engines
    without a text painter skip it (its default simplifier yields nothing).
    """

    __slots__ = ("_string", "_position", "_size")
    _params = ("string", "position", "size")
    string = parameter("string", "The text.")
    position = parameter("position", "Anchor (x, y, z) in model coordinates (2 numbers: z = 0).")
    size = parameter("size", "Text height in pixels, > 0.")

    hints = frozenset({"2d"})

    def __init__(self, string: str, position: Sequence[float] = (0.0, 0.0, 0.0), size: float = 16.0) -> None:
        super().__init__(string=string, position=position, size=size)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        if not isinstance(p["string"], str):
            raise ValueError(f"Text: string must be a str, got {type(p['string']).__name__}")
        pos = p["position"]
        try:
            if len(pos) == 2:
                pos = (*pos, 0.0)
        except TypeError:
            pass
        return {
            "string": p["string"],
            "position": _check.vector("Text", "position", pos, 3),
            "size": _check.scalar("Text", "size", p["size"], positive=True),
        }, {}
