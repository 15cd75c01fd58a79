"""Light fields: calibrated views (pinhole intrinsics and extrinsics) with depth maps, in memory or in a folder.

A :class:`LightFieldView` is one image with its depth map and camera:

* ``image``: (H, W, 4) uint8 RGBA, colour premultiplied by alpha (what a
  renderer produces over transparent black; photographs have alpha 255);
* ``depth``: (H, W) float32 distance along the camera's viewing axis, inf
  (or nan, or <= 0) where nothing was seen;
* ``intrinsics``: ``(fx, fy, cx, cy)`` in pixels, the image origin at the
  top-left corner of the top-left pixel, y pointing down;
* ``view``: the 4x4 world-to-camera matrix with OpenGL axes (x right, y up,
  the camera looking down -z), as ``om.Camera.view_matrix()``.

A :class:`LightField` holds two or more views and computes, once, the
bounding box of the intersection of their viewing frusta (each frustum cut at
the nearest and farthest depth its view saw): the region the light field
describes.  ``save(folder)`` writes ``cameras.json`` plus one PNG and one
``.npy`` depth map per view; :meth:`LightField.load` reads them back.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...core.camera import Camera

__all__ = ["LightFieldView", "LightField", "FORMAT"]

#: ``format`` value of cameras.json.
FORMAT = "omnirender.lightfield/1"


@dataclass(eq=False)
class LightFieldView:
    """One calibrated view of a light field (see the module docstring for the conventions)."""

    image: np.ndarray
    depth: np.ndarray
    intrinsics: tuple[float, float, float, float]
    view: np.ndarray

    def __post_init__(self) -> None:
        image = np.asarray(self.image)
        if image.ndim == 3 and image.shape[2] == 3:
            image = np.concatenate([image, np.full(image.shape[:2] + (1,), 255, image.dtype)], axis=2)
        if image.ndim != 3 or image.shape[2] != 4 or image.dtype != np.uint8:
            raise ValueError(
                f"LightFieldView: image must be (H, W, 4) uint8 RGBA, got shape {image.shape} dtype {image.dtype}"
            )
        h, w = image.shape[:2]
        if h < 2 or w < 2:
            raise ValueError(f"LightFieldView: image must be at least 2x2 pixels, got {w}x{h}")
        depth = np.asarray(self.depth, dtype=np.float32)
        if depth.shape != (h, w):
            raise ValueError(f"LightFieldView: depth must be (H, W) = {(h, w)} like the image, got {depth.shape}")
        depth = np.where(np.isfinite(depth) & (depth > 0), depth, np.inf).astype(np.float32)
        try:
            fx, fy, cx, cy = (float(v) for v in self.intrinsics)
        except (TypeError, ValueError):
            raise ValueError(f"LightFieldView: intrinsics must be (fx, fy, cx, cy), got {self.intrinsics!r}") from None
        if not (fx > 0 and fy > 0 and all(math.isfinite(v) for v in (fx, fy, cx, cy))):
            raise ValueError(f"LightFieldView: focal lengths must be > 0 and finite, got {self.intrinsics!r}")
        view = np.asarray(self.view, dtype=np.float64)
        if view.shape != (4, 4) or not np.all(np.isfinite(view)):
            raise ValueError(f"LightFieldView: view must be a finite 4x4 world-to-camera matrix, got {view.shape}")
        rot = view[:3, :3]
        if not np.allclose(rot @ rot.T, np.eye(3), atol=1e-5) or not np.allclose(view[3], (0, 0, 0, 1)):
            raise ValueError("LightFieldView: view must be a rigid world-to-camera matrix (rotation and translation)")
        image.setflags(write=False)
        depth.setflags(write=False)
        self.image, self.depth, self.intrinsics, self.view = image, depth, (fx, fy, cx, cy), view

    @classmethod
    def from_camera(cls, camera: Camera, image: Any, depth: Any, world: np.ndarray | None = None) -> LightFieldView:
        """A view from an ``om.Camera`` (perspective; placed by ``world``) and the image and depth it rendered."""
        if camera.is_orthographic:
            raise ValueError("LightFieldView: light-field views are pinhole (perspective) cameras, not orthographic")
        h, w = np.asarray(image).shape[:2]
        fy = (h / 2.0) / math.tan(math.radians(camera.fov) / 2.0)
        view = camera.view_matrix() if world is None else camera.view_matrix() @ np.linalg.inv(world)
        return cls(image, depth, (fy, fy, w / 2.0, h / 2.0), view)

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.image.shape[1], self.image.shape[0]

    @property
    def center(self) -> np.ndarray:
        """The camera position in world coordinates."""
        rot, t = self.view[:3, :3], self.view[:3, 3]
        return -rot.T @ t

    @property
    def axis(self) -> np.ndarray:
        """The unit viewing direction in world coordinates."""
        return -self.view[2, :3] / np.linalg.norm(self.view[2, :3])

    def valid(self) -> np.ndarray:
        """(H, W) bool: where the depth map holds a surface."""
        return np.isfinite(self.depth)

    def projection(self, near: float, far: float) -> np.ndarray:
        """The OpenGL projection matrix of this pinhole camera (off-centre principal points included)."""
        fx, fy, cx, cy = self.intrinsics
        w, h = self.size
        m = np.zeros((4, 4))
        m[0, 0] = 2.0 * fx / w
        m[1, 1] = 2.0 * fy / h
        m[0, 2] = 1.0 - 2.0 * cx / w
        m[1, 2] = 2.0 * cy / h - 1.0
        m[2, 2] = (far + near) / (near - far)
        m[2, 3] = 2.0 * far * near / (near - far)
        m[3, 2] = -1.0
        return m

    def camera(self, near: float = 0.1, far: float = 1000.0) -> Camera:
        """An ``om.Camera`` looking like this view (centred principal point assumed; vertical field of view)."""
        fx, fy, cx, cy = self.intrinsics
        h = self.size[1]
        fov = math.degrees(2.0 * math.atan((h / 2.0) / fy))
        inv = np.linalg.inv(self.view)
        return Camera(self.center, self.center + self.axis, inv[:3, 1], fov=fov, near=near, far=far)

    def world_points(self, step: int = 1) -> np.ndarray:
        """(N, 3) world positions of every ``step``-th pixel centre with a valid depth."""
        fx, fy, cx, cy = self.intrinsics
        depth = self.depth[::step, ::step]
        ys, xs = np.nonzero(np.isfinite(depth))
        z = depth[ys, xs].astype(np.float64)
        px = xs * step + 0.5
        py = ys * step + 0.5
        eye = np.stack([(px - cx) / fx * z, -(py - cy) / fy * z, -z], axis=1)
        rot, t = self.view[:3, :3], self.view[:3, 3]
        return (eye - t) @ rot  # rot^T (eye - t)

    def surface(self, step: int = 2, discontinuity: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
        """The depth map as a triangle mesh: (M, 3) world vertices of every ``step``-th pixel and (T, 3) triangles.

        Neighbouring samples are joined where all are valid and their depths
        differ by less than ``discontinuity`` (relative), so the mesh breaks
        at depth edges instead of bridging them.
        """
        fx, fy, cx, cy = self.intrinsics
        depth = self.depth[::step, ::step].astype(np.float64)
        rows, cols = depth.shape
        ys, xs = np.mgrid[0:rows, 0:cols]
        z = np.where(np.isfinite(depth), depth, 0.0)
        px, py = xs * step + 0.5, ys * step + 0.5
        eye = np.stack([(px - cx) / fx * z, -(py - cy) / fy * z, -z], axis=-1).reshape(-1, 3)
        rot, t = self.view[:3, :3], self.view[:3, 3]
        vertices = ((eye - t) @ rot).astype(np.float32)
        i = (np.arange(rows - 1)[:, None] * cols + np.arange(cols - 1)[None, :]).ravel()
        triangles = np.concatenate([np.stack([i, i + cols, i + 1], 1), np.stack([i + 1, i + cols, i + cols + 1], 1)])
        flat = depth.ravel()
        corner = flat[triangles]
        lo, hi = corner.min(axis=1), corner.max(axis=1)
        keep = np.isfinite(hi) & (hi <= lo * (1.0 + discontinuity))
        return vertices, triangles[keep].astype(np.uint32)

    def frustum_planes(self) -> np.ndarray | None:
        """(6, 4) planes ``n . x <= d`` (rows ``n, d``) of the frustum cut at the nearest and farthest depth seen."""
        valid = self.depth[np.isfinite(self.depth)]
        if valid.size == 0:
            return None
        near, far = float(valid.min()) * 0.99, float(valid.max()) * 1.01
        fx, fy, cx, cy = self.intrinsics
        w, h = self.size
        # eye-space planes through the eye (normals pointing out of the frustum) and the depth cuts
        # pixel u = cx + fx x / -z in [0, w] and v = cy - fy y / -z in [0, h] (z < 0 in front of the camera)
        eye_planes = [
            (np.array([-fx, 0.0, cx]), 0.0),  # u >= 0:  -fx x + cx z <= 0
            (np.array([fx, 0.0, w - cx]), 0.0),  # u <= w:  fx x + (w - cx) z <= 0
            (np.array([0.0, fy, cy]), 0.0),  # v >= 0:  fy y + cy z <= 0
            (np.array([0.0, -fy, h - cy]), 0.0),  # v <= h:  -fy y + (h - cy) z <= 0
            (np.array([0.0, 0.0, 1.0]), -near),  # z <= -near
            (np.array([0.0, 0.0, -1.0]), far),  # z >= -far
        ]
        rot, t = self.view[:3, :3], self.view[:3, 3]
        out = []
        for n_eye, d_eye in eye_planes:
            # n_eye . (R x + t) <= d_eye  <=>  (R^T n_eye) . x <= d_eye - n_eye . t
            n = rot.T @ n_eye
            out.append((*n, d_eye - float(n_eye @ t)))
        return np.array(out)


class LightField:
    """Two or more :class:`LightFieldView` s of one scene; ``bounds`` is where their frusta intersect."""

    def __init__(self, views: Iterable[LightFieldView]) -> None:
        views = list(views)
        for i, view in enumerate(views):
            if not isinstance(view, LightFieldView):
                raise TypeError(f"LightField: view {i} is a {type(view).__name__}, not a LightFieldView")
        if len(views) < 2:
            raise ValueError(f"LightField: needs at least 2 views, got {len(views)}")
        if not any(view.valid().any() for view in views):
            raise ValueError("LightField: no view has any valid depth; depth maps must hold the surfaces seen")
        self.views = views
        self._bounds: tuple[np.ndarray, np.ndarray] | None = None
        self._points: dict[tuple[int, int], np.ndarray] = {}

    @classmethod
    def combine(cls, *fields: LightField) -> LightField:
        """Several light fields of one scene as one: all their views (in order), one blending field.

        Rendered by a :class:`~.renderer.LightFieldRenderer`, a camera moving from
        the region one field captured to another's passes smoothly from the one
        to the other: the unstructured lumigraph's blending weights are
        continuous in the viewer's position, so the cameras of the field left
        behind fade out as those of the field approached fade in, and where only
        one field's cameras are among the ``k`` best the image is that field's
        alone.
        """
        for i, lf in enumerate(fields):
            if not isinstance(lf, LightField):
                raise TypeError(f"LightField.combine: field {i} is a {type(lf).__name__}, not a LightField")
        if not fields:
            raise ValueError("LightField.combine: give one or more light fields")
        return cls([view for lf in fields for view in lf.views])

    def __len__(self) -> int:
        return len(self.views)

    def __getitem__(self, index: int) -> LightFieldView:
        return self.views[index]

    @property
    def centers(self) -> np.ndarray:
        """(N, 3) camera positions."""
        return np.array([v.center for v in self.views])

    @property
    def axes(self) -> np.ndarray:
        """(N, 3) unit viewing directions."""
        return np.array([v.axis for v in self.views])

    def points(self, index: int, step: int = 2) -> np.ndarray:
        """World points of view ``index`` at every ``step``-th pixel (cached)."""
        key = (index, step)
        found = self._points.get(key)
        if found is None:
            found = self._points[key] = self.views[index].world_points(step)
        return found

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World (min, max) of the intersection of the views' frusta (computed once).

        Falls back to the box of every depth sample when the frusta do not all overlap.
        """
        if self._bounds is None:
            self._bounds = _frusta_bounds(self)
        return self._bounds

    # -- files -------------------------------------------------------------------------------
    def save(self, folder: str | Path) -> Path:
        """Write the light field into ``folder`` (created): ``cameras.json``, ``view_NNN.png``, ``view_NNN.npy``."""
        from PIL import Image as PILImage

        from ...fileio import atomic_write

        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        cameras = []
        for i, view in enumerate(self.views):
            image, depth = f"view_{i:03d}.png", f"view_{i:03d}.npy"
            with atomic_write(folder / image, "wb") as f:
                PILImage.fromarray(np.ascontiguousarray(view.image), "RGBA").save(f, format="PNG")
            with atomic_write(folder / depth, "wb") as f:
                np.save(f, np.asarray(view.depth, dtype=np.float32))
            fx, fy, cx, cy = view.intrinsics
            cameras.append(
                {"image": image, "depth": depth, "fx": fx, "fy": fy, "cx": cx, "cy": cy, "view": view.view.tolist()}
            )
        text = json.dumps({"format": FORMAT, "depth": "distance along the viewing axis", "views": cameras}, indent=1)
        with atomic_write(folder / "cameras.json") as f:
            f.write(text)
        return folder

    @classmethod
    def load(cls, folder: str | Path) -> LightField:
        """Read a light field written by :meth:`save` (or by hand in the same format)."""
        from PIL import Image as PILImage

        folder = Path(folder)
        index = folder / "cameras.json"
        try:
            spec = json.loads(index.read_text())
        except FileNotFoundError:
            raise FileNotFoundError(
                f"LightField.load: {index} not found; a light-field folder holds cameras.json"
            ) from None
        except json.JSONDecodeError as exc:
            raise ValueError(f"LightField.load: {index} is not valid JSON ({exc})") from None
        if not isinstance(spec, dict) or spec.get("format") != FORMAT or not isinstance(spec.get("views"), list):
            raise ValueError(f"LightField.load: {index} must be an object with format {FORMAT!r} and a views list")
        views = []
        for i, cam in enumerate(spec["views"]):
            try:
                image_path = _inside(folder, cam["image"], index)
                depth_path = _inside(folder, cam["depth"], index)
                intrinsics = (cam["fx"], cam["fy"], cam["cx"], cam["cy"])
                view = cam["view"]
            except (KeyError, TypeError):
                raise ValueError(
                    f"LightField.load: view {i} of {index} needs image, depth, fx, fy, cx, cy and view"
                ) from None
            with PILImage.open(image_path) as im:
                image = np.asarray(im.convert("RGBA"))
            depth = np.load(depth_path, allow_pickle=False)
            views.append(LightFieldView(image, depth, intrinsics, view))
        return cls(views)


