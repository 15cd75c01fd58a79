"""Lights with OpenGL's parameters (poly attributes of the shared category ``Light``).

Every light has a ``color`` and an ``intensity`` (>= 0) and OpenGL's ambient,
diffuse and specular colours; ``diffuse`` and ``specular`` default to
``color * intensity`` (pass a colour to set them explicitly; ``parameters()``
keeps None for the default so a rebuilt light still follows ``color``).
Positions and directions are in the coordinates of the place the light sits in
the graph; ``world_position(m)`` / ``world_direction(m)`` apply the world matrix
that ``engine.lights()`` reports.

Attenuation is OpenGL's: ``f(d) = 1 / (C + L d + Q d^2)``; a spot light
multiplies it by ``spot_factor(cos_angle) = cos_angle ** exponent`` inside the
cone (angle to the spot axis <= ``cutoff`` degrees) and 0 outside.  A point or
spot light's ``reach()`` is where its contribution falls below ``threshold``
(the GL deferred pipeline draws the light only that far).

Area lights (``RectLight``, ``DiscLight``) are flat emitters of uniform
radiance ``diffuse`` (``color * intensity``) on one side (``two_sided``: both);
they fall off physically, by their form factor, and have no OpenGL
attenuation: the rule is :func:`omnirender.attributes.photometry.area_form_factor`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from ..core.light import Light
from ._params import (
    Param,
    Parameterised,
    check_bool,
    check_direction,
    check_number,
    check_rgb,
    check_vector,
    optional,
)

__all__ = [
    "LightSource",
    "DirectionalLight",
    "PointLight",
    "SpotLight",
    "AreaLight",
    "RectLight",
    "DiscLight",
    "AmbientLight",
    "default_lights",
]

_nonneg = check_number(0.0)
#: Default ``threshold`` of point and spot lights: a light's reach ends where it adds less than 1/1024 of its
#: brightest channel (under 2 of 255 sRGB levels on black, and less on lit surfaces).
DEFAULT_THRESHOLD = 1.0 / 1024.0


def _scaled(color: tuple[float, ...], intensity: float) -> tuple[float, float, float]:
    return (color[0] * intensity, color[1] * intensity, color[2] * intensity)


class _Defaulted(Param):
    """A colour parameter that reads as ``color * intensity`` while unset (None)."""

    __slots__ = ()

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        value = getattr(obj, self.slot)
        return _scaled(obj._color, obj._intensity) if value is None else value


class LightSource(Parameterised, Light):
    """Base of the concrete lights: colour, intensity and OpenGL's colour terms."""

    __slots__ = ("_color", "_intensity", "_ambient", "_diffuse", "_specular", "_casts_shadows", "_enabled")
    color = Param(check_rgb, "light colour (RGB in [0, 1])")
    intensity = Param(_nonneg, "scale of the colour (>= 0)")
    ambient = Param(check_rgb, "ambient contribution (RGB)")
    diffuse = _Defaulted(optional(check_rgb), "diffuse colour; None: color * intensity")
    specular = _Defaulted(optional(check_rgb), "specular colour; None: color * intensity")
    casts_shadows = Param(check_bool, "shapes between the light and a surface shadow it (every engine)")
    enabled = Param(check_bool, "False switches the light off in every engine, as if it were absent (ArtiSynth)")

    def __init__(
        self,
        color: Sequence[float] = (1.0, 1.0, 1.0),
        intensity: float = 1.0,
        ambient: Sequence[float] = (0.0, 0.0, 0.0),
        diffuse: Sequence[float] | None = None,
        specular: Sequence[float] | None = None,
        casts_shadows: bool = True,
        enabled: bool = True,
    ) -> None:
        super().__init__()
        self.enabled = enabled
        self.color = color
        self.intensity = intensity
        self.ambient = ambient
        self.diffuse = diffuse
        self.specular = specular
        self.casts_shadows = casts_shadows

    @property
    def radiance(self) -> tuple[float, float, float]:
        """``color * intensity``: what physically based engines emit."""
        return _scaled(self._color, self._intensity)

    def attenuation(self, distance: float | np.ndarray) -> float | np.ndarray:
        """Distance attenuation factor (1 for lights without attenuation)."""
        d = np.asarray(distance, dtype=np.float64)
        return 1.0 if d.ndim == 0 else np.ones_like(d)


