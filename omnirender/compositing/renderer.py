"""Renderer trees: renderers and filters are the leaves, renderer groups the inner nodes.

A **renderer** makes an image from data (a scene graph, a volume, a light
field) and draws it into the canvas's framebuffer with colour and a depth
consistent with it.  A **filter** changes the image already made.  A
**renderer group** calls its children -- in registration order by default; it
may reorder them or call them several times -- and decides how their results
are combined with what is already in the framebuffer.  The tree is traversed
depth first and everything draws into the current framebuffer; groups switch
to offscreen targets only when they need to.

Every renderer is also a GL technique (``om.gl.GLTechnique``), so a tree is
used in two ways:

* on its own: ``tree.render(size)`` or ``om.render(tree, engine="gl")`` draws
  it into an ``om.Image`` (the camera is the first scene camera found in the
  tree, else one that frames the tree's bounds);
* inside a scene graph: a node holding a renderer applies it to the rest of the
  node -- a group takes the node's content as its first child (a node holding
  a ``ShadowGroup`` shadows its children), a leaf draws after the node's content
  (a node holding a ``LuminanceFilter`` greys what was drawn up to it).

Subclass :class:`Renderer` (``draw(canvas)``), :class:`Filter` or
:class:`RendererGroup` (``composite(canvas, children)``) for new ones, and
check them with :func:`~omnirender.compositing.check_rules`.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..geometry.bounds import union
from ..gl.engine.technique import GLTechnique
from .canvas import Canvas

__all__ = ["Renderer", "Filter", "RendererGroup", "NodeContent", "draw_all", "Bounds"]

Bounds = tuple[np.ndarray, np.ndarray]


class Renderer(GLTechnique):
    """A leaf of a renderer tree: draws its data into ``canvas.framebuffer`` (override :meth:`draw`).

    The integration rules (DESIGN.md) apply: keep what earlier renderers drew
    outside your footprint, write depth exactly where you write colour, leave
    the stencil buffer alone and restore the GL state you change
    (``with canvas.preserved():``).
    """

    __slots__ = ()

    def __init__(self) -> None:
        super().__init__(passes=1)

    # -- what subclasses define ---------------------------------------------------------
    def draw(self, canvas: Canvas) -> None:
        """Draw into ``canvas`` (its framebuffer, size and camera matrices)."""
        raise NotImplementedError(f"{type(self).__name__}.draw(canvas) is not implemented")

    def bounds(self) -> Bounds | None:
        """World-space (min, max) of what this renderer draws, or None (unknown or nothing)."""
        return None

    def frame_bounds(self, canvas: Canvas) -> Bounds | None:
        """Bounds while a frame is drawn (the node content's bounds are known only then)."""
        return self.bounds()

    def draws_layers(self) -> bool:
        """Whether :meth:`draw_layer` is implemented (the renderer can be a ``DepthPeelGroup``'s child)."""
        return False

    def draw_layer(self, canvas: Canvas, peel: str | None) -> None:
        """Draw one depth-peeled layer (see :mod:`~omnirender.compositing.peeling`): the nearest fragments
        behind the depth of target ``peel`` (None: the nearest fragments), colour unblended (RGB and alpha
        as shaded), depth written, depth-tested ``less`` against what ``canvas`` holds."""
        raise NotImplementedError(
            f"{type(self).__name__} cannot draw depth-peeled layers (draw_layer); draw it outside a DepthPeelGroup"
        )

    def scene_camera(self) -> tuple[Camera, np.ndarray] | None:
        """A camera this renderer's data brings along, as ``(camera, world matrix)``, or None."""
        return None

    # -- in a scene graph ---------------------------------------------------------------
    def draw_in_graph(self, canvas: Canvas) -> None:
        """What a node holding this renderer draws: the node's content, then this renderer."""
        canvas.scope()
        self.draw(canvas)

    def prepare_pass(self, engine: Any) -> None:
        from ..gl import Pass

        engine.set_pass(Pass(type(self).__name__, custom=self._in_graph))

    def _in_graph(self, engine: Any, draw: Any) -> int:
        canvas = Canvas(engine, draw)
        self.draw_in_graph(canvas)
        return canvas.calls

    # -- on its own -------------------------------------------------------------------
    def default_camera(self, aspect: float = 4 / 3) -> tuple[Camera, np.ndarray]:
        """The tree's camera: the first scene camera met depth first, else one framing :meth:`bounds`."""
        found = self.scene_camera()
        if found is not None:
            return found
        box = self.bounds()
        if box is None:
            return Camera.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), np.eye(4)
        return Camera.fit(box, aspect), np.eye(4)

    def as_scene(self, engine: str = "gl", size: tuple[int, int] = (640, 480), camera: Camera | None = None) -> Any:
        """A scene graph that draws this tree (what ``om.render(tree, engine, size)`` renders): a camera
        (``camera``, else :meth:`default_camera` for the image's aspect) and the tree.

        Renderer trees composite with the GL engine; other engine names are refused with the fix.
        """
        from ..core.transform import Matrix
        from ..scene.node import Node

        if engine != "gl":
            raise ValueError(
                f"{type(self).__name__}: renderer trees are composited by the GL engine (engine='gl'), not "
                f"{engine!r}; render the scene graphs of the tree's SceneRenderers with {engine!r} instead"
            )
        if camera is not None and not isinstance(camera, Camera):
            raise TypeError(f"{type(self).__name__}: camera must be an om.Camera, got {camera!r:.60}")
        placed, world = (camera, np.eye(4)) if camera is not None else self.default_camera(size[0] / size[1])
        items = [placed] if np.allclose(world, np.eye(4)) else [Matrix(world), placed]
        return Node.transient([Node("camera", items), Tree(self)], name="renderer-tree")

    def render(self, size: tuple[int, int] = (640, 480), *, camera: Camera | None = None, **options: Any) -> Any:
        """Draw the tree into an ``om.Image`` with the GL engine (``samples``, ``background``, ... as ``om.render``)."""
        from ..render import render

        return render(self.as_scene("gl", size, camera), engine="gl", size=size, **options)

    def release(self) -> None:
        """Free GPU resources this renderer keeps between frames (engines, textures); it draws again on demand."""


