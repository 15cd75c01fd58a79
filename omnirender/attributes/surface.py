"""Surface resolution shared by engines that translate appearance to another renderer.

Engines that do not draw through OpenGL (Mitsuba, the exporters) need to know
which appearance applies to a shape the way the GL engine sees it: the
innermost ``Material`` or ``PBRMaterial``, and a ``Color`` only if it became
active after that material (it then replaces the material's colour).  They
keep the appearance attributes in activation order with tracking painters
registered by :func:`track_surfaces` and resolve them with :func:`resolve_surface`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..core import AttributePainter, default_for
from .appearance import Color, Material, PBRMaterial

__all__ = ["resolve_surface", "track_surfaces", "SurfaceTracker"]


def resolve_surface(stack: Sequence[Any]) -> tuple[Any, Any]:
    """(material, colour) from appearance attributes in activation order (either may be None)."""
    material = color = None
    for attr in reversed(stack):
        if isinstance(attr, Color):
            if color is None:
                color = attr
        else:
            material = attr
            break
    return material, color


class SurfaceTracker(AttributePainter):
    """Keeps ``engine.surface_stack`` (a list) in activation order."""

    __slots__ = ()

    def exec(self, attribute: Any, engine: Any) -> None:
        engine.surface_stack.append(attribute)

    def unexec(self, attribute: Any, engine: Any) -> None:
        stack = engine.surface_stack
        for i in range(len(stack) - 1, -1, -1):
            if stack[i] is attribute:
                del stack[i]
                return


def track_surfaces(engine_cls: type) -> None:
    """Register surface trackers for Color, Material and PBRMaterial as defaults of ``engine_cls``."""
    for target in (Color, Material, PBRMaterial):
        name = f"{engine_cls.__name__}{target.__name__}Tracker"
        cls = type(name, (SurfaceTracker,), {"__slots__": (), "service": engine_cls.service, "target": target})
        default_for(engine_cls)(cls)
