"""The canvas: what a renderer of a tree draws on while the GL engine draws a frame.

A renderer tree runs inside a GL frame, as the custom pass of a technique
(``om.gl.Pass(custom=...)``).  A :class:`Canvas` wraps that moment: the engine,
the framebuffer being drawn into (the frame's, or a group's offscreen target),
its size, and the camera of the pass (the tree's, or a light's while a shadow
group renders its shadow map).  Renderers draw into :attr:`Canvas.framebuffer`
with the canvas's matrices; groups open nested passes with :meth:`Canvas.into`
(children drawn into an offscreen target, optionally from another camera),
merge images with :meth:`Canvas.fullscreen` (the engine's shared full-screen
triangle) and read what is already drawn with :meth:`Canvas.copy` (a depth
sprite: colour and depth saved into textures).  Everything goes through the GL
engine's public API, so every step shows up in ``engine.stats["passes"]``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

__all__ = ["Canvas", "target_name", "eye_distance", "EYE_DISTANCE", "fraction"]

#: GLSL: window depth -> distance along the view axis, for ``camera = (near, far, orthographic ? 1 : 0)``.
EYE_DISTANCE = """
float eye_distance(float d, vec3 camera) {
    if (camera.z > 0.5) return mix(camera.x, camera.y, d);
    return 2.0 * camera.x * camera.y / ((camera.y + camera.x) - (d * 2.0 - 1.0) * (camera.y - camera.x));
}
"""


def target_name(owner: Any, role: str) -> str:
    """A frame-unique offscreen target name for ``owner`` (a renderer instance) and its ``role``."""
    return f"{type(owner).__name__}@{id(owner):x}.{role}"


def eye_distance(window: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """Window depths in [0, 1] -> distances along the view axis of ``projection`` (inf where the depth is 1)."""
    from ..gl.engine.frame import ProjectionInfo

    info = ProjectionInfo.of(projection)
    n, f = info.near, info.far
    d = np.asarray(window, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = n + d * (f - n) if info.is_orthographic else 2.0 * f * n / ((f + n) - (2.0 * d - 1.0) * (f - n))
    return np.where(d < 1.0, z, np.inf)


def fraction(owner: str, name: str, value: Any) -> float:
    """``value`` as a float in [0, 1], or ValueError naming ``owner`` and ``name``."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        value = float("nan")
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"{owner}: {name} must be a number in [0, 1], got {value!r}")
    return value


class Canvas:
    """The GL engine in the middle of a frame, seen through the pass being drawn.

    ``engine`` is the :class:`~omnirender.gl.GLEngine`; ``calls`` counts the
    draw calls renderers report with :meth:`count`.
    """

    __slots__ = ("engine", "_draw", "calls")

    def __init__(self, engine: Any, draw: Callable[..., int]) -> None:
        self.engine = engine
        self._draw = draw
        self.calls = 0

    # -- where and how things are seen --------------------------------------------------
    @property
    def ctx(self) -> Any:
        """The moderngl context (current while the frame is drawn)."""
        return self.engine.ctx

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of :attr:`framebuffer` in pixels."""
        return tuple(self.engine.target_size)

    @property
    def framebuffer(self) -> Any:
        """The moderngl framebuffer to draw into."""
        return self.engine.current_framebuffer

    @property
    def view(self) -> np.ndarray:
        """World-to-eye matrix of the pass's camera."""
        return self.engine.frame_view

    @property
    def projection(self) -> np.ndarray:
        """Eye-to-clip matrix of the pass's camera."""
        return self.engine.frame_projection

    @property
    def view_projection(self) -> np.ndarray:
        """World-to-clip matrix."""
        return self.engine.frame_projection @ self.engine.frame_view

    @property
    def orthographic(self) -> bool:
        return bool(self.engine.frame_orthographic)

    @property
    def eye(self) -> np.ndarray:
        """The camera position in world coordinates (for an orthographic camera: a point on its axis)."""
        return np.linalg.inv(self.view)[:3, 3]

    @property
    def depth_range(self) -> tuple[float, float]:
        """(near, far) distances of the pass's projection."""
        from ..gl.engine.frame import ProjectionInfo

        info = ProjectionInfo.of(self.projection)
        return info.near, info.far

    @property
    def camera_uniform(self) -> tuple[float, float, float]:
        """(near, far, 1 if orthographic else 0): the ``camera`` argument of the GLSL :data:`EYE_DISTANCE`."""
        near, far = self.depth_range
        return near, far, 1.0 if self.orthographic else 0.0

    # -- drawing -----------------------------------------------------------------------------
    def scope(self) -> int:
        """Draw the scene content of the node the tree sits in (its scope), as the current pass describes it."""
        return self._draw()

    def into(
        self,
        name: str,
        draw: Callable[[Canvas], Any],
        *,
        target: Any = None,
        clear: Any = None,
        camera: Any = None,
    ) -> int:
        """Run ``draw(canvas)`` as a nested pass: into ``target`` (an ``om.gl.Target``), cleared by ``clear``
        (an ``om.gl.Clear``), seen by ``camera`` (an ``om.Camera`` or ``(view, projection)``)."""
        from ..gl import Pass

        def custom(engine: Any, nested: Callable[..., int]) -> int:
            inner = Canvas(engine, nested)
            draw(inner)
            return inner.calls

        return self._draw(Pass(name, target=target, clear=clear, camera=camera, custom=custom))

    def fullscreen(
        self,
        name: str,
        fragment: str,
        inputs: Any = (),
        uniforms: Any = (),
        *,
        blend: bool = False,
        depth: bool = False,
        depth_test: str | None = None,
        state: Any = (),
    ) -> int:
        """Draw the shared full-screen triangle shaded by ``fragment`` (see ``om.gl.FullScreen``) into
        :attr:`framebuffer`; ``inputs`` name ``(target, attachment)`` pairs of this frame's targets and
        ``state`` holds GL state attributes for it (e.g. an ``om.gl.StencilTest``)."""
        from ..gl import FullScreen, Pass

        effect = FullScreen(fragment, inputs=inputs, uniforms=uniforms, blend=blend, depth=depth, depth_test=depth_test)
        return self._draw(Pass(name, items="none", state=state, fullscreen=effect))

    def copy(self, target: Any) -> Any:
        """Save colour and depth of :attr:`framebuffer` into the offscreen ``target`` (an ``om.gl.Target``
        with at most one colour attachment); returns its GPU target (``.texture(name)``, ``.depth``)."""
        return self.engine.copy_framebuffer(target)

    def target(self, name: str) -> Any:
        """The GPU target of this frame called ``name``."""
        return self.engine.target(name)

    def program(self, name: str, vertex: str, fragment: str) -> Any:
        """A moderngl program compiled once per engine (the engine's shader header and sRGB helpers included)."""
        programs = self.engine.programs
        if not programs.registered(name):
            programs.register(name, vertex, fragment)
        return programs.get(name)

    @contextmanager
    def preserved(self) -> Iterator[Any]:
        """Run a block that changes GL state and put back the state found (integration rule 4)."""
        from ..gl.engine.glstate import preserved_state

        with preserved_state(self.framebuffer) as saved:
            yield saved

    def count(self, calls: int, items: int = 0) -> None:
        """Report draw calls made directly with moderngl (they appear in the engine's pass report)."""
        self.calls += int(calls)
        self.engine.count(int(calls), int(items))
