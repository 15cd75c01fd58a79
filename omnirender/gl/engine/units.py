"""The texture units of the GL engine, in one table.

=====================  =======  ==========================================================================
what                   units    bound by
=====================  =======  ==========================================================================
a draw's textures      0-7      the drawer (``DrawState.textures``: materials, layers, bump/roughness maps)
the shadow-map atlas   8        ``ShadowPlan.apply`` (lit mesh programs with ``SHADOW_MAPS``)
a pass's inputs        9-14     the drawer (``Shader(inputs=...)``: targets and textures a pass names)
the material table     15       the deferred pipeline (its G-buffer pass)
=====================  =======  ==========================================================================

Full-screen passes (``FullScreen``) and the drawers of their own kinds (text, volumes) draw alone and bind
their inputs from :data:`FULLSCREEN_FIRST` on.
"""

from __future__ import annotations

__all__ = ["DRAW_TEXTURES", "SHADOW_ATLAS", "PASS_INPUTS", "MATERIAL_TABLE", "FULLSCREEN_FIRST"]

#: how many textures one draw binds (units 0 .. DRAW_TEXTURES - 1)
DRAW_TEXTURES = 8
#: the shadow-map atlas (a depth comparison texture)
SHADOW_ATLAS = 8
#: the first unit of a pass's Shader inputs
PASS_INPUTS = 9
#: the deferred pipeline's material table
MATERIAL_TABLE = 15
#: the first unit of a full-screen pass's (or a custom-kind drawer's) inputs
FULLSCREEN_FIRST = 0
