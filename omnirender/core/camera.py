"""The camera: a mono attribute the engine pre-evaluates wherever it sits.

``Camera.look_at`` makes a perspective camera with a vertical field of view in
degrees, ``Camera.orthographic`` a parallel one whose view volume is ``height``
world units tall.  Both follow the legacy OpenGL convention: the eye looks down
its -z axis towards ``center`` with ``up`` projected to +y.  Every engine
derives its projection from these matrices so that images agree.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .component import MonoAttribute
from .limits import MIN_MAGNITUDE, as_float
from .transform import finite_vector

__all__ = ["Camera", "look_at_matrix", "perspective_matrix", "orthographic_matrix"]


def look_at_matrix(eye: Sequence[float], center: Sequence[float], up: Sequence[float]) -> np.ndarray:
    """World-to-eye matrix: eye at the origin looking down -z, ``up`` towards +y."""
    eye = np.asarray(eye, dtype=np.float64)
    f = np.asarray(center, dtype=np.float64) - eye
    f = f / np.linalg.norm(f)
    s = np.cross(f, np.asarray(up, dtype=np.float64))
    s = s / np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective_matrix(fov_y: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL perspective projection; ``fov_y`` is the vertical angle in degrees."""
    f = 1.0 / math.tan(math.radians(fov_y) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def orthographic_matrix(height: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL orthographic projection of a view volume ``height`` units tall."""
    m = np.eye(4)
    m[0, 0] = 2.0 / (height * aspect)
    m[1, 1] = 2.0 / height
    m[2, 2] = -2.0 / (far - near)
    m[2, 3] = -(far + near) / (far - near)
    return m


class Camera(MonoAttribute):
    """Where the scene is seen from and how it is projected."""

    __slots__ = ("eye", "center", "up", "fov", "height", "near", "far", "mask")
    declared = "first"  # the first camera met is the scene's (declarative pre-evaluation)

    def __init__(
        self,
        eye: Sequence[float] = (0.0, 0.0, 5.0),
        center: Sequence[float] = (0.0, 0.0, 0.0),
        up: Sequence[float] = (0.0, 1.0, 0.0),
        fov: float | None = 35.0,
        height: float | None = None,
        near: float = 0.1,
        far: float = 1000.0,
        mask: str | None = None,
    ) -> None:
        super().__init__()
        e = finite_vector("Camera", "eye", eye, 3)
        c = finite_vector("Camera", "center", center, 3)
        u = finite_vector("Camera", "up", up, 3)
        d = c - e
        if np.linalg.norm(d) == 0.0:
            raise ValueError("Camera: center must differ from eye")
        if np.linalg.norm(np.cross(d, u)) < 1e-12 * np.linalg.norm(d) * max(np.linalg.norm(u), 1e-300):
            raise ValueError("Camera: up must not be parallel to the viewing direction center - eye")
        fov = None if fov is None else as_float("Camera", "fov", fov)
        height = None if height is None else as_float("Camera", "height", height)
        near, far = as_float("Camera", "near", near), as_float("Camera", "far", far)
        if mask is not None:
            from .mask import MaskError, compile_mask

            try:
                compile_mask(mask)
            except MaskError as exc:
                raise ValueError(f"Camera: bad mask: {exc}") from None
        if (fov is None) == (height is None):
            raise ValueError("Camera: give exactly one of fov (perspective) or height (orthographic)")
        if fov is not None and not (0.0 < fov < 180.0):
            raise ValueError(f"Camera: fov must be in (0, 180) degrees, got {fov}")
        if height is not None and not (height > 0.0 and math.isfinite(height)):
            raise ValueError(f"Camera: height must be > 0, got {height}")
        if not (0.0 < near < far and math.isfinite(far)):
            raise ValueError(f"Camera: need 0 < near < far, got near={near}, far={far}")
        if near < MIN_MAGNITUDE or (height is not None and height < MIN_MAGNITUDE):
            raise ValueError(
                f"Camera: near and height must be at least {MIN_MAGNITUDE:.0e}, got near={near}, height={height}"
            )
        self.eye = tuple(float(x) for x in e)
        self.center = tuple(float(x) for x in c)
        self.up = tuple(float(x) for x in u)
        self.fov = None if fov is None else float(fov)
        self.height = None if height is None else float(height)
        self.near = float(near)
        self.far = float(far)
        self.mask = mask

    @classmethod
    def look_at(
        cls,
        eye: Sequence[float],
        center: Sequence[float] = (0.0, 0.0, 0.0),
        up: Sequence[float] = (0.0, 1.0, 0.0),
        fov: float = 35.0,
        near: float = 0.1,
        far: float = 1000.0,
        mask: str | None = None,
    ) -> Camera:
        """A perspective camera; ``fov`` is the vertical field of view in degrees."""
        return cls(eye, center, up, fov=fov, near=near, far=far, mask=mask)

    @classmethod
    def orthographic(
        cls,
        eye: Sequence[float],
        center: Sequence[float] = (0.0, 0.0, 0.0),
        up: Sequence[float] = (0.0, 1.0, 0.0),
        height: float = 2.0,
        near: float = 0.1,
        far: float = 1000.0,
        mask: str | None = None,
    ) -> Camera:
        """A parallel-projection camera whose view volume is ``height`` units tall."""
        return cls(eye, center, up, fov=None, height=height, near=near, far=far, mask=mask)

    @classmethod
    def fitted(cls, bounds: Any, size: Sequence[int] = (640, 480), fov: float = 35.0) -> Camera:
        """The camera every engine uses for a scene without one: looking at ``bounds`` (min, max) from +z.

        The bounding sphere fills the view (vertical ``fov``, narrowed for tall
        images); near and far planes enclose it.  ``bounds`` None gives the
        default camera (eye at (0, 0, 5)).
        """
        if bounds is None:
            return cls.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
        w, h = (int(v) for v in size)
        return cls.fit(bounds, w / h, fov)

    @classmethod
    def fit(
        cls,
        bounds: tuple[Sequence[float], Sequence[float]],
        aspect: float,
        fov: float = 35.0,
        direction: Sequence[float] = (0.0, 0.0, 1.0),
        margin: float = 1.02,
    ) -> Camera:
        """A perspective camera looking at the box ``bounds = (lo, hi)`` along ``-direction`` (from +z by default):
        its bounding sphere fills the view, with ``margin``.

        Near and far enclose the sphere with room to spare; ``aspect`` is the image's width/height.
        """
        lo, hi = (finite_vector("Camera.fit", "bounds", b, 3) for b in bounds)
        d = finite_vector("Camera.fit", "direction", direction, 3)
        if float(np.linalg.norm(d)) == 0.0:
            raise ValueError("Camera.fit: direction must not be the zero vector")
        d = d / np.linalg.norm(d)
        center = (lo + hi) / 2.0
        radius = max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-6)
        half = math.radians(fov) / 2.0
        if aspect < 1.0:
            half = math.atan(math.tan(half) * aspect)
        dist = radius / math.sin(half) * margin
        near = max(dist - radius * 1.5, dist * 1e-3)
        far = dist + radius * 1.5
        up = (0.0, 1.0, 0.0) if abs(d[1]) < 0.99 else (0.0, 0.0, -1.0)
        return cls.look_at(tuple(center + d * dist), tuple(center), up, fov=fov, near=near, far=far)

    @property
    def is_orthographic(self) -> bool:
        return self.height is not None

    def view_matrix(self) -> np.ndarray:
        """World-to-eye matrix of the camera in its own coordinates."""
        return look_at_matrix(self.eye, self.center, self.up)

    def projection_matrix(self, aspect: float) -> np.ndarray:
        """Eye-to-clip matrix for an image of width/height ``aspect``."""
        if self.height is not None:
            return orthographic_matrix(self.height, aspect, self.near, self.far)
        return perspective_matrix(self.fov, aspect, self.near, self.far)
