"""Camera paths: orbits, turntables and look-at paths.

:class:`Orbit` turns a component's positions and directions about an axis in
world space: a camera's eye, centre and up, a light's position and direction,
a ``LookAt``'s eye, centre and up, a ``Translation``'s offset.  It keeps the
values it started from (``base``) so that any time can be set in any order,
and the component's world matrix at creation (``frame``), so that a light
nested under transforms turns about the same world axis as the camera.

:func:`turntable` puts a whole scene on a turntable: the camera and (by
default) the lights orbit the scene's centre together, which looks exactly as
if the scene turned in front of a fixed camera and studio lights.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..attributes import AmbientLight, DirectionalLight, LightSource, LookAt, PointLight, SpotLight
from ..core.camera import Camera
from ..core.component import RenderingComponent
from ..core.transform import Translation, axis_angle_matrix, finite_vector
from .tracks import Keyframes, Track, _check_target, check_time

__all__ = ["Orbit", "ORBIT_PARAMETERS", "orbit", "turntable", "camera_path"]

#: Component class -> its parameters an Orbit turns, each a point or a direction.
ORBIT_PARAMETERS: dict[type, tuple[tuple[str, str], ...]] = {
    Camera: (("eye", "point"), ("center", "point"), ("up", "direction")),
    LookAt: (("eye", "point"), ("center", "point"), ("up", "direction")),
    SpotLight: (("position", "point"), ("direction", "direction")),
    PointLight: (("position", "point"),),
    DirectionalLight: (("direction", "direction"),),
    Translation: (("offset", "point"),),
}


def _orbit_parameters(target: Any) -> tuple[tuple[str, str], ...]:
    for klass in type(target).__mro__:
        found = ORBIT_PARAMETERS.get(klass)
        if found is not None:
            return found
    known = ", ".join(sorted(c.__name__ for c in ORBIT_PARAMETERS))
    raise ValueError(f"Orbit: cannot orbit a {type(target).__name__} (orbitable: {known})")


class Orbit(Track):
    """Turn ``target`` by ``turns`` full turns about ``axis`` through ``center`` in ``seconds``.

    ``Orbit(target, seconds, center=None, axis=(0, 1, 0), turns=1.0, start=0.0, frame=None, base=None)``.
    The turn begins at time ``start`` and advances uniformly (positive turns
    are counter-clockwise seen from the tip of ``axis``).  ``center`` and
    ``axis`` are in world coordinates; ``frame`` is the target's
    local-to-world matrix (identity by default; :func:`turntable` fills it in
    from the scene).  ``center`` defaults to a camera's or LookAt's centre,
    else the world origin.  ``base`` (the values at turn 0) is taken from the
    target when the orbit is made.
    """

    __slots__ = ("_target", "_seconds", "_center", "_axis", "_turns", "_start", "_frame", "_base")

    def __init__(
        self,
        target: RenderingComponent,
        seconds: float,
        center: Sequence[float] | None = None,
        axis: Sequence[float] = (0.0, 1.0, 0.0),
        turns: float = 1.0,
        start: float = 0.0,
        frame: Any = None,
        base: dict[str, Any] | None = None,
    ) -> None:
        super().__init__()
        target = _check_target("Orbit", target)
        params = _orbit_parameters(target)
        seconds = check_time("Orbit", seconds, "seconds", positive=True)
        start = check_time("Orbit", start, "start")
        turns = check_time("Orbit", turns, "turns")
        a = finite_vector("Orbit", "axis", axis, 3)
        if np.linalg.norm(a) == 0.0:
            raise ValueError("Orbit: axis must not be the zero vector")
        m = np.eye(4) if frame is None else np.array(frame, dtype=np.float64)
        if m.shape != (4, 4) or not np.all(np.isfinite(m)) or abs(np.linalg.det(m[:3, :3])) < 1e-12:
            raise ValueError("Orbit: frame must be an invertible 4x4 local-to-world matrix")
        if base is None:
            base = {name: tuple(float(x) for x in getattr(target, name)) for name, _ in params}
        else:
            base = {
                str(k): tuple(float(x) for x in finite_vector("Orbit", f"base[{k!r}]", v, 3)) for k, v in base.items()
            }
            missing = {name for name, _ in params} - set(base)
            if missing:
                raise ValueError(f"Orbit: base lacks {sorted(missing)} for a {type(target).__name__}")
        if center is None:
            local = base.get("center", (0.0, 0.0, 0.0)) if isinstance(target, (Camera, LookAt)) else (0.0, 0.0, 0.0)
            center = (m @ np.array([*local, 1.0]))[:3]
        c = finite_vector("Orbit", "center", center, 3)
        object.__setattr__(self, "_target", target)
        object.__setattr__(self, "_seconds", seconds)
        object.__setattr__(self, "_center", tuple(float(x) for x in c))
        object.__setattr__(self, "_axis", tuple(float(x) for x in a / np.linalg.norm(a)))
        object.__setattr__(self, "_turns", turns)
        object.__setattr__(self, "_start", start)
        m.setflags(write=False)
        object.__setattr__(self, "_frame", m)
        object.__setattr__(self, "_base", base)

    @property
    def target(self) -> RenderingComponent:
        return self._target

    @property
    def end(self) -> float:
        return self._start + self._seconds

    def describe(self) -> str:
        return f"Orbit({type(self._target).__name__})"

    def angle_at(self, t: float) -> float:
        """The orbit angle at time ``t`` in degrees."""
        u = min(max((float(t) - self._start) / self._seconds, 0.0), 1.0)
        return 360.0 * self._turns * u

    def matrix_at(self, t: float) -> np.ndarray:
        """The world-space rotation (4x4, about the axis through the centre) at time ``t``."""
        c = np.asarray(self._center)
        to, back = np.eye(4), np.eye(4)
        to[:3, 3], back[:3, 3] = c, -c
        return to @ axis_angle_matrix(np.asarray(self._axis), math.radians(self.angle_at(t))) @ back

    def apply(self, t: float, scene: Any = None) -> None:
        local = np.linalg.solve(self._frame, self.matrix_at(t) @ self._frame)  # frame^-1 R frame
        for name, kind in _orbit_parameters(self._target):
            v = np.asarray(self._base[name])
            turned = local[:3, :3] @ v + (local[:3, 3] if kind == "point" else 0.0)
            setattr(self._target, name, tuple(float(x) for x in turned))

    def parameters(self) -> dict[str, Any]:
        return {
            "target": self._target,
            "seconds": self._seconds,
            "center": list(self._center),
            "axis": list(self._axis),
            "turns": self._turns,
            "start": self._start,
            "frame": self._frame.tolist(),
            "base": {k: list(v) for k, v in self._base.items()},
        }


def orbit(
    camera: Camera,
    seconds: float,
    center: Sequence[float] | None = None,
    axis: Sequence[float] = (0.0, 1.0, 0.0),
    turns: float = 1.0,
    start: float = 0.0,
) -> Orbit:
    """A camera orbit: ``camera`` circles ``center`` (its own centre by default) about ``axis``.

    Add the returned track to an ``om.Animation``.
    """
    if not isinstance(camera, Camera):
        raise TypeError(f"om.orbit: camera must be an om.Camera, got {type(camera).__name__}; use om.Orbit for others")
    return Orbit(camera, seconds, center=center, axis=axis, turns=turns, start=start)


def camera_path(
    camera: Camera,
    times: Sequence[float],
    eyes: Sequence[Sequence[float]],
    centers: Sequence[Sequence[float]] | None = None,
    interpolation: str = "cubic",
) -> list[Keyframes]:
    """Tracks moving ``camera``'s eye through ``eyes`` (and its centre through ``centers``) at ``times``.

    The camera keeps looking at its centre (look-at along a path); cubic
    interpolation gives a smooth flight through the keys.
    """
    if not isinstance(camera, Camera):
        raise TypeError(f"om.camera_path: camera must be an om.Camera, got {type(camera).__name__}")
    tracks = [Keyframes(camera, "eye", times, eyes, interpolation)]
    if centers is not None:
        tracks.append(Keyframes(camera, "center", times, centers, interpolation))
    return tracks


def turntable(
    scene: Any,
    seconds: float,
    turns: float = 1.0,
    axis: Sequence[float] = (0.0, 1.0, 0.0),
    center: Sequence[float] | None = None,
    lights: bool = True,
    fps: float = 24.0,
) -> Any:
    """Add to ``scene`` (its root node) an animation turning it ``turns`` times in ``seconds``; returns it.

    The scene's camera orbits ``center`` (default: the centre of the scene's
    bounds) about ``axis`` (world coordinates, default vertical), and with
    ``lights=True`` the lights orbit with it, so the result looks like the
    scene turning on a turntable in front of a fixed camera and fixed studio
    lights.  The scene needs a camera.  Remove the animation with
    ``scene.remove(animation)``.
    """
    from ..scene.node import Node
    from ..techniques import bounds
    from .animation import Animation

    if not isinstance(scene, Node):
        raise TypeError(f"om.turntable: scene must be an om.Node, got {type(scene).__name__}")
    found_lights, camera = scene.preevaluate()
    if camera is None:
        raise ValueError(
            f"om.turntable: the scene {scene.path} has no camera to turn; add one, "
            "e.g. scene.add(om.Camera.look_at(eye=(4, 3, 6), center=(0, 1, 0)))"
        )
    if center is None:
        box = bounds(scene)
        if box is None:
            raise ValueError(f"om.turntable: the scene {scene.path} is empty; give center=(x, y, z)")
        center = (np.asarray(box[0]) + np.asarray(box[1])) / 2.0
    tracks: list[Track] = [Orbit(camera[0], seconds, center, axis, turns, frame=camera[1])]
    if lights:
        seen: set[int] = set()
        for light, world in found_lights:
            if isinstance(light, AmbientLight) or not isinstance(light, LightSource) or id(light) in seen:
                continue
            seen.add(id(light))
            tracks.append(Orbit(light, seconds, center, axis, turns, frame=world))
    animation = Animation(tracks, duration=seconds, fps=fps)
    scene.add(animation)
    return animation
