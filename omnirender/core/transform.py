"""Modelling transforms: mono attributes of the shared category ``Transform``.

The context entry of the ``Transform`` category is the *accumulated* model
matrix: pushing composes with the current matrix, popping restores it.  The
convention is column vectors and pre-multiplication (``p' = M @ p``), float64.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from itertools import chain, compress
from operator import attrgetter
from typing import Any

import numpy as np

from .component import (  # _PENDING: the list note_later appends to (Translation's setter appends inline)
    _JOURNALS,
    _PENDING,
    PENDING_LIMIT,
    MonoAttribute,
    RenderingComponent,
    _Owners,
    flush_changes,
    note_later,
)
from .limits import MAX_MAGNITUDE, MIN_MAGNITUDE, as_float, check_array_magnitude

__all__ = [
    "Transform",
    "Matrix",
    "Translation",
    "Rotation",
    "Scaling",
    "TranslationArray",
    "finite_vector",
    "plain_triple",
    "axis_angle_matrix",
]


def finite_vector(owner: str, name: str, value, size: int) -> np.ndarray:
    """``value`` as a float64 vector of ``size`` finite numbers within the magnitude limit, or ValueError naming it."""
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{owner}: {name} must be {size} numbers, got {value!r:.60}")
    try:
        arr = np.array(value, dtype=np.float64).reshape(-1)
    except OverflowError:
        raise ValueError(
            f"{owner}: {name} must be {size} numbers of at most {MAX_MAGNITUDE:.0e}, got {value!r:.60}"
        ) from None
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: {name} must be {size} numbers, got {value!r:.60}") from None
    if arr.shape != (size,):
        raise ValueError(f"{owner}: {name} must be {size} numbers, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{owner}: {name} must be finite, got {value!r}")
    check_array_magnitude(owner, name, arr)
    return arr


#: Scalar types taken as they are by the setters' fast path (bool is left to the validating path).
_SCALARS = frozenset({float, int, np.float64, np.float32, np.float16, np.int64, np.int32, np.int16, np.int8,
                      np.uint64, np.uint32, np.uint16, np.uint8})  # fmt: skip
_REAL_KINDS = frozenset("fiu")


def plain_triple(value: object) -> tuple[float, float, float] | None:
    """``value`` as three Python floats when it plainly is three finite numbers within the magnitude limit.

    The setters' fast path (a simulation loop assigns thousands per frame):
    a tuple or list of three Python or numpy numbers, or a numpy array of
    shape (3,) of a real dtype.  Anything else, or a value out of the limits,
    gives None and the caller validates it the slow way (:func:`finite_vector`),
    which also makes the error message.
    """
    cls = value.__class__
    if cls is tuple or cls is list:
        if len(value) != 3:  # type: ignore[arg-type]
            return None
        x, y, z = value  # type: ignore[misc]
        if x.__class__ is not float or y.__class__ is not float or z.__class__ is not float:
            if x.__class__ not in _SCALARS or y.__class__ not in _SCALARS or z.__class__ not in _SCALARS:
                return None
            try:
                x, y, z = float(x), float(y), float(z)
            except OverflowError:  # an integer beyond float's range
                return None
    elif cls is np.ndarray:
        if value.dtype.kind not in _REAL_KINDS:  # type: ignore[attr-defined]
            return None
        try:
            x, y, z = value.tolist()  # type: ignore[attr-defined]  (shape (3,); another shape fails or nests)
        except (TypeError, ValueError):
            return None
        if x.__class__ is not float:  # an integer array, or nested lists of another shape
            if x.__class__ is not int:
                return None
            x, y, z = float(x), float(y), float(z)
    else:
        return None
    # comparisons are False for NaN: a non-finite number takes the validating path
    if -_MAX <= x <= _MAX and -_MAX <= y <= _MAX and -_MAX <= z <= _MAX:
        return (x, y, z)
    return None


_MAX = MAX_MAGNITUDE
_MAX2 = MAX_MAGNITUDE * MAX_MAGNITUDE
_NDARRAY = np.ndarray


_DIAGONAL = np.arange(4)


def _named(transform: RenderingComponent) -> str:
    """``Translation``, or ``Translation (in node /scene/b3)`` once a node holds it: how errors name a transform."""
    owners = transform._owners
    path = getattr(owners[0], "path", None) if owners else None
    return type(transform).__name__ + (f" (in node {path})" if path else "")


class Transform(MonoAttribute):
    """Base of all modelling transforms; subclasses share its category.

    The matrix is made when somebody asks for it (``matrix``), not when a
    parameter is set: a simulation that moves thousands of transforms per
    frame pays for validation and bookkeeping only, and each matrix is built
    once, when a renderer reads it.
    """

    __slots__ = ("_matrix",)
    shares_category = True
    #: The matrix depends only on the transform's parameters (not on the camera, as a Billboard's does).
    static = True

    @property
    def matrix(self) -> np.ndarray:
        """The 4x4 float64 matrix this transform multiplies onto the current one."""
        m = self._matrix
        if m is None:
            m = self._build_matrix()
            m.setflags(write=False)
            object.__setattr__(self, "_matrix", m)
        return m

    def _build_matrix(self) -> np.ndarray:  # pragma: no cover - every static subclass defines it
        raise NotImplementedError(f"{type(self).__name__} does not build a matrix")

    @classmethod
    def stack_matrices(cls, transforms: Sequence[Transform]) -> np.ndarray:
        """The (N, 4, 4) matrices of ``transforms`` (all of this class), for renderers that move many at once.

        Subclasses whose matrices follow from a few numbers build the stack
        from them directly (:class:`Translation` does), without making and
        caching one matrix object per transform.
        """
        return np.stack([t.matrix for t in transforms]) if transforms else np.empty((0, 4, 4))

    def touch(self) -> None:
        """Mark the transform changed: its version moves now; its nodes and the journals hear of it when next observed.

        Transforms are what simulations change thousands of per frame: the
        owners' ``touch()`` and the journals' stores are done once for all of
        them, at the next observation (:func:`~omnirender.core.component.note_later`).
        Every reader of a node's version or of a journal sees the change.
        """
        _set_version(self, self._version + 1)
        if _JOURNALS or self._owners:  # (also in no node while a journal lives: the same transforms, the same batch)
            note_later(self)

    def _changed(self) -> None:
        """The parameters changed: forget the matrix (assigning the public parameter touches the owners)."""
        object.__setattr__(self, "_matrix", None)

    def _set_matrix(self, m: np.ndarray) -> None:
        m.setflags(write=False)
        object.__setattr__(self, "_matrix", m)
        self.touch()


class Matrix(Transform):
    """An affine 4x4 matrix (column vectors): invertible linear part, bottom row (0, 0, 0, 1).

    Like ``Scaling`` refusing a zero factor, a matrix that flattens space
    (singular, e.g. all zeros) is refused: normals, picking and every engine's
    inverse transforms need the inverse.  Projective matrices are refused too,
    since not every engine can express them (POV-Ray's ``matrix`` is affine).
    """

    __slots__ = ()

    def __init__(self, matrix: Sequence[Sequence[float]] | np.ndarray) -> None:
        super().__init__()
        if isinstance(matrix, (str, bytes)):
            raise ValueError(f"Matrix: matrix must be 4x4 numbers, got {matrix!r:.60}")
        try:
            m = np.array(matrix, dtype=np.float64)
        except OverflowError:
            raise ValueError(f"Matrix: entries must be at most {MAX_MAGNITUDE:.0e} in magnitude") from None
        except (TypeError, ValueError):
            raise ValueError(
                f"Matrix: matrix must be 4x4 numbers (a nested list or an array), got {matrix!r:.80}"
            ) from None
        if m.shape != (4, 4):
            raise ValueError(f"Matrix: matrix must be 4x4, got shape {m.shape}")
        rows = m.tolist()  # the checks in Python floats: a tenth of numpy's per-call cost for 16 numbers
        (a, b, c, x), (d, e, f, y), (g, h, i, z), last = rows
        values = (a, b, c, x, d, e, f, y, g, h, i, z, *last)
        # (a NaN or an infinity makes the sum not finite: then the checks that name it; a finite sum means
        # every entry is finite, so the largest magnitude decides the bound)
        if not (math.isfinite(sum(values)) and max(map(abs, values)) <= _MAX):
            if not np.all(np.isfinite(m)):
                raise ValueError("Matrix: matrix must be finite")
            check_array_magnitude("Matrix", "matrix", m)
        if not (_rank3(a, b, c, d, e, f, g, h, i) or _invertible(m[:3, :3])):
            raise ValueError(
                "Matrix: the upper-left 3x3 part is singular (it flattens space, e.g. all zeros); give an "
                "invertible matrix (hide a subgraph with a group mask instead of scaling it to nothing)"
            )
        if last != [0.0, 0.0, 0.0, 1.0]:
            raise ValueError(
                f"Matrix: the bottom row must be (0, 0, 0, 1) (an affine transform), got {tuple(last)}; "
                "projective matrices are not supported by every engine"
            )
        # stored without the version bump and journal entry of a change: nothing can have compiled a matrix being
        # made (as a Translation being made; a node's transform replaced per frame tells no journal of it)
        m.setflags(write=False)
        _set_matrix(self, m)

    def parameters(self) -> dict:
        return {"matrix": self._matrix.tolist()}


def _invertible(m3: np.ndarray) -> bool:
    """``np.linalg.matrix_rank(m3) == 3``, without its SVD when the determinant already decides (:func:`_rank3`)."""
    return _rank3(*m3.ravel().tolist()) or bool(np.linalg.matrix_rank(m3) == 3)


def _rank3(a: float, b: float, c: float, d: float, e: float, f: float, g: float, h: float, i: float) -> bool:
    """Whether the 3x3 matrix of rows ``(a, b, c), (d, e, f), (g, h, i)`` surely has rank 3 (False: not known;
    ``np.linalg.matrix_rank`` decides).

    The smallest singular value is at least ``|det| / |m3|_F**2`` and the rank's
    tolerance is ``3 eps`` times the largest, at most ``|m3|_F``: a determinant
    above ``64 eps |m3|_F**3`` (the margin covers its rounding) means rank 3.
    """
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    norm = math.sqrt(a * a + b * b + c * c + d * d + e * e + f * f + g * g + h * h + i * i)
    return abs(det) > 64.0 * _EPS * norm**3


_EPS = float(np.finfo(np.float64).eps)


class Translation(Transform):
    """Move by (x, y, z).

    A translation of an :class:`TranslationArray` views its row: after the
    array's ``touch()`` it reads its offset from the array's snapshot when
    next asked (``offset``, ``matrix``); assigning ``offset`` sets its own
    value until the array's next ``touch()``.
    """

    __slots__ = ("_offset", "_bound", "_row", "_synced", "_matrix_of")
    #: the array binding is not copied or pickled: a copy is an ordinary translation with the current offset
    _transient = {"_bound": lambda: None, "_row": lambda: 0, "_synced": lambda: 0, "_matrix_of": lambda: None}

    def __init__(
        self,
        x: float | Sequence[float] = 0.0,
        y: float = 0.0,
        z: float = 0.0,
        *,
        offset: Sequence[float] | None = None,
    ) -> None:
        super().__init__()
        self._bound = None  # the TranslationArray whose row it views (see there)
        self._matrix = None
        self._matrix_of = None  # the offset object the kept matrix was made from
        self._row = 0
        self._synced = 0  # the array's version its own offset is current for
        # checked and stored without the version bump and journal entry of an assignment: nothing can have
        # compiled a translation being made (a node added per frame pays no move)
        self._offset = _checked_offset(
            self, offset if offset is not None else x if isinstance(x, (Sequence, np.ndarray)) else (x, y, z)
        )

    #: Attributes are stored as they are: ``offset`` is a property that touches itself, and every other slot is
    #: private (a simulation loop's ``t.offset = row`` runs one Python function, not ``__setattr__`` and then
    #: the property; subclasses that add public parameters get the components' ``__setattr__`` back)
    __setattr__ = object.__setattr__

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "__setattr__" not in cls.__dict__:
            cls.__setattr__ = _subclass_setattr  # type: ignore[method-assign,assignment]

    @property
    def offset(self) -> tuple[float, float, float]:
        if self._bound is not None:
            self._sync()
        offset = self._offset
        return offset if offset.__class__ is tuple else tuple(offset)

    @offset.setter
    def offset(self, value: Sequence[float]) -> None:
        # a simulation loop's ``t.offset = row``: a numpy row or three Python floats checked here, inline (the
        # other plain inputs take plain_triple, the rest the validating path, which writes the message)
        if value.__class__ is _NDARRAY:
            try:
                offset = value.tolist()  # shape (3,): three Python numbers; any other shape fails or nests
                x, y, z = offset
            except (TypeError, ValueError):
                x = None
        elif value.__class__ is tuple and len(value) == 3:  # type: ignore[arg-type]
            x, y, z = offset = value  # type: ignore[misc]
        else:
            x = None
        # three Python floats whose squares sum to at most _MAX2 are each within the limit (NaN compares False,
        # an infinity or an overflow gives one: they take the validating path, as a sum above it does); the
        # list that tolist() made is kept as it is (nobody else holds it; ``offset`` reads it as a tuple)
        if x.__class__ is float and y.__class__ is float and z.__class__ is float and x * x + y * y + z * z <= _MAX2:
            self._offset = offset
        else:
            self._offset = _checked_offset(self, value)
        # Transform.touch, inline: a version bump and one list append (the kept matrix is of another offset
        # object now: see matrix)
        self._version += 1
        bound = self._bound
        if bound is not None:  # its own value holds until the array's next touch
            self._synced = bound._version
        # (also without owners while a journal lives: a loop over the same translations gives the same batch
        # after one of them left its node, whose owners are patched, not collected again; the journals asked
        # first: while an engine lives the owner list, elsewhere in memory, is not read, a cache miss a call)
        if _JOURNALS or self._owners:
            _append(self)
            if len(_PENDING) > PENDING_LIMIT:
                flush_changes()

    @property
    def version(self) -> int:
        """Counter bumped on every change: its own assignments, plus its array's touches (TranslationArray)."""
        bound = self._bound
        return self._version if bound is None else self._version + bound._version

    @property
    def matrix(self) -> np.ndarray:
        """The 4x4 float64 matrix (an array's translation takes its row first).

        The matrix is kept with the offset object it was made from: the
        setter stores a new offset tuple and leaves the kept matrix alone.
        """
        if self._bound is not None:
            self._sync()
        m = self._matrix
        offset = self._offset
        if m is None or self._matrix_of is not offset:
            m = self._build_matrix()
            m.setflags(write=False)
            _set_matrix(self, m)
            _set_matrix_of(self, offset)
        return m

    def _sync(self) -> None:
        """A translation of an array touched since its offset was last current takes its row of the snapshot."""
        bound = self._bound
        if self._synced != bound._version:
            _set_offset(self, tuple(bound._offsets[self._row].tolist()))
            _set_matrix(self, None)
            _set_synced(self, bound._version)

    def _bind(self, array: TranslationArray, row: int) -> None:
        _EVER_BOUND[0] = True
        object.__setattr__(self, "_bound", array)
        object.__setattr__(self, "_row", row)
        object.__setattr__(self, "_synced", array._version)

    def _attach(self, owner: Any) -> None:
        super()._attach(owner)
        if self._bound is not None:
            self._bound._owners_changed()

    def _detach(self, owner: Any) -> None:
        super()._detach(owner)
        if self._bound is not None:
            self._bound._owners_changed()

    def __getstate__(self) -> dict[str, Any]:
        if self._bound is not None:
            self._sync()
        return super().__getstate__()

    def _build_matrix(self) -> np.ndarray:
        m = np.eye(4)
        m[:3, 3] = self._offset
        return m

    @classmethod
    def stack_matrices(cls, transforms: Sequence[Transform]) -> np.ndarray:
        out = np.zeros((len(transforms), 4, 4))
        out[:, _DIAGONAL, _DIAGONAL] = 1.0
        if transforms:
            out[:, :3, 3] = Translation.stack_offsets(transforms)  # type: ignore[arg-type]
        return out

    @staticmethod
    def stack_offsets(translations: Sequence[Translation]) -> np.ndarray:
        """The ``(N, 3)`` float64 offsets of ``translations``, read with no Python step per translation."""
        n = len(translations)
        if _EVER_BOUND[0] and any(map(_BOUND, translations)):  # an array's translations take their rows first
            deque(map(Translation._sync, compress(translations, map(_BOUND, translations))), 0)
        flat = chain.from_iterable(map(_OFFSET, translations))  # C-level loops
        return np.fromiter(flat, np.float64, 3 * n).reshape(n, 3)

    def parameters(self) -> dict:
        return {"offset": list(self.offset)}


_OFFSET = attrgetter("_offset")
#: whether a translation was ever bound to an array (until then no translation needs its row read first)
_EVER_BOUND = [False]
_BOUND = attrgetter("_bound")
_set_synced = Translation._synced.__set__  # type: ignore[attr-defined]
_append = _PENDING.append
_SUBCLASS_SETATTR = RenderingComponent.__setattr__


def _subclass_setattr(self: Translation, name: str, value: Any) -> None:
    """``__setattr__`` of a subclass of ``Translation``: ``offset`` touches itself, other public names touch."""
    if name == "offset":
        object.__setattr__(self, name, value)
    else:
        _SUBCLASS_SETATTR(self, name, value)


def _checked_offset(translation: Translation, value: Any) -> tuple[float, float, float]:
    """``value`` as an offset (three Python floats), or the validating path's ValueError naming the translation
    and its node."""
    offset = plain_triple(value)
    if offset is None:
        offset = tuple(float(c) for c in finite_vector(_named(translation), "offset", value, 3))
    return offset  # type: ignore[return-value]


_set_version = RenderingComponent._version.__set__  # type: ignore[attr-defined]
_set_offset = Translation._offset.__set__  # type: ignore[attr-defined]
_set_matrix = Transform._matrix.__set__  # type: ignore[attr-defined]
_set_matrix_of = Translation._matrix_of.__set__  # type: ignore[attr-defined]


def axis_angle_matrix(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """4x4 right-handed rotation by ``angle_rad`` radians about the unit vector ``axis``."""
    x, y, z = axis
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    t = 1.0 - c
    m = np.eye(4)
    m[:3, :3] = [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
    return m


class Rotation(Transform):
    """Rotate by ``angle`` degrees about ``axis`` (right-handed)."""

    __slots__ = ("_angle", "_axis")

    def __init__(self, angle: float, axis: Sequence[float] = (0.0, 0.0, 1.0)) -> None:
        super().__init__()
        self._assign(angle, axis)

    def _assign(self, angle: float, axis: Sequence[float]) -> None:
        a = finite_vector("Rotation", "axis", axis, 3)
        n = float(np.linalg.norm(a))
        if n == 0.0:
            raise ValueError("Rotation: axis must not be the zero vector")
        angle = as_float("Rotation", "angle (degrees)", angle)
        if n != 1.0:
            a = a / n
        object.__setattr__(self, "_angle", angle)
        object.__setattr__(self, "_axis", tuple(float(c) for c in a))
        self._changed()

    def _build_matrix(self) -> np.ndarray:
        return axis_angle_matrix(np.asarray(self._axis), math.radians(self._angle))

    @classmethod
    def stack_matrices(cls, transforms: Sequence[Transform]) -> np.ndarray:
        """Rodrigues' formula for all of them at once: ``cos I + sin [a]x + (1 - cos) a a^T``."""
        out = np.zeros((len(transforms), 4, 4))
        out[:, 3, 3] = 1.0
        if not transforms:
            return out
        a = np.array([t._axis for t in transforms])  # type: ignore[attr-defined]
        angle = np.radians([t._angle for t in transforms])  # type: ignore[attr-defined]
        c, s = np.cos(angle)[:, None, None], np.sin(angle)[:, None, None]
        x, y, z = a[:, 0], a[:, 1], a[:, 2]
        zero = np.zeros(len(a))
        cross = np.stack([zero, -z, y, z, zero, -x, -y, x, zero], axis=1).reshape(-1, 3, 3)
        out[:, :3, :3] = c * np.eye(3) + s * cross + (1.0 - c) * (a[:, :, None] * a[:, None, :])
        return out

    @property
    def angle(self) -> float:
        """Angle in degrees."""
        return self._angle

    @angle.setter
    def angle(self, value: float) -> None:
        if value.__class__ is not float and value.__class__ in _SCALARS:  # a numpy number, an int
            value = float(value)
        if value.__class__ is float and -MAX_MAGNITUDE <= value <= MAX_MAGNITUDE:  # a simulation loop's case
            object.__setattr__(self, "_angle", value)
            _set_matrix(self, None)
        else:
            self._assign(value, self._axis)

    @property
    def axis(self) -> tuple[float, float, float]:
        """Unit rotation axis."""
        return self._axis

    @axis.setter
    def axis(self, value: Sequence[float]) -> None:
        self._assign(self._angle, value)

    def parameters(self) -> dict:
        return {"angle": self._angle, "axis": list(self._axis)}

    @classmethod
    def from_quaternion(cls, w: float, x: float, y: float, z: float) -> Rotation:
        """The rotation of the unit quaternion w + xi + yj + zk (normalised first)."""
        q = finite_vector("Rotation", "quaternion", (w, x, y, z), 4)
        n = float(np.linalg.norm(q))
        if n == 0.0:
            raise ValueError("Rotation: quaternion must not be zero")
        w, x, y, z = q / n
        angle = 2.0 * math.degrees(math.acos(max(-1.0, min(1.0, w))))
        s = math.sqrt(max(0.0, 1.0 - w * w))
        axis = (0.0, 0.0, 1.0) if s < 1e-12 else (x / s, y / s, z / s)
        return cls(angle, axis)

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """(w, x, y, z) of this rotation."""
        h = math.radians(self.angle) / 2.0
        s = math.sin(h)
        return (math.cos(h), self.axis[0] * s, self.axis[1] * s, self.axis[2] * s)


class Scaling(Transform):
    """Scale by (sx, sy, sz); a single number scales uniformly."""

    __slots__ = ("_factors",)

    def __init__(
        self,
        sx: float | Sequence[float] = 1.0,
        sy: float | None = None,
        sz: float | None = None,
        *,
        factors: Sequence[float] | None = None,
    ) -> None:
        super().__init__()
        if factors is not None:
            self.factors = factors
        elif isinstance(sx, (Sequence, np.ndarray)):
            self.factors = sx
        elif sy is None and sz is None:
            self.factors = (sx, sx, sx)
        else:
            self.factors = (sx, 1.0 if sy is None else sy, 1.0 if sz is None else sz)

    @property
    def factors(self) -> tuple[float, float, float]:
        return self._factors

    @factors.setter
    def factors(self, value: Sequence[float]) -> None:
        plain = plain_triple(value)  # a simulation loop's case: three numbers, a numpy row
        if plain is not None:
            x, y, z = plain
            if MIN_MAGNITUDE <= abs(x) and MIN_MAGNITUDE <= abs(y) and MIN_MAGNITUDE <= abs(z):
                object.__setattr__(self, "_factors", plain)
                _set_matrix(self, None)
                return
        who = _named(self)
        v = finite_vector(who, "factors", value, 3)
        if np.any(v == 0.0):
            raise ValueError(f"{who}: factors must be non-zero, got {tuple(float(c) for c in v)}")
        if np.any(np.abs(v) < MIN_MAGNITUDE):
            raise ValueError(
                f"{who}: factors must be at least {MIN_MAGNITUDE:.0e} in magnitude (their inverse must stay "
                f"below {MAX_MAGNITUDE:.0e}), got {tuple(float(c) for c in v)}"
            )
        object.__setattr__(self, "_factors", tuple(float(c) for c in v))
        self._changed()

    def _build_matrix(self) -> np.ndarray:
        return np.diag([*self._factors, 1.0])

    @classmethod
    def stack_matrices(cls, transforms: Sequence[Transform]) -> np.ndarray:
        out = np.zeros((len(transforms), 4, 4))
        out[:, 3, 3] = 1.0
        if transforms:
            out[:, _DIAGONAL[:3], _DIAGONAL[:3]] = [t._factors for t in transforms]  # type: ignore[attr-defined]
        return out

    def parameters(self) -> dict:
        return {"factors": list(self.factors)}


class TranslationArray(Sequence[Translation]):
    """Many :class:`Translation` attributes whose offsets are the rows of one ``(N, 3)`` array you own.

    The bulk way to move thousands of nodes: the array is held *without
    copying* (as :class:`~omnirender.shapes.InstanceSet` holds its arrays);
    ``moves[i]`` is an ordinary ``om.Translation`` that you add to node ``i``.
    Write the array in place and call :meth:`touch`: the whole array is
    validated at once (finite, within the magnitude limit) and kept as a
    snapshot, and every translation changes exactly as if its ``offset`` had
    been assigned its row, so every engine (GL, POV-Ray, Mitsuba, Radiance,
    picking, bounds) sees the same scene.  Between two :meth:`touch` calls
    the translations keep the offsets of the last one; assigning one's
    ``offset`` sets it until the next :meth:`touch`.

    A touch writes no translation: each views its row of the snapshot and
    takes it when next read (``offset``, ``matrix``) and counts the array's
    touches in its ``version``; their nodes hear of the change at the next
    observation, with the change journals, which record the array once (an
    engine that knows it applies the rows at once).
    """

    __slots__ = ("_array", "_translations", "_offsets", "_version", "_owner_list")

    def __init__(self, offsets: np.ndarray | Sequence[Sequence[float]]) -> None:
        a = self._checked(offsets if isinstance(offsets, np.ndarray) else np.asarray(offsets, dtype=np.float64))
        self._array = offsets if isinstance(offsets, np.ndarray) else a
        self._translations = [Translation(offset=row) for row in a.tolist()]
        self._offsets = a.copy()
        self._offsets.setflags(write=False)
        self._version = 0
        self._owner_list: list[Any] | None = None
        for i, t in enumerate(self._translations):
            t._bind(self, i)

    @property
    def array(self) -> np.ndarray:
        """The bound array (the application's own object when it was a numpy array)."""
        return self._array

    @property
    def version(self) -> int:
        """Counter bumped by every :meth:`touch`."""
        return self._version

    @property
    def owners(self) -> tuple[Any, ...]:
        """The nodes that hold its translations (what a change journal's reader asks of what changed)."""
        return tuple(self._owners)

    @property
    def _owners(self) -> list[Any]:
        # what the changes noted for later touch (core.component.flush_changes): kept until a translation is
        # added to a node or removed from one
        found = self._owner_list
        if found is None:
            found = self._owner_list = _Owners(chain.from_iterable(filter(None, map(_OWNERS_OF, self._translations))))
        return found

    def _owners_changed(self) -> None:
        self._owner_list = None

    def __len__(self) -> int:
        return len(self._translations)

    def __getitem__(self, index):  # type: ignore[override]
        return self._translations[index]

    def __iter__(self):
        return iter(self._translations)

    @property
    def offsets(self) -> np.ndarray:
        """The offsets as of the last :meth:`touch` (or construction): a read-only ``(N, 3)`` float64 copy.

        Engines that apply the whole array at once read it (the GL engine
        writes it into its batch rows in one numpy operation per batch).
        """
        return self._offsets

    def touch(self) -> None:
        """Every translation takes its row of the array (written in place since): one validation and one copy.

        Each translation's version moves at once (it counts its array's
        touches) and its nodes' versions at the next observation, as if its
        ``offset`` had been assigned; it reads its row when next asked.  The engines' change journals record the
        array once (:func:`~omnirender.core.component.note_later`), so an
        engine that knows it applies the rows at once.
        """
        a = self._checked(self._array)
        offsets = a.copy()
        offsets.setflags(write=False)
        self._offsets = offsets
        self._version += 1  # every translation's offset is stale now (Translation._sync) and its version moved
        note_later(self)

    def __getstate__(self) -> dict[str, Any]:
        return {"array": self._array, "translations": self._translations, "offsets": self._offsets,
                "version": self._version}  # fmt: skip

    def __setstate__(self, state: dict[str, Any]) -> None:
        self._array = state["array"]
        self._translations = state["translations"]
        self._offsets = state["offsets"]
        self._version = state["version"]
        self._owner_list = None
        for i, t in enumerate(self._translations):  # pickled with their current offsets: current for this version
            t._bind(self, i)

    def _checked(self, offsets: np.ndarray) -> np.ndarray:
        a = np.asarray(offsets, dtype=np.float64) if offsets.dtype != np.float64 else offsets
        bound = hasattr(self, "_translations")
        n = len(self._translations) if bound else len(a)
        if a.ndim != 2 or a.shape[1] != 3 or len(a) != n:
            rows = f" of {n} rows" if bound else ""
            raise ValueError(
                f"TranslationArray: offsets must be an (N, 3) array{rows}, got shape {a.shape}; write the array in "
                "place (positions[:] = ...) rather than replacing it"
            )
        bad = ~(np.abs(a) <= MAX_MAGNITUDE).all(axis=1)  # NaN compares False
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            where = ""
            if hasattr(self, "_translations"):
                owners = self._translations[i].owners
                where = f" (in node {owners[0].path})" if owners else ""
            raise ValueError(
                f"TranslationArray: offset of translation {i} is {tuple(a[i].tolist())}{where}; offsets must be "
                f"finite and at most {MAX_MAGNITUDE:.0e} in magnitude"
            )
        return a


_OWNERS_OF = attrgetter("_owners")
