"""Image information: where the shapes at a node path land in the image.

The :class:`ImageInfoEngine` (service ``"image.info"``) evaluates only the
shapes at or below the path (the node is the engine's scope, evaluated from
its root) and projects them with the scene's camera: spheres under a
similarity transform analytically (tangent planes through the eye, so the
rectangle is the exact silhouette's), everything else through its triangle,
line or point sets (simplifiers supply them).  Triangles and segments are
clipped against the camera's near and far planes before they are projected,
as a rasteriser does, so geometry crossing the eye plane (a floor seen from
eye height) covers the part of the image it really covers and its depth range
starts at the near plane.  Texts are their anchor plus a rectangle of roughly
``0.6 * size`` pixels per character by ``size`` pixels (anchor at its
lower-left corner).  Depths are eye-space distances along the viewing axis
(-z in eye coordinates).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..core.handler import SIMPLIFY, ShapePainter, default_for
from ..shapes import LineSet, PointSet, Polyline, Sphere, Text, TriangleSet
from .base import AnalysisEngine, check_scene, evaluate_in_place
from .picking import _size, scene_camera

__all__ = ["ImageInfo", "ImageInfoEngine", "image_info"]

INFO = "image.info"


@dataclass
class ImageInfo:
    """Where shapes land in an image.

    ``rect`` = (x0, y0, x1, y1) in whole pixels, top-left origin, end exclusive,
    clipped to the image (None when nothing is in view); ``extent`` the same
    unclipped and unrounded; ``depth`` = (near, far) eye-space depth range.
    """

    rect: tuple[int, int, int, int] | None
    extent: tuple[float, float, float, float] | None
    depth: tuple[float, float] | None
    size: tuple[int, int]

    @property
    def visible(self) -> bool:
        return self.rect is not None


class ImageInfoEngine(AnalysisEngine):
    """Accumulates NDC x/y ranges and depth ranges of the shapes it evaluates (its scope: the path's node).

    ``size`` (width, height) in pixels is needed for texts (sized in pixels);
    without it a text counts as its anchor point.
    """

    service = INFO

    def __init__(
        self,
        path: str,
        view: np.ndarray,
        camera: Camera,
        aspect: float,
        *,
        mask: Any = None,
        size: tuple[int, int] | None = None,
    ) -> None:
        super().__init__(mask=mask)
        self.path = path
        self.view = np.asarray(view, dtype=np.float64)
        self.camera_attr = camera
        self.projection = camera.projection_matrix(aspect)
        self.near = max(float(camera.near), 1e-12) if not camera.is_orthographic else float(camera.near)
        self.far = float(camera.far)
        self.size = size
        self.ranges: np.ndarray | None = None  # [xmin, xmax, ymin, ymax, zmin, zmax]

    def include(self, xmin: float, xmax: float, ymin: float, ymax: float, dmin: float, dmax: float) -> None:
        r = np.array([xmin, xmax, ymin, ymax, dmin, dmax])
        if self.ranges is None:
            self.ranges = r
        else:
            self.ranges[0::2] = np.minimum(self.ranges[0::2], r[0::2])
            self.ranges[1::2] = np.maximum(self.ranges[1::2], r[1::2])

    def to_eye(self, local_points: np.ndarray) -> np.ndarray:
        """Points of the current model frame in eye coordinates (N, 3)."""
        m = self.view @ self.model_matrix()
        return np.asarray(local_points, dtype=np.float64).reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]

    def include_eye(self, p: np.ndarray) -> None:
        """Project eye-space points that lie between the near and far planes."""
        if not len(p):
            return
        depth = -p[:, 2]
        clip = np.c_[p, np.ones(len(p))] @ self.projection.T
        ndc = clip[:, :2] / clip[:, 3:4]
        self.include(ndc[:, 0].min(), ndc[:, 0].max(), ndc[:, 1].min(), ndc[:, 1].max(), depth.min(), depth.max())

    def include_points(self, local_points: np.ndarray) -> None:
        """Points in the current model frame; those outside the near/far slab are not seen."""
        p = self.to_eye(local_points)
        d = -p[:, 2]
        self.include_eye(p[(d >= self.near) & (d <= self.far)])

    def include_segments(self, local_points: np.ndarray, segments: np.ndarray) -> None:
        """Segments (K, 2 indices) and the polygons they bound, clipped against the near and far planes.

        The clipped pieces' corners are the endpoints inside the slab and the
        points where segments cross a plane; their projections bound the
        clipped geometry's projection (for triangles: pass their three edges).
        """
        p = self.to_eye(local_points)
        seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
        if not len(seg):
            return
        d = -p[:, 2]
        used = np.zeros(len(p), dtype=bool)
        used[seg.ravel()] = True
        inside = used & (d >= self.near) & (d <= self.far)
        pieces = [p[inside]]
        a, b = seg[:, 0], seg[:, 1]
        for plane in (self.near, self.far):
            sa, sb = d[a] - plane, d[b] - plane
            cross = sa * sb < 0.0
            if np.any(cross):
                sa, sb = sa[cross], sb[cross]
                t = (sa / (sa - sb))[:, None]
                pa, pb = p[a[cross]], p[b[cross]]
                q = pa + t * (pb - pa)
                q[:, 2] = -plane  # exactly on the plane
                pieces.append(q)
        self.include_eye(np.concatenate(pieces))

    def include_text(self, text: Text) -> None:
        """A label: its anchor, and with a known image size the rectangle its glyphs roughly cover."""
        p = self.to_eye(np.asarray([text.position], dtype=np.float64))
        d = float(-p[0, 2])
        if not (self.near <= d <= self.far):
            return
        clip = np.append(p[0], 1.0) @ self.projection.T
        x, y = clip[:2] / clip[3]
        if self.size is None:
            self.include(x, x, y, y, d, d)
            return
        w, h = self.size
        width = 0.6 * float(text.size) * len(text.string)
        self.include(x, x + 2.0 * width / w, y, y + 2.0 * float(text.size) / h, d, d)


@default_for(ImageInfoEngine)
class TriangleSetInfo(ShapePainter):
    """Triangles clipped against the near and far planes (through their edges)."""

    __slots__ = ()
    service = INFO
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: ImageInfoEngine) -> None:
        idx = shape.index_array()
        if len(idx):
            engine.include_segments(shape.vertex_array(), idx[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2))


class _SegmentInfo(ShapePainter):
    __slots__ = ()
    service = INFO

    def exec(self, shape: Any, engine: ImageInfoEngine) -> None:
        engine.include_segments(shape.vertex_array(), shape.index_array())


@default_for(ImageInfoEngine)
class LineSetInfo(_SegmentInfo):
    __slots__ = ()
    target = LineSet


@default_for(ImageInfoEngine)
class PolylineInfo(_SegmentInfo):
    __slots__ = ()
    target = Polyline


@default_for(ImageInfoEngine)
class PointSetInfo(ShapePainter):
    __slots__ = ()
    service = INFO
    target = PointSet

    def exec(self, shape: PointSet, engine: ImageInfoEngine) -> None:
        engine.include_points(shape.vertex_array())


@default_for(ImageInfoEngine)
class TextInfo(ShapePainter):
    """A label's anchor and the pixel rectangle its glyphs roughly cover."""

    __slots__ = ()
    service = INFO
    target = Text

    def exec(self, shape: Text, engine: ImageInfoEngine) -> None:
        engine.include_text(shape)


@default_for(ImageInfoEngine)
class SphereInfo(ShapePainter):
    """Exact projected extent of a sphere under a similarity transform (else its simplification)."""

    __slots__ = ()
    service = INFO
    target = Sphere

    def exec(self, shape: Sphere, engine: ImageInfoEngine) -> None:
        m = engine.view @ engine.model_matrix()
        a = m[:3, :3]
        scale = abs(np.linalg.det(a)) ** (1.0 / 3.0)
        similar = scale > 0 and np.allclose(a.T @ a, scale * scale * np.eye(3), rtol=1e-9, atol=1e-12 * scale * scale)
        c = a @ np.asarray(shape.center, dtype=np.float64) + m[:3, 3]
        r = shape.radius * scale
        depth = -c[2]
        p = engine.projection
        if depth + r < engine.near or depth - r > engine.far:
            return  # wholly in front of the near plane or beyond the far plane
        within = engine.near <= depth - r and depth + r <= engine.far
        if similar and within and engine.camera_attr.is_orthographic:
            x = (p[0, 0] * (c[0] - r) + p[0, 3], p[0, 0] * (c[0] + r) + p[0, 3])
            y = (p[1, 1] * (c[1] - r) + p[1, 3], p[1, 1] * (c[1] + r) + p[1, 3])
            engine.include(*x, *y, depth - r, depth + r)
            return
        if similar and within:
            xs = _tangents(c[0], c[2], r)
            ys = _tangents(c[1], c[2], r)
            x = sorted(-p[0, 0] * k for k in xs)
            y = sorted(-p[1, 1] * k for k in ys)
            engine.include(x[0], x[1], y[0], y[1], depth - r, depth + r)
            return
        simplifier = engine.find_handler(SIMPLIFY, Sphere)
        if simplifier is not None:
            engine.evaluate(simplifier.exec(shape, engine))


def _tangents(u: float, z: float, r: float) -> tuple[float, float]:
    """Slopes k of the planes u = k z through the eye that touch a sphere at (u, z) of radius r."""
    a = z * z - r * r
    b = -2.0 * u * z
    c = u * u - r * r
    disc = math.sqrt(max(b * b - 4 * a * c, 0.0))
    return (-b - disc) / (2 * a), (-b + disc) / (2 * a)


def image_info(scene: Any, path: str, size: Any, camera: Camera | None = None, mask: str | None = None) -> ImageInfo:
    """Pixel rectangle and depth range of the shapes at (or below) ``path`` for the scene's camera.

    ``camera`` overrides the scene's camera; the camera's group mask applies unless ``mask`` is given.
    """
    w, h = _size(size)
    check_scene("image_info", scene)
    if not hasattr(scene, "_compile_node"):
        raise TypeError(f"image_info: scene must be an om.Node (paths name its nodes), got {type(scene).__name__}")
    node = scene[path]
    cam, world = scene_camera(scene, camera, mask)
    if mask is None and cam.mask:
        mask = cam.mask
    view = cam.view_matrix() if world is None else cam.view_matrix() @ np.linalg.inv(world)
    engine = ImageInfoEngine(node.path, view, cam, w / h, mask=mask, size=(w, h))
    evaluate_in_place(engine, node, mask)
    if engine.ranges is None:
        return ImageInfo(None, None, None, (w, h))
    xmin, xmax, ymin, ymax, dmin, dmax = engine.ranges
    extent = ((xmin + 1) / 2 * w, (1 - ymax) / 2 * h, (xmax + 1) / 2 * w, (1 - ymin) / 2 * h)
    # whole pixels touched; a degenerate extent (a point, an edge-on disk) still covers one pixel
    x0, y0 = math.floor(extent[0]), math.floor(extent[1])
    x1, y1 = max(math.ceil(extent[2]), x0 + 1), max(math.ceil(extent[3]), y0 + 1)
    x0, y0, x1, y1 = max(0, x0), max(0, y0), min(w, x1), min(h, y1)
    rect = (x0, y0, x1, y1) if x0 < x1 and y0 < y1 else None
    return ImageInfo(rect, tuple(float(e) for e in extent), (float(dmin), float(dmax)), (w, h))
