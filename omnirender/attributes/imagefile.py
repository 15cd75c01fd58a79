"""Decoding image files within :mod:`omnirender.core.limits` (decompression bombs refused before decoding).

Every image omnirender reads from a file (a ``Texture`` path, a glTF image, an
OBJ texture map) goes through :func:`read_image`: Pillow reads the header, the
announced size is checked against ``MAX_IMAGE_SIDE`` / ``MAX_IMAGE_PIXELS``,
and only then are the pixels decoded.
"""

from __future__ import annotations

import io
import os
import re
import struct
import warnings
from typing import Any

import numpy as np

from ..core import limits
from ..core.limits import ResourceLimitError, check_image_size

__all__ = ["read_image", "image_header_size"]


def _open(source: bytes | str | os.PathLike[str]) -> Any:
    try:
        from PIL import Image as PILImage
    except ImportError:  # pragma: no cover - Pillow is a dependency of the gl extra
        raise RuntimeError("reading image files needs Pillow (pip install pillow)") from None
    return PILImage.open(io.BytesIO(source) if isinstance(source, (bytes, bytearray, memoryview)) else source)


def image_header_size(source: bytes | str | os.PathLike[str]) -> tuple[int, int]:
    """(width, height) an image file announces, without decoding it; OSError when it is not an image."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Pillow's own bomb warning: core.limits decides
        with _open(source) as img:
            return int(img.size[0]), int(img.size[1])


def read_image(source: bytes | str | os.PathLike[str], name: str, what: str = "the image") -> np.ndarray:
    """The image in ``source`` (bytes or a path) as an (H, W, 4) uint8 RGBA array.

    ``name`` (the file, or the file holding the bytes) and ``what`` name the
    image in errors.  Raises :class:`~omnirender.core.limits.ResourceLimitError`
    for an image beyond the limits, FileNotFoundError for a missing file and
    ValueError for one that is not a readable image.
    """
    from PIL import Image as PILImage

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PILImage.DecompressionBombWarning)
            with _open(source) as img:
                check_image_size(name, what, int(img.size[0]), int(img.size[1]))
                return np.asarray(img.convert("RGBA"), dtype=np.uint8)
    except ResourceLimitError:
        raise
    except FileNotFoundError:
        raise FileNotFoundError(f"{name}: {what} does not exist") from None
    except PILImage.DecompressionBombError as exc:  # Pillow refuses at open() beyond twice its own limit
        found = re.search(r"\((\d+) pixels\)", str(exc))
        count = f"{int(found.group(1)):,} pixels" if found else "too many pixels"
        raise ResourceLimitError(
            name,
            f"{what} announces {count}, more than {limits.MAX_IMAGE_PIXELS:,} (a decompression bomb?); Pillow "
            f"refuses it too (its PIL.Image.MAX_IMAGE_PIXELS)",
            "MAX_IMAGE_PIXELS",
        ) from None
    except (OSError, SyntaxError, ValueError, EOFError, IndexError, struct.error) as exc:
        raise ValueError(f"{name}: {what} is not a readable image ({type(exc).__name__}: {exc})") from None
