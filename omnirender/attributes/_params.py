"""Validated parameters for attribute declarations.

A :class:`Param` is a data descriptor that validates on every assignment and
stores the result in a private slot (``color`` lives in ``_color``).  Because
the public name is assigned through ``RenderingComponent.__setattr__``, every
change still bumps the component's version.  :class:`Parameterised` gives
``parameters()`` from the declared params, in declaration order, so that
``type(x)(**x.parameters())`` rebuilds any attribute (scene files rely on it).

The ``check_*`` functions raise ValueError naming the class and the parameter
(``"Material: shininess must be >= 0, got -1.0"``).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..core.limits import MAX_MAGNITUDE, as_float, check_array_magnitude

__all__ = [
    "Param",
    "assign_new",
    "Parameterised",
    "check_color",
    "check_rgb",
    "check_rgba",
    "check_number",
    "check_choice",
    "check_vector",
    "check_direction",
    "check_bool",
]

Check = Callable[[str, str, Any], Any]


class Param:
    """A validated public parameter stored in the private slot ``_<name>``."""

    __slots__ = ("name", "slot", "check", "doc", "last")

    def __init__(self, check: Check, doc: str = "") -> None:
        self.check = check
        self.doc = doc
        self.name = ""
        self.slot = ""
        #: ``(value, checked)`` of the last immutable value a constructor checked (:func:`assign_new`): the same
        #: object again (a default left out, a constant the application passes every time) is not checked again
        self.last: tuple[Any, Any] | None = None

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name
        self.slot = "_" + name

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        return getattr(obj, self.slot)

    def __set__(self, obj: Any, value: Any) -> None:
        object.__setattr__(obj, self.slot, self.check(type(obj).__name__, self.name, value))

    def raw(self, obj: Any) -> Any:
        """The stored value as given (what ``parameters()`` reports)."""
        return getattr(obj, self.slot)


_NAMES_CACHE: dict[type, tuple[Param, ...]] = {}


def declared_params(cls: type) -> tuple[Param, ...]:
    """The :class:`Param` descriptors of ``cls`` in the order of its constructor's arguments.

    Params the constructor does not name follow in declaration order (base classes first).
    """
    found = _NAMES_CACHE.get(cls)
    if found is None:
        seen: dict[str, Param] = {}
        for klass in reversed(cls.__mro__):
            for key, value in vars(klass).items():
                if isinstance(value, Param):
                    seen[key] = value
        try:
            order = list(inspect.signature(cls.__init__).parameters)
        except (TypeError, ValueError):  # pragma: no cover - every attribute has a Python __init__
            order = []
        rank = {name: i for i, name in enumerate(order)}
        names = sorted(seen, key=lambda n: rank.get(n, len(order)))
        found = _NAMES_CACHE[cls] = tuple(seen[n] for n in names)
    return found


def assign_new(obj: Any, values: tuple[tuple[str, Any], ...]) -> None:
    """Set the parameters of ``obj`` under construction: ``(name, value)`` pairs, each checked as an assignment
    is, without a version bump and a journal entry per parameter (nothing can have compiled a component that
    is being made; an application making a node per frame pays one pass)."""
    cls = type(obj)
    owner = cls.__name__
    for name, value in values:
        param = getattr(cls, name)
        last = param.last
        if last is not None and last[0] is value:  # (the memo holds the value: its identity is its own)
            checked = last[1]
        else:
            checked = param.check(owner, name, value)
            kind = value.__class__
            if kind in _IMMUTABLE or (kind is tuple and all(c.__class__ in _NUMBERS for c in value)):
                param.last = (value, checked)
        object.__setattr__(obj, param.slot, checked)


#: kinds of values whose check gives the same result for the same object, always (assign_new's memo)
_IMMUTABLE = frozenset((float, int, bool, str, type(None)))
_NUMBERS = frozenset((float, int))


class Parameterised:
    """Mixin: ``parameters()`` from the class's :class:`Param` declarations."""

    __slots__ = ()

    def parameters(self) -> dict[str, Any]:
        """Constructor keyword arguments that rebuild this attribute."""
        return {p.name: p.raw(self) for p in declared_params(type(self))}


# -- checks -------------------------------------------------------------------
def _numbers(owner: str, name: str, value: Any) -> np.ndarray:
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{owner}: {name} must be numbers, got {value!r:.60}")
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except OverflowError:
        raise ValueError(f"{owner}: {name} must be numbers of at most {MAX_MAGNITUDE:.0e} in magnitude") from None
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: {name} must be numbers, got {value!r:.60}") from None
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{owner}: {name} must be finite, got {value!r:.60}")
    return check_array_magnitude(owner, name, arr)


