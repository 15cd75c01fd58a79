"""Frame drivers: how a viewer gets a frame out of a particular engine.

The viewer builds a :class:`~omnirender.viewer.frame.FrameRoot` and hands it
to a driver, which prepares the engine's target, runs the frame and returns an
``om.Image`` (or None for engines that draw nothing, e.g. recorders in tests).
``begin_pass`` is called before each of the four passes and once with
``"end"``; engines that support it switch blending and depth testing there.
"""

from __future__ import annotations

from typing import Any

from ..core.engine import Engine

__all__ = ["EngineDriver", "driver_for"]


class EngineDriver:
    """Runs frames on any ``om.Engine``; uses the engine's optional frame hooks.

    Hooks an engine may offer: ``begin_frame(viewer)``, ``begin_pass(name)``,
    ``end_frame() -> om.Image``.
    """

    def __init__(self, engine: Engine, viewer: Any) -> None:
        self.engine = engine
        self.viewer = viewer

    def draw(self, root: Any) -> Any:
        mask = getattr(self.viewer, "mask", None)
        if self.engine.mask != mask:
            self.engine.mask = mask
        begin = getattr(self.engine, "begin_frame", None)
        if begin is not None:
            begin(self.viewer)
        self.engine.run(root)
        end = getattr(self.engine, "end_frame", None)
        return end() if end is not None else None

    def begin_pass(self, engine: Engine, name: str) -> None:
        hook = getattr(engine, "begin_pass", None)
        if hook is not None:
            hook(name)

    def pass_attributes(self, name: str) -> list[Any]:
        """Attributes pushed around the pass ``name`` (none for a generic engine)."""
        return []

    def release(self) -> None:
        pass


def driver_for(engine: Engine, viewer: Any) -> Any:
    """The driver for ``engine`` (the GL driver for a GLEngine, else the generic one)."""
    if type(engine).__module__.startswith("omnirender.gl"):
        from .gl_driver import GLDriver

        return GLDriver(viewer, engine=engine)
    return EngineDriver(engine, viewer)
