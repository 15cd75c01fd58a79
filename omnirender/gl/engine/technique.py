"""The base class of multi-pass GL effects (:class:`GLTechnique`).

A :class:`GLTechnique` is put into a scene like an attribute; it scopes the
rest of its node.  The GL engine compiles what it scopes once and, on every
frame, calls its pass control: ``prepare_pass`` describes each pass with
``engine.set_pass(om.gl.Pass(...))`` (see :mod:`.passes`).  Engines that
cannot run GL passes ignore it and evaluate what it scopes once
(``supported``): POV-Ray and Mitsuba render the scene without the effect.

The default technique, ``Forward``, lives in ``gl/techniques/forward.py``.
"""

from __future__ import annotations

from typing import Any

from ...core.technique import Technique

__all__ = ["GLTechnique"]


class GLTechnique(Technique):
    """Base of GL multi-pass techniques: supported only by the GL engine.

    Subclasses describe their passes in ``prepare_pass`` with
    ``engine.set_pass(Pass(...))``; the pass index is ``engine.current_pass``.
    What other engines do instead: they evaluate the technique's scope once,
    as if the technique were not there.
    """

    __slots__ = ()

    def __init__(self, passes: int = 1) -> None:
        super().__init__(service=None, passes=passes)

    def supported(self, engine: Any) -> bool:
        return callable(getattr(engine, "set_pass", None))

    def parameters(self) -> dict:
        """The subclass's own public parameters (its pass count and service are fixed by the class)."""
        params = super().parameters()
        params.pop("service", None)
        params.pop("passes", None)
        return params
