"""Renderers of scene graphs through the GL engine: :class:`SceneRenderer` and :class:`VolumeRenderer`.

A scene renderer draws its scene with a GL engine of its own -- its own
compiled draw list, lights and options (a group mask, a technique such as a
deferred pipeline) -- that shares the tree's OpenGL context and draws straight
into the tree's current framebuffer with the tree's camera
(``GLEngine.draw(clear=False, camera=..., framebuffer=...)``).  Nothing is
copied: the scene's fragments are depth-tested against what earlier renderers
drew, so colour and depth stay consistent, and the scene is compiled once and
replayed on later frames while it does not change.

Colour and depth stay consistent for translucent surfaces too (integration
rule 2): where no technique is given, the scene is drawn by
:class:`TreeForward`, the engine's forward technique whose transparent-depth
pass writes the depth of every translucent fragment that shows (alpha at
least 1/255), not only of the mostly opaque ones as an image's depth does.
A :class:`~omnirender.compositing.DepthPeelGroup` draws the scene's layers
with a second engine of its own (:meth:`SceneRenderer.draw_layer`).
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..core.component import RenderingComponent
from ..core.technique import Technique
from ..gl import Blend, ColorMask, DepthMask, Pass, Shader
from ..gl.techniques.forward import Forward
from ..scene.node import Node
from .canvas import Canvas
from .renderer import Bounds, Renderer

__all__ = ["SceneRenderer", "VolumeRenderer", "TreeForward"]


class TreeForward(Forward):
    """``om.gl.Forward`` whose transparent-depth pass writes depth wherever a translucent fragment adds colour
    (alpha >= 1/255): in a renderer tree every coloured pixel has a depth (integration rule 2)."""

    __slots__ = ()
    PASSES = tuple(
        Pass(
            "transparent depth",
            items="transparent",
            scopes=False,
            state=(ColorMask(False, False, False, False), DepthMask(True), Blend(None)),
            shader=Shader(depth_only=True, alpha_cutoff=1.0 / 255.0),
        )
        if p.name == "transparent depth"
        else p
        for p in Forward.PASSES
    )


class SceneRenderer(Renderer):
    """Draws ``scene`` (an ``om.Node`` or a list of components) with the GL engine.

    ``mask`` is a group-mask expression (only the matching subgraphs are drawn,
    e.g. one part of a shared scene), ``technique`` replaces the engine's
    default technique (``om.gl.Forward``) for this scene only, ``on_missing``
    is the engine's policy for shapes without a painter.  The scene's own
    camera is ignored while it is drawn (the tree's is used); its lights light
    only this scene.  A node that is part of a larger graph is drawn in its own
    coordinates, as a root (the transforms above it do not apply); to draw a
    part of a graph where it sits, give the whole graph and a group mask.
    """

    __slots__ = ("scene", "mask", "technique", "on_missing", "_engines", "_bounds", "_peelers")
    _transient = {
        "_engines": weakref.WeakKeyDictionary,
        "_bounds": lambda: None,
        "_peelers": weakref.WeakKeyDictionary,
    }

    def __init__(
        self, scene: Any, mask: str | None = None, technique: Technique | None = None, on_missing: str = "raise"
    ) -> None:
        super().__init__()
        if isinstance(scene, (list, tuple)):
            scene = Node("scene", list(scene))
        if not isinstance(scene, Node):
            if isinstance(scene, RenderingComponent):
                scene = Node("scene", [scene])
            else:
                raise TypeError(
                    f"{type(self).__name__}: scene must be an om.Node or a list of components, got {scene!r:.60}"
                )
        if mask is not None:
            from ..core.mask import compile_mask

            compile_mask(mask)  # a syntax error is reported here, with the expression
        if technique is not None and not isinstance(technique, Technique):
            raise TypeError(f"{type(self).__name__}: technique must be an om.Technique, got {technique!r:.60}")
        if on_missing not in ("raise", "warn", "skip"):
            raise ValueError(f"{type(self).__name__}: on_missing must be 'raise', 'warn' or 'skip', got {on_missing!r}")
        self.scene = scene
        self.mask = mask
        self.technique = technique
        self.on_missing = on_missing
        object.__setattr__(self, "_engines", weakref.WeakKeyDictionary())
        object.__setattr__(self, "_peelers", weakref.WeakKeyDictionary())
        object.__setattr__(self, "_bounds", None)

    def engine(self, host: Any) -> Any:
        """The GL engine drawing this scene in frames of ``host`` (made on first use, on host's context)."""
        from ..gl.glengine import GLEngine

        found = self._engines.get(host)
        key = (self.mask, self.technique, self.on_missing)
        if found is not None and found[0] == key:
            return found[1]
        if found is not None:
            found[1].release()
        technique = self.technique if self.technique is not None else TreeForward()
        engine = GLEngine(size=(1, 1), samples=0, context=host.ctx, technique=technique, on_missing=self.on_missing)
        self._engines[host] = (key, engine)
        return engine

    def peeler(self, host: Any) -> tuple[Any, Any]:
        """(engine, its :class:`~omnirender.compositing.peeling.PeelLayer` technique) drawing this scene's
        depth-peeled layers in frames of ``host`` (made on first use)."""
        from ..gl.glengine import GLEngine
        from .peeling import PeelLayer

        found = self._peelers.get(host)
        key = (self.mask, self.on_missing)
        if found is not None and found[0] == key:
            return found[1], found[2]
        if found is not None:
            found[1].release()
        technique = PeelLayer()
        engine = GLEngine(size=(1, 1), samples=0, context=host.ctx, technique=technique, on_missing=self.on_missing)
        self._peelers[host] = (key, engine, technique)
        return engine, technique

    def draw(self, canvas: Canvas) -> None:
        with canvas.preserved():  # making an engine or drawing changes GL state: put it back
            engine = self.engine(canvas.engine)
            engine.compile(self.scene, mask=self.mask)
            engine.draw(clear=False, camera=(canvas.view, canvas.projection), framebuffer=canvas.framebuffer)
        canvas.count(engine.stats["draw_calls"], engine.stats["items"])

    def draws_layers(self) -> bool:
        return True

    def draw_layer(self, canvas: Canvas, peel: str | None) -> None:
        """One depth-peeled layer of the scene (forward shading; a ``technique`` given does not apply)."""
        with canvas.preserved():
            engine, technique = self.peeler(canvas.engine)
            object.__setattr__(technique, "peel", None if peel is None else canvas.target(peel).depth)
            engine.compile(self.scene, mask=self.mask)
            try:
                engine.draw(clear=False, camera=(canvas.view, canvas.projection), framebuffer=canvas.framebuffer)
            finally:
                object.__setattr__(technique, "peel", None)
        canvas.count(engine.stats["draw_calls"], engine.stats["items"])

    def bounds(self) -> Bounds | None:
        cached = self._bounds
        if cached is not None and cached[0] == self.scene.version:
            return cached[1]
        from ..techniques import bounds

        box = bounds(Node.transient([self.scene]), mask=self.mask)  # in its own coordinates, as it is drawn
        if box is not None:
            box = (np.asarray(box[0], dtype=np.float64), np.asarray(box[1], dtype=np.float64))
            if not (np.all(np.isfinite(box[0])) and np.all(np.isfinite(box[1]))):
                box = None
        object.__setattr__(self, "_bounds", (self.scene.version, box))
        return box

    def scene_camera(self) -> tuple[Camera, np.ndarray] | None:
        return self.scene.declarations().camera

    def release(self) -> None:
        for _, engine in list(self._engines.values()):
            engine.release()
        self._engines.clear()
        for _, engine, _ in list(self._peelers.values()):
            engine.release()
        self._peelers.clear()


class VolumeRenderer(SceneRenderer):
    """Ray casting of an ``om.Volume`` whose depth is consistent with its colour.

    ``attributes`` (transforms, ...) apply to the volume.  The GL engine's
    volume painter marches each ray front to back through the 3D texture and
    writes the depth where the accumulated opacity first exceeds 5 %; rays end
    at the depth already drawn, so meshes inside the volume hide what lies
    behind them.
    """

    __slots__ = ()

    def __init__(self, volume: Any, *attributes: Any) -> None:
        from ..shapes import Volume

        if not isinstance(volume, Volume):
            raise TypeError(f"VolumeRenderer: volume must be an om.Volume, got {volume!r:.60}")
        super().__init__(Node("volume", [*attributes, volume]))

    def scene_camera(self) -> tuple[Camera, np.ndarray] | None:
        return None

    def draws_layers(self) -> bool:
        return False  # ray casting is not peeled: draw the volume outside a DepthPeelGroup
