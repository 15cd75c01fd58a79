"""Mouse and key controls of a viewer, shared by the glfw window and the notebook widget.

:class:`ViewControl` turns device-independent input into camera moves: a
left drag orbits around the viewing centre, a right or middle drag (or a
shift + left drag) pans, the wheel zooms, a left click that did not move more
than :data:`CLICK_PIXELS` picks, and the keys of :data:`KEYS` switch views.
Front ends translate their own events (glfw callbacks, jupyter_rfb event
dicts) into these calls and redraw when a call returns True.
"""

from __future__ import annotations

from typing import Any

from .axial import AxisAlignedRotation

__all__ = ["ViewControl", "KEYS", "CLICK_PIXELS", "ORBIT_DEGREES_PER_PIXEL", "ZOOM_PER_STEP", "LEFT", "RIGHT", "MIDDLE"]

#: A press and release closer than this (in window units) is a click, not a drag.
CLICK_PIXELS = 3.0
#: Orbit speed of a drag.
ORBIT_DEGREES_PER_PIXEL = 0.4
#: Zoom factor of one wheel step (a step towards the scene brings the eye 10 % closer).
ZOOM_PER_STEP = 0.9
LEFT, RIGHT, MIDDLE = "left", "right", "middle"

#: Key -> (action, with shift): axial views, fit, reset, wireframe, projection.
KEYS: dict[str, tuple[str, Any, Any]] = {
    "1": ("view", AxisAlignedRotation.X_Y, AxisAlignedRotation.NX_Y),
    "2": ("view", AxisAlignedRotation.NZ_Y, AxisAlignedRotation.Z_Y),
    "3": ("view", AxisAlignedRotation.X_NZ, AxisAlignedRotation.X_Z),
    "f": ("fit", None, None),
    "r": ("reset", None, None),
    "w": ("wireframe", None, None),
    "p": ("projection", None, None),
}


class ViewControl:
    """Camera control of ``viewer`` from presses, moves, releases, wheel steps and keys (see the module docs)."""

    def __init__(self, viewer: Any) -> None:
        self.viewer = viewer
        self._buttons: dict[str, list[Any]] = {}  # button -> [start x, start y, moved]
        self._cursor = (0.0, 0.0)
        self._initial: tuple | None = None

    def remember_view(self) -> None:
        """Store the current camera as the one ``reset`` returns to."""
        self._initial = self.viewer.camera.state()

    def reset_view(self) -> None:
        """Back to the remembered view (auto-fit if none)."""
        if self._initial is None:
            self.viewer.auto_fit()
        else:
            self.viewer.camera.restore(self._initial)

    @property
    def dragging(self) -> bool:
        return bool(self._buttons)

    @property
    def cursor(self) -> tuple[float, float]:
        """The last cursor position given to :meth:`press`, :meth:`move` or :meth:`release`."""
        return self._cursor

    def press(self, button: str, x: float, y: float) -> None:
        self._cursor = (x, y)
        self._buttons[button] = [x, y, False]

    def move(self, x: float, y: float, height: float, shift: bool = False) -> bool:
        """The cursor moved to (x, y) in a view ``height`` units tall; returns whether the camera moved."""
        px, py = self._cursor
        self._cursor = (x, y)
        if not self._buttons:
            return False
        for state in self._buttons.values():
            if not state[2] and abs(x - state[0]) + abs(y - state[1]) > CLICK_PIXELS:
                state[2] = True
        dx, dy = x - px, y - py
        camera = self.viewer.camera
        if LEFT in self._buttons and not shift:
            if not self._buttons[LEFT][2]:
                return False
            camera.orbit(dx * ORBIT_DEGREES_PER_PIXEL, dy * ORBIT_DEGREES_PER_PIXEL)
            return True
        camera.pan(dx / height, -dy / height)
        return True

    def release(self, button: str, x: float, y: float) -> bool:
        """A button went up; returns True when it was a left click (not a drag): the caller picks at (x, y)."""
        self._cursor = (x, y)
        state = self._buttons.pop(button, None)
        return state is not None and button == LEFT and not state[2]

    def wheel(self, steps: float) -> None:
        """Zoom by ``steps`` wheel steps (positive: towards the scene)."""
        self.viewer.camera.zoom(ZOOM_PER_STEP**steps)

    def key(self, name: str, shift: bool = False) -> bool:
        """Apply the key ``name`` (``"1"``, ``"f"``...); returns whether it was one of :data:`KEYS`."""
        found = KEYS.get(name.lower())
        if found is None:
            return False
        action, plain, shifted = found
        v = self.viewer
        if action == "view":
            v.set_axial_view(shifted if shift else plain)
        elif action == "fit":
            v.auto_fit()
        elif action == "reset":
            self.reset_view()
        elif action == "wireframe":
            v.wireframe = not v.wireframe
        elif action == "projection":
            (v.auto_fit_perspective if v.is_orthogonal() else v.auto_fit_ortho)()
        return True
