"""Attribute painters of the GL engine: they only mark what the next draw item must re-read.

They change the compile through its public compile state (``engine.compile_state``, a
:class:`~..engine.compile_state.CompileState`), never the compiler's own attributes.

Material, PBRMaterial and Color go on one surface stack so the innermost of
them decides (a Color inside a Material tints it; a Material inside a Color
replaces it).  Raster-state attributes (every ``om.gl.GLState`` subclass,
through the base class) mark the interned draw state dirty.
Clip planes are captured in world coordinates where they are added (OpenGL's
glClipPlane semantics).
"""

from __future__ import annotations

from typing import Any

from ...attributes import (
    BumpMap,
    ClipPlane,
    Color,
    DrawStyle,
    Fog,
    Highlight,
    Material,
    Mirror,
    MultiTexture,
    PBRMaterial,
    Shadowing,
    Texture,
)
from ...core.handler import AttributePainter, registry
from ...core.light import LightSwitch
from ..engine import attributes as glattr
from ..glengine import GLEngine

__all__ = ["SurfacePainter", "StatePainter", "ClipPlanePainter", "MAX_CLIP_PLANES"]

MAX_CLIP_PLANES = 6


class SurfacePainter(AttributePainter):
    """Material, PBRMaterial, Color: the surface stack."""

    __slots__ = ()
    service = "gl.paint"

    def exec(self, attribute: Any, engine: GLEngine) -> None:
        engine.compile_state.push_surface(attribute)

    def unexec(self, attribute: Any, engine: GLEngine) -> None:
        engine.compile_state.remove_surface(attribute)


class HighlightPainter(AttributePainter):
    __slots__ = ()
    service = "gl.paint"
    target = Highlight

    def exec(self, attribute: Any, engine: GLEngine) -> None:
        engine.compile_state.surface_changed()

    unexec = exec


class StatePainter(AttributePainter):
    """Raster state (draw style, texture, fog, light switch, GL attributes): re-read on the next draw item."""

    __slots__ = ()
    service = "gl.paint"

    def exec(self, attribute: Any, engine: GLEngine) -> None:
        engine.compile_state.state_changed()

    unexec = exec


class ClipPlanePainter(AttributePainter):
    """Capture the plane in world coordinates; at most six at a time (gl_ClipDistance[0..5])."""

    __slots__ = ()
    service = "gl.paint"
    target = ClipPlane

    def exec(self, attribute: ClipPlane, engine: GLEngine) -> None:
        state = engine.compile_state
        if state.clip_count >= MAX_CLIP_PLANES:
            raise ValueError(
                f"ClipPlane in node {engine.node_path}: at most {MAX_CLIP_PLANES} clip planes can be active at once "
                f"in the GL engine; remove one"
            )
        plane = attribute.world_plane(engine.model_matrix())
        state.push_clip(attribute, tuple(float(x) for x in plane))  # type: ignore[arg-type]

    def unexec(self, attribute: ClipPlane, engine: GLEngine) -> None:
        engine.compile_state.remove_clip(attribute)


def _register() -> None:
    for target in (Material, PBRMaterial, Color):
        cls = type(f"SurfacePainter_{target.__name__}", (SurfacePainter,), {"__slots__": (), "target": target})
        registry.register(cls(), [GLEngine])
    # every GL state attribute, also one defined later, through the base class (handler look-up walks the MRO)
    state_targets = (DrawStyle, Texture, MultiTexture, BumpMap, Fog, LightSwitch, Shadowing, Mirror, glattr.GLState)
    for target in state_targets:
        cls = type(f"StatePainter_{target.__name__}", (StatePainter,), {"__slots__": (), "target": target})
        registry.register(cls(), [GLEngine])
    registry.register(HighlightPainter(), [GLEngine])
    from ..deferred.models import MaterialDescription

    registry.register(type("MaterialDescriptionPainter", (HighlightPainter,), {"__slots__": (),
                                                                                "target": MaterialDescription})(),
                      [GLEngine])  # fmt: skip
    registry.register(ClipPlanePainter(), [GLEngine])


_register()
