"""The compile state attribute painters change: element stacks and what the next draw item re-resolves.

Coin3D keeps the traversal state in ``SoState`` element stacks that actions
push and pop; the GL engine's compile keeps the few stacks that are not the
core's attribute stacks here: the *surface* stack (``Material``,
``PBRMaterial``, ``Color``, innermost decides), the active clip planes in
world coordinates, and two dirty flags.  Attribute painters (``gl/painters/
attributes.py``) change it only through these methods; the
:class:`~.compiler.DrawListCompiler` owns it, reads the stacks and clears the
flags when it resolved the draw state and the surface row again.
"""

from __future__ import annotations

from typing import Any

__all__ = ["CompileState"]


class CompileState:
    """The surface stack, the clip planes and the dirty flags of one compile (see the module doc)."""

    __slots__ = ("surface", "clips", "state_dirty", "surface_dirty", "changes")

    def __init__(self) -> None:
        #: Material, PBRMaterial and Color attributes in force, outermost first
        self.surface: list[Any] = []
        #: (ClipPlane, world plane (a, b, c, d)) of the active clip planes, outermost first
        self.clips: list[tuple[Any, tuple[float, float, float, float]]] = []
        #: the draw state (raster state, features, clip planes, fog...) must be resolved again
        self.state_dirty = True
        #: the surface row and texture set must be resolved again
        self.surface_dirty = True
        #: bumped whenever anything but the surface stack changes (raster state, textures, clip planes,
        #: highlight...): what the compiler read besides the surface stack holds while it has not moved
        self.changes = 0

    def push_surface(self, attribute: Any) -> None:
        """``attribute`` (a Material, PBRMaterial or Color) is in force from now on."""
        self.surface.append(attribute)
        self.surface_dirty = True

    def remove_surface(self, attribute: Any) -> None:
        """``attribute`` is no longer in force (the innermost occurrence of it leaves the stack)."""
        surface = self.surface
        for i in range(len(surface) - 1, -1, -1):
            if surface[i] is attribute:
                del surface[i]
                break
        self.surface_dirty = True

    def push_clip(self, attribute: Any, plane: tuple[float, float, float, float]) -> None:
        """The clip plane ``attribute`` is active, as ``plane`` in world coordinates."""
        self.clips.append((attribute, plane))
        self.state_dirty = True
        self.changes += 1

    def remove_clip(self, attribute: Any) -> None:
        """The clip plane ``attribute`` is no longer active."""
        clips = self.clips
        for i in range(len(clips) - 1, -1, -1):
            if clips[i][0] is attribute:
                del clips[i]
                break
        self.state_dirty = True
        self.changes += 1

    @property
    def clip_count(self) -> int:
        """How many clip planes are active."""
        return len(self.clips)

    def state_changed(self) -> None:
        """A raster-state attribute (draw style, texture, fog, an ``om.gl`` state...) came or went."""
        self.state_dirty = True
        self.surface_dirty = True
        self.changes += 1

    def surface_changed(self) -> None:
        """Something the surface row reads (a Highlight, a material description) came or went."""
        self.surface_dirty = True
        self.changes += 1

    def invalidate(self) -> None:
        """Resolve everything again before the next draw item (a new traversal begins)."""
        self.state_dirty = True
        self.surface_dirty = True
        self.changes += 1

    def clear(self) -> None:
        """Drop the stacks after a failed compile (the traversal state was rolled back)."""
        self.surface.clear()
        self.clips.clear()
        self.invalidate()
