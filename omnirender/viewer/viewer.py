"""``om.Viewer``: renderables, render lists, camera and lights (ArtiSynth's viewer).

Applications add renderables (any :class:`IsRenderable`, or ``om.Node``) and
call :meth:`Viewer.rerender` after changing them (prerender + repaint) or
:meth:`Viewer.repaint` to redraw the cached lists (camera moves, window
exposes).  Several viewers can share one prerendered :class:`RenderList`
(``set_external_render_list``) updated by a simulation thread.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.engine import Engine
from ..core.light import Light
from .axial import AxisAlignedRotation
from .camera import ViewerCamera
from .frame import FrameRoot, FrameShape, ViewCamera
from .render_list import RenderList
from .renderable import NodeRenderable, as_renderable

__all__ = ["Viewer", "default_lights"]

_SPACES = ("camera", "world")


def default_lights() -> list[Any]:
    """The default light set (eye coordinates): key, fill and back light, like ArtiSynth's."""
    from ..attributes.lights import default_lights as lights

    return lights()


class Viewer:
    """Draws renderables with an engine from a camera; see the module docs.

    ``engine`` is ``"gl"`` (an ``om.gl.GLEngine`` created on the first repaint)
    or an engine instance.  ``window=True`` opens an interactive glfw window
    (see :func:`om.view`).
    """

    def __init__(
        self,
        size: tuple[int, int] = (640, 480),
        engine: str | Engine = "gl",
        window: bool = False,
        *,
        samples: int = 4,
        background: Sequence[float] = (0.18, 0.19, 0.22, 1.0),
        title: str = "omnirender",
        stereo: Any = None,
    ) -> None:
        self._size = _check_size(size)
        self.stereo = stereo
        self._camera = ViewerCamera(self._size)
        self._renderables: list[Any] = []
        self._by_source: dict[int, Any] = {}
        self._render_list = RenderList()
        self._external: RenderList | None = None
        self._lights: list[tuple[Any, str]] = [(light, "camera") for light in default_lights()]
        self._highlighted: set[int] = set()
        self._picked: Any = None
        self._frame_count = 0
        self._lock = threading.RLock()
        self._image: Any = None
        self._driver: Any = None
        self._widget: Any = None
        self._engine_spec = engine
        self._samples = samples
        self.background = background
        self.wireframe = False
        self._mask: str | None = None
        self.window: Any = None
        if isinstance(engine, Engine):
            from .drivers import driver_for

            self._driver = driver_for(engine, self)
        elif engine != "gl":
            raise ValueError(f"Viewer: engine must be 'gl' or an om.Engine instance, got {engine!r}")
        if window:
            from .window import Window

            self.window = Window(self, title=title)

    # -- engine ----------------------------------------------------------
    @property
    def stereo(self) -> Any:
        """The ``om.gl.Stereo`` every frame is drawn with (two eyes, off-axis projections), or None."""
        return self._stereo

    @stereo.setter
    def stereo(self, value: Any) -> None:
        if value is not None:
            from ..gl.techniques.stereo import Stereo

            if not isinstance(value, Stereo):
                raise TypeError(f"Viewer: stereo must be an om.gl.Stereo(...) or None, got {value!r:.60}")
        self._stereo = value

    @property
    def engine(self) -> Engine:
        """The renderer renderables draw with (created on first use)."""
        return self._get_driver().engine

    def _get_driver(self) -> Any:
        if self._driver is None:
            from .gl_driver import GLDriver

            self._driver = GLDriver(self, samples=self._samples)
        return self._driver

    # -- size / background -------------------------------------------------
    @property
    def size(self) -> tuple[int, int]:
        return self._size

    def set_size(self, width: int, height: int) -> None:
        """Resize the image (the field-of-view projection follows the new aspect)."""
        self._size = _check_size((width, height))
        self._camera.size = self._size

    @property
    def background(self) -> tuple[float, float, float, float]:
        return self._background

    @background.setter
    def background(self, color: Sequence[float]) -> None:
        try:
            values = [float(c) for c in color]
        except (TypeError, ValueError):
            raise ValueError(
                f"Viewer.background: need 3 or 4 numbers in [0, 1] (RGB or RGBA), got {color!r:.60}"
            ) from None
        if len(values) == 3:
            values.append(1.0)
        if len(values) != 4 or not all(0.0 <= c <= 1.0 for c in values):
            raise ValueError(f"Viewer.background: need 3 or 4 values in [0, 1], got {color!r}")
        self._background = tuple(values)  # type: ignore[assignment]

    @property
    def mask(self) -> str | None:
        """The group-mask expression the viewer draws and picks with (None: everything).

        ``om.view`` sets it to the scene camera's own mask, so what a click
        picks is what the camera shows.
        """
        return self._mask

    @mask.setter
    def mask(self, expression: str | None) -> None:
        if expression is not None:
            from ..core.mask import compile_mask

            compile_mask(expression)  # MaskError (a ValueError) names what is wrong
        self._mask = expression

    def set_background_color(self, color: Sequence[float]) -> None:
        self.background = color

    def get_background_color(self) -> tuple[float, float, float, float]:
        return self.background

    # -- renderables -------------------------------------------------------
    def add_renderable(self, renderable: Any) -> Any:
        """Add a renderable (Nodes are wrapped in a NodeRenderable); returns what the viewer draws."""
        with self._lock:
            wrapped = as_renderable(renderable)
            self._renderables.append(wrapped)
            self._by_source[id(renderable)] = wrapped
            return wrapped

    def remove_renderable(self, renderable: Any) -> bool:
        """Remove a renderable (or the Node it wraps); returns whether it was there."""
        with self._lock:
            wrapped = self._by_source.pop(id(renderable), renderable)
            for i, r in enumerate(self._renderables):
                if r is wrapped:
                    del self._renderables[i]
                    self._highlighted.discard(id(r))
                    return True
            return False

    def clear_renderables(self) -> None:
        with self._lock:
            self._renderables.clear()
            self._by_source.clear()
            self._highlighted.clear()
            self._render_list.clear()

    def renderables(self) -> list[Any]:
        """The viewer's own renderables (NodeRenderables for added nodes)."""
        return list(self._renderables)

    def renderable_for(self, obj: Any) -> Any:
        """What the viewer draws for ``obj`` (the NodeRenderable of a Node), or None."""
        return self._by_source.get(id(obj))

    def set_highlight(self, renderable: Any, on: bool = True) -> None:
        """Draw ``renderable`` (or a Node's renderable) with the HIGHLIGHT flag."""
        r = self._by_source.get(id(renderable), renderable)
        if on:
            self._highlighted.add(id(r))
        else:
            self._highlighted.discard(id(r))

    def set_picked(self, hit: Any) -> None:
        """Show ``hit`` (an ``om.Hit`` from picking, with ``root`` set) highlighted; None clears it."""
        from .picking import PickHighlight

        with self._lock:
            if self._picked is not None:
                self._renderables = [r for r in self._renderables if r is not self._picked]
                self._picked = None
            root = getattr(hit, "root", None) if hit is not None else None
            if root is not None:
                self._picked = PickHighlight(root, hit.path, hit.shape)
                self._renderables.append(self._picked)

    @property
    def picked(self) -> Any:
        """The highlight overlay of the last pick, or None."""
        return self._picked

    @property
    def render_list(self) -> RenderList:
        """The viewer's own render list."""
        return self._render_list

    def set_external_render_list(self, render_list: RenderList | None) -> None:
        """Also draw ``render_list``, prerendered elsewhere (shared by viewers); None detaches it."""
        if render_list is not None and not isinstance(render_list, RenderList):
            raise TypeError(f"set_external_render_list needs an om.RenderList, got {type(render_list).__name__}")
        self._external = render_list

    def get_external_render_list(self) -> RenderList | None:
        return self._external

    # -- drawing -----------------------------------------------------------
    def rerender(self) -> Any:
        """Prerender the viewer's renderables, then repaint; returns the image."""
        with self._lock:
            self._render_list.prerender(list(self._renderables))
        return self.repaint()

    def repaint(self) -> Any:
        """Redraw from the cached render lists (no prerender); returns the image (an om.Image)."""
        with self._lock:
            lists = [self._render_list] + ([self._external] if self._external is not None else [])
            driver = self._get_driver()
            for rl in lists:
                rl.lock.acquire()
            try:
                self._frame_count += 1
                root = FrameRoot(
                    ViewCamera(
                        self._camera.to_camera(), self._camera.get_view_matrix(), self._camera.get_projection_matrix()
                    ),
                    FrameShape(lists, set(self._highlighted), driver, self._overrides()),
                    [light for light, space in self._lights if space == "world"],
                    [light for light, space in self._lights if space == "camera"],
                    self._camera.get_eye_to_world(),
                    [r.node for rl in lists for r in rl if isinstance(r, NodeRenderable)],
                    self._frame_count,
                )
                self._image = driver.draw(root)
            finally:
                for rl in reversed(lists):
                    rl.lock.release()
            return self._image

    def image(self) -> Any:
        """The last frame as an ``om.Image`` (rendering one if nothing was drawn yet)."""
        if self._image is None:
            if self._render_list.generation == 0:
                return self.rerender()
            return self.repaint()
        return self._image

    def _repr_png_(self) -> bytes:
        image = self.image()
        return image._repr_png_()

    def widget(self, scene: Any = None) -> Any:
        """The interactive notebook view of this viewer (made once; needs jupyter_rfb, see ``om.show``).

        ``scene`` limits picking to one graph (default: every node the viewer draws).
        """
        if self._widget is None:
            from .notebook import ViewerWidget

            self._widget = ViewerWidget(self, scene)
        return self._widget

    def _repr_mimebundle_(self, include: Any = None, exclude: Any = None) -> dict[str, Any]:
        """In a notebook kernel with jupyter_rfb: the interactive widget, with the PNG as the static fallback."""
        import base64

        data: dict[str, Any] = {"text/plain": repr(self)}
        from .notebook import in_kernel, widget_available

        if in_kernel() and widget_available()[0]:
            found = self.widget()._repr_mimebundle_(include=include, exclude=exclude)
            data.update(found[0] if isinstance(found, tuple) else found)
        data["image/png"] = base64.b64encode(self._repr_png_()).decode("ascii")
        return data

    # -- camera: frames ----------------------------------------------------
    @property
    def camera(self) -> ViewerCamera:
        """The camera state (eye frame, centre, projection)."""
        return self._camera

    def get_view_matrix(self) -> np.ndarray:
        """World-to-eye matrix."""
        return self._camera.get_view_matrix()

    def set_view_matrix(self, matrix: Any) -> None:
        self._camera.set_view_matrix(matrix)

    def get_eye_to_world(self) -> np.ndarray:
        return self._camera.get_eye_to_world()

    def set_eye_to_world(self, eye_or_matrix: Any, center: Any = None, up: Any = None) -> None:
        """``set_eye_to_world(T)`` with a rigid 4x4, or ``(eye, center, up)`` (look-at convention)."""
        self._camera.set_eye_to_world(eye_or_matrix, center, up)

    def get_eye(self) -> np.ndarray:
        return self._camera.eye

    def set_eye(self, eye: Sequence[float]) -> None:
        self._camera.set_eye(eye)

    def get_center(self) -> np.ndarray:
        return self._camera.center

    def set_center(self, center: Sequence[float]) -> None:
        self._camera.set_center(center)

    def get_up_vector(self) -> np.ndarray:
        return self._camera.up

    def set_up_vector(self, up: Sequence[float]) -> None:
        self._camera.set_up_vector(up)

    def set_axial_view(self, rotation: AxisAlignedRotation | str) -> None:
        self._camera.set_axial_view(rotation)

    # -- camera: projection ----------------------------------------------
    def set_perspective(self, *args: float) -> None:
        """``(fov, near, far)`` (vertical fov, degrees) or ``(left, right, bottom, top, near, far)``."""
        self._camera.set_perspective(*args)

    def set_orthogonal(self, *args: float) -> None:
        """``(field_height, near, far)`` or ``(left, right, bottom, top, near, far)``."""
        self._camera.set_orthogonal(*args)

    def get_projection_matrix(self) -> np.ndarray:
        return self._camera.get_projection_matrix()

    @property
    def view_plane_width(self) -> float:
        return self._camera.view_plane_width

    @property
    def view_plane_height(self) -> float:
        return self._camera.view_plane_height

    @property
    def view_plane_distance(self) -> float:
        return self._camera.view_plane_distance

    @property
    def far_plane_distance(self) -> float:
        return self._camera.far_plane_distance

    @property
    def vertical_field_of_view(self) -> float:
        """The vertical field of view in degrees; setting it makes the projection perspective (near/far kept)."""
        return self._camera.fov

    @vertical_field_of_view.setter
    def vertical_field_of_view(self, fov: float) -> None:
        self._camera.set_vertical_field_of_view(fov)

    def set_vertical_field_of_view(self, fov: float) -> None:
        """ArtiSynth's ``setVerticalFieldOfView``: perspective with vertical ``fov`` degrees, near/far kept."""
        self._camera.set_vertical_field_of_view(fov)

    def get_vertical_field_of_view(self) -> float:
        return self._camera.fov

    def get_eye_z_direction(self) -> np.ndarray:
        """ArtiSynth's ``getEyeZDirection``: the eye's z axis in world coordinates (from the centre to the eye)."""
        return self._camera.eye_z_direction

    def is_orthogonal(self) -> bool:
        return self._camera.is_orthogonal

    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """World box of every renderable (own and external lists), or None when empty."""
        pmin = np.full(3, np.inf)
        pmax = np.full(3, -np.inf)
        items = list(self._renderables)
        if self._external is not None:
            with self._external.lock:
                items.extend(self._external)
        for r in items:
            r.update_bounds(pmin, pmax)
        if not (np.all(np.isfinite(pmin)) and np.all(np.isfinite(pmax))):
            return None
        return pmin, pmax

    def auto_fit(self) -> None:
        """Place the eye so every renderable is visible, keeping direction and projection kind."""
        self._camera.auto_fit(self.bounds())

    def auto_fit_perspective(self) -> None:
        self._camera.auto_fit_perspective(self.bounds())

    def auto_fit_ortho(self) -> None:
        self._camera.auto_fit_ortho(self.bounds())

    def set_camera(self, camera: Any, world: np.ndarray | None = None) -> None:
        """Adopt an ``om.Camera`` (e.g. the one found in a scene)."""
        self._camera.set_from_camera(camera, world)

    # -- lights ------------------------------------------------------------
    def num_lights(self) -> int:
        return len(self._lights)

    def get_light(self, index: int) -> Any:
        return self._light_entry(index)[0]

    def get_light_space(self, index: int) -> str:
        """``"camera"`` (moves with the eye) or ``"world"``."""
        return self._light_entry(index)[1]

    def _light_entry(self, index: int) -> Any:
        if not -len(self._lights) <= index < len(self._lights):
            have = f"indices 0..{len(self._lights) - 1}" if self._lights else "it has none yet (add_light())"
            raise IndexError(f"Viewer: no light {index}; {have} (num_lights() = {len(self._lights)})")
        return self._lights[index]

    def get_index_of_light(self, light: Any) -> int:
        """Index of ``light`` or -1."""
        for i, (existing, _) in enumerate(self._lights):
            if existing is light:
                return i
        return -1

    def add_light(self, light: Any, space: str = "world") -> int:
        """Add a light (``om.PointLight``...) in world or camera space; effective at the next repaint."""
        if not isinstance(light, Light):
            raise TypeError(f"add_light needs an om.Light (e.g. om.PointLight), got {type(light).__name__}")
        if space not in _SPACES:
            raise ValueError(f"add_light: space must be one of {_SPACES}, got {space!r}")
        with self._lock:
            if self.get_index_of_light(light) >= 0:
                raise ValueError(f"add_light: {light!r} is already in the viewer")
            self._lights.append((light, space))
            return len(self._lights) - 1

    def remove_light(self, light: Any) -> bool:
        """Remove a light (or the light at an index); returns whether one was removed."""
        with self._lock:
            index = light if isinstance(light, int) else self.get_index_of_light(light)
            if 0 <= index < len(self._lights):
                del self._lights[index]
                return True
            return False

    def clear_lights(self) -> None:
        with self._lock:
            self._lights.clear()

    def _overrides(self) -> list[Any]:
        """Attributes pushed around the whole frame (the wireframe toggle)."""
        if not self.wireframe:
            return []
        from ..attributes import DrawStyle

        return [DrawStyle(mode="wireframe")]

    # -- window --------------------------------------------------------------
    def close(self) -> None:
        """Release the engine, then close the window (if any): GPU objects go while their context lives."""
        if self._driver is not None:
            self._driver.release()
            self._driver = None
        if self.window is not None:
            self.window.close()
            self.window = None

    def __repr__(self) -> str:
        w, h = self._size
        return f"Viewer({w}x{h}, {len(self._renderables)} renderables, {len(self._lights)} lights)"


def _check_size(size: Any) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ValueError(f"Viewer: size must be (width, height), got {size!r}") from None
    if w <= 0 or h <= 0:
        raise ValueError(f"Viewer: size must be positive, got {w}x{h}")
    return w, h