def _inside(folder: Path, name: Any, index: Path) -> Path:
    """``folder / name``, refusing names that leave the folder."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"LightField.load: file names in {index} must be non-empty strings, got {name!r}")
    path = (folder / name).resolve()
    if folder.resolve() not in path.parents:
        raise ValueError(f"LightField.load: {name!r} in {index} points outside the light-field folder")
    return path


def _frusta_bounds(lf: LightField) -> tuple[np.ndarray, np.ndarray]:
    """Box of the intersection of the views' frusta: one frustum's box clipped by every frustum's planes."""
    samples = np.concatenate([lf.points(i, 4) for i in range(len(lf))])
    fallback = (samples.min(axis=0), samples.max(axis=0))
    planes = [p for p in (view.frustum_planes() for view in lf.views) if p is not None]
    faces = _box_faces(*_corners_box(planes[0]))
    for plane in np.concatenate(planes):
        faces = _clip(faces, plane[:3], plane[3])
        if not faces:
            return fallback
    points = np.array([p for face in faces for p in face])
    return points.min(axis=0), points.max(axis=0)


def _corners_box(planes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The box of a frustum's 8 corners (each the meeting point of a side pair and a depth plane)."""
    corners = []
    for a, b in ((0, 2), (0, 3), (1, 2), (1, 3)):
        for c in (4, 5):
            m = planes[[a, b, c], :3]
            corners.append(np.linalg.solve(m, planes[[a, b, c], 3]))
    corners = np.array(corners)
    return corners.min(axis=0), corners.max(axis=0)


def _box_faces(lo: np.ndarray, hi: np.ndarray) -> list[list[np.ndarray]]:
    c = [np.array([x, y, z]) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return [[c[i] for i in q] for q in quads]


def _clip(faces: list[list[np.ndarray]], normal: np.ndarray, d: float) -> list[list[np.ndarray]]:
    """A convex polyhedron (its faces) cut by the half-space ``normal . x <= d``; the cut is closed by a new face."""
    out: list[list[np.ndarray]] = []
    cut: list[np.ndarray] = []
    for face in faces:
        kept: list[np.ndarray] = []
        for i, a in enumerate(face):
            b = face[(i + 1) % len(face)]
            da, db = float(normal @ a) - d, float(normal @ b) - d
            if da <= 0.0:
                kept.append(a)
            if (da <= 0.0) != (db <= 0.0):
                p = a + (b - a) * (da / (da - db))
                kept.append(p)
                cut.append(p)
        if len(kept) >= 3:
            out.append(kept)
    if len(cut) >= 3:
        center = np.mean(cut, axis=0)
        u = cut[0] - center
        if np.linalg.norm(u) > 0:
            u = u / np.linalg.norm(u)
            v = np.cross(normal, u)
            order = np.argsort([math.atan2(float((p - center) @ v), float((p - center) @ u)) for p in cut])
            out.append([cut[i] for i in order])
    return out
