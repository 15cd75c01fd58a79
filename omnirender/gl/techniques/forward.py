"""The default GL technique, :class:`Forward`.

:class:`Forward` is the engine's default technique: opaque items front to
back, transparent items back to front with blending and without depth writes,
2D overlays last.  Every pass that draws items runs it, so nested techniques'
passes draw transparency and text the usual way.  Replace it with
``GLEngine(technique=...)``.
"""

from __future__ import annotations

from typing import Any

from ..engine.attributes import Blend, ColorMask, DepthMask
from ..engine.passes import Pass, Shader
from ..engine.technique import GLTechnique

__all__ = ["Forward"]


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
    #: its passes are the same every frame (data): a steady frame may replay them (``gl/engine/plan.py``);
    #: a subclass is replayable only when it says so itself
    replayable = True
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
