"""The camera: a mono attribute the engine pre-evaluates wherever it sits.

``Camera.look_at`` makes a perspective camera with a vertical field of view in
degrees, ``Camera.orthographic`` a parallel one whose view volume is ``height``
world units tall.  Both follow the legacy OpenGL convention: the eye looks down
its -z axis towards ``center`` with ``up`` projected to +y.  Every engine
derives its projection from these matrices so that images agree.

``shift=(sx, sy)`` makes the frustum off-axis (a lens shift): the view window
moves by ``sx``, ``sy`` image *heights* on the image plane, right and up, so
its centre is no longer on the viewing axis.  ``Camera.from_screen`` builds
such a camera from a screen rectangle and an eye position (guacamole's screen
and eye nodes; Kooima's generalized perspective projection): every point on
the screen projects to the same pixel whatever the eye position, which is
what head-tracked VR and stereo on a physical screen need.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .component import MonoAttribute
from .limits import MIN_MAGNITUDE, as_float
from .transform import finite_vector

__all__ = ["Camera", "look_at_matrix", "perspective_matrix", "orthographic_matrix", "screen_frame"]


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


def perspective_matrix(
    fov_y: float, aspect: float, near: float, far: float, shift: Sequence[float] = (0.0, 0.0)
) -> np.ndarray:
    """OpenGL perspective projection; ``fov_y`` is the vertical angle in degrees.

    ``shift`` moves the window by (sx, sy) image heights (``glFrustum`` with
    ``left + right = 2 sx (top - bottom)``, ``bottom + top = 2 sy (top - bottom)``).
    """
    f = 1.0 / math.tan(math.radians(fov_y) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[0, 2] = 2.0 * shift[0] / aspect
    m[1, 2] = 2.0 * shift[1]
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def orthographic_matrix(
    height: float, aspect: float, near: float, far: float, shift: Sequence[float] = (0.0, 0.0)
) -> np.ndarray:
    """OpenGL orthographic projection of a view volume ``height`` units tall, moved by ``shift`` heights."""
    m = np.eye(4)
    m[0, 0] = 2.0 / (height * aspect)
    m[1, 1] = 2.0 / height
    m[0, 3] = -2.0 * shift[0] / aspect
    m[1, 3] = -2.0 * shift[1]
    m[2, 2] = -2.0 / (far - near)
    m[2, 3] = -(far + near) / (far - near)
    return m


def screen_frame(corners: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(lower-left corner, unit right axis, unit up axis, unit normal towards the viewer) of a screen.

    ``corners`` = (lower-left, lower-right, upper-left) world points of a
    rectangle; the up axis is made perpendicular to the right axis.
    """
    try:
        pts = np.asarray(corners, dtype=np.float64)
    except (TypeError, ValueError):
        pts = np.zeros(0)
    if pts.shape != (3, 3) or not np.all(np.isfinite(pts)):
        raise ValueError(
            "Camera.from_screen: the screen must be three finite world points (lower-left, lower-right, "
            f"upper-left), got {corners!r:.120}"
        )
    pa, pb, pc = pts
    vr = pb - pa
    vu = pc - pa
    width = float(np.linalg.norm(vr))
    if width < MIN_MAGNITUDE:
        raise ValueError("Camera.from_screen: the screen's lower-left and lower-right corners coincide")
    vr = vr / width
    vu = vu - (vu @ vr) * vr
    height = float(np.linalg.norm(vu))
    if height < MIN_MAGNITUDE:
        raise ValueError("Camera.from_screen: the screen's upper-left corner is on its bottom edge (no height)")
    vu = vu / height
    return pa, vr, vu, np.cross(vr, vu)


