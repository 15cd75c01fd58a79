"""The interactive Jupyter view: an ``om.Viewer`` streamed to the notebook by jupyter_rfb.

:class:`ViewerWidget` is a ``jupyter_rfb.RemoteFrameBuffer`` (the remote
frame-buffer widget pygfx uses): the GL engine renders on the kernel side and
the widget sends the frames as images; the browser sends pointer, wheel, key
and resize events back, which :class:`~.interaction.ViewControl` turns into
camera moves exactly as in the glfw window (left drag orbits, right drag or
shift + left pans, the wheel zooms, a click picks and highlights the shape,
keys 1/2/3 F R W P).  Everything can be driven from Python through
:meth:`ViewerWidget.handle_event` with jupyter_rfb's event dicts, which is how
the tests use it without a browser.

``om.show(scene)`` returns such a widget (or, without jupyter_rfb, a viewer
that shows itself as a static PNG); an ``om.Viewer`` displayed in a notebook
shows its widget with the PNG as the static fallback.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .interaction import LEFT, MIDDLE, RIGHT, ViewControl

__all__ = ["ViewerWidget", "show", "widget_available", "in_kernel"]

#: jupyter_rfb button numbers (DOM MouseEvent.button + 1) -> ViewControl buttons.
_BUTTONS = {1: LEFT, 2: RIGHT, 3: MIDDLE}
#: Wheel units (pixels) per zoom step: a mouse-wheel notch scrolls about 100.
WHEEL_UNITS_PER_STEP = 100.0


def widget_available() -> tuple[bool, str]:
    """Whether the interactive widget can be made here (jupyter_rfb importable), and why not."""
    if _RemoteFrameBuffer is None:
        return False, f"jupyter_rfb is not installed ({_IMPORT_ERROR}): pip install 'omnirender[notebook]'"
    return True, ""


try:
    from jupyter_rfb import RemoteFrameBuffer as _RemoteFrameBuffer
except ImportError as exc:  # the notebook extra is not installed: om.show falls back to a PNG
    _RemoteFrameBuffer = None
    _IMPORT_ERROR = str(exc)
    _Base: type = object
else:
    _Base = _RemoteFrameBuffer


class ViewerWidget(_Base):  # type: ignore[misc, valid-type]
    """An interactive notebook view of an ``om.Viewer`` (see the module docs).

    ``ViewerWidget(viewer, scene=None, **traits)`` (jupyter_rfb traits such as
    ``css_width``); ``scene`` limits picking to one graph.  Attributes:
    ``viewer``, ``control`` (the camera control), ``picked`` (the last
    ``om.Hit``), ``frames`` (frames rendered).
    """

    def __init__(self, viewer: Any, scene: Any = None, **kwargs: Any) -> None:
        ok, why = widget_available()
        if not ok:
            raise RuntimeError(f"om.viewer.ViewerWidget: {why}")
        w, h = viewer.size
        kwargs.setdefault("css_width", f"{w}px")
        kwargs.setdefault("css_height", f"{h}px")
        super().__init__(**kwargs)
        self.viewer = viewer
        self.scene = scene
        self.control = ViewControl(viewer)
        self.control.remember_view()
        self.picked: Any = None
        self.frames = 0
        self._prerender = True

    # -- drawing ---------------------------------------------------------------
    def get_frame(self) -> np.ndarray:
        """The next frame (H, W, 4) uint8, rendered by the viewer's engine on the kernel side."""
        image = self.viewer.rerender() if self._prerender else self.viewer.repaint()
        self._prerender = False
        self.frames += 1
        return np.ascontiguousarray(image.array)

    def _repr_mimebundle_(self, **kwargs: Any) -> Any:
        """The widget, plus the current picture as ``image/png`` for static notebook renderers."""
        import base64

        from ..image import Image

        found = super()._repr_mimebundle_(**kwargs)
        data = found[0] if isinstance(found, tuple) else found
        if isinstance(data, dict):
            png = Image(self.get_frame())._repr_png_()
            data["image/png"] = base64.b64encode(png).decode("ascii")
        return found

    def refresh(self) -> None:
        """Prerender again (after the scene changed) and send a new frame."""
        self._prerender = True
        self.request_draw()

    # -- events ------------------------------------------------------------------
    def handle_event(self, event: dict[str, Any]) -> None:
        """React to a jupyter_rfb event dict (``type`` or ``event_type``: resize, pointer_*, wheel, key_down)."""
        kind = event.get("type") or event.get("event_type")
        shift = "Shift" in tuple(event.get("modifiers", ()))
        x, y = float(event.get("x", 0.0)), float(event.get("y", 0.0))
        if kind == "resize":
            w, h = int(round(event["width"])), int(round(event["height"]))
            if w > 0 and h > 0 and (w, h) != tuple(self.viewer.size):
                self.viewer.set_size(w, h)
                self.request_draw()
        elif kind == "pointer_down" and event.get("button") in _BUTTONS:
            self.control.press(_BUTTONS[event["button"]], x, y)
        elif kind == "pointer_move":
            if self.control.move(x, y, self.viewer.size[1], shift):
                self.request_draw()
        elif kind == "pointer_up" and event.get("button") in _BUTTONS:
            if self.control.release(_BUTTONS[event["button"]], x, y):
                self.pick(x, y)
        elif kind == "wheel":
            self.control.wheel(-float(event.get("dy", 0.0)) / WHEEL_UNITS_PER_STEP)
            self.request_draw()
        elif kind == "key_down" and self.control.key(str(event.get("key", "")), shift):
            self.request_draw()

    def pick(self, x: float, y: float) -> Any:
        """Pick at widget position (x, y): highlight the nearest shape; returns its ``om.Hit`` (or None)."""
        from .picking import pick_in_viewer

        w, h = self.viewer.size
        px, py = min(max(int(x), 0), w - 1), min(max(int(y), 0), h - 1)
        hit = pick_in_viewer(self.viewer, self.scene, px, py)
        self.picked = hit
        self.viewer.set_picked(hit)
        self.title = hit.path if hit is not None else ""
        self.refresh()
        return hit


def in_kernel() -> bool:
    """Whether this code runs in a Jupyter kernel (where widgets can be shown)."""
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and hasattr(shell, "kernel")


def show(scene: Any, size: tuple[int, int] = (640, 480), **options: Any) -> Any:
    """An interactive view of ``scene`` for a notebook cell (see the module docs).

    The scene's camera, lights and background are used as in ``om.view``.
    Returns a :class:`ViewerWidget`, or without jupyter_rfb the ``om.Viewer``
    itself, which a notebook shows as a PNG.
    """
    from .viewer import Viewer
    from .window import open_scene

    viewer = Viewer(size=size, **options)
    open_scene(viewer, scene)
    if not widget_available()[0]:
        return viewer
    return viewer.widget(scene if hasattr(scene, "walk") else None)
