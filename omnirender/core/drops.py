"""Nothing is dropped silently: what a loader cannot use is a warning, or an error when the caller is strict.

A texture whose image is missing, a ``http://`` image, a decompression bomb, a
material library that cannot be read, an extension omnirender does not
support: the model still loads (without it), and :func:`report_drop` says so
with a :class:`DroppedContentWarning` naming the file and what was dropped.
A pipeline that must not publish a model without its textures passes
``strict=True`` to the loader: the same report then raises
:class:`DroppedContentError` (a ValueError).  Filter the warnings with
``warnings.filterwarnings("ignore", category=om.DroppedContentWarning)``.
"""

from __future__ import annotations

import warnings

__all__ = ["DroppedContentWarning", "DroppedContentError", "report_drop"]


class DroppedContentWarning(UserWarning):
    """Part of a file (a texture, a material, an extension) could not be used and was left out."""


class DroppedContentError(ValueError):
    """Raised instead of :class:`DroppedContentWarning` when the loader was called with ``strict=True``."""


def report_drop(source: str, message: str, *, strict: bool = False, stacklevel: int = 3) -> None:
    """Warn (or raise, when ``strict``) that ``source`` lost something: ``message`` says what and why.

    The text reads ``"<source>: <message>"``; write ``message`` as "images[2]
    ('http://x/y.png') dropped: omnirender never downloads" so a reader knows
    what is missing from the result.
    """
    text = f"{source}: {message}"
    if strict:
        raise DroppedContentError(f"{text} (strict=True turns this warning into an error)")
    warnings.warn(text, DroppedContentWarning, stacklevel=stacklevel)
