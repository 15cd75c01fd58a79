"""Radiance pictures (RGBE, ``.hdr``) written with numpy, and ``rpict``'s raw depth files read back.

Textures reach ``colorpict``/``mixpict`` as pictures of linear values.  Rows
are written top first under the standard ``-Y H +X W`` orientation, so
Radiance's picture coordinate ``v = 0`` is the image's bottom row, as
omnirender's texture coordinates (OpenGL's) expect.  Scanlines of 8 to 32767
pixels use Radiance's run-length format (with literal runs only), which a
reader cannot mistake for the flat format whatever the first pixel is.
"""

from __future__ import annotations

import os

import numpy as np

__all__ = ["rgbe", "picture_bytes", "write_picture", "read_depth", "FHUGE"]

#: What ``rpict -z`` writes for rays that hit nothing (Radiance's FHUGE).
FHUGE = 1e10


def rgbe(rgb: np.ndarray) -> np.ndarray:
    """(H, W, 3) linear floats >= 0 to (H, W, 4) uint8 RGBE (Ward's shared-exponent encoding)."""
    rgb = np.clip(np.asarray(rgb, dtype=np.float64), 0.0, None)
    v = rgb.max(axis=2)
    mantissa, exponent = np.frexp(v)
    scale = np.where(v > 1e-32, mantissa * 256.0 / np.where(v > 1e-32, v, 1.0), 0.0)
    out = np.zeros(rgb.shape[:2] + (4,), np.uint8)
    out[:, :, :3] = np.clip(np.floor(rgb * scale[:, :, None]), 0, 255).astype(np.uint8)
    out[:, :, 3] = np.where(v > 1e-32, exponent + 128, 0).astype(np.uint8)
    return out


def _scanlines(pixels: np.ndarray) -> bytes:
    """New-style run-length scanlines with literal runs of at most 128 bytes per component."""
    h, w = pixels.shape[:2]
    chunks = -(-w // 128)
    starts = np.arange(chunks) * 128
    lengths = np.minimum(128, w - starts)
    # each component of a scanline: [len, bytes..., len, bytes...]
    positions = starts + np.arange(chunks)  # where each length byte goes
    is_data = np.ones(w + chunks, bool)
    is_data[positions] = False
    out = np.empty((h, 4, w + chunks), np.uint8)
    out[:, :, positions] = lengths.astype(np.uint8)
    out[:, :, is_data] = np.transpose(pixels, (0, 2, 1))
    header = np.empty((h, 4), np.uint8)
    header[:] = (2, 2, w >> 8, w & 255)
    return np.concatenate([header, out.reshape(h, -1)], axis=1).tobytes()


def picture_bytes(rgb: np.ndarray) -> bytes:
    """A complete Radiance picture of (H, W, 3) linear values."""
    pixels = rgbe(rgb)
    h, w = pixels.shape[:2]
    head = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n".encode("ascii")
    body = _scanlines(pixels) if 8 <= w <= 0x7FFF else pixels.tobytes()
    return head + body


def write_picture(path: str | os.PathLike[str], rgb: np.ndarray) -> None:
    """Write (H, W, 3) linear values as a Radiance picture file."""
    with open(path, "wb") as fh:
        fh.write(picture_bytes(rgb))


def read_depth(path: str | os.PathLike[str], size: tuple[int, int]) -> np.ndarray:
    """``rpict -z`` output: (H, W) float32 ray distances from the view's fore plane (FHUGE for misses)."""
    w, h = size
    data = np.fromfile(path, dtype=np.float32)
    if data.size != w * h:
        raise ValueError(f"Radiance: rpict wrote {data.size} depth values, expected {w}x{h}")
    return data.reshape(h, w)
