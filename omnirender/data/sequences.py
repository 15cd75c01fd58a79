"""Data sequences: the VRS paper's *data iterators*, backed by numpy.

A shape's per-vertex data (coordinates, normals, colours, indices) is often
regular: a constant colour, a vertex list replicated per face, a strip repeated,
a selection through an index list, several arrays one after the other. The
sequences in this module describe such data *without building it*: a shape can
share another shape's array, or generate its data from a few parameters.

Every sequence is

* a Python iterable with ``len()`` and ``seq[i]`` (negative ``i`` allowed), for
  code that walks the data element by element, and
* able to build the whole sequence at once with vectorised numpy through
  ``.array()`` (a view of the source where possible; ``Array(a).array()`` is
  ``a`` itself), for painters that upload whole buffers.

Elements are scalars or vectors: over an ``(N, 3)`` array, element ``i`` is a
row of length 3 and ``.shape`` (the element shape) is ``(3,)``. Sources may be
other sequences, numpy arrays or array-likes; a Python string is a sequence of
its characters. Sequences are immutable: their parameters cannot change after
construction, so lengths computed at construction stay valid.

The arrays returned by ``.array()`` may share memory with the sources (or be
read-only broadcast views, for ``Constant``): treat them as read-only.

This module imports nothing from the rest of omnirender.
"""

from __future__ import annotations

import bisect
import operator
from abc import ABC, abstractmethod
from collections.abc import Iterator
from itertools import chain, repeat
from typing import Any

import numpy as np

__all__ = [
    "Array",
    "Composite",
    "Constant",
    "Indexed",
    "Repeat",
    "Replicate",
    "Sequence",
    "Skip",
    "as_array",
]


# --------------------------------------------------------------------------
# helpers


def _convert(x: Any, where: str) -> np.ndarray:
    """Turn an array-like into an ndarray; ``where`` names it in errors."""
    if isinstance(x, Sequence):
        return x.array()
    if isinstance(x, np.ndarray):
        return x
    if isinstance(x, str):
        # A string is the sequence of its characters.
        return np.array(list(x), dtype="<U1")
    try:
        a = np.asarray(x)
    except (ValueError, TypeError):
        raise ValueError(
            f"{where} is not a regular array: its rows have different lengths or mix numbers with other "
            "things; give every element the same shape"
        ) from None
    if a.dtype == object:
        raise ValueError(
            f"{where} is not a regular array of numbers or strings (ragged "
            "vectors or mixed element types?); give every element the same "
            "shape"
        )
    return a


def as_array(x: Any, dtype: Any = None, *, name: str = "data") -> np.ndarray:
    """Return ``x`` as an ndarray: a sequence's ``.array()``, an ndarray
    unchanged, an array-like converted (a string becomes its characters).

    With ``dtype`` the result is converted (without copying when it already
    has that dtype). ``name`` names ``x`` in error messages, e.g.
    ``as_array(vertices, float, name="TriangleSet: vertices")``.
    Ragged input and failed conversions raise ValueError.
    """
    a = _convert(x, name)
    if dtype is not None:
        try:
            a = a.astype(dtype, copy=False)
        except (ValueError, TypeError) as exc:
            raise ValueError(f"{name} cannot be converted to {np.dtype(dtype)}: {exc}") from None
    return a


def _as_source(x: Any, where: str) -> Sequence:
    """Wrap ``x`` as a Sequence (sequences are returned as they are)."""
    if isinstance(x, Sequence):
        return x
    arr = Array.__new__(Array)
    arr._init(_convert(x, where), where)
    return arr


def _count(owner: str, name: str, value: Any, minimum: int = 0) -> int:
    """Validate an integer parameter >= ``minimum``."""
    if isinstance(value, (bool, np.bool_)):
        # ValueError, like every other invalid parameter of a sequence.
        raise ValueError(  # noqa: TRY004
            f"{owner}: {name} must be an integer, got {value!r}"
        )
    try:
        n = operator.index(value)
    except TypeError:
        raise ValueError(f"{owner}: {name} must be an integer, got {value!r}") from None
    if n < minimum:
        raise ValueError(f"{owner}: {name} must be >= {minimum}, got {n}")
    return n