class _Attenuated(LightSource):
    """A light at a position, attenuated with distance (OpenGL's C, L, Q)."""

    __slots__ = ("_position", "_constant", "_linear", "_quadratic", "_threshold")
    position = Param(check_vector(3), "position in the light's coordinates")
    constant = Param(_nonneg, "constant attenuation C")
    linear = Param(_nonneg, "linear attenuation L")
    quadratic = Param(_nonneg, "quadratic attenuation Q")
    threshold = Param(
        check_number(0.0, 1.0, min_open=True),
        "contribution (relative to the brightest colour channel) below which the light counts as out of reach: "
        "where the GL deferred pipeline's light proxy ends",
    )

    def _init_attenuation(
        self, position: Sequence[float], constant: float, linear: float, quadratic: float, threshold: float
    ) -> None:
        self.position = position
        self.constant = constant
        self.linear = linear
        self.quadratic = quadratic
        self.threshold = threshold
        if self._constant == 0.0 and self._linear == 0.0 and self._quadratic == 0.0:
            raise ValueError(f"{type(self).__name__}: constant, linear and quadratic must not all be 0")

    def reach(self) -> float:
        """The distance beyond which the light adds less than ``threshold`` of its brightest colour channel.

        ``inf`` for a light without linear or quadratic attenuation, 0 for one too faint everywhere.
        """
        brightest = max(max(self.diffuse), max(self.specular))
        need = brightest / self._threshold  # C + L d + Q d^2 must exceed this for the light to fade out
        c, lin, q = self._constant, self._linear, self._quadratic
        if c >= need:
            return 0.0
        if q > 0.0:
            return float((-lin + math.sqrt(lin * lin + 4.0 * q * (need - c))) / (2.0 * q))
        return float((need - c) / lin) if lin > 0.0 else math.inf

    def attenuation(self, distance: float | np.ndarray) -> float | np.ndarray:
        """``1 / (C + L d + Q d^2)`` for distance(s) ``d`` >= 0."""
        d = np.asarray(distance, dtype=np.float64)
        f = 1.0 / (self._constant + self._linear * d + self._quadratic * d * d)
        return float(f) if d.ndim == 0 else f

    def world_position(self, matrix: np.ndarray) -> np.ndarray:
        """The position in world coordinates under ``matrix`` (the light's world matrix)."""
        return (np.asarray(matrix, dtype=np.float64) @ np.array([*self._position, 1.0]))[:3]


class DirectionalLight(LightSource):
    """A light infinitely far away; ``direction`` is the way the light travels (into the scene)."""

    __slots__ = ("_direction",)
    direction = Param(check_direction, "direction of travel (normalised)")

    def __init__(
        self,
        direction: Sequence[float] = (0.0, 0.0, -1.0),
        color: Sequence[float] = (1.0, 1.0, 1.0),
        intensity: float = 1.0,
        ambient: Sequence[float] = (0.0, 0.0, 0.0),
        diffuse: Sequence[float] | None = None,
        specular: Sequence[float] | None = None,
        casts_shadows: bool = True,
        enabled: bool = True,
    ) -> None:
        super().__init__(color, intensity, ambient, diffuse, specular, casts_shadows, enabled)
        self.direction = direction

    def world_direction(self, matrix: np.ndarray) -> np.ndarray:
        """The unit direction of travel in world coordinates under ``matrix``."""
        d = np.asarray(matrix, dtype=np.float64)[:3, :3] @ np.asarray(self._direction)
        return d / np.linalg.norm(d)


class PointLight(_Attenuated):
    """A light at ``position`` shining in all directions."""

    __slots__ = ()

    def __init__(
        self,
        position: Sequence[float] = (0.0, 0.0, 0.0),
        color: Sequence[float] = (1.0, 1.0, 1.0),
        intensity: float = 1.0,
        constant: float = 1.0,
        linear: float = 0.0,
        quadratic: float = 0.0,
        ambient: Sequence[float] = (0.0, 0.0, 0.0),
        diffuse: Sequence[float] | None = None,
        specular: Sequence[float] | None = None,
        casts_shadows: bool = True,
        threshold: float = DEFAULT_THRESHOLD,
        enabled: bool = True,
    ) -> None:
        super().__init__(color, intensity, ambient, diffuse, specular, casts_shadows, enabled)
        self._init_attenuation(position, constant, linear, quadratic, threshold)


