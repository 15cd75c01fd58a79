"""Modelling transforms beyond the core ones: ``LookAt``, ``Billboard`` and the VRS's
``Reflection``, ``DirectionOfFlight`` and ``Polar``.

Both are :class:`~omnirender.core.transform.Transform` subclasses, so they
share the ``Transform`` category and compose with the accumulated model matrix.

``LookAt(eye, center, up)`` places an object at ``eye`` with its -z axis
towards ``center`` and +y towards ``up``: the inverse of the look-at view
matrix (a camera placed with it would see what ``Camera.look_at`` sees).

``Billboard(axis=None)`` has no fixed matrix.  Its default simplifier (for every
engine) computes, from the current model matrix and ``engine.view_matrix()``,
the rotation that turns the object's +z axis towards the camera eye (with
+y towards the camera's up), or with ``axis`` the rotation about that axis only
(cylindrical billboard, e.g. a tree turning about its trunk), and pushes it as
an ``om.Matrix`` / ``om.Rotation``.  Because it is a simplified attribute the
engine keeps a frame for it; popping the ``Transform`` category at that depth
undoes the computed rotation (the paper's billboarding example).

The VRS transforms (static matrices, so every engine and exporter takes them
like an ``om.Matrix``):

* ``Reflection(normal, point)`` mirrors in the plane through ``point`` with
  ``normal`` (determinant -1: engines keep the lit side facing out, see the
  GL fragment shader's mirror test);
* ``DirectionOfFlight(velocity, up, position)`` turns the object's +z axis
  along ``velocity`` (a moving object oriented along its flight), +y towards
  ``up``, and moves it to ``position``;
* ``Polar(radius, azimuth, elevation, orient)`` places the object at spherical
  coordinates: azimuth in degrees about +y from +z towards +x, elevation in
  degrees above the xz plane; with ``orient`` its +z axis points radially
  outwards and +y towards increasing elevation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.camera import look_at_matrix
from ..core.engine import Engine
from ..core.handler import AttributeSimplifier, default_for
from ..core.transform import Matrix, Rotation, Transform, finite_vector
from ._params import unit_tuple

__all__ = ["LookAt", "Billboard", "BillboardSimplifier", "Reflection", "DirectionOfFlight", "Polar"]


class LookAt(Transform):
    """Place an object at ``eye``, its -z axis towards ``center``, +y towards ``up``."""

    __slots__ = ("_eye", "_center", "_up")

    def __init__(
        self,
        eye: Sequence[float] = (0.0, 0.0, 0.0),
        center: Sequence[float] = (0.0, 0.0, -1.0),
        up: Sequence[float] = (0.0, 1.0, 0.0),
    ) -> None:
        super().__init__()
        self._assign(eye, center, up)

    def _assign(self, eye: Any, center: Any, up: Any) -> None:
        e = finite_vector("LookAt", "eye", eye, 3)
        c = finite_vector("LookAt", "center", center, 3)
        u = finite_vector("LookAt", "up", up, 3)
        d = c - e
        if np.linalg.norm(d) == 0.0:
            raise ValueError("LookAt: eye and center must differ")
        if np.linalg.norm(u) == 0.0:
            raise ValueError("LookAt: up must not be the zero vector")
        if np.linalg.norm(np.cross(d / np.linalg.norm(d), u / np.linalg.norm(u))) < 1e-12:
            raise ValueError("LookAt: up must not be parallel to center - eye")
        object.__setattr__(self, "_eye", tuple(float(x) for x in e))
        object.__setattr__(self, "_center", tuple(float(x) for x in c))
        object.__setattr__(self, "_up", tuple(float(x) for x in u))
        self._set_matrix(np.linalg.inv(look_at_matrix(e, c, u)))

    @property
    def eye(self) -> tuple[float, float, float]:
        return self._eye

    @eye.setter
    def eye(self, value: Sequence[float]) -> None:
        self._assign(value, self._center, self._up)

    @property
    def center(self) -> tuple[float, float, float]:
        return self._center

    @center.setter
    def center(self, value: Sequence[float]) -> None:
        self._assign(self._eye, value, self._up)

    @property
    def up(self) -> tuple[float, float, float]:
        return self._up

    @up.setter
    def up(self, value: Sequence[float]) -> None:
        self._assign(self._eye, self._center, value)

    def parameters(self) -> dict[str, Any]:
        return {"eye": list(self._eye), "center": list(self._center), "up": list(self._up)}


class Billboard(Transform):
    """Turn the object's +z axis towards the camera (optionally only about ``axis``).

    ``axis`` is in the object's coordinates and must not be parallel to +z.
    Without a camera (``engine.view_matrix()`` is None) nothing is turned.
    The rotation depends on the viewpoint, so a Billboard has no ``matrix``;
    pre-evaluation of lights and cameras ignores it.
    """

    __slots__ = ("_axis",)
    static = False  # the rotation depends on the camera

    def __init__(self, axis: Sequence[float] | None = None) -> None:
        super().__init__()
        self.axis = axis

    @property
    def axis(self) -> tuple[float, float, float] | None:
        """Unit rotation axis in object coordinates, or None (turn freely)."""
        return self._axis

    @axis.setter
    def axis(self, value: Sequence[float] | None) -> None:
        if value is None:
            object.__setattr__(self, "_axis", None)
        else:
            a = finite_vector("Billboard", "axis", value, 3)
            n = float(np.linalg.norm(a))
            if n == 0.0:
                raise ValueError("Billboard: axis must not be the zero vector")
            a = np.asarray(unit_tuple(a, n))
            if abs(a[2]) > 1.0 - 1e-12:
                raise ValueError("Billboard: axis must not be parallel to +z (the axis that is turned to the camera)")
            object.__setattr__(self, "_axis", tuple(float(x) for x in a))
        self.touch()

    @property
    def matrix(self) -> np.ndarray:  # type: ignore[override]
        raise AttributeError(
            "Billboard has no fixed matrix: its simplifier computes the rotation from the camera at evaluation time"
        )

    def parameters(self) -> dict[str, Any]:
        return {"axis": None if self._axis is None else list(self._axis)}

    def rotation(self, model_matrix: np.ndarray, view_matrix: np.ndarray | None) -> np.ndarray:
        """The 4x4 object-space rotation that makes the object face the camera.

        ``model_matrix`` is the current model-to-world matrix, ``view_matrix``
        world-to-eye.  Returns the identity when there is no camera or the eye
        sits on the object's origin (or on its axis).
        """
        if view_matrix is None:
            return np.eye(4)
        to_world = np.asarray(view_matrix, dtype=np.float64)
        eye_to_model = np.linalg.inv(np.asarray(model_matrix, dtype=np.float64)) @ np.linalg.inv(to_world)
        eye = eye_to_model[:3, 3] / eye_to_model[3, 3]
        if self._axis is None:
            n = float(np.linalg.norm(eye))
            if n < 1e-300:
                return np.eye(4)
            z = eye / n
            up = eye_to_model[:3, 1]  # the camera's up direction in object coordinates
            x = np.cross(up, z)
            if np.linalg.norm(x) < 1e-12 * max(np.linalg.norm(up), 1e-300):
                helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
                x = np.cross(helper, z)
            x /= np.linalg.norm(x)
            y = np.cross(z, x)
            m = np.eye(4)
            m[:3, 0], m[:3, 1], m[:3, 2] = x, y, z
            return m
        return Rotation(math.degrees(self._axis_angle(eye)), self._axis).matrix

    def _axis_angle(self, eye: np.ndarray) -> float:
        """Angle (radians) about the axis that turns +z's projection towards ``eye``'s."""
        a = np.asarray(self._axis)
        target = eye - np.dot(eye, a) * a
        if np.linalg.norm(target) < 1e-300:
            return 0.0
        front = np.array([0.0, 0.0, 1.0]) - a[2] * a
        return math.atan2(float(np.dot(a, np.cross(front, target))), float(np.dot(front, target)))

    def pushed_transform(self, model_matrix: np.ndarray, view_matrix: np.ndarray) -> Transform:
        """The transform the simplifier pushes: an ``om.Rotation`` about the axis, else an ``om.Matrix``."""
        if self._axis is None:
            return Matrix(self.rotation(model_matrix, view_matrix))
        eye = _eye_in_model(model_matrix, view_matrix)
        return Rotation(math.degrees(self._axis_angle(eye)), self._axis)


def _eye_in_model(model_matrix: np.ndarray, view_matrix: np.ndarray) -> np.ndarray:
    eye_to_model = np.linalg.inv(np.asarray(model_matrix, dtype=np.float64)) @ np.linalg.inv(view_matrix)
    return eye_to_model[:3, 3] / eye_to_model[3, 3]


@default_for(Engine)
class BillboardSimplifier(AttributeSimplifier):
    """Push the camera-facing rotation of a :class:`Billboard`; the default unexec pops it."""

    __slots__ = ()
    target = Billboard

    def exec(self, billboard: Billboard, engine: Engine) -> None:
        view = engine.view_matrix()
        if view is None:
            return
        engine.push(billboard.pushed_transform(engine.model_matrix(), view))


class _Parametric(Transform):
    """A static transform whose matrix follows from a few named parameters (re-validated when one is set)."""

    __slots__ = ()
    _names: tuple[str, ...] = ()

    def _assign(self, **values: Any) -> None:
        current = {name: getattr(self, "_" + name) for name in self._names if hasattr(self, "_" + name)}
        current.update(values)
        checked, matrix = self._build(current)
        for name, value in checked.items():
            object.__setattr__(self, "_" + name, value)
        self._set_matrix(matrix)

    def _build(self, values: dict[str, Any]) -> tuple[dict[str, Any], np.ndarray]:  # pragma: no cover
        raise NotImplementedError

    def __getattr__(self, name: str) -> Any:
        if name in type(self)._names:
            return object.__getattribute__(self, "_" + name)
        raise AttributeError(f"{type(self).__name__} has no attribute {name!r}")

    def __setattr__(self, name: str, value: Any) -> None:
        if name in type(self)._names:
            self._assign(**{name: value})
        else:
            super().__setattr__(name, value)

    def parameters(self) -> dict[str, Any]:
        out = {}
        for name in self._names:
            v = getattr(self, "_" + name)
            out[name] = list(v) if isinstance(v, tuple) else v
        return out


def _unit(owner: str, name: str, value: Any) -> np.ndarray:
    v = finite_vector(owner, name, value, 3)
    n = float(np.linalg.norm(v))
    if n < 1e-300:
        raise ValueError(f"{owner}: {name} must not be the zero vector")
    return v / n


def _degrees(owner: str, name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ValueError(f"{owner}: {name} must be a number of degrees, got {value!r:.40}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{owner}: {name} must be finite, got {v}")
    return v


class Reflection(_Parametric):
    """Mirror in the plane through ``point`` with ``normal`` (a VRS reflection transform; determinant -1)."""

    __slots__ = ("_normal", "_point")
    _names = ("normal", "point")

    def __init__(self, normal: Sequence[float] = (1.0, 0.0, 0.0), point: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        super().__init__()
        self._assign(normal=normal, point=point)

    def _build(self, values: dict[str, Any]) -> tuple[dict[str, Any], np.ndarray]:
        n = _unit("Reflection", "normal", values["normal"])
        p = finite_vector("Reflection", "point", values["point"], 3)
        m = np.eye(4)
        m[:3, :3] -= 2.0 * np.outer(n, n)
        m[:3, 3] = 2.0 * float(n @ p) * n
        return {"normal": tuple(float(x) for x in n), "point": tuple(float(x) for x in p)}, m


class DirectionOfFlight(_Parametric):
    """Turn the object's +z axis along ``velocity`` (+y towards ``up``) and move it to ``position`` (VRS)."""

    __slots__ = ("_velocity", "_up", "_position")
    _names = ("velocity", "up", "position")

    def __init__(
        self,
        velocity: Sequence[float] = (0.0, 0.0, 1.0),
        up: Sequence[float] = (0.0, 1.0, 0.0),
        position: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> None:
        super().__init__()
        self._assign(velocity=velocity, up=up, position=position)

    def _build(self, values: dict[str, Any]) -> tuple[dict[str, Any], np.ndarray]:
        z = _unit("DirectionOfFlight", "velocity", values["velocity"])
        u = _unit("DirectionOfFlight", "up", values["up"])
        p = finite_vector("DirectionOfFlight", "position", values["position"], 3)
        x = np.cross(u, z)
        if float(np.linalg.norm(x)) < 1e-9:
            raise ValueError("DirectionOfFlight: up must not be parallel to the velocity; give another up")
        x /= np.linalg.norm(x)
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(z, x), z, p
        checked = {
            "velocity": tuple(float(v) for v in finite_vector("DirectionOfFlight", "velocity", values["velocity"], 3)),
            "up": tuple(float(v) for v in finite_vector("DirectionOfFlight", "up", values["up"], 3)),
            "position": tuple(float(v) for v in p),
        }
        return checked, m


class Polar(_Parametric):
    """Place the object at spherical coordinates (VRS polar transform; see the module docstring)."""

    __slots__ = ("_radius", "_azimuth", "_elevation", "_orient")
    _names = ("radius", "azimuth", "elevation", "orient")

    def __init__(self, radius: float = 1.0, azimuth: float = 0.0, elevation: float = 0.0, orient: bool = False):
        super().__init__()
        self._assign(radius=radius, azimuth=azimuth, elevation=elevation, orient=orient)

    def _build(self, values: dict[str, Any]) -> tuple[dict[str, Any], np.ndarray]:
        r = _degrees("Polar", "radius", values["radius"])
        if r < 0.0:
            raise ValueError(f"Polar: radius must be >= 0, got {r}")
        az = math.radians(_degrees("Polar", "azimuth", values["azimuth"]))
        el = math.radians(_degrees("Polar", "elevation", values["elevation"]))
        orient = values["orient"]
        if not isinstance(orient, (bool, np.bool_)):
            raise ValueError(f"Polar: orient must be True or False, got {orient!r:.40}")
        radial = np.array([math.cos(el) * math.sin(az), math.sin(el), math.cos(el) * math.cos(az)])
        m = np.eye(4)
        m[:3, 3] = r * radial
        if orient:
            east = np.array([math.cos(az), 0.0, -math.sin(az)])
            m[:3, 0], m[:3, 1], m[:3, 2] = east, np.cross(radial, east), radial
        checked = {
            "radius": r,
            "azimuth": float(values["azimuth"]),
            "elevation": float(values["elevation"]),
            "orient": bool(orient),
        }
        return checked, m