class Camera(MonoAttribute):
    """Where the scene is seen from and how it is projected."""

    __slots__ = ("eye", "center", "up", "fov", "height", "near", "far", "mask", "shift")
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
        shift: Sequence[float] = (0.0, 0.0),
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
        sh = finite_vector("Camera", "shift", shift, 2)
        #: the off-axis window shift (sx, sy) in image heights; (0, 0) for a symmetric frustum
        self.shift = (float(sh[0]), float(sh[1]))

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

    @classmethod
    def from_screen(
        cls,
        screen: Any,
        eye: Sequence[float],
        near: float = 0.1,
        far: float = 1000.0,
        mask: str | None = None,
    ) -> Camera:
        """The off-axis perspective camera of an eye looking through a screen rectangle (guacamole's screen node).

        ``screen`` = (lower-left, lower-right, upper-left) world corners
        (``om.screen_corners(node)`` gives them for a node holding an
        ``om.Rectangle``); ``eye`` is the world eye position, in front of the
        screen (on the side its normal ``right x up`` points to).  The camera
        looks along the screen's normal, its up is the screen's up, and its
        window is exactly the screen: the screen's height fills the image
        height and a point on the screen lands on the same pixel for every eye
        position.  Render at the screen's aspect ratio to see exactly the
        screen (another aspect shows more or less of the plane to its sides).
        """
        pa, vr, vu, vn = screen_frame(screen)
        pts = np.asarray(screen, dtype=np.float64)
        e = finite_vector("Camera.from_screen", "eye", eye, 3)
        d = float((e - pa) @ vn)
        if d <= MIN_MAGNITUDE:
            raise ValueError(
                f"Camera.from_screen: the eye {tuple(e)} is not in front of the screen (distance {d:.3g} along its "
                "normal right x up); move the eye or give the corners in the order lower-left, lower-right, upper-left"
            )
        va, vb, vc = pts[0] - e, pts[1] - e, pts[2] - e
        left, right = float(vr @ va) / d, float(vr @ vb) / d
        bottom, top = float(vu @ va) / d, float(vu @ vc) / d
        h = top - bottom
        fov = math.degrees(2.0 * math.atan(h / 2.0))
        shift = ((left + right) / (2.0 * h), (bottom + top) / (2.0 * h))
        center = e - d * vn  # the eye's foot on the screen plane
        return cls(tuple(e), tuple(center), tuple(vu), fov=fov, near=near, far=far, mask=mask, shift=shift)

    @property
    def is_orthographic(self) -> bool:
        return self.height is not None

    @property
    def is_off_axis(self) -> bool:
        """Whether the frustum is shifted off the viewing axis (``shift`` is not (0, 0))."""
        return self.shift != (0.0, 0.0)

    def window(self, aspect: float) -> tuple[float, float, float, float]:
        """(left, right, bottom, top) of the view window for an image of width/height ``aspect``.

        Perspective: on the plane at unit distance in front of the eye (tangents);
        orthographic: in eye-space world units.  ``shift`` moves it off-axis.
        """
        h = float(self.height) if self.height is not None else 2.0 * math.tan(math.radians(self.fov) / 2.0)
        cx, cy = self.shift[0] * h, self.shift[1] * h
        return cx - aspect * h / 2.0, cx + aspect * h / 2.0, cy - h / 2.0, cy + h / 2.0

    def pixel_grid(self, size: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """(x of each column, y of each row) of the pixel centres on the window (row 0 at the top).

        The units are those of :meth:`window`: a perspective ray through pixel
        (i, j) has the eye-space direction ``(x[i], y[j], -1)``.
        """
        w, h = (int(v) for v in size)
        left, right, bottom, top = self.window(w / h)
        xs = left + (np.arange(w) + 0.5) / w * (right - left)
        ys = top - (np.arange(h) + 0.5) / h * (top - bottom)
        return xs, ys

    def view_matrix(self) -> np.ndarray:
        """World-to-eye matrix of the camera in its own coordinates."""
        return look_at_matrix(self.eye, self.center, self.up)

    def projection_matrix(self, aspect: float) -> np.ndarray:
        """Eye-to-clip matrix for an image of width/height ``aspect``."""
        if self.height is not None:
            return orthographic_matrix(self.height, aspect, self.near, self.far, self.shift)
        return perspective_matrix(self.fov, aspect, self.near, self.far, self.shift)
