"""Frames on the GL engine: evaluate renderables into its immediate draw list, then draw and read.

The GL engine compiles what painters submit into a draw list and draws that
list with the camera it pre-evaluated.  A viewer frame therefore runs the
frame root through the engine (renderables push/eval/pop; painters submit
draw items), then ``engine.render(None)`` installs and draws those items.  A
repaint whose render lists (their prerender generations), highlights and overrides are
unchanged skips the traversal: only the camera and lights are re-evaluated and
the installed list is drawn again (orbiting a big scene costs one draw).

The replay is for node renderables only, whose ``render`` draws the snapshot
their prerender took.  The viewer contract (ArtiSynth's) is that every repaint
calls ``render(renderer, flags)`` of every renderable: a custom renderable may
draw something different each time (an animated marker, a simulation state it
reads under the render list's lock), so a frame holding one is always
traversed again.
"""

from __future__ import annotations

from typing import Any

from .renderable import replays

__all__ = ["GLDriver"]


def _gl_engine_class() -> type:
    try:
        from ..gl import GLEngine
    except ImportError:
        from ..gl.glengine import GLEngine
    return GLEngine


class GLDriver:
    """Drives an ``om.gl.GLEngine`` (created here, or given) for a viewer."""

    def __init__(self, viewer: Any, engine: Any = None, samples: int = 4) -> None:
        self.viewer = viewer
        if engine is None:
            window = getattr(viewer, "window", None)
            context = window.ctx if window is not None else None
            engine = _gl_engine_class()(size=viewer.size, samples=samples, context=context)
        self.engine = engine
        # An empty first frame puts the engine in immediate mode: what painters submit outside
        # engine.render(scene) goes to the list render(None) draws (a fresh GLEngine needs it).
        engine.render(None, read_depth=False)
        self._key: Any = None
        self._depth_off: list[Any] | None = None

    def frame_key(self, root: Any) -> tuple:
        """What decides whether the installed draw list is still right for this frame."""
        shape = root._shape
        lists = shape._lists
        # No node versions: nodes draw the snapshot their prerender took, so a node changed since then
        # shows only after the next prerender (which bumps the list's generation).  A custom renderable's
        # render() runs on every repaint: the frame number makes every such frame new.
        custom = any(not replays(r) for rl in lists for r in rl)
        return (
            root._version if custom else None,
            tuple((id(rl), rl.generation) for rl in lists),
            frozenset(shape._highlighted),
            tuple(type(a).__name__ + repr(a.parameters()) for a in shape._overrides),
            self.viewer.mask,
        )

    def draw(self, root: Any) -> Any:
        engine = self.engine
        if tuple(engine.size) != tuple(self.viewer.size):
            engine.size = self.viewer.size
            self._key = None
        background = self.viewer.background
        if engine.mask != self.viewer.mask:
            engine.mask = self.viewer.mask
        stereo = getattr(self.viewer, "stereo", None)
        if getattr(engine, "stereo", None) is not stereo:
            engine.stereo = stereo
        key = self.frame_key(root)
        with engine.ctx:  # make the engine's context current (several contexts may live in one thread)
            if key == self._key:
                engine.begin(root)  # camera and lights only: they change with the eye
                engine.end(root)
                engine.draw(background=background)
                return engine.read()
            self._key = None
            engine.run(root)
            image = engine.render(None, background=background)
        self._key = key
        return image

    def begin_pass(self, engine: Any, name: str) -> None:
        pass

    def pass_attributes(self, name: str) -> list[Any]:
        """2D passes draw with the depth test off."""
        if not name.endswith("_2d"):
            return []
        if self._depth_off is None:
            from ..gl.engine.attributes import DepthTest

            self._depth_off = [DepthTest(enabled=False)]
        return self._depth_off

    def release(self) -> None:
        release = getattr(self.engine, "release", None)
        if release is not None:
            release()
