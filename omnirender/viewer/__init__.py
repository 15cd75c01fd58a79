"""The viewer: renderables, render lists, camera control and the interactive window.

``om.Viewer`` draws :class:`IsRenderable` objects (and ``om.Node``) with an
engine, ArtiSynth style: ``rerender()`` prerenders into a :class:`RenderList`
and repaints; ``repaint()`` redraws the cached lists.  ``om.view(scene)``
opens an interactive glfw window.  ``RenderThreads`` and ``RenderClient``
draw immutable scene snapshots in render threads of their own.
"""

from __future__ import annotations

from typing import Any

from .axial import AxisAlignedRotation
from .camera import ViewerCamera
from .render_list import PASSES, RenderList
from .renderable import HIGHLIGHT, TRANSPARENT, TWO_DIMENSIONAL, IsRenderable, NodeRenderable, as_renderable
from .threads import RenderClient, RenderThreads
from .viewer import Viewer, default_lights

__all__ = [
    "Viewer",
    "view",
    "show",
    "RenderList",
    "PASSES",
    "AxisAlignedRotation",
    "IsRenderable",
    "NodeRenderable",
    "as_renderable",
    "ViewerCamera",
    "default_lights",
    "TRANSPARENT",
    "TWO_DIMENSIONAL",
    "HIGHLIGHT",
    "RenderThreads",
    "RenderClient",
]


def show(scene: Any, size: tuple[int, int] = (640, 480), **options: Any) -> Any:
    """An interactive notebook view of ``scene`` (see :mod:`omnirender.viewer.notebook`)."""
    from .notebook import show as _show

    return _show(scene, size=size, **options)


def view(scene: Any, size: tuple[int, int] = (960, 720), **options: Any) -> Any:
    """Open an interactive window on ``scene`` (a Node or renderable); returns when it is closed.

    See :func:`omnirender.viewer.window.view` for the mouse and key bindings.
    """
    from .window import view as _view

    return _view(scene, size=size, **options)