class SpotLight(_Attenuated):
    """A point light restricted to a cone around ``direction``.

    ``cutoff`` is the cone's half angle in degrees (0 < cutoff <= 90),
    ``exponent`` (>= 0) concentrates the light towards the axis.
    """

    __slots__ = ("_direction", "_cutoff", "_exponent")
    direction = Param(check_direction, "spot axis (normalised)")
    cutoff = Param(check_number(0.0, 90.0, min_open=True), "half angle of the cone in degrees")
    exponent = Param(_nonneg, "spot exponent >= 0")

    def __init__(
        self,
        position: Sequence[float] = (0.0, 0.0, 0.0),
        direction: Sequence[float] = (0.0, 0.0, -1.0),
        cutoff: float = 30.0,
        exponent: float = 0.0,
        color: Sequence[float] = (1.0, 1.0, 1.0),
        intensity: float = 1.0,
        constant: float = 1.0,
        linear: float = 0.0,
        quadratic: float = 0.0,
        ambient: Sequence[float] = (0.0, 0.0, 0.0),
        diffuse: Sequence[float] | None = None,
        specular: Sequence[float] | None = None,
        casts_shadows: bool = True,
        threshold: float = DEFAULT_THRESHOLD,
        enabled: bool = True,
    ) -> None:
        super().__init__(color, intensity, ambient, diffuse, specular, casts_shadows, enabled)
        self._init_attenuation(position, constant, linear, quadratic, threshold)
        self.direction = direction
        self.cutoff = cutoff
        self.exponent = exponent

    @property
    def cos_cutoff(self) -> float:
        """cos(cutoff), the smallest cosine still inside the cone."""
        return math.cos(math.radians(self._cutoff))

    def spot_factor(self, cos_angle: float | np.ndarray) -> float | np.ndarray:
        """``cos_angle ** exponent`` inside the cone, 0 outside.

        ``cos_angle`` is the cosine between the spot axis and the direction from
        the light to the lit point.
        """
        c = np.asarray(cos_angle, dtype=np.float64)
        inside = c >= self.cos_cutoff - 1e-12
        f = np.where(inside, np.power(np.clip(c, 0.0, 1.0), self._exponent), 0.0)
        return float(f) if c.ndim == 0 else f

    def world_direction(self, matrix: np.ndarray) -> np.ndarray:
        """The unit spot axis in world coordinates under ``matrix``."""
        d = np.asarray(matrix, dtype=np.float64)[:3, :3] @ np.asarray(self._direction)
        return d / np.linalg.norm(d)


def _check_size(owner: str, name: str, value: Any) -> float:
    x = check_number(0.0, min_open=True)(owner, name, value)
    return float(x)


