"""``om.video``: frames to an MP4 (imageio + imageio-ffmpeg, H.264) or an animated GIF (Pillow).

The file is written atomically: a video being encoded never replaces a good
one until it is complete.
"""

from __future__ import annotations

import glob
import os
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ..fileio import atomic_path

__all__ = ["video", "VIDEO_EXTENSIONS"]

#: Extensions ``om.video`` writes: GIF through Pillow, the others through ffmpeg.
VIDEO_EXTENSIONS = (".mp4", ".mov", ".mkv", ".webm", ".gif")
_INSTALL = "pip install 'omnirender[video]'"


def _frame_list(frames: Any) -> list[Any]:
    """Paths or arrays from a FrameReport, a pattern (``frames/%05d.png``, a glob) or a sequence."""
    if hasattr(frames, "files") and hasattr(frames, "paths"):  # a FrameReport
        return list(frames.files)
    if isinstance(frames, (str, os.PathLike)):
        text = os.fspath(frames)
        if "%" in text or "{frame" in text:  # a render_frames pattern: its frame field becomes a wildcard
            text = os.path.join(glob.escape(os.path.dirname(text)), _wildcard(os.path.basename(text)))
        found = sorted(glob.glob(text), key=_natural)
        if not found:
            raise FileNotFoundError(f"om.video: no frame files match {os.fspath(frames)!r}")
        return found
    if isinstance(frames, Iterable):
        return list(frames)
    raise TypeError(f"om.video: frames must be frame files, images or arrays, got {type(frames).__name__}")


def _wildcard(name: str) -> str:
    """``%05d.png`` / ``{frame:05d}.png`` -> ``*.png`` (the frame field as a glob wildcard)."""
    return re.sub(r"%0?\d*d|\{frame[^}]*\}", "*", name)


def _natural(name: str) -> list[Any]:
    """Sort key putting ``2.png`` before ``10.png``."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", name)]


def _array(frame: Any, index: int) -> np.ndarray:
    if hasattr(frame, "array") and not isinstance(frame, np.ndarray):  # om.Image
        frame = frame.array
    if isinstance(frame, (str, os.PathLike)):
        from PIL import Image as PILImage

        try:
            with PILImage.open(frame) as img:
                frame = np.asarray(img.convert("RGB"))
        except OSError as exc:
            raise ValueError(f"om.video: frame {index} ({os.fspath(frame)!r}) is not a readable image: {exc}") from None
    arr = np.asarray(frame)
    if arr.ndim != 3 or arr.shape[2] not in (3, 4) or arr.dtype != np.uint8:
        raise ValueError(f"om.video: frame {index} must be an (H, W, 3|4) uint8 image, got {arr.dtype} {arr.shape}")
    return np.ascontiguousarray(arr[:, :, :3])


def video(frames: Any, path: str | os.PathLike[str], fps: float = 24.0, quality: int = 8, loop: int = 0) -> Path:
    """Write ``frames`` as a video or GIF at ``path`` (format from the extension); returns the path.

    ``frames``: a :class:`FrameReport`, a frame-file pattern (``"frames/%05d.png"``
    or a glob), or a list of files, ``om.Image`` s or (H, W, 3|4) uint8 arrays,
    all the same size.  ``quality`` (0-10) is the MP4 encoder's; ``loop`` is
    the GIF's repeat count (0: forever).
    """
    target = Path(path)
    ext = target.suffix.lower()
    if ext not in VIDEO_EXTENSIONS:
        raise ValueError(f"om.video: cannot write {target.name!r}; use one of {', '.join(VIDEO_EXTENSIONS)}")
    try:
        rate = float(fps)
    except (TypeError, ValueError):
        raise ValueError(f"om.video: fps must be a positive number, got {fps!r}") from None
    if not rate > 0 or not np.isfinite(rate):
        raise ValueError(f"om.video: fps must be a positive number, got {fps!r}")
    items = _frame_list(frames)
    if not items:
        raise ValueError("om.video: no frames")
    first = _array(items[0], 0)
    shape = first.shape

    def arrays() -> Iterable[np.ndarray]:
        yield first
        for i, item in enumerate(items[1:], start=1):
            arr = _array(item, i)
            if arr.shape != shape:
                raise ValueError(f"om.video: frame {i} is {arr.shape[1]}x{arr.shape[0]}, frame 0 {shape[1]}x{shape[0]}")
            yield arr

    target.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(target) as tmp:
        if ext == ".gif":
            _gif(arrays(), tmp, rate, loop)
        else:
            _ffmpeg(arrays(), tmp, rate, quality)
    return target


def _gif(arrays: Iterable[np.ndarray], path: Path, fps: float, loop: int) -> None:
    from PIL import Image as PILImage

    images = [PILImage.fromarray(a) for a in arrays]
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:], duration=round(1000.0 / fps), loop=loop)


def _ffmpeg(arrays: Iterable[np.ndarray], path: Path, fps: float, quality: int) -> None:
    try:
        import imageio.v2 as imageio
        import imageio_ffmpeg  # noqa: F401  (imageio finds ffmpeg through it)
    except ImportError:
        raise RuntimeError(f"om.video: MP4 needs imageio and imageio-ffmpeg: {_INSTALL}") from None
    writer = imageio.get_writer(
        path, format="FFMPEG", mode="I", fps=fps, codec="libx264", quality=quality, pixelformat="yuv420p",
        macro_block_size=1, ffmpeg_log_level="error",
    )  # fmt: skip
    try:
        for arr in arrays:
            # yuv420p halves the chroma resolution: even sizes only (an odd edge is repeated)
            pad = ((0, arr.shape[0] % 2), (0, arr.shape[1] % 2), (0, 0))
            writer.append_data(np.pad(arr, pad, mode="edge") if any(p[1] for p in pad) else arr)
    finally:
        writer.close()
