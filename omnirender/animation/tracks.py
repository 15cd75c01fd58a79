"""Tracks: what drives one component parameter over time.

A track names its *target* component directly (not by path), so the reference
survives ``copy.deepcopy``, pickling (the graph and its animation travel
together) and scene files (where the target is written once and referred to by
``$ref``).  :class:`Keyframes` interpolates keys (step, linear, cubic; unit
quaternions by slerp); :class:`~omnirender.animation.orbit.Orbit` turns
positions and directions about an axis.  Any Python callable ``f(t, scene)``
is a track too (see :class:`~omnirender.animation.animation.Animation`).

Setting a parameter goes through the component's own validation, so a track
that drives a colour out of [0, 1] fails with the component's message plus the
track and the time.  A few parameters are set through adapters
(:data:`SETTERS`): ``Rotation.quaternion`` (w, x, y, z) sets the rotation's
axis and angle.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..core.component import RenderingComponent
from ..core.transform import Rotation
from ..shapes._check import scalar
from .interpolate import INTERPOLATIONS, interpolate

__all__ = ["Track", "Keyframes", "SETTERS", "register_setter", "set_parameter"]


def _set_rotation_quaternion(rotation: Rotation, q: Sequence[float]) -> None:
    r = Rotation.from_quaternion(*q)
    rotation.axis = r.axis
    rotation.angle = r.angle


#: (component class, parameter) -> setter(component, value) for parameters without a plain attribute setter.
SETTERS: dict[tuple[type, str], Callable[[Any, Any], None]] = {(Rotation, "quaternion"): _set_rotation_quaternion}


def register_setter(cls: type, parameter: str, setter: Callable[[Any, Any], None]) -> None:
    """Let tracks drive ``parameter`` of ``cls`` components through ``setter(component, value)``."""
    SETTERS[(cls, parameter)] = setter


def _setter(component: Any, parameter: str) -> Callable[[Any, Any], None] | None:
    for klass in type(component).__mro__:
        found = SETTERS.get((klass, parameter))
        if found is not None:
            return found
    return None


def set_parameter(component: Any, parameter: str, value: Any) -> None:
    """Assign ``value`` to ``component.parameter`` (through :data:`SETTERS` where registered)."""
    setter = _setter(component, parameter)
    if setter is not None:
        setter(component, value)
    else:
        setattr(component, parameter, value)


class Track(RenderingComponent):
    """Base of tracks: ``apply(t, scene)`` sets the target's parameters for time ``t`` (seconds).

    Tracks live in an :class:`~omnirender.animation.animation.Animation`, not
    directly in a node.
    """

    __slots__ = ()

    @property
    def end(self) -> float:
        """The time after which the track no longer changes anything (seconds)."""
        return 0.0

    def apply(self, t: float, scene: Any) -> None:  # pragma: no cover - abstract
        raise NotImplementedError(f"{type(self).__name__}.apply is not implemented")

    def describe(self) -> str:
        """A short name for error messages: ``Keyframes(Material.diffuse)``."""
        return type(self).__name__


def _check_target(owner: str, target: Any) -> RenderingComponent:
    if not isinstance(target, RenderingComponent):
        raise TypeError(
            f"{owner}: target must be a component of the scene (e.g. the om.Rotation to animate), "
            f"got {type(target).__name__}"
        )
    return target


def _kind(current: Any) -> str:
    """How values of a parameter are interpolated: 'vector', 'scalar', 'integer' or 'discrete'."""
    if isinstance(current, (bool, np.bool_)) or current is None or isinstance(current, str):
        return "discrete"
    if isinstance(current, numbers.Integral):
        return "integer"
    if isinstance(current, numbers.Real):
        return "scalar"
    if isinstance(current, (tuple, list, np.ndarray)):
        try:
            arr = np.asarray(current, dtype=np.float64)
        except (TypeError, ValueError):
            return "discrete"
        return "vector" if arr.ndim == 1 else "discrete"
    return "discrete"


class Keyframes(Track):
    """Keys of one parameter of one component, interpolated in time.

    ``Keyframes(target, parameter, times, values, interpolation="linear", tangents=None)``:
    ``times`` strictly increasing seconds, one value per time, shaped like the
    parameter (a number, or a vector such as an offset or a colour).
    ``interpolation`` is ``"step"``, ``"linear"`` or ``"cubic"`` (numbers and
    vectors; other values, such as strings and booleans, only step).  The
    parameter ``"quaternion"`` (an ``om.Rotation``'s, as (w, x, y, z)) is
    interpolated on the unit sphere (slerp).  ``tangents`` = ``(in, out)``
    arrays shaped like ``values`` give a cubic curve's slopes (units per
    second), as glTF's CUBICSPLINE keys do; without them cubic curves use
    Catmull-Rom slopes.
    """

    __slots__ = ("_target", "_parameter", "_times", "_values", "_interpolation", "_tangents", "_kind")

    def __init__(
        self,
        target: RenderingComponent,
        parameter: str,
        times: Sequence[float],
        values: Sequence[Any],
        interpolation: str = "linear",
        tangents: Sequence[Sequence[Any]] | None = None,
    ) -> None:
        super().__init__()
        name = "Keyframes"
        target = _check_target(name, target)
        if not isinstance(parameter, str) or not parameter:
            raise ValueError(f"{name}: parameter must be the name of a parameter of the target, got {parameter!r}")
        where = f"{name}({type(target).__name__}.{parameter})"
        try:
            current = getattr(target, parameter)
        except AttributeError:
            known = ", ".join(target.parameters()) or "none"
            raise ValueError(
                f"{where}: {type(target).__name__} has no parameter {parameter!r} (parameters: {known})"
            ) from None
        if _setter(target, parameter) is None and isinstance(getattr(type(target), parameter, None), property):
            if getattr(type(target), parameter).fset is None:
                raise ValueError(f"{where}: {parameter!r} is read-only on {type(target).__name__}")
        if interpolation not in INTERPOLATIONS:
            raise ValueError(f"{where}: interpolation must be one of {INTERPOLATIONS}, got {interpolation!r}")
        kind = _kind(current)
        if kind == "discrete" and interpolation != "step":
            raise ValueError(
                f"{where}: {type(current).__name__} values cannot be interpolated {interpolation}ly; use "
                "interpolation='step'"
            )
        t = _times(where, times)
        if kind == "discrete":
            vals: Any = list(values)
            if len(vals) != len(t):
                raise ValueError(f"{where}: {len(t)} times but {len(vals)} values")
        else:
            vals = _values(where, values, len(t), np.asarray(current, np.float64).shape)
        tans = None
        if tangents is not None:
            if interpolation != "cubic" or kind == "discrete":
                raise ValueError(f"{where}: tangents are only used by cubic interpolation")
            if len(tangents) != 2:
                raise ValueError(f"{where}: tangents must be (in_tangents, out_tangents)")
            tans = tuple(_values(f"{where} tangents", tv, len(t), vals.shape[1:]) for tv in tangents)
        object.__setattr__(self, "_target", target)
        object.__setattr__(self, "_parameter", parameter)
        object.__setattr__(self, "_times", t)
        object.__setattr__(self, "_values", vals)
        object.__setattr__(self, "_interpolation", interpolation)
        object.__setattr__(self, "_tangents", tans)
        object.__setattr__(self, "_kind", kind)

    @property
    def target(self) -> RenderingComponent:
        return self._target

    @property
    def parameter(self) -> str:
        return self._parameter

    @property
    def times(self) -> np.ndarray:
        return self._times

    @property
    def values(self) -> Any:
        return self._values

    @property
    def interpolation(self) -> str:
        return self._interpolation

    @property
    def end(self) -> float:
        return float(self._times[-1])

    def describe(self) -> str:
        return f"Keyframes({type(self._target).__name__}.{self._parameter})"

    def value_at(self, t: float) -> Any:
        """The parameter's value at time ``t`` (converted to the parameter's type)."""
        if self._kind == "discrete":
            k = int(np.searchsorted(self._times, t, side="right")) - 1
            return self._values[max(k, 0)]
        v = interpolate(
            self._times,
            self._values,
            float(t),
            self._interpolation,
            quaternion=self._parameter == "quaternion",
            tangents=self._tangents,
        )
        if self._kind == "integer":
            return int(round(float(v)))
        if self._kind == "scalar":
            return float(v)
        return tuple(float(x) for x in v)

    def apply(self, t: float, scene: Any = None) -> None:
        set_parameter(self._target, self._parameter, self.value_at(t))

    def parameters(self) -> dict[str, Any]:
        values = self._values if self._kind == "discrete" else self._values.tolist()
        return {
            "target": self._target,
            "parameter": self._parameter,
            "times": self._times.tolist(),
            "values": values,
            "interpolation": self._interpolation,
            "tangents": None if self._tangents is None else [a.tolist() for a in self._tangents],
        }


def _times(where: str, times: Any) -> np.ndarray:
    try:
        t = np.array(times, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: times must be numbers (seconds), got {times!r:.60}") from None
    if len(t) == 0:
        raise ValueError(f"{where}: needs at least one key")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{where}: times must be finite")
    if np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0))
        raise ValueError(f"{where}: times must increase strictly, but key {k + 1} ({t[k + 1]}) follows {t[k]}")
    t.setflags(write=False)
    return t


def _values(where: str, values: Any, count: int, shape: tuple[int, ...]) -> np.ndarray:
    try:
        v = np.array(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: values must be numbers shaped like the parameter, got {values!r:.60}") from None
    if v.shape != (count, *shape):
        want = f"{count} numbers" if not shape else f"{count} vectors of {shape[0]}"
        raise ValueError(f"{where}: expected {want} (one per time), got an array of shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{where}: values must be finite")
    v.setflags(write=False)
    return v


def check_time(owner: str, t: Any, name: str = "time", **limits: bool) -> float:
    """``t`` as a finite number of seconds (``positive=True`` / ``nonnegative=True``), or ValueError naming it."""
    return scalar(owner, name, t, **limits)
