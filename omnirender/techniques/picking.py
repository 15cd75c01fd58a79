"""Ray picking: which shapes a ray (or a pixel's ray) hits, nearest first.

The :class:`PickEngine` (service ``"ray.intersect"``) evaluates the scene with
ray intersectors.  Analytic shapes intersect in their local coordinates: the
world ray is carried into the shape's frame by the inverse model matrix with
its direction left unnormalised, so the ray parameter is the world distance.
Triangle sets use a BVH cached per (triangle set, version) — Intel Embree
through ``embreex`` when importable, else the numpy BVH — and every other shape
reaches them through its simplifier.  Outermost shapes whose exact world box
the ray misses are skipped before any tessellation.

Clip planes (``ClipPlane``) are given in the coordinates where they sit in the
graph: the model matrix at the time the plane is added carries it to world
space (as OpenGL's ``glClipPlane`` does with the modelview matrix), and hits on
the clipped side are discarded.  Group masks select subgraphs as in every
engine.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..attributes import ClipPlane, PickId
from ..core.camera import Camera
from ..core.handler import AttributePainter, RayIntersector, default_for
from ..core.mask import compile_mask
from ..geometry import intersect as gi
from ..geometry.bvh import bvh_for, embree_available
from ..shapes import Box, Cone, Cylinder, Disk, LineSet, PointSet, Polyline, Rectangle, Sphere, TriangleSet
from ..shapes.instances import InstanceId
from ..shapes.splats import GaussianSplats
from .base import AnalysisEngine, check_scene, root_of, run_analysis
from .bounds import analytic_bounds

__all__ = ["Hit", "PickEngine", "pick", "pixel_ray", "ClipPlaneTracker"]

RAY = "ray.intersect"


@dataclass(eq=False)
class Hit:
    """One crossing of the pick ray with a shape.

    ``distance`` along the ray in world units; ``point`` and ``normal`` in
    world space (the geometric normal, unit length, turned towards the ray's
    origin side); ``shape`` the shape the scene holds and ``path`` its node
    path; ``primitive`` the triangle index in the (possibly simplified)
    triangle set, the splat's index for an ``om.GaussianSplats`` (also as
    ``splat``), -1 for analytic shapes; ``part`` the shape actually
    intersected (a simplifier's triangle set, or ``shape`` itself).
    ``pick_ids`` are the ids of the ``om.PickId`` attributes active for the
    shape, outermost first (ids nest), and ``pick_id`` the innermost one (None
    without any).  Hits compare by identity (their arrays make value equality
    ambiguous).
    """

    distance: float
    point: np.ndarray
    normal: np.ndarray
    shape: Any
    path: str
    primitive: int = -1
    part: Any = field(default=None, repr=False)
    #: the index of the instance hit when ``shape`` is an ``om.InstanceSet``, else -1
    instance: int = -1
    #: the ids of the active ``om.PickId`` attributes, outermost first
    pick_ids: tuple[int | str, ...] = ()

    @property
    def splat(self) -> int:
        """The index of the splat hit when ``shape`` is an ``om.GaussianSplats`` (its ``primitive``), else -1."""
        return self.primitive if isinstance(self.shape, GaussianSplats) else -1

    @property
    def pick_id(self) -> int | str | None:
        """The innermost ``om.PickId`` id active for the shape hit, or None."""
        return self.pick_ids[-1] if self.pick_ids else None


class PickEngine(AnalysisEngine):
    """Intersects one world-space ray with everything it evaluates; ``hits`` collects the results.

    ``nearest=True`` keeps only the nearest hit (and prunes with it);
    ``backend`` chooses the triangle BVH: "auto" (Embree when importable),
    "numpy" or "embree".
    """

    service = RAY

    def __init__(
        self,
        origin: Any,
        direction: Any,
        *,
        mask: Any = None,
        nearest: bool = False,
        backend: str = "auto",
        on_missing: str = "warn",
    ) -> None:
        super().__init__(mask=mask, on_missing=on_missing)
        o = np.asarray(origin, dtype=np.float64).reshape(-1)
        d = np.asarray(direction, dtype=np.float64).reshape(-1)
        if o.shape != (3,) or d.shape != (3,) or not (np.all(np.isfinite(o)) and np.all(np.isfinite(d))):
            raise ValueError(
                f"PickEngine: the ray needs a finite 3D origin and direction, got {origin!r}, {direction!r}"
            )
        length = float(np.linalg.norm(d))
        if length == 0.0:
            raise ValueError("PickEngine: the ray direction must not be the zero vector")
        if backend not in ("auto", "numpy", "embree"):
            raise ValueError(f"PickEngine: backend must be 'auto', 'numpy' or 'embree', got {backend!r}")
        if backend == "embree" and not embree_available():
            raise ValueError("PickEngine: backend 'embree' needs the embreex package (pip install embreex)")
        self.origin = o
        self.direction = d / length
        self.inv_direction = gi.safe_inverse(self.direction)
        self.nearest = nearest
        self.backend = backend
        self.hits: list[Hit] = []
        self.tmax = np.inf
        self.clip_planes: dict[int, np.ndarray] = {}
        self._local_key: Any = None
        self._local: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    # -- skipping ---------------------------------------------------------
    def accepts(self, shape: Any) -> bool:
        """Skip an analytic shape whose exact world box the ray misses."""
        box = analytic_bounds(shape, self.model_matrix())
        if box is None:
            return True
        hit, _ = gi.ray_aabb(self.origin, self.inv_direction, box[0], box[1], self.tmax)
        return bool(hit)

    # -- ray in the current frame -------------------------------------------
    def local_ray(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(origin, direction, inverse model matrix) of the ray in the current model frame.

        The direction is not normalised, so ray parameters are world distances.
        """
        m = self.model_matrix()
        if self._local_key is not m:
            inv = np.linalg.inv(m)
            o = inv[:3, :3] @ self.origin + inv[:3, 3]
            d = inv[:3, :3] @ self.direction
            self._local = (o, d, inv)
            self._local_key = m
        return self._local  # type: ignore[return-value]

    def report(self, t: np.ndarray, local_normals: np.ndarray, primitives: Any = -1, part: Any = None) -> None:
        """Record crossings at ray parameters ``t`` with normals in the current model frame."""
        t = np.asarray(t, dtype=np.float64).reshape(-1)
        if not t.size:
            return
        _, _, inv = self.local_ray()
        normals = np.asarray(local_normals, dtype=np.float64).reshape(-1, 3) @ inv[:3, :3]  # inverse transpose
        lengths = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = normals / np.where(lengths > 0, lengths, 1.0)
        facing = normals @ self.direction > 0.0
        normals[facing] *= -1.0
        points = self.origin + t[:, None] * self.direction
        keep = (t > 0.0) & (t <= self.tmax)
        for clip in self.poly(ClipPlane):
            plane = self.clip_planes.get(id(clip))
            if plane is None:
                plane = clip.world_plane(np.eye(4))
            keep &= points @ plane[:3] + plane[3] >= -1e-12
        prims = np.broadcast_to(np.asarray(primitives), t.shape)
        shape = self.scene_shape
        ids = self.poly(InstanceId)
        instance = ids[-1].index if ids else -1
        pick_ids = self.pick_ids()
        for i in np.nonzero(keep)[0]:
            self.hits.append(
                Hit(float(t[i]), points[i], normals[i], shape, self.scene_path, int(prims[i]), part, instance, pick_ids)
            )
        if self.nearest and self.hits:
            best = min(self.hits, key=lambda h: h.distance)
            self.hits = [best]
            self.tmax = best.distance

    def pick_ids(self) -> tuple[int | str, ...]:
        """The ids of the ``om.PickId`` attributes active now, outermost first."""
        return tuple(p.id for p in self.poly(PickId))

    def sorted_hits(self) -> list[Hit]:
        """The hits nearest first."""
        return sorted(self.hits, key=lambda h: h.distance)


@default_for(PickEngine)
class ClipPlaneTracker(AttributePainter):
    """Remembers each clip plane's world equation (model matrix at the time it is added)."""

    __slots__ = ()
    service = RAY
    target = ClipPlane

    def exec(self, attribute: ClipPlane, engine: PickEngine) -> None:
        engine.clip_planes[id(attribute)] = attribute.world_plane(engine.model_matrix())

    def unexec(self, attribute: ClipPlane, engine: PickEngine) -> None:
        if not any(c is attribute for c in engine.poly(ClipPlane)):
            engine.clip_planes.pop(id(attribute), None)


# -- intersectors -----------------------------------------------------------------


class AnalyticIntersector(RayIntersector):
    """Base: intersect in local coordinates with ``local(shape, o, d) -> (t, normals)``."""

    __slots__ = ()

    def local(self, shape: Any, o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def exec(self, shape: Any, engine: PickEngine) -> None:
        o, d, _ = engine.local_ray()
        t, n = self.local(shape, o, d)
        engine.report(t, n, -1, shape)


@default_for(PickEngine)
class SphereIntersector(AnalyticIntersector):
    __slots__ = ()
    target = Sphere

    def local(self, shape, o, d):
        return gi.ray_sphere(o, d, shape.center, shape.radius)


@default_for(PickEngine)
class BoxIntersector(AnalyticIntersector):
    __slots__ = ()
    target = Box

    def local(self, shape, o, d):
        return gi.ray_box(o, d, shape.center, shape.size)


@default_for(PickEngine)
class CylinderIntersector(AnalyticIntersector):
    __slots__ = ()
    target = Cylinder

    def local(self, shape, o, d):
        return gi.ray_cylinder(o, d, shape.radius, shape.height)


@default_for(PickEngine)
class ConeIntersector(AnalyticIntersector):
    __slots__ = ()
    target = Cone

    def local(self, shape, o, d):
        return gi.ray_cone(o, d, shape.radius, shape.height)


@default_for(PickEngine)
class DiskIntersector(AnalyticIntersector):
    __slots__ = ()
    target = Disk

    def local(self, shape, o, d):
        return gi.ray_disk(o, d, shape.radius)


@default_for(PickEngine)
class RectangleIntersector(AnalyticIntersector):
    __slots__ = ()
    target = Rectangle

    def local(self, shape, o, d):
        return gi.ray_rectangle(o, d, shape.size)


@default_for(PickEngine)
class TriangleSetIntersector(RayIntersector):
    """Triangle sets through their cached BVH (Embree or numpy, per the engine's ``backend``)."""

    __slots__ = ()
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: PickEngine) -> None:
        if shape.triangle_count == 0:
            return
        o, d, _ = engine.local_ray()
        hits = bvh_for(shape, engine.backend).intersect(o, d, tmax=engine.tmax)
        if not len(hits):
            return
        tri = shape.vertex_array()[shape.index_array()[hits.triangle]].astype(np.float64)
        normals = gi.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        engine.report(hits.t, normals, hits.triangle, shape)


class _NotPickable(RayIntersector):
    """Lines and points have no area: rays pass them (explicitly, so no warning is issued)."""

    __slots__ = ()

    def exec(self, shape: Any, engine: PickEngine) -> None:
        return None


@default_for(PickEngine)
class LineSetIntersector(_NotPickable):
    __slots__ = ()
    target = LineSet


@default_for(PickEngine)
class PolylineIntersector(_NotPickable):
    __slots__ = ()
    target = Polyline


@default_for(PickEngine)
class PointSetIntersector(_NotPickable):
    __slots__ = ()
    target = PointSet


# -- rays through pixels ----------------------------------------------------------


def pixel_ray(camera: Camera, camera_world: np.ndarray | None, pixel: Any, size: Any) -> tuple[np.ndarray, np.ndarray]:
    """World ray (origin, unit direction) through the centre of ``pixel`` for an image of ``size``.

    Pixel (0, 0) is the top-left pixel.  Perspective rays start at the eye;
    orthographic rays start on the eye plane.  ``camera_world`` is the
    camera's world matrix (where it sits in the graph), None for identity.
    """
    w, h = _size(size)
    try:
        px, py = (float(c) for c in pixel)
    except (TypeError, ValueError):
        raise ValueError(f"pick: pixel must be (x, y), got {pixel!r}") from None
    if not (np.isfinite(px) and np.isfinite(py)):
        raise ValueError(f"pick: pixel must be finite, got {pixel!r}")
    if not (0.0 <= px < w and 0.0 <= py < h):
        raise ValueError(
            f"pick: pixel {pixel!r} is outside the {w}x{h} image; x must lie in [0, {w}) and y in [0, {h}) "
            f"(pixel (0, 0) is the top-left one)"
        )
    ndc_x = 2.0 * (px + 0.5) / w - 1.0
    ndc_y = 1.0 - 2.0 * (py + 0.5) / h
    inv_proj = np.linalg.inv(camera.projection_matrix(w / h))
    near = inv_proj @ np.array([ndc_x, ndc_y, -1.0, 1.0])
    far = inv_proj @ np.array([ndc_x, ndc_y, 1.0, 1.0])
    near, far = near[:3] / near[3], far[:3] / far[3]
    d_eye = far - near
    o_eye = np.array([near[0], near[1], 0.0]) if camera.is_orthographic else np.zeros(3)
    view = camera.view_matrix()
    if camera_world is not None:
        view = view @ np.linalg.inv(camera_world)
    eye_to_world = np.linalg.inv(view)
    o = eye_to_world[:3, :3] @ o_eye + eye_to_world[:3, 3]
    d = eye_to_world[:3, :3] @ d_eye
    return o, d / np.linalg.norm(d)


def _size(size: Any) -> tuple[int, int]:
    """(width, height) as positive whole numbers of pixels; ValueError naming ``size`` otherwise."""
    try:
        values = [float(c) for c in size]
    except (TypeError, ValueError):
        raise ValueError(f"size must be (width, height) in pixels, got {size!r}") from None
    if len(values) != 2 or not all(np.isfinite(values)) or any(v != int(v) for v in values):
        raise ValueError(f"size must be two whole numbers of pixels (width, height), got {size!r}")
    w, h = (int(v) for v in values)
    if w <= 0 or h <= 0:
        raise ValueError(f"size must be positive, got {size!r}")
    return w, h


def scene_camera(scene: Any, camera: Camera | None, mask: Any) -> tuple[Camera, np.ndarray | None]:
    """The given camera (at identity), else the scene's pre-evaluated camera with its world matrix."""
    if camera is not None:
        if not isinstance(camera, Camera):
            raise TypeError(f"camera must be an om.Camera, got {type(camera).__name__}")
        return camera, None
    found = None
    if hasattr(scene, "preevaluate"):
        root = root_of(scene)  # a subgraph is seen by the camera of its graph
        _, found = root.preevaluate(compile_mask(mask) if isinstance(mask, str) else mask)
    if found is None:
        raise ValueError(
            "pick/image_info: the scene has no camera; add an om.Camera to the scene "
            "or pass camera=om.Camera.look_at(...)"
        )
    return found


def pick(
    scene: Any,
    ray: Any = None,
    *,
    pixel: Any = None,
    size: Any = None,
    camera: Camera | None = None,
    mask: str | None = None,
    nearest: bool = False,
    backend: str = "auto",
) -> list[Hit]:
    """Every crossing of a ray with the scene's shapes, nearest first.

    Give either ``ray=(origin, direction)`` in world coordinates, or
    ``pixel=(x, y)`` with ``size=(width, height)``: the ray through that
    pixel's centre (pixel (0, 0) top-left) for ``camera`` or, by default, the
    camera found in the scene; then the camera's group mask applies unless
    ``mask`` is given.  ``nearest=True`` returns at most the nearest hit.
    ``scene`` is a Node (a subgraph is picked where it sits: everything before
    it from its root applies, and its root's camera is the default camera) or
    a list of components.  A pixel outside the image raises ValueError.
    """
    scene = check_scene("pick", scene)  # a Node, or the components as a list (a generator is read once)
    if (ray is None) == (pixel is None):
        raise ValueError("pick: give exactly one of ray=(origin, direction) or pixel=(x, y) with size=(w, h)")
    if pixel is not None:
        if size is None:
            raise ValueError("pick: pixel=(x, y) needs size=(width, height) of the image")
        cam, world = scene_camera(scene, camera, mask)
        origin, direction = pixel_ray(cam, world, pixel, size)
        if mask is None and cam.mask:
            mask = cam.mask  # what the camera shows is what its pixels pick (as the GL engine renders)
    else:
        try:
            origin, direction = ray
        except (TypeError, ValueError):
            raise ValueError(f"pick: ray must be (origin, direction), got {ray!r}") from None
    engine = PickEngine(origin, direction, mask=mask, nearest=nearest, backend=backend)
    run_analysis(engine, "pick", scene, mask)
    return engine.sorted_hits()