def _describe(seq: Sequence) -> str:
    return f"len={len(seq)}, shape={seq.shape}, dtype={seq.dtype}"


# --------------------------------------------------------------------------
# base class


class Sequence(ABC):
    """Abstract base of all data sequences.

    Subclasses set ``_length``, ``_shape`` (element shape) and ``_dtype`` in
    their constructor and implement ``_item`` (element at a normalised
    index), ``array`` and, for speed, ``__iter__``.
    """

    __slots__ = ("_dtype", "_length", "_shape")

    _length: int
    _shape: tuple[int, ...]
    _dtype: np.dtype

    def __len__(self) -> int:
        return self._length

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of one element: ``()`` for scalars, ``(3,)`` for 3-vectors."""
        return self._shape

    @property
    def dtype(self) -> np.dtype:
        """numpy dtype of the elements (and of ``.array()``)."""
        return self._dtype

    def __getitem__(self, index: Any) -> Any:
        try:
            i = operator.index(index)
        except TypeError:
            raise TypeError(f"{type(self).__name__} indices must be integers, not {type(index).__name__}") from None
        n = self._length
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError(f"{type(self).__name__} index {index} out of range for length {n}")
        return self._item(i)

    def __iter__(self) -> Iterator[Any]:
        item = self._item
        return (item(i) for i in range(self._length))

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        a = self.array()
        if dtype is not None:
            a = a.astype(dtype, copy=False)
        if copy:
            a = a.copy()
        return a

    @abstractmethod
    def _item(self, i: int) -> Any:
        """Element ``i``, with ``0 <= i < len(self)`` already checked."""

    @abstractmethod
    def array(self) -> np.ndarray:
        """The whole sequence as an ndarray of shape ``(len,) + shape``."""


# --------------------------------------------------------------------------
# sequences


class Array(Sequence):
    """An ndarray (or array-like) seen as a sequence of its rows.

    The leaf of every sequence tree: ``Array(a).array()`` returns ``a``
    itself, so a shape holding an ``Array`` shares the caller's data.
    """

    __slots__ = ("_data",)

    def __init__(self, data: Any) -> None:
        self._init(_convert(data, "Array: data"), "Array: data")

    def _init(self, a: np.ndarray, where: str) -> None:
        if a.ndim == 0:
            raise ValueError(f"{where} must be a sequence of elements (at least 1-D), got a scalar {a!r}")
        self._data = a
        self._length = a.shape[0]
        self._shape = a.shape[1:]
        self._dtype = a.dtype

    def _item(self, i: int) -> Any:
        return self._data[i]

    def __iter__(self) -> Iterator[Any]:
        return iter(self._data)

    def array(self) -> np.ndarray:
        return self._data

    def __repr__(self) -> str:
        return f"Array({_describe(self)})"


class Constant(Sequence):
    """``count`` times the same ``value``: a single colour or normal for all
    vertices, stored once.

    ``.array()`` is a read-only broadcast view, no memory per element.
    """

    __slots__ = ("_value",)

    def __init__(self, value: Any, count: int) -> None:
        if isinstance(value, str):
            v = np.array(value)  # one string element, not its characters
        else:
            v = np.array(_convert(value, "Constant: value"))  # private copy
        v.flags.writeable = False
        self._value = v
        self._length = _count("Constant", "count", count)
        self._shape = v.shape
        self._dtype = v.dtype

    @property
    def value(self) -> np.ndarray:
        """The repeated element (read-only)."""
        return self._value

    def _item(self, i: int) -> Any:
        return self._value[()]

    def __iter__(self) -> Iterator[Any]:
        return repeat(self._value[()], self._length)

    def array(self) -> np.ndarray:
        return np.broadcast_to(self._value, (self._length, *self._shape))

    def __repr__(self) -> str:
        return f"Constant({self._value!r}, count={self._length})"


class Replicate(Sequence):
    """Each element of ``source`` repeated ``times`` times in place:
    ``Replicate("abcd", 3)`` is ``"aaabbbcccddd"``.

    Typical use: one colour or normal per face expanded to its vertices.
    """

    __slots__ = ("_source", "_times")

    def __init__(self, source: Any, times: int) -> None:
        self._source = _as_source(source, "Replicate: source")
        self._times = _count("Replicate", "times", times)
        self._length = len(self._source) * self._times
        self._shape = self._source.shape
        self._dtype = self._source.dtype

    @property
    def source(self) -> Sequence:
        return self._source

    @property
    def times(self) -> int:
        return self._times

    def _item(self, i: int) -> Any:
        return self._source._item(i // self._times)

    def __iter__(self) -> Iterator[Any]:
        t = self._times
        return chain.from_iterable(repeat(x, t) for x in self._source)

    def array(self) -> np.ndarray:
        a = self._source.array()
        if self._times == 1:
            return a
        return np.repeat(a, self._times, axis=0)

    def __repr__(self) -> str:
        return f"Replicate({self._source!r}, times={self._times})"


class Repeat(Sequence):
    """The slice ``[start, stop)`` of ``source`` repeated ``times`` times:
    ``Repeat("abcde", 1, 4, 4)`` is ``"bcdbcdbcdbcd"``.

    Typical use: the same pattern (a strip, a profile) used again and again.
    ``stop=None`` means the end of the source.
    """

    __slots__ = ("_source", "_start", "_stop", "_times")

    def __init__(self, source: Any, start: int = 0, stop: int | None = None, times: int = 1) -> None:
        src = _as_source(source, "Repeat: source")
        n = len(src)
        start = _count("Repeat", "start", start)
        stop = n if stop is None else _count("Repeat", "stop", stop)
        if stop > n:
            raise ValueError(f"Repeat: stop = {stop} is out of range for a source of length {n}")
        if start > stop:
            raise ValueError(f"Repeat: start = {start} must not exceed stop = {stop}")
        self._source = src
        self._start = start
        self._stop = stop
        self._times = _count("Repeat", "times", times)
        self._length = (stop - start) * self._times
        self._shape = src.shape
        self._dtype = src.dtype

    @property
    def source(self) -> Sequence:
        return self._source

    @property
    def start(self) -> int:
        return self._start

    @property
    def stop(self) -> int:
        return self._stop

    @property
    def times(self) -> int:
        return self._times

    def _item(self, i: int) -> Any:
        return self._source._item(self._start + i % (self._stop - self._start))

    def __iter__(self) -> Iterator[Any]:
        src, start, stop = self._source, self._start, self._stop
        if start == 0 and stop == len(src):
            return chain.from_iterable(src for _ in range(self._times))
        item = src._item
        return (item(j) for _ in range(self._times) for j in range(start, stop))

    def array(self) -> np.ndarray:
        part = self._source.array()[self._start : self._stop]
        if self._times == 1:
            return part
        return np.tile(part, (self._times,) + (1,) * (part.ndim - 1))

    def __repr__(self) -> str:
        return f"Repeat({self._source!r}, start={self._start}, stop={self._stop}, times={self._times})"


class Skip(Sequence):
    """``source`` without every ``every``-th element (1-based positions
    ``every``, ``2*every``, ...): ``Skip("abcdefghij", 3)`` is ``"abdeghj"``.

    Typical use: dropping the closing vertex of each ring or strip in a
    flattened list. ``every == 1`` drops everything.
    """

    __slots__ = ("_every", "_source")

    def __init__(self, source: Any, every: int) -> None:
        self._source = _as_source(source, "Skip: source")
        self._every = _count("Skip", "every", every, minimum=1)
        n = len(self._source)
        self._length = n - n // self._every
        self._shape = self._source.shape
        self._dtype = self._source.dtype

    @property
    def source(self) -> Sequence:
        return self._source

    @property
    def every(self) -> int:
        return self._every

    def _item(self, i: int) -> Any:
        # every == 1 has length 0, so _item is never called for it.
        return self._source._item(i + i // (self._every - 1))

    def __iter__(self) -> Iterator[Any]:
        e = self._every
        return (x for k, x in enumerate(self._source, 1) if k % e)

    def array(self) -> np.ndarray:
        a = self._source.array()
        e = self._every
        if e > a.shape[0]:
            return a
        return np.delete(a, np.s_[e - 1 :: e], axis=0)

    def __repr__(self) -> str:
        return f"Skip({self._source!r}, every={self._every})"


class Indexed(Sequence):
    """The elements of ``source`` picked by ``indices`` (0-based):
    ``Indexed([2, 0, 0], "abc")`` is ``"caa"``.

    Typical use: vertices shared between faces, addressed through an index
    list. ``indices`` may itself be a sequence (e.g. a ``Repeat``). Indices
    are validated (and copied) at construction.
    """

    __slots__ = ("_indices", "_source")

    def __init__(self, indices: Any, source: Any) -> None:
        src = _as_source(source, "Indexed: source")
        idx = _convert(indices, "Indexed: indices")
        if idx.ndim != 1:
            raise ValueError(f"Indexed: indices must be 1-D, got an array of shape {idx.shape}")
        if idx.size == 0:
            idx = np.empty(0, dtype=np.intp)
        elif idx.dtype.kind not in "iu":
            raise ValueError(f"Indexed: indices must be integers, got dtype {idx.dtype}")
        n = len(src)
        bad = np.flatnonzero((idx < 0) | (idx >= n))
        if bad.size:
            k = int(bad[0])
            raise ValueError(f"Indexed: indices[{k}] = {int(idx[k])} is out of range for a source of length {n}")
        idx = idx.astype(np.intp)  # private copy: later edits cannot invalidate
        idx.flags.writeable = False
        self._indices = idx
        self._source = src
        self._length = idx.shape[0]
        self._shape = src.shape
        self._dtype = src.dtype

    @property
    def indices(self) -> np.ndarray:
        """The validated indices (read-only intp array)."""
        return self._indices

    @property
    def source(self) -> Sequence:
        return self._source

    def _item(self, i: int) -> Any:
        return self._source._item(int(self._indices[i]))

    def __iter__(self) -> Iterator[Any]:
        item = self._source._item
        return (item(i) for i in self._indices.tolist())

    def array(self) -> np.ndarray:
        return self._source.array()[self._indices]

    def __repr__(self) -> str:
        return f"Indexed(<{self._length} indices>, {self._source!r})"


class Composite(Sequence):
    """Several sequences one after the other: ``Composite("ab", "cde")`` is
    ``"abcde"``.

    Typical use: a shape's vertices gathered from several sources without
    concatenating them by hand. All sources must have the same element shape
    and compatible dtypes.
    """

    __slots__ = ("_offsets", "_sources")

    def __init__(self, *sources: Any) -> None:
        if not sources:
            raise ValueError("Composite: sources must not be empty; give at least one")
        srcs = tuple(_as_source(s, f"Composite: sources[{k}]") for k, s in enumerate(sources))
        first = srcs[0]
        for k, s in enumerate(srcs[1:], 1):
            if s.shape != first.shape:
                raise ValueError(
                    f"Composite: sources[{k}] has element shape {s.shape}, expected {first.shape} like sources[0]"
                )
            if (s.dtype.kind in "US") != (first.dtype.kind in "US"):
                raise ValueError(
                    f"Composite: sources[{k}] has dtype {s.dtype}, incompatible with dtype {first.dtype} of sources[0]"
                )
        try:
            dtype = np.result_type(*(s.dtype for s in srcs))
        except TypeError as exc:
            raise ValueError(f"Composite: sources have incompatible dtypes: {exc}") from None
        offsets = [0]
        for s in srcs:
            offsets.append(offsets[-1] + len(s))
        self._sources = srcs
        self._offsets = offsets
        self._length = offsets[-1]
        self._shape = first.shape
        self._dtype = dtype

    @property
    def sources(self) -> tuple[Sequence, ...]:
        return self._sources

    def _item(self, i: int) -> Any:
        k = bisect.bisect_right(self._offsets, i) - 1
        return self._sources[k]._item(i - self._offsets[k])

    def __iter__(self) -> Iterator[Any]:
        return chain.from_iterable(self._sources)

    def array(self) -> np.ndarray:
        if len(self._sources) == 1:
            return self._sources[0].array()
        return np.concatenate([s.array() for s in self._sources], axis=0, dtype=self._dtype)

    def __repr__(self) -> str:
        return "Composite(" + ", ".join(repr(s) for s in self._sources) + ")"
