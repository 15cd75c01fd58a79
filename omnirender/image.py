"""``om.Image``: what every rendering engine returns."""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

import numpy as np

from .fileio import atomic_path

__all__ = ["Image", "develop"]


class Image:
    """A rendered image.

    ``array`` is (H, W, 4) uint8 sRGB with straight alpha; ``depth`` is (H, W)
    float32 eye-space distance along the viewing axis (``inf`` where nothing
    was drawn) or None when the engine cannot tell; ``hdr`` is (H, W, 3 or 4)
    float32 linear radiance for physically based engines, else None.
    ``coverage`` is (H, W) float32 in [0, 1], the fraction of each pixel
    covered by shapes (whatever the background), or None (then the depth or
    the alpha channel tells).  ``info`` holds engine-specific facts (timings,
    sample counts, file names).

    Every engine gives the same meaning to :attr:`mask` (the pixels shapes
    cover, with or without an ``om.Background``) and paints the same default
    background (:data:`~omnirender.attributes.environment.DEFAULT_BACKGROUND`,
    opaque) when the scene has none; ``om.Background((0, 0, 0, 0))`` asks for
    a transparent one.
    """

    __slots__ = ("array", "depth", "hdr", "engine", "info", "coverage")

    def __init__(
        self,
        array: np.ndarray,
        depth: np.ndarray | None = None,
        hdr: np.ndarray | None = None,
        engine: str = "",
        info: dict[str, Any] | None = None,
        coverage: np.ndarray | None = None,
    ) -> None:
        array = np.asarray(array)
        if array.ndim != 3 or array.shape[2] not in (3, 4) or array.dtype != np.uint8:
            hint = ""
            if array.dtype.kind == "f" and array.ndim == 3:
                hint = "; convert floats in [0, 1] with (np.clip(a, 0, 1) * 255 + 0.5).astype(np.uint8)"
            raise ValueError(f"Image: array must be (H, W, 3|4) uint8, got {array.shape} {array.dtype}{hint}")
        if array.shape[0] == 0 or array.shape[1] == 0:
            raise ValueError(f"Image: array must be at least 1x1 pixels, got {array.shape[1]}x{array.shape[0]}")
        if array.shape[2] == 3:
            alpha = np.full(array.shape[:2] + (1,), 255, np.uint8)
            array = np.concatenate([array, alpha], axis=2)
        if depth is not None:
            depth = np.asarray(depth, dtype=np.float32)
            if depth.shape != array.shape[:2]:
                raise ValueError(f"Image: depth must be {array.shape[:2]}, got {depth.shape}")
        if hdr is not None:
            hdr = np.asarray(hdr)
            if hdr.shape[:2] != array.shape[:2] or hdr.ndim != 3 or hdr.shape[2] not in (3, 4) or hdr.dtype.kind != "f":
                raise ValueError(
                    f"Image: hdr must be ({array.shape[0]}, {array.shape[1]}, 3|4) floats (linear radiance), "
                    f"got {hdr.shape} {hdr.dtype}"
                )
        if coverage is not None:
            coverage = np.asarray(coverage, dtype=np.float32)
            if coverage.shape != array.shape[:2]:
                raise ValueError(f"Image: coverage must be {array.shape[:2]}, got {coverage.shape}")
        self.array = array
        self.coverage = coverage
        self.depth = depth
        self.hdr = hdr
        self.engine = engine
        self.info = dict(info or {})

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return (self.array.shape[1], self.array.shape[0])

    @property
    def width(self) -> int:
        return self.array.shape[1]

    @property
    def height(self) -> int:
        return self.array.shape[0]

    @property
    def rgb(self) -> np.ndarray:
        """(H, W, 3) uint8 colour without alpha."""
        return self.array[:, :, :3]

    @property
    def mask(self) -> np.ndarray:
        """(H, W) bool: the pixels shapes cover, whatever the background.

        From the engine's ``coverage`` (pixels at least half covered, as a
        rasteriser's pixel-centre sample decides), else the finite depth, else alpha > 0.
        """
        if self.coverage is not None:
            return self.coverage >= 0.5
        if self.depth is not None:
            return np.isfinite(self.depth)
        return self.array[:, :, 3] > 0

    def pixel(self, x: int, y: int) -> tuple[int, int, int, int]:
        """RGBA at column ``x``, row ``y`` (row 0 at the top); IndexError outside the image."""
        if not (0 <= x < self.width and 0 <= y < self.height):
            raise IndexError(
                f"Image.pixel: ({x}, {y}) is outside the {self.width}x{self.height} image; "
                f"x must lie in [0, {self.width}) and y in [0, {self.height}) (pixel (0, 0) is the top-left one)"
            )
        return tuple(int(v) for v in self.array[y, x])  # type: ignore[return-value]

    def to_pil(self) -> Any:
        from PIL import Image as PILImage

        return PILImage.fromarray(self.array, "RGBA")

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the colour image (format from the extension) atomically; returns the path."""
        target = Path(path)
        fmt = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG", ".bmp": "BMP", ".tif": "TIFF", ".tiff": "TIFF"}.get(
            target.suffix.lower()
        )
        if fmt is None:
            raise ValueError(
                f"Image.save: unsupported extension {target.suffix!r} in {target}; use .png, .jpg, .bmp or .tif"
            )
        pil = self.to_pil()
        if fmt in ("JPEG", "BMP"):
            pil = pil.convert("RGB")
        with atomic_path(target) as tmp:
            pil.save(tmp, format=fmt)
        return target

    def _repr_png_(self) -> bytes:
        buf = io.BytesIO()
        self.to_pil().save(buf, format="PNG")
        return buf.getvalue()

    def __repr__(self) -> str:
        extra = ", depth" if self.depth is not None else ""
        extra += ", hdr" if self.hdr is not None else ""
        return f"Image({self.width}x{self.height}{extra}, engine={self.engine!r})"


def develop(data: np.ndarray, background: Any = None, *, premultiplied: bool = True) -> np.ndarray:
    """Linear RGBA film data (physically based engines) -> (H, W, 4) uint8 sRGB with straight alpha.

    ``premultiplied``: the colour is black where nothing was hit, so dividing
    by coverage gives the straight colour; otherwise the colour already
    contains what is seen behind the shapes and is kept.  With a
    ``background`` RGB(A) colour (sRGB display values) a premultiplied image
    is composited over it.
    """
    from .attributes.photometry import linear_to_srgb, srgb_to_linear

    rgb = np.asarray(data[:, :, :3], np.float64)
    alpha = np.clip(np.asarray(data[:, :, 3], np.float64), 0.0, 1.0)
    if not premultiplied:
        rgb = rgb * alpha[..., None]
    if background is not None:
        bg = np.asarray(background, np.float64)
        bg_alpha = bg[3] if len(bg) > 3 else 1.0
        rgb = rgb + srgb_to_linear(bg[:3]) * (bg_alpha * (1.0 - alpha))[..., None]
        alpha = alpha + bg_alpha * (1.0 - alpha)
    straight = np.where(alpha[..., None] > 1e-6, rgb / np.maximum(alpha, 1e-6)[..., None], 0.0)
    out = np.empty(data.shape[:2] + (4,), np.uint8)
    out[:, :, :3] = np.round(linear_to_srgb(straight) * 255.0)
    out[:, :, 3] = np.round(alpha * 255.0)
    return out
