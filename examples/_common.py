"""Shared helpers for the examples: where images go, and side-by-side composites."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import omnirender as om


def output_dir() -> Path:
    """The folder given as the first argument, else examples/output/ (git-ignored).

    Long work reports its progress: a bar on a terminal, lines on stderr elsewhere (omnirender.progress).
    """
    from omnirender.progress import show_progress_lines

    show_progress_lines()
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent / "output"
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def side_by_side(images: list[om.Image], gap: int = 4) -> om.Image:
    """One image with ``images`` next to each other (same height), separated by white gaps."""
    h = max(img.height for img in images)
    parts = []
    for i, img in enumerate(images):
        if i:
            parts.append(np.full((h, gap, 4), 255, np.uint8))
        pad = np.full((h - img.height, img.width, 4), 255, np.uint8)
        parts.append(np.concatenate([img.array, pad]) if len(pad) else img.array)
    return om.Image(np.concatenate(parts, axis=1))
