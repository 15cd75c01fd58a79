"""One viewer frame as something any engine can run.

A frame is evaluated by ``engine.run(FrameRoot)``: the root's declarative
pre-evaluation hands the engine the viewer's lights (camera-space ones placed
by the eye-to-world matrix), the lights of every scene node in the render
lists, and a camera carrying the viewer's exact view and projection matrices.
Its program evaluates a single :class:`FrameShape`, whose simplifier (a
default for every engine) draws the four passes by calling each renderable's
``render(engine, flags)``.  Because the frame runs inside one traversal, nodes
evaluated by renderables do not redo pre-evaluation, so lights and camera stay
those of the frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..core.component import Shape
from ..core.engine import Engine
from ..core.handler import ShapeSimplifier, default_for
from ..core.program import EVAL
from ..core.transform import Matrix
from .render_list import PASSES
from .renderable import HIGHLIGHT, TRANSPARENT, TWO_DIMENSIONAL

__all__ = ["ViewCamera", "FrameShape", "FrameRoot", "FrameSimplifier", "PASS_FLAGS"]

#: Flags given to ``render`` in each pass.
PASS_FLAGS = {
    "opaque": 0,
    "transparent": TRANSPARENT,
    "opaque_2d": TWO_DIMENSIONAL,
    "transparent_2d": TRANSPARENT | TWO_DIMENSIONAL,
}


class ViewCamera(Camera):
    """An ``om.Camera`` whose view and projection are given as matrices by the viewer."""

    __slots__ = ("_view", "_projection")

    def __init__(self, camera: Camera, view: np.ndarray, projection: np.ndarray) -> None:
        if camera.is_orthographic:
            super().__init__(camera.eye, camera.center, camera.up, fov=None, height=camera.height,
                             near=camera.near, far=camera.far)  # fmt: skip
        else:
            super().__init__(camera.eye, camera.center, camera.up, fov=camera.fov, near=camera.near, far=camera.far)
        object.__setattr__(self, "_view", np.array(view, dtype=np.float64))
        object.__setattr__(self, "_projection", np.array(projection, dtype=np.float64))

    def view_matrix(self) -> np.ndarray:
        return self._view.copy()

    def projection_matrix(self, aspect: float) -> np.ndarray:
        return self._projection.copy()


class FrameShape(Shape):
    """Stands for "draw the viewer's render lists" inside an engine traversal.

    ``driver`` supplies ``begin_pass(engine, name)`` (a hook, also called with
    ``"end"``) and ``pass_attributes(name)`` (attributes pushed around a pass,
    e.g. depth test off for 2D); ``overrides`` are pushed around the whole frame
    (e.g. a wireframe draw style).
    """

    __slots__ = ("_lists", "_highlighted", "_driver", "_overrides")

    def __init__(
        self,
        lists: Sequence[Any],
        highlighted: set[int],
        driver: Any = None,
        overrides: Sequence[Any] = (),
    ) -> None:
        super().__init__()
        object.__setattr__(self, "_lists", tuple(lists))
        object.__setattr__(self, "_highlighted", highlighted)
        object.__setattr__(self, "_driver", driver)
        object.__setattr__(self, "_overrides", tuple(overrides))


@default_for(Engine)
class FrameSimplifier(ShapeSimplifier):
    """Draws a frame: opaque, transparent, 2D opaque, 2D transparent, each list in turn."""

    __slots__ = ()
    target = FrameShape

    def exec(self, shape: FrameShape, engine: Engine) -> None:
        highlighted = shape._highlighted
        driver = shape._driver
        for attribute in shape._overrides:
            engine.push(attribute)
        try:
            for name in PASSES:
                items = [r for rl in shape._lists for r in rl.sublist(name)]
                if not items:
                    continue
                if driver is not None:
                    driver.begin_pass(engine, name)
                attributes = driver.pass_attributes(name) if driver is not None else ()
                for attribute in attributes:
                    engine.push(attribute)
                base = PASS_FLAGS[name]
                for r in items:
                    lit = id(r) in highlighted or id(getattr(r, "owner", None)) in highlighted  # a node's parts
                    r.render(engine, base | HIGHLIGHT if lit else base)
                for attribute in reversed(attributes):
                    engine.pop(attribute.category)
            if driver is not None:
                driver.begin_pass(engine, "end")
        finally:
            for attribute in reversed(shape._overrides):
                engine.pop(attribute.category)
        return None


class FrameRoot:
    """A duck-typed graph root for ``engine.run``: ``groups``, ``preevaluate`` and ``program``.

    It also exposes the node-like ``_items``/``_groups``/``_version`` that
    engines walking graphs themselves (the GL engine's cached pre-evaluation)
    read: the camera, the world-space lights, every scene node drawn (for their
    lights), then the eye-to-world matrix followed by the camera-space lights.
    """

    __slots__ = ("_items", "_camera", "_shape", "_lights", "_version", "name", "path", "__weakref__")

    def __init__(
        self,
        camera: ViewCamera,
        shape: FrameShape,
        world_lights: Sequence[Any],
        camera_lights: Sequence[Any],
        eye_to_world: np.ndarray,
        nodes: Sequence[Any],
        version: int = 0,
    ) -> None:
        self._camera = camera
        self._shape = shape
        self._items: list[Any] = [camera, *world_lights, *nodes]
        self._lights: list[tuple[Any, np.ndarray]] = [(light, np.eye(4)) for light in world_lights]
        if camera_lights:
            self._items.append(Matrix(eye_to_world))
            self._items.extend(camera_lights)
            self._lights.extend((light, eye_to_world) for light in camera_lights)
        self._version = version
        self.name = "viewer"
        self.path = "/viewer"

    groups: frozenset[str] = frozenset()
    _groups: frozenset[str] = frozenset()

    def preevaluate(self, mask_fn: Any = None) -> tuple[list[tuple[Any, np.ndarray]], tuple[Camera, np.ndarray]]:
        lights = list(self._lights)
        seen = {id(light) for light, _ in lights}
        for item in self._items:
            if hasattr(item, "preevaluate") and hasattr(item, "_items"):
                for light, matrix in item.preevaluate(mask_fn)[0]:
                    if id(light) not in seen:
                        seen.add(id(light))
                        lights.append((light, matrix))
        return lights, (self._camera, np.eye(4))

    def program(self) -> list[tuple[int, Any]]:
        return [(EVAL, self._shape)]