def _plain_unit_values(value: Any) -> tuple[float, ...] | None:
    """``value`` as 3 or 4 floats when it is a flat tuple or list of Python (or numpy float64) numbers, or a
    flat float array, each in [0, 1]; None otherwise (NaN included): the general check decides and words the
    error.  What a new colour costs: no numpy call for a tuple of numbers (a Material checks four colours)."""
    kind = type(value)
    if kind is np.ndarray:
        if value.ndim != 1 or value.dtype.kind != "f":
            return None
        value = value.tolist()
    elif kind is not tuple and kind is not list:
        return None
    if len(value) != 3 and len(value) != 4:
        return None
    out = []
    for c in value:
        if type(c) is not int and not isinstance(c, float):  # bool, strings, nested lists: the general check
            return None
        x = float(c)
        if not 0.0 <= x <= 1.0:
            return None
        out.append(x)
    return tuple(out)


#: tuples of plain numbers checked as colours -> the colour (equal tuples give equal colours): the defaults and
#: the few colours an application repeats are not checked again
_COLORS: dict[tuple, tuple[float, ...]] = {}


def check_color(owner: str, name: str, value: Any) -> tuple[float, ...]:
    """3 or 4 finite values in [0, 1], returned as given (length kept)."""
    if value.__class__ is tuple:
        try:
            found = _COLORS.get(value)
        except TypeError:  # unhashable members: the general check words the error
            found = None
        if found is not None:
            return found
    plain = _plain_unit_values(value)
    if plain is not None:
        if value.__class__ is tuple:
            if len(_COLORS) >= 1024:
                _COLORS.clear()
            _COLORS[value] = plain
        return plain
    arr = _numbers(owner, name, value)
    if arr.size not in (3, 4):
        raise ValueError(f"{owner}: {name} must be 3 (RGB) or 4 (RGBA) values, got {arr.size}")
    if np.any(arr < 0.0) or np.any(arr > 1.0):
        raise ValueError(f"{owner}: {name} values must be in [0, 1], got {tuple(arr.tolist())}")
    return tuple(float(c) for c in arr)


def check_rgb(owner: str, name: str, value: Any) -> tuple[float, float, float]:
    """A colour stored as RGB; a 4th (alpha) value is accepted and dropped (use ``opacity``)."""
    return check_color(owner, name, value)[:3]  # type: ignore[return-value]


def check_rgba(owner: str, name: str, value: Any) -> tuple[float, float, float, float]:
    """A colour stored as RGBA; alpha defaults to 1."""
    c = check_color(owner, name, value)
    return c if len(c) == 4 else (*c, 1.0)  # type: ignore[return-value]


def optional(check: Check) -> Check:
    """``check`` that also accepts None."""

    def run(owner: str, name: str, value: Any) -> Any:
        return None if value is None else check(owner, name, value)

    return run


def check_number(
    minimum: float | None = None,
    maximum: float | None = None,
    *,
    min_open: bool = False,
    max_open: bool = False,
    integer: bool = False,
) -> Check:
    """A finite number in the given range (open or closed ends)."""

    def run(owner: str, name: str, value: Any) -> float | int:
        x = as_float(owner, name, value)
        if integer:
            if x != int(x):
                raise ValueError(f"{owner}: {name} must be an integer, got {value!r}")
            x = int(x)
        if minimum is not None and (x <= minimum if min_open else x < minimum):
            raise ValueError(f"{owner}: {name} must be {'>' if min_open else '>='} {minimum}, got {value!r}")
        if maximum is not None and (x >= maximum if max_open else x > maximum):
            raise ValueError(f"{owner}: {name} must be {'<' if max_open else '<='} {maximum}, got {value!r}")
        return x

    return run


def check_choice(*choices: str) -> Check:
    """One of the given strings."""

    def run(owner: str, name: str, value: Any) -> str:
        if value not in choices:
            raise ValueError(f"{owner}: {name} must be one of {', '.join(map(repr, choices))}; got {value!r}")
        return value

    return run


def check_vector(size: int = 3) -> Check:
    """``size`` finite numbers as a tuple of floats."""

    def run(owner: str, name: str, value: Any) -> tuple[float, ...]:
        arr = _numbers(owner, name, value)
        if arr.size != size:
            raise ValueError(f"{owner}: {name} must be {size} numbers, got {arr.size}")
        return tuple(float(c) for c in arr)

    return run


def check_direction(owner: str, name: str, value: Any) -> tuple[float, float, float]:
    """A non-zero 3-vector, normalised."""
    arr = np.asarray(check_vector(3)(owner, name, value))
    n = float(np.linalg.norm(arr))
    if n == 0.0:
        raise ValueError(f"{owner}: {name} must not be the zero vector")
    return unit_tuple(arr, n)


def unit_tuple(arr: np.ndarray, norm: float) -> tuple[float, ...]:
    """``arr / norm`` as floats; an already unit vector is kept bit for bit (stable round trips)."""
    if abs(norm - 1.0) > 4.0 * np.finfo(np.float64).eps:
        arr = arr / norm
    return tuple(float(c) for c in arr)


def check_bool(owner: str, name: str, value: Any) -> bool:
    """True or False (numpy booleans accepted)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ValueError(f"{owner}: {name} must be True or False, got {value!r}")


def as_vector(value: Sequence[float]) -> np.ndarray:
    """A float64 array of a stored tuple (helper for methods)."""
    return np.asarray(value, dtype=np.float64)