class Filter(Renderer):
    """A renderer that changes the image already made (its colour; never its depth)."""

    __slots__ = ()


class RendererGroup(Renderer):
    """An inner node: calls ``children`` and combines their results (override :meth:`composite`)."""

    __slots__ = ("children",)

    def __init__(self, children: Iterable[Renderer] = ()) -> None:
        super().__init__()
        self.children = _children(type(self).__name__, children)

    def add(self, child: Renderer) -> Renderer:
        """Append ``child`` (drawn after the others); returns it."""
        self.children = _children(type(self).__name__, (*self.children, child))
        return child

    def composite(self, canvas: Canvas, children: tuple[Renderer, ...]) -> None:
        """Draw ``children`` and merge their results into ``canvas`` (default: in order, by the depth test).

        It runs with the GL state preserved around it (passes of the engine change state freely).
        """
        draw_all(canvas, children)

    def draw(self, canvas: Canvas) -> None:
        with canvas.preserved():
            self.composite(canvas, self.children)

    def draw_in_graph(self, canvas: Canvas) -> None:
        """In a scene graph the node's content is the group's first child."""
        with canvas.preserved():
            self.composite(canvas, (NODE_CONTENT, *self.children))

    def bounds(self) -> Bounds | None:
        box = None
        for child in self.children:
            box = union(box, child.bounds())
        return box

    def frame_bounds(self, canvas: Canvas) -> Bounds | None:
        box = None
        for child in self.children:
            box = union(box, child.frame_bounds(canvas))
        return box

    def scene_camera(self) -> tuple[Camera, np.ndarray] | None:
        for child in self.children:
            found = child.scene_camera()
            if found is not None:
                return found
        return None

    def release(self) -> None:
        for child in self.children:
            child.release()


class NodeContent(Renderer):
    """The content of the scene-graph node a group sits in (a group's first child there)."""

    __slots__ = ()

    def draw(self, canvas: Canvas) -> None:
        canvas.scope()

    def frame_bounds(self, canvas: Canvas) -> Bounds | None:
        return canvas.engine.scene_bounds()


NODE_CONTENT = NodeContent()


class Tree(GLTechnique):
    """The technique a stand-alone tree is drawn by: the root renderer, over an empty scope."""

    __slots__ = ("root",)

    def __init__(self, root: Renderer) -> None:
        super().__init__(passes=1)
        self.root = root

    def prepare_pass(self, engine: Any) -> None:
        from ..gl import Pass

        engine.set_pass(Pass(type(self.root).__name__, custom=self._draw))

    def _draw(self, engine: Any, draw: Any) -> int:
        canvas = Canvas(engine, draw)
        self.root.draw(canvas)
        return canvas.calls


def draw_all(canvas: Canvas, children: Iterable[Renderer]) -> None:
    """Draw ``children`` in order into ``canvas`` (what a plain depth group does)."""
    for child in children:
        child.draw(canvas)


def _children(owner: str, children: Iterable[Renderer]) -> tuple[Renderer, ...]:
    if isinstance(children, Renderer):
        children = (children,)
    out = tuple(children)
    for i, child in enumerate(out):
        if not isinstance(child, Renderer):
            raise TypeError(
                f"{owner}: child {i} is a {type(child).__name__} ({child!r:.60}), not a renderer; wrap scene graphs "
                "in om.compositing.SceneRenderer(scene), volumes in VolumeRenderer(volume)"
            )
    return out
