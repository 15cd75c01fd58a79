"""Picking in a viewer: the shape under a pixel, seen through the viewer's camera, and its highlight."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.transform import Matrix
from ..techniques.base import AnalysisEngine
from .frame import ViewCamera
from .renderable import TRANSPARENT, NodeRenderable

__all__ = ["pick_in_viewer", "viewer_camera", "PickHighlight", "shape_world_matrix"]


def viewer_camera(viewer: Any) -> ViewCamera:
    """An ``om.Camera`` with exactly the viewer's view and projection matrices."""
    cam = viewer.camera
    return ViewCamera(cam.to_camera(), cam.get_view_matrix(), cam.get_projection_matrix())


def pick_in_viewer(viewer: Any, scene: Any, x: int, y: int) -> Any:
    """The nearest ``om.Hit`` at pixel (x, y) (top-left origin) of ``viewer``, or None.

    ``scene`` None picks among every Node the viewer draws.  The viewer's
    group mask applies (what is not drawn is not picked).
    """
    from ..techniques import pick

    roots = [scene] if scene is not None else [r.node for r in viewer.renderables() if isinstance(r, NodeRenderable)]
    camera = viewer_camera(viewer)
    best = None
    for root in roots:
        hits = pick(root, pixel=(x, y), size=viewer.size, camera=camera, nearest=True, mask=viewer.mask)
        if hits and (best is None or hits[0].distance < best[1].distance):
            best = (root, hits[0])
    if best is None:
        return None
    root, hit = best
    return _with_root(hit, root)


def _with_root(hit: Any, root: Any) -> Any:
    try:
        hit.root = root
    except AttributeError:
        pass
    return hit


class _PlacementProbe(AnalysisEngine):
    """Records the model matrix where one shape is evaluated in the node occurrence at one path."""

    def __init__(self, path: str, shape: Any) -> None:
        super().__init__(on_missing="skip")
        self.path = path
        self.shape = shape
        self.matrix: np.ndarray | None = None

    def eval(self, shape: Any) -> None:
        if self.matrix is None and shape is self.shape and self.node_path == self.path:
            self.matrix = np.array(self.model_matrix())


def shape_world_matrix(root: Any, path: str, shape: Any) -> np.ndarray:
    """Model matrix of ``shape`` in the node at ``path`` under ``root``, following that very path.

    The root is evaluated through an analysis engine (the one interpreter of
    node semantics), so every transform before the shape on the way applies,
    including a ``Billboard`` facing the root's camera, and a node shared by
    several parents is placed where ``path`` says, not where its first
    parent puts it.
    """
    probe = _PlacementProbe(path if path.startswith("/") else "/" + path, shape)
    probe.run(root)
    if probe.matrix is None:
        raise KeyError(f"no occurrence of {type(shape).__name__} at {path!r} under {root.path}")
    return probe.matrix


class PickHighlight:
    """Renderable drawing a picked shape again, translucent in the highlight colour, over its visible parts.

    It is drawn in the transparent pass with the depth test ``lequal``, so the
    copy covers exactly the visible pixels of the shape (the same geometry lies
    at the same depth) and nothing in front of it.
    """

    def __init__(self, root: Any, path: str, shape: Any, color: tuple[float, float, float] = (1.0, 0.85, 0.1)) -> None:
        self.root = root
        self.path = path
        self.shape = shape
        self.color = color
        self.visible = True
        self.z_order = 1000
        self._matrix = np.eye(4)

    def prerender(self, render_list: Any) -> None:
        self._matrix = shape_world_matrix(self.root, self.path, self.shape)

    def render(self, renderer: Any, flags: int) -> None:
        from ..attributes import Color, Highlight

        attributes = [Matrix(self._matrix), Color(*self.color, a=0.5), Highlight(self.color), *_depth_lequal()]
        for a in attributes:
            renderer.push(a)
        try:
            renderer.eval(self.shape)
        finally:
            for a in reversed(attributes):
                renderer.pop(a.category)

    def update_bounds(self, pmin: np.ndarray, pmax: np.ndarray) -> None:
        pass

    def render_hints(self) -> int:
        return TRANSPARENT


def _depth_lequal() -> list[Any]:
    """``gl.DepthTest(func="lequal")`` when the GL adapter is there (other engines ignore it)."""
    try:
        from ..gl.engine.attributes import DepthTest
    except ImportError:
        return []
    return [DepthTest(enabled=True, func="lequal")]
