"""Viewer camera: eye frame, viewing centre and projection (ArtiSynth conventions).

The *eye* frame has the eye at its origin looking down its -z axis with +y up
(legacy OpenGL).  ``eye_to_world`` is its rigid 4x4 pose in world coordinates;
the view matrix (world to eye) is its inverse.  The viewing *centre* is the
point the mouse orbits around and ``set_eye``/``set_center``/``set_up_vector``
re-aim at.  The projection is either perspective or orthogonal and is given by
a field of view (vertical, degrees; the width follows the window's aspect) or
an explicit frustum ``left, right, bottom, top`` at the near plane.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.camera import Camera, look_at_matrix
from ..core.transform import finite_vector
from .axial import AxisAlignedRotation

__all__ = ["ViewerCamera", "frustum_matrix", "ortho_matrix", "DEFAULT_FOV"]

DEFAULT_FOV = 35.0


def frustum_matrix(left: float, right: float, bottom: float, top: float, near: float, far: float) -> np.ndarray:
    """OpenGL ``glFrustum`` projection."""
    m = np.zeros((4, 4))
    m[0, 0] = 2 * near / (right - left)
    m[0, 2] = (right + left) / (right - left)
    m[1, 1] = 2 * near / (top - bottom)
    m[1, 2] = (top + bottom) / (top - bottom)
    m[2, 2] = -(far + near) / (far - near)
    m[2, 3] = -2 * far * near / (far - near)
    m[3, 2] = -1.0
    return m


def ortho_matrix(left: float, right: float, bottom: float, top: float, near: float, far: float) -> np.ndarray:
    """OpenGL ``glOrtho`` projection."""
    m = np.eye(4)
    m[0, 0] = 2 / (right - left)
    m[0, 3] = -(right + left) / (right - left)
    m[1, 1] = 2 / (top - bottom)
    m[1, 3] = -(top + bottom) / (top - bottom)
    m[2, 2] = -2 / (far - near)
    m[2, 3] = -(far + near) / (far - near)
    return m


class ViewerCamera:
    """Eye frame + centre + projection, with the viewer's camera operations."""

    def __init__(self, size: tuple[int, int] = (640, 480)) -> None:
        self.size = size
        self._eye_to_world = np.linalg.inv(look_at_matrix((0, 0, 5), (0, 0, 0), (0, 1, 0)))
        self._center = np.zeros(3)
        self._orthogonal = False
        self._fov: float | None = DEFAULT_FOV  # vertical, degrees; None when an explicit frustum is set
        self._field_height = 2.0  # orthogonal view volume height when _fov-style (field) mode
        self._frustum: tuple[float, float, float, float] | None = None
        self._near = 0.1
        self._far = 1000.0

    # -- frames ----------------------------------------------------------
    @property
    def aspect(self) -> float:
        w, h = self.size
        return w / h

    def get_eye_to_world(self) -> np.ndarray:
        return self._eye_to_world.copy()

    def set_eye_to_world(
        self,
        eye_or_matrix: Any,
        center: Sequence[float] | None = None,
        up: Sequence[float] | None = None,
    ) -> None:
        if center is None and up is None:
            m = np.array(eye_or_matrix, dtype=np.float64)
            if m.shape != (4, 4) or not np.all(np.isfinite(m)):
                raise ValueError(f"set_eye_to_world: need a finite 4x4 matrix, got shape {m.shape}")
            r = m[:3, :3]
            if not np.allclose(r.T @ r, np.eye(3), atol=1e-6) or np.linalg.det(r) < 0:
                raise ValueError("set_eye_to_world: the matrix must be rigid (a rotation plus a translation)")
            distance = self.distance
            self._eye_to_world = m
            self._center = m[:3, 3] - distance * m[:3, 2]
            return
        if center is None or up is None:
            raise TypeError("set_eye_to_world takes a 4x4 matrix, or eye, center and up")
        eye = finite_vector("set_eye_to_world", "eye", eye_or_matrix, 3)
        c = finite_vector("set_eye_to_world", "center", center, 3)
        u = finite_vector("set_eye_to_world", "up", up, 3)
        self._look(eye, c, u)

    def _look(self, eye: np.ndarray, center: np.ndarray, up: np.ndarray) -> None:
        d = center - eye
        if np.linalg.norm(d) == 0:
            raise ValueError("the eye and the centre must differ")
        if np.linalg.norm(np.cross(d, up)) <= 1e-9 * np.linalg.norm(d) * max(np.linalg.norm(up), 1e-300):
            raise ValueError("the up vector must not be parallel to the viewing direction (centre - eye)")
        self._eye_to_world = np.linalg.inv(look_at_matrix(eye, center, up))
        self._center = np.array(center, dtype=np.float64)

    def get_view_matrix(self) -> np.ndarray:
        """World-to-eye matrix."""
        r = self._eye_to_world[:3, :3]
        m = np.eye(4)
        m[:3, :3] = r.T
        m[:3, 3] = -r.T @ self._eye_to_world[:3, 3]
        return m

    def set_view_matrix(self, matrix: Any) -> None:
        """Set the world-to-eye matrix (rigid); the centre stays at the same distance ahead."""
        m = np.array(matrix, dtype=np.float64)
        if m.shape != (4, 4) or not np.all(np.isfinite(m)):
            raise ValueError(f"set_view_matrix: need a finite 4x4 matrix, got shape {m.shape}")
        self.set_eye_to_world(np.linalg.inv(m))

    @property
    def eye(self) -> np.ndarray:
        return self._eye_to_world[:3, 3].copy()

    @property
    def center(self) -> np.ndarray:
        return self._center.copy()

    @property
    def up(self) -> np.ndarray:
        return self._eye_to_world[:3, 1].copy()

    @property
    def eye_z_direction(self) -> np.ndarray:
        """The eye frame's z axis in world coordinates: unit, pointing from the centre back to the eye."""
        z = self._eye_to_world[:3, 2]
        return z / np.linalg.norm(z)

    @property
    def distance(self) -> float:
        """Eye-to-centre distance."""
        return float(np.linalg.norm(self._center - self._eye_to_world[:3, 3]))

    def set_eye(self, eye: Sequence[float]) -> None:
        """Move the eye, keeping the centre; the up vector is kept unless it became the viewing direction."""
        self._reaim(finite_vector("set_eye", "eye", eye, 3), self._center)

    def set_center(self, center: Sequence[float]) -> None:
        """Move the centre, keeping the eye; the up vector is kept unless it became the viewing direction."""
        self._reaim(self.eye, finite_vector("set_center", "center", center, 3))

    def _reaim(self, eye: np.ndarray, center: np.ndarray) -> None:
        d = center - eye
        up = self.up
        if np.linalg.norm(d) > 0 and np.linalg.norm(np.cross(d / np.linalg.norm(d), up)) < 1e-6:
            up = -self._eye_to_world[:3, 2]  # looking along the old up: the old forward becomes up
        self._look(eye, center, up)

    def set_up_vector(self, up: Sequence[float]) -> None:
        self._look(self.eye, self._center, finite_vector("set_up_vector", "up", up, 3))

    def set_axial_view(self, rotation: AxisAlignedRotation | str) -> None:
        """Look at the centre from the same distance with an axis-aligned orientation."""
        if isinstance(rotation, str):
            rotation = AxisAlignedRotation.from_name(rotation)
        if not isinstance(rotation, AxisAlignedRotation):
            raise TypeError(f"set_axial_view needs an om.AxisAlignedRotation, got {type(rotation).__name__}")
        m = np.eye(4)
        m[:3, :3] = rotation.matrix()
        m[:3, 3] = self._center + self.distance * rotation.backward
        self._eye_to_world = m

    # -- orbit / pan / zoom (interactive) --------------------------------
    def orbit(self, yaw_degrees: float, pitch_degrees: float) -> None:
        """Rotate the eye around the centre: yaw about the eye's up, pitch about its right axis."""
        r = self._eye_to_world[:3, :3]
        rot = _axis_angle(r[:, 1], -math.radians(yaw_degrees)) @ _axis_angle(r[:, 0], -math.radians(pitch_degrees))
        m = np.eye(4)
        m[:3, :3] = rot @ r
        m[:3, 3] = self._center + rot @ (self._eye_to_world[:3, 3] - self._center)
        self._eye_to_world = m

    def pan(self, dx: float, dy: float) -> None:
        """Move eye and centre by ``dx, dy`` view-plane heights (at the centre's depth)."""
        h = self.field_height_at(self.distance)
        shift = self._eye_to_world[:3, :3] @ np.array([-dx * h, -dy * h, 0.0])
        self._eye_to_world[:3, 3] += shift
        self._center += shift

    def zoom(self, factor: float) -> None:
        """Scale the eye-centre distance (perspective) or field height (orthogonal) by ``factor``.

        In perspective the eye moves along its axis, so the near and far planes
        move with it (by the change of distance): what was between them before
        the zoom still is.  Zooming in past the near plane keeps the near plane
        at 1/1000 of the far one (so depth precision holds), never behind the eye.
        """
        if not (factor > 0 and math.isfinite(factor)):
            raise ValueError(f"zoom factor must be > 0, got {factor}")
        if self._orthogonal:
            if self._frustum is not None:
                self._frustum = tuple(v * factor for v in self._frustum)  # type: ignore[assignment]
            else:
                self._field_height *= factor
            return
        offset = self._eye_to_world[:3, 3] - self._center
        self._eye_to_world[:3, 3] = self._center + offset * factor
        delta = float(np.linalg.norm(offset)) * (factor - 1.0)
        far = self._far + delta
        if not far > 0:
            return
        near = max(self._near + delta, 1e-3 * far)
        if self._frustum is not None:  # an explicit frustum lies on the near plane: keep its angles
            self._frustum = tuple(v * near / self._near for v in self._frustum)  # type: ignore[assignment]
        self._near, self._far = near, far

    def field_height_at(self, depth: float) -> float:
        """Height of the visible region at ``depth`` in front of the eye."""
        if self._orthogonal:
            return self.view_plane_height
        return self.view_plane_height * depth / self._near

    # -- projection ------------------------------------------------------
    def set_perspective(self, *args: float) -> None:
        """``(fov, near, far)`` with vertical fov in degrees, or ``(left, right, bottom, top, near, far)``."""
        self._set_projection("set_perspective", False, args)

    def set_vertical_field_of_view(self, fov: float) -> None:
        """Make the projection perspective with vertical field ``fov`` degrees, keeping near and far."""
        self._set_projection("set_vertical_field_of_view", False, (fov, self._near, self._far))

    def set_orthogonal(self, *args: float) -> None:
        """``(field_height, near, far)`` or ``(left, right, bottom, top, near, far)``."""
        self._set_projection("set_orthogonal", True, args)

    def _set_projection(self, name: str, orthogonal: bool, args: tuple[float, ...]) -> None:
        values = [float(a) for a in args]
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"{name}: arguments must be finite, got {args}")
        if len(values) == 3:
            first, near, far = values
            _check_depths(name, near, far, orthogonal)
            if orthogonal:
                if first <= 0:
                    raise ValueError(f"{name}: field height must be > 0, got {first}")
                self._field_height = first
            elif not 0 < first < 180:
                raise ValueError(f"{name}: fov must be in (0, 180) degrees, got {first}")
            else:
                self._fov = first
            self._frustum = None
        elif len(values) == 6:
            left, right, bottom, top, near, far = values
            _check_depths(name, near, far, orthogonal)
            if not (left < right and bottom < top):
                raise ValueError(f"{name}: need left < right and bottom < top, got {values[:4]}")
            self._frustum = (left, right, bottom, top)
        else:
            raise TypeError(f"{name} takes (fov_or_height, near, far) or (left, right, bottom, top, near, far)")
        self._orthogonal = orthogonal
        self._near, self._far = near, far

    def frustum(self) -> tuple[float, float, float, float]:
        """``(left, right, bottom, top)`` of the view plane at the near distance."""
        if self._frustum is not None:
            return self._frustum
        if self._orthogonal:
            h = self._field_height / 2
        else:
            h = self._near * math.tan(math.radians(self.fov) / 2)
        w = h * self.aspect
        return (-w, w, -h, h)

    def get_projection_matrix(self) -> np.ndarray:
        """Eye-to-clip matrix (OpenGL conventions) for the current size."""
        args = (*self.frustum(), self._near, self._far)
        return ortho_matrix(*args) if self._orthogonal else frustum_matrix(*args)

    @property
    def fov(self) -> float:
        """Vertical field of view in degrees (derived from the frustum when one is set)."""
        if self._frustum is not None and not self._orthogonal:
            _, _, b, t = self._frustum
            return math.degrees(math.atan(t / self._near) - math.atan(b / self._near))
        return self._fov if self._fov is not None else DEFAULT_FOV

    @property
    def is_orthogonal(self) -> bool:
        return self._orthogonal

    @property
    def view_plane_width(self) -> float:
        left, right, _, _ = self.frustum()
        return right - left

    @property
    def view_plane_height(self) -> float:
        _, _, bottom, top = self.frustum()
        return top - bottom

    @property
    def view_plane_distance(self) -> float:
        return self._near

    @property
    def far_plane_distance(self) -> float:
        return self._far

    # -- auto fit --------------------------------------------------------
    def auto_fit(self, bounds: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Fit ``bounds`` keeping the current kind of projection and viewing direction."""
        if self._orthogonal:
            self.auto_fit_ortho(bounds)
        else:
            self.auto_fit_perspective(bounds)

    def auto_fit_perspective(self, bounds: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Perspective fit: the eye backs off along its viewing axis until every box corner is inside."""
        center, corners = self._corners(bounds)
        fov = self.fov
        ty = math.tan(math.radians(fov) / 2)
        tx = ty * self.aspect
        # corner (x, y, z) in eye axes relative to the centre; the centre sits at depth d
        x, y, z = np.abs(corners[:, 0]), np.abs(corners[:, 1]), corners[:, 2]
        margin = 1.05
        distance = float(np.max(np.maximum(z + margin * x / tx, z + margin * y / ty)))
        extent = float(np.max(np.linalg.norm(corners, axis=1)))
        distance = max(distance, 1e-3 * extent, 1e-6)
        self._place(center, distance)
        nearest = distance - float(np.max(z))
        farthest = distance - float(np.min(z))
        near = max(0.5 * nearest, 1e-3 * farthest)
        self.set_perspective(fov, near, max(1.5 * farthest, near * 2))

    def auto_fit_ortho(self, bounds: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Orthogonal fit: the field height covers every box corner; the eye stands clear of the box."""
        center, corners = self._corners(bounds)
        margin = 1.05
        half = max(float(np.max(np.abs(corners[:, 1]))), float(np.max(np.abs(corners[:, 0]))) / self.aspect)
        height = 2 * margin * max(half, 1e-6)
        depth = float(np.max(np.abs(corners[:, 2]))) or half
        distance = 2.0 * depth
        self._place(center, distance)
        self.set_orthogonal(height, distance - 1.5 * depth, distance + 1.5 * depth)

    def _corners(self, bounds: tuple[np.ndarray, np.ndarray] | None) -> tuple[np.ndarray, np.ndarray]:
        """The box centre and its 8 corners relative to it in eye axes (a unit box when empty or flat)."""
        center, radius = _sphere(bounds)
        if bounds is not None and _finite_box(bounds):
            lo, hi = (np.asarray(b, dtype=np.float64) for b in bounds)
        else:
            lo, hi = center - 0.5, center + 0.5
        if np.all(hi - lo <= 1e-12):
            lo, hi = center - radius, center + radius
        corners = np.array(list(itertools.product(*zip(lo, hi, strict=True)))) - center
        return center, corners @ self._eye_to_world[:3, :3]

    def _place(self, center: np.ndarray, distance: float) -> None:
        m = self._eye_to_world.copy()
        m[:3, 3] = center + distance * m[:3, 2]
        self._eye_to_world = m
        self._center = center.copy()

    # -- saving / restoring ---------------------------------------------------
    def state(self) -> tuple:
        """Everything that defines the view (for :meth:`restore`, e.g. a window's reset key)."""
        return (self._eye_to_world.copy(), self._center.copy(), self._orthogonal, self._fov, self._field_height,
                self._frustum, self._near, self._far)  # fmt: skip

    def restore(self, state: tuple) -> None:
        """Go back to a view saved by :meth:`state`."""
        eye_to_world, center, self._orthogonal, self._fov, self._field_height, self._frustum, self._near, self._far = (
            state
        )
        self._eye_to_world = eye_to_world.copy()
        self._center = center.copy()

    # -- conversion -------------------------------------------------------
    def to_camera(self) -> Camera:
        """An equivalent ``om.Camera``: an explicit frustum's height and off-centre window become its field
        (or height) and ``shift``; its width follows the image's aspect."""
        eye, up = self.eye, self.up
        center = self._center if self.distance > 0 else eye - self._eye_to_world[:3, 2]
        left, right, bottom, top = self.frustum()
        height = top - bottom
        shift = ((left + right) / (2.0 * height), (bottom + top) / (2.0 * height))
        if self._orthogonal:
            return Camera(eye, center, up, fov=None, height=height, near=self._near, far=self._far, shift=shift)
        fov = math.degrees(2.0 * math.atan(height / (2.0 * self._near)))  # the window's height at unit distance
        return Camera(eye, center, up, fov=fov, near=self._near, far=self._far, shift=shift)

    def set_from_camera(self, camera: Camera, world: np.ndarray | None = None) -> None:
        """Adopt an ``om.Camera`` (placed by ``world``, its node's accumulated matrix)."""
        view = camera.view_matrix()
        if world is not None:
            view = view @ np.linalg.inv(world)
        eye_to_world = np.linalg.inv(view)
        center = np.asarray(camera.center, dtype=np.float64)
        if world is not None:
            center = (world @ np.append(center, 1.0))[:3]
        self._eye_to_world = eye_to_world
        self._center = center
        if camera.is_orthographic:
            self.set_orthogonal(camera.height, camera.near, camera.far)
        else:
            self.set_perspective(camera.fov, camera.near, camera.far)


def _check_depths(name: str, near: float, far: float, orthogonal: bool) -> None:
    # orthogonal views could take near <= 0 in OpenGL, but om.Camera (and depth read-back) need 0 < near
    if not (0 < near < far):
        raise ValueError(f"{name}: need 0 < near < far, got near={near}, far={far}")


def _sphere(bounds: tuple[np.ndarray, np.ndarray] | None) -> tuple[np.ndarray, float]:
    if bounds is None:
        return np.zeros(3), 1.0
    lo, hi = (np.asarray(b, dtype=np.float64) for b in bounds)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))) or np.any(hi < lo):
        return np.zeros(3), 1.0
    radius = float(np.linalg.norm(hi - lo)) / 2
    if radius <= 0:
        radius = max(1e-3, float(np.max(np.abs(lo))) * 1e-3)
    return (lo + hi) / 2, radius


def _finite_box(bounds: tuple[np.ndarray, np.ndarray]) -> bool:
    lo, hi = (np.asarray(b, dtype=np.float64) for b in bounds)
    return bool(np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi >= lo))


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)