class AreaLight(LightSource):
    """Base of the flat area lights: a shape of uniform radiance at ``position``, emitting along ``direction``.

    The light's plane is perpendicular to ``direction`` (the side it lights;
    ``two_sided=True`` lights both sides); ``up`` turns the shape about
    ``direction`` (a rectangle's ``height`` runs along it).  Position, size and
    orientation are in the coordinates of the place the light sits: the
    transforms in effect move, turn and scale it (a non-uniform scaling makes a
    disc an ellipse).

    Photometry (one rule, :mod:`.photometry`): the surface emits the radiance
    ``diffuse`` (``color * intensity``, W/(m^2 sr) per RGB channel in the
    physically based engines), so a diffuse surface of colour ``kd`` shows
    ``kd * diffuse * F``, ``F`` the light's form factor seen from the point
    (:func:`.photometry.area_form_factor`); under a very large light this is a
    directional light's ``kd * diffuse`` head-on.  One side emits the power
    ``pi * diffuse * area`` (W per channel).
    """

    __slots__ = ("_position", "_direction", "_up", "_two_sided")
    position = Param(check_vector(3), "centre of the light in the light's coordinates")
    direction = Param(check_direction, "the light's normal: the side it lights (normalised)")
    up = Param(
        optional(check_direction),
        "turns the shape about direction (a rectangle's height runs along it); None: +y, or -z for a light along y",
    )
    two_sided = Param(check_bool, "True: both faces emit (each with the full radiance)")

    def _init_area(self, position: Sequence[float], direction: Sequence[float], up: Sequence[float],
                   two_sided: bool) -> None:  # fmt: skip
        self.position = position
        self.direction = direction
        self.up = up
        self.two_sided = two_sided
        if self._up is not None and abs(float(np.dot(self._direction, self._up))) > 1.0 - 1e-9:
            raise ValueError(
                f"{type(self).__name__}: up {self._up} is parallel to direction {self._direction}; "
                "give an up that is not along the light's direction"
            )

    def _half_axes(self) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def local_frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit vectors (u, v, n) in the light's coordinates: width axis, height axis (``up``), normal."""
        n = np.asarray(self._direction, np.float64)
        up = self._up
        if up is None:
            up = (0.0, 1.0, 0.0) if abs(n[1]) < 0.999 else (0.0, 0.0, -1.0)
        v = np.asarray(up, np.float64) - n * float(np.dot(n, up))
        v /= np.linalg.norm(v)
        return np.cross(n, v), v, n

    def world_frame(self, matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(centre, half_u, half_v, normal)`` in world coordinates under ``matrix`` (the light's world matrix).

        ``half_u`` and ``half_v`` are the shape's half extents as vectors (a
        rectangle's corners are ``centre +- half_u +- half_v``; a disc is the
        ellipse they span), ``normal`` the unit normal of the lit side.
        """
        m = np.asarray(matrix, np.float64)
        hu, hv = self._half_axes()
        centre = (m @ np.array([*self._position, 1.0]))[:3]
        half_u, half_v = m[:3, :3] @ hu, m[:3, :3] @ hv
        normal = np.cross(half_u, half_v)
        length = float(np.linalg.norm(normal))
        scale = float(np.linalg.norm(half_u) * np.linalg.norm(half_v))
        if not scale > 0.0 or length <= 1e-9 * scale:
            raise ValueError(
                f"{type(self).__name__}: the transforms in effect flatten the light to zero area; "
                "scale it by non-zero factors in its plane"
            )
        # the lit side follows the transformed direction (a mirroring transform flips the axes' cross product)
        local = float(np.dot(np.cross(hu, hv), self._direction))
        det = float(np.linalg.det(m[:3, :3]))
        normal *= math.copysign(1.0, local) * (-1.0 if det < 0.0 else 1.0) / length
        return centre, half_u, half_v, normal

    def world_area(self, matrix: np.ndarray) -> float:
        """The area of one face in world units."""
        _, hu, hv, _ = self.world_frame(matrix)
        return self._area_factor * float(np.linalg.norm(np.cross(hu, hv)))

    _area_factor = 4.0

    def world_polygon(self, matrix: np.ndarray, segments: int = 32) -> np.ndarray:
        """The outline in world coordinates, counter-clockwise seen from the lit side (``(k, 3)`` array).

        A rectangle gives its 4 corners; a disc ``segments`` points on its
        ellipse, pushed outwards so that the polygon has the ellipse's area.
        """
        c, hu, hv, n = self.world_frame(matrix)
        if isinstance(self, RectLight):
            pts = np.array([c - hu - hv, c + hu - hv, c + hu + hv, c - hu + hv])
        else:
            t = np.arange(segments) * (2.0 * math.pi / segments)
            grow = math.sqrt(2.0 * math.pi / (segments * math.sin(2.0 * math.pi / segments)))
            pts = c + grow * (np.cos(t)[:, None] * hu + np.sin(t)[:, None] * hv)
        if float(np.dot(np.cross(pts[1] - pts[0], pts[2] - pts[0]), n)) < 0.0:
            pts = pts[::-1].copy()
        return pts

    def world_position(self, matrix: np.ndarray) -> np.ndarray:
        """The centre in world coordinates under ``matrix``."""
        return (np.asarray(matrix, dtype=np.float64) @ np.array([*self._position, 1.0]))[:3]

    def world_direction(self, matrix: np.ndarray) -> np.ndarray:
        """The unit normal of the lit side in world coordinates."""
        return self.world_frame(matrix)[3]


class RectLight(AreaLight):
    """A rectangle of ``width`` x ``height`` emitting uniformly (see :class:`AreaLight` for placement and units).

    ``width`` runs along ``cross(direction, up)``, ``height`` along ``up``.
    Every engine: GL by linearly transformed cosines with soft shadows,
    POV-Ray ``area_light``, Mitsuba an ``area`` emitter on a ``rectangle``,
    Radiance a ``light`` polygon, RIB ``PxrRectLight``, USD ``RectLight``.
    """

    __slots__ = ("_width", "_height")
    width = Param(_check_size, "extent along cross(direction, up) (> 0)")
    height = Param(_check_size, "extent along up (> 0)")

    def __init__(
        self,
        position: Sequence[float] = (0.0, 0.0, 0.0),
        direction: Sequence[float] = (0.0, 0.0, -1.0),
        width: float = 1.0,
        height: float = 1.0,
        up: Sequence[float] | None = None,
        two_sided: bool = False,
        color: Sequence[float] = (1.0, 1.0, 1.0),
        intensity: float = 1.0,
        ambient: Sequence[float] = (0.0, 0.0, 0.0),
        diffuse: Sequence[float] | None = None,
        specular: Sequence[float] | None = None,
        casts_shadows: bool = True,
        enabled: bool = True,
    ) -> None:
        super().__init__(color, intensity, ambient, diffuse, specular, casts_shadows, enabled)
        self.width = width
        self.height = height
        self._init_area(position, direction, up, two_sided)

    def _half_axes(self) -> tuple[np.ndarray, np.ndarray]:
        u, v, _ = self.local_frame()
        return u * (0.5 * self._width), v * (0.5 * self._height)


class DiscLight(AreaLight):
    """A disc of ``radius`` emitting uniformly (see :class:`AreaLight` for placement and units).

    Every engine: GL by linearly transformed cosines over an equal-area
    polygon, POV-Ray a ``circular`` ``area_light``, Mitsuba an ``area`` emitter
    on a ``disk``, Radiance a ``light`` ring, RIB ``PxrDiskLight``, USD ``DiskLight``.
    """

    __slots__ = ("_radius",)
    radius = Param(_check_size, "radius (> 0)")
    _area_factor = math.pi

    def __init__(
        self,
        position: Sequence[float] = (0.0, 0.0, 0.0),
        direction: Sequence[float] = (0.0, 0.0, -1.0),
        radius: float = 0.5,
        up: Sequence[float] | None = None,
        two_sided: bool = False,
        color: Sequence[float] = (1.0, 1.0, 1.0),
        intensity: float = 1.0,
        ambient: Sequence[float] = (0.0, 0.0, 0.0),
        diffuse: Sequence[float] | None = None,
        specular: Sequence[float] | None = None,
        casts_shadows: bool = True,
        enabled: bool = True,
    ) -> None:
        super().__init__(color, intensity, ambient, diffuse, specular, casts_shadows, enabled)
        self.radius = radius
        self._init_area(position, direction, up, two_sided)

    def _half_axes(self) -> tuple[np.ndarray, np.ndarray]:
        u, v, _ = self.local_frame()
        return u * self._radius, v * self._radius


class AmbientLight(LightSource):
    """Light that reaches every surface equally from everywhere (``ambient = color * intensity``)."""

    __slots__ = ()

    def __init__(self, color: Sequence[float] = (1.0, 1.0, 1.0), intensity: float = 0.2, enabled: bool = True) -> None:
        super().__init__(color, intensity, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), False, enabled)

    @property
    def ambient(self) -> tuple[float, float, float]:  # type: ignore[override]
        return _scaled(self._color, self._intensity)

    @ambient.setter
    def ambient(self, value: Sequence[float]) -> None:
        object.__setattr__(self, "_ambient", check_rgb("AmbientLight", "ambient", value))

    def parameters(self) -> dict[str, Any]:
        return {"color": self._color, "intensity": self._intensity, "enabled": self._enabled}


class EyeLight(NamedTuple):
    """One light of the default set, in eye coordinates."""

    direction: tuple[float, float, float]  # of travel
    intensity: float
    ambient: tuple[float, float, float]
    casts_shadows: bool


#: The default light set in eye coordinates, ArtiSynth's.  Only the key light casts shadows, as in a
#: photographer's setup (fill and back lights soften, they add no shadows of their own); it also keeps the
#: GL engine at one shadow map for scenes that bring no lights.
DEFAULT_EYE_LIGHTS = (
    EyeLight((0.35, -0.45, -1.0), 0.8, (0.12, 0.12, 0.12), True),  # key light, from above left of the eye
    EyeLight((-0.7, 0.2, -0.6), 0.35, (0.0, 0.0, 0.0), False),  # fill light, from the right
    EyeLight((0.1, -0.3, 1.0), 0.2, (0.0, 0.0, 0.0), False),  # back light
)


def default_lights(eye_to_world: np.ndarray | None = None) -> list[DirectionalLight]:
    """Key, fill and back light: in eye coordinates, or in world coordinates for a camera's ``eye_to_world``.

    The viewer keeps them in eye space (they move with the eye); a scene made
    around a mesh file places them for its fitted camera.
    """
    rotation = np.eye(3) if eye_to_world is None else np.asarray(eye_to_world, dtype=np.float64)[:3, :3]
    return [
        DirectionalLight(
            direction=tuple(rotation @ np.asarray(light.direction)),
            intensity=light.intensity,
            ambient=light.ambient,
            casts_shadows=light.casts_shadows,
        )
        for light in DEFAULT_EYE_LIGHTS
    ]
