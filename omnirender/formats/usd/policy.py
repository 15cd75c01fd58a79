"""The asset path policy for USD stages: layers and textures inside the stage's folder unless trusted.

USD composes the stage itself (sublayers, references, payloads, variants);
what it reached is checked here: every layer the stage used and every texture
it names must resolve inside the folder of the root layer (symlinks followed),
or inside a ``.usdz`` package there.  Absolute paths elsewhere, ``..``
escapes and URL schemes raise :class:`UntrustedContentError` unless the
caller trusts the file (``trusted=True``, ``--trusted`` on the command line).
An in-memory stage (no folder) is taken as trusted: its author is the caller.

This is the USD reader's own small check; when the project's shared path
policy lands, it should call that instead (one rule for every loader).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

from ...scene.registry import UntrustedContentError

__all__ = ["check_layers", "check_asset", "usd_error", "UntrustedContentError"]

_URL = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]+:")  # a scheme (one letter would be a Windows drive)


def usd_error(name: str, message: str) -> ValueError:
    """An error naming the stage."""
    return ValueError(f"load_usd {name}: {message}")


def _inside(path: str, folder: Path) -> bool:
    package = path.split("[", 1)[0] if path.endswith("]") else path  # "a.usdz[tex.png]": the package file
    try:
        real = Path(os.path.realpath(package))
        return real == folder or folder in real.parents
    except (OSError, ValueError):
        return False


def check_asset(authored: str, resolved: str, folder: Path | None, trusted: bool, what: str) -> None:
    """Refuse ``authored`` (resolved to ``resolved``) when it leaves ``folder`` and the stage is not trusted."""
    if trusted or folder is None:
        return
    if _URL.match(authored):
        raise UntrustedContentError(what, f"{authored!r} is a URL; only files inside {str(folder)!r} are read")
    if resolved and not _inside(resolved, Path(os.path.realpath(folder))):
        raise UntrustedContentError(
            what, f"{authored!r} resolves to {resolved!r}, outside the stage's folder {str(folder)!r}"
        )


def check_layers(stage: Any, folder: Path | None, trusted: bool) -> None:
    """Every layer the composed stage used lies inside ``folder`` (or the stage is trusted)."""
    if trusted or folder is None:
        return
    for layer in stage.GetUsedLayers():
        if layer.anonymous or not layer.realPath:
            continue
        check_asset(layer.identifier, layer.realPath, folder, trusted, f"load_usd {stage.GetRootLayer().identifier}")
