"""Mitsuba 3 adapter (``om.mitsuba``): a physically based engine over the same scene graph.

``om.render(scene, engine="mitsuba", size=(w, h), spp=64)`` renders with the
``scalar_rgb`` variant (never ``llvm_*``: it aborts the process on machines
without a working LLVM).  ``MitsubaEngine`` builds the Mitsuba scene through
handlers of service ``"mitsuba.paint"``; :class:`BSDF`, :class:`Emitter` and
:class:`Integrator` pass Mitsuba's own plugins through and are ignored by the
other engines.  Mitsuba itself is imported on first use only.
"""

from __future__ import annotations

from typing import Any

from . import painters  # noqa: F401  (registers the default handlers)
from ._mi import VARIANT
from ._mi import available as _available
from .attributes import BSDF, Emitter, Integrator
from .engine import MitsubaEngine

__all__ = ["render", "available", "MitsubaEngine", "BSDF", "Emitter", "Integrator", "VARIANT"]


def available() -> tuple[bool, str]:
    """(True, description) when Mitsuba with the ``scalar_rgb`` variant can be used, else (False, reason)."""
    return _available()


def render(scene: Any, size: tuple[int, int] = (640, 480), spp: int | None = None, **options: Any) -> Any:
    """Render ``scene`` with Mitsuba 3; see :func:`omnirender.mitsuba.rendering.render` for the options."""
    import inspect

    from .rendering import render as _render

    accepted = [p for p in inspect.signature(_render).parameters if p not in ("scene", "size", "spp")]
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        from ..options import options_hint

        raise TypeError(
            f"mitsuba.render: unknown option(s) {unknown}; accepted: spp, {', '.join(accepted)}"
            + options_hint(unknown, ["spp", *accepted])
        )
    return _render(scene, size, spp, **options)
