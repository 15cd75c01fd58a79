"""GL techniques: the base class of multi-pass GL effects, and the default forward technique.

A :class:`GLTechnique` is put into a scene like an attribute; it scopes the
rest of its node.  The GL engine compiles what it scopes once and, on every
frame, calls its pass control: ``prepare_pass`` describes each pass with
``engine.set_pass(om.gl.Pass(...))`` (see :mod:`.passes`).  Engines that
cannot run GL passes ignore it and evaluate what it scopes once
(``supported``): POV-Ray and Mitsuba render the scene without the effect.

:class:`Forward` is the engine's default technique: opaque items front to
back, transparent items back to front with blending and without depth writes,
2D overlays last.  Every pass that draws items runs it, so nested techniques'
passes draw transparency and text the usual way.  Replace it with
``GLEngine(technique=...)``.
"""

from __future__ import annotations

from typing import Any

from ..core.technique import Technique
from .attributes import Blend, ColorMask, DepthMask
from .passes import Pass, Shader

__all__ = ["GLTechnique", "Forward"]


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


class Forward(GLTechnique):
    """The default GL technique: three passes, opaque, transparent, overlay.

    * ``opaque``: opaque items, batched and instanced (big batches front to
      back, so early depth tests skip hidden fragments), and the nested
      technique scopes where they were met;
    * ``transparent``: transparent items back to front, blended ("over" where
      no ``Blend`` is set), depth writes off, closed shapes back faces first;
    * ``transparent depth``: the transparent items' depth where their alpha is
      at least one half, colour untouched, so the depth (and the mask) of the
      image shows them as POV-Ray, Mitsuba and picking do;
    * ``overlay``: 2D items (text) over everything.
    """

    __slots__ = ()
    PASSES = (
        Pass("opaque", items="opaque"),
        Pass("transparent", items="transparent", scopes=False),
        Pass(
            "transparent depth",
            items="transparent",
            scopes=False,
            state=(ColorMask(False, False, False, False), DepthMask(True), Blend(None)),
            shader=Shader(depth_only=True, alpha_cutoff=0.5),
        ),
        Pass("overlay", items="overlay", scopes=False),
    )

    def __init__(self) -> None:
        super().__init__(passes=len(self.PASSES))

    def prepare_pass(self, engine: Any) -> None:
        engine.set_pass(self.PASSES[engine.current_pass])
