"""Intel Open Image Denoise for Mitsuba's previews (the PyPI package ``pyoidn`` ships the library).

A path tracer's image at a few samples per pixel is grainy; OIDN's ``RT``
filter, given the noisy linear radiance (optionally with the first hit's albedo
and shading normal), returns a clean image.  The Mitsuba renderer passes the
colour alone (see docs/NOTES.md: the auxiliary images cost more than they
gain there).  :func:`denoise` is the only place that talks to pyoidn.
"""

from __future__ import annotations

import numpy as np

__all__ = ["available", "denoise", "INSTALL"]

#: What installs the denoiser.
INSTALL = "pip install 'omnirender[mitsuba]' (or pip install pyoidn)"


def available() -> bool:
    """True when pyoidn can be imported."""
    try:
        import pyoidn  # noqa: F401
    except Exception:  # ImportError, or a broken native library
        return False
    return True


def denoise(color: np.ndarray, albedo: np.ndarray | None = None, normal: np.ndarray | None = None) -> np.ndarray:
    """The denoised (H, W, 3) float32 linear radiance of ``color`` (HDR, any range), with optional
    first-hit ``albedo`` and ``normal`` images of the same shape (they keep edges and textures sharp)."""
    import pyoidn

    def prepared(image: np.ndarray | None) -> np.ndarray | None:
        if image is None:
            return None
        return np.ascontiguousarray(np.nan_to_num(image[..., :3], nan=0.0, posinf=0.0, neginf=0.0), np.float32)

    color32 = prepared(color)
    assert color32 is not None
    albedo32 = prepared(albedo)
    normal32 = prepared(normal) if albedo32 is not None else None  # OIDN takes a normal only with an albedo
    if albedo32 is not None:
        np.clip(albedo32, 0.0, 1.0, out=albedo32)
    out = pyoidn.denoise(color32, albedo32, normal32, hdr=True, quality="high")
    return np.maximum(np.asarray(out, dtype=np.float32), 0.0)
