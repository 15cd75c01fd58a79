"""Post-processing: a user-ordered chain of image-space effects (``om.gl.PostProcess``) in linear HDR.

See :mod:`.chain` for the passes of a frame with a chain and :mod:`.effects` for the effects.
"""

from __future__ import annotations

from .chain import PostProcess
from .effects import (
    FXAA,
    SSAO,
    Bloom,
    ColorGrading,
    CustomEffect,
    DepthFog,
    DepthOfField,
    Effect,
    LightShafts,
    ToneMap,
    Vignette,
)

__all__ = [
    "PostProcess",
    "Effect",
    "FXAA",
    "ToneMap",
    "Bloom",
    "SSAO",
    "DepthFog",
    "Vignette",
    "LightShafts",
    "DepthOfField",
    "ColorGrading",
    "CustomEffect",
]
