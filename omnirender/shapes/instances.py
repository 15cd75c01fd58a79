"""``InstanceSet``: one shape drawn many times, placed and coloured by the application's own arrays.

The data-iterator idea of the VRS paper applied to instancing: the per-instance
transforms (``(N, 4, 4)`` matrices or ``(N, 3)`` positions), colours, scales
and visibility are numpy arrays (or ``om.data`` sequences) the instance set
holds *without copying*.  A simulation writes its array in place and calls
``instances.touch()``; the next frame reads the array once (the GL engine
uploads it as one instanced draw).  ``touch("transforms")`` says that only
the named arrays were written, so an engine need not look at the others
(:meth:`InstanceSet.written_at`).  Assigning a new array (of any length)
works too.

Every engine sees N shapes: the default simplifier gives one node per visible
instance (its matrix, colour and an ``InstanceId``), so POV-Ray, Mitsuba,
Radiance, exporters, bounds and collisions need nothing special, and picking
reports the instance's index (``Hit.instance``).  Arrays are checked when an
engine reads them; a bad row is named by its index.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.component import PolyAttribute, Shape
from ..core.engine import Engine
from ..core.handler import ShapeSimplifier, default_for

__all__ = ["InstanceSet", "InstanceId"]


class InstanceId(PolyAttribute):
    """Which instance of an ``InstanceSet`` the shapes that follow are (set by its simplifier; picking reports it)."""

    __slots__ = ("index",)

    def __init__(self, index: int) -> None:
        super().__init__()
        object.__setattr__(self, "index", int(index))


def _array(value: Any) -> Any:
    """The array behind ``value``: numpy arrays as they are (no copy), sequences through ``.array()``."""
    if value is None:
        return None
    if hasattr(value, "array") and not isinstance(value, np.ndarray):
        return value.array()
    return value


class InstanceSet(Shape):
    """``shape`` drawn once per row of ``transforms``.

    ``transforms``: ``(N, 4, 4)`` model matrices (column vectors) or ``(N, 3)``
    positions; ``colors``: ``(N, 3|4)`` RGB(A) display values in [0, 1] (they
    replace the colour of the material in effect, as ``om.Color`` does), or
    None; ``scales``: ``(N,)`` uniform or ``(N, 3)`` per-axis scale factors
    applied before the transform, or None; ``visible``: ``(N,)`` booleans, or
    None for all.  ``shape`` may be any shape (a ``Box``, a ``TriangleSet``,
    a ``MeshFile``...).
    """

    __slots__ = ("_shape", "_transforms", "_colors", "_scales", "_visible", "_written", "_touched_at")
    #: which touch wrote which array: not pickled (an unpickled set counts every array as written at its version)
    _transient = {"_written": lambda: None, "_touched_at": lambda: -1}
    #: the arrays ``touch`` may name
    ARRAYS = ("transforms", "colors", "scales", "visible")

    def __init__(
        self,
        shape: Shape,
        transforms: Any,
        colors: Any = None,
        scales: Any = None,
        visible: Any = None,
    ) -> None:
        super().__init__()
        if not isinstance(shape, Shape) or isinstance(shape, InstanceSet):
            raise ValueError(
                f"InstanceSet: shape must be a shape (om.Box(), om.TriangleSet(...)), not {type(shape).__name__}"
            )
        object.__setattr__(self, "_shape", shape)
        object.__setattr__(self, "_written", None)
        object.__setattr__(self, "_touched_at", -1)
        for name, value in (("transforms", transforms), ("colors", colors), ("scales", scales), ("visible", visible)):
            object.__setattr__(self, "_" + name, value)
        self.validate()
        shape.attach_owner(self)  # a changed base shape changes the instance set (its nodes recompile)

    # -- parameters -------------------------------------------------------------------
    @property
    def shape(self) -> Shape:
        return self._shape

    @property
    def transforms(self) -> Any:
        """The transforms array (the application's own object)."""
        return self._transforms

    @transforms.setter
    def transforms(self, value: Any) -> None:
        object.__setattr__(self, "_transforms", value)
        self.validate()

    @property
    def colors(self) -> Any:
        return self._colors

    @colors.setter
    def colors(self, value: Any) -> None:
        object.__setattr__(self, "_colors", value)
        self.validate()

    @property
    def scales(self) -> Any:
        return self._scales

    @scales.setter
    def scales(self, value: Any) -> None:
        object.__setattr__(self, "_scales", value)
        self.validate()

    @property
    def visible(self) -> Any:
        return self._visible

    @visible.setter
    def visible(self, value: Any) -> None:
        object.__setattr__(self, "_visible", value)
        self.validate()

    def parameters(self) -> dict[str, Any]:
        return {
            "shape": self._shape,
            "transforms": self._transforms,
            "colors": self._colors,
            "scales": self._scales,
            "visible": self._visible,
        }

    def __len__(self) -> int:
        return len(_array(self._transforms))

    # -- changes ------------------------------------------------------------------------
    def touch(self, *arrays: str) -> None:
        """Say that the arrays were written in place (the version is bumped, as for any component).

        With no names any array may have changed.  Name the ones written
        (``touch("transforms")``, ``touch("transforms", "colors")``, from
        :attr:`ARRAYS`) when only those were: an engine then need not look at
        the others (GL compares the colours with the ones it converted
        otherwise).  Naming an array that was not written is harmless; leaving
        out one that was is a bug of the caller (its change may not be drawn).
        """
        for name in arrays:
            if name not in self.ARRAYS:
                raise ValueError(
                    f"InstanceSet.touch: {name!r} is not one of its arrays; name some of {', '.join(self.ARRAYS)} "
                    "(or none: any may have changed)"
                )
        written = self._written
        if written is None or self._touched_at != self._version or not arrays:
            # changed since the last touch through another route (a parameter assigned): all written then
            written = dict.fromkeys(self.ARRAYS, self._version)
        super().touch()
        version = self._version
        for name in arrays or self.ARRAYS:
            written[name] = version
        object.__setattr__(self, "_written", written)
        object.__setattr__(self, "_touched_at", version)

    def written_at(self, name: str) -> int:
        """The :attr:`version` at which the array ``name`` was last (maybe) written: equal at two moments means
        it was not written in between (only touches naming other arrays came)."""
        written = self._written
        if written is None or self._touched_at != self._version:
            return self._version
        return written[name]

    # -- the arrays, checked ------------------------------------------------------------
    def validate(self) -> None:
        """Check every array against the transforms' length (ValueError naming the bad instance)."""
        self.matrices()
        self.color_array()
        self.visible_array()

    def matrices(self) -> np.ndarray:
        """``(N, 4, 4)`` float64 model matrices of the instances (scales applied first)."""
        t = np.asarray(_array(self._transforms), dtype=np.float64)
        if t.ndim == 2 and t.shape[1] == 3:
            m = np.zeros((len(t), 4, 4))
            m[:, 0, 0] = m[:, 1, 1] = m[:, 2, 2] = m[:, 3, 3] = 1.0
            m[:, :3, 3] = t
        elif t.ndim == 3 and t.shape[1:] == (4, 4):
            m = t
        else:
            raise ValueError(
                f"InstanceSet: transforms must be (N, 4, 4) matrices or (N, 3) positions, got shape {t.shape}"
            )
        _check_finite(_rows(t), "transforms")  # the application's rows, as it wrote them
        if t.ndim == 3 and len(m):
            singular = np.nonzero(np.abs(determinants(m[:, :3, :3])) < SINGULAR)[0]
            if len(singular):
                raise ValueError(
                    f"InstanceSet: the transform of instance {int(singular[0])} is singular (it flattens the shape, "
                    "so its normals are undefined); give invertible matrices, or hide the instance with visible="
                )
        scales = _array(self._scales)
        if scales is not None:
            s = np.asarray(scales, dtype=np.float64)
            if s.shape not in ((len(m),), (len(m), 3)):
                raise ValueError(f"InstanceSet: scales must be ({len(m)},) or ({len(m)}, 3), got shape {s.shape}")
            _check_finite(_rows(s), "scales")
            bad = np.nonzero((_rows(s) == 0).any(axis=1))[0]
            if len(bad):
                raise ValueError(f"InstanceSet: scales of instance {int(bad[0])} are zero; give non-zero scales")
            s3 = np.repeat(s[:, None], 3, axis=1) if s.ndim == 1 else s
            m = m.copy()
            m[:, :3, :3] *= s3[:, None, :]
        return m

    def may_mirror(self) -> bool:
        """Whether some instance may be mirrored: only matrices or negative scales can mirror (positions cannot)."""
        if np.ndim(_array(self._transforms)) == 3:
            return True
        scales = _array(self._scales)
        return scales is not None and bool((np.asarray(scales) < 0).any())

    def color_array(self) -> np.ndarray | None:
        """``(N, 4)`` RGBA display values, or None."""
        colors = _array(self._colors)
        if colors is None:
            return None
        c = np.asarray(colors, dtype=np.float64)
        n = len(self)
        if c.ndim != 2 or c.shape[0] != n or c.shape[1] not in (3, 4):
            raise ValueError(f"InstanceSet: colors must be ({n}, 3) or ({n}, 4), got shape {c.shape}")
        _check_finite(c, "colors")
        bad = np.nonzero(((c < 0) | (c > 1)).any(axis=1))[0]
        if len(bad):
            raise ValueError(f"InstanceSet: colours of instance {int(bad[0])} are {c[bad[0]].tolist()}; use [0, 1]")
        if c.shape[1] == 3:
            c = np.concatenate([c, np.ones((n, 1))], axis=1)
        return c

    def visible_array(self) -> np.ndarray | None:
        """``(N,)`` booleans, or None (all visible)."""
        visible = _array(self._visible)
        if visible is None:
            return None
        v = np.asarray(visible)
        if v.shape != (len(self),):
            raise ValueError(f"InstanceSet: visible must have shape ({len(self)},), got {v.shape}")
        return v.astype(bool)

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__(state)
        self._shape.attach_owner(self)


#: |det| of an instance matrix's 3x3 part below which it counts as singular (a scale of about 1e-4 per axis).
SINGULAR = 1e-12


def determinants(m: np.ndarray) -> np.ndarray:
    """The determinants of ``(N, 3, 3)`` matrices by cofactors, column by column (``numpy.linalg.det`` factors
    each small matrix: 20 times slower for thousands of them)."""
    a, b, c = m[:, 0, 0], m[:, 0, 1], m[:, 0, 2]
    d, e, f = m[:, 1, 0], m[:, 1, 1], m[:, 1, 2]
    g, h, i = m[:, 2, 0], m[:, 2, 1], m[:, 2, 2]
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def _rows(a: np.ndarray) -> np.ndarray:
    """``a`` as one row per instance (also when there are none)."""
    return a.reshape(a.shape[0], int(np.prod(a.shape[1:], dtype=np.int64)))


def _check_finite(values: np.ndarray, name: str) -> None:
    finite = np.isfinite(values).all(axis=1)
    if not finite.all():
        bad = int(np.argmin(finite))
        raise ValueError(
            f"InstanceSet: {name} of instance {bad} are not finite: {values[bad].tolist()}; "
            "write finite numbers, or hide the instance with visible="
        )


@default_for(Engine)
class InstanceSetSimplifier(ShapeSimplifier):
    """One transient node per visible instance: its matrix, an ``InstanceId``, its colour, the shape."""

    __slots__ = ()
    target = InstanceSet

    def exec(self, shape: InstanceSet, engine: Engine) -> list[Any]:
        # lazy imports: the same deliberate exception as the other simplifiers' (docs/NOTES.md)
        from ..attributes import Color
        from ..core.transform import Matrix
        from ..scene.node import Node

        matrices = shape.matrices()
        colors = shape.color_array()
        visible = shape.visible_array()
        out = []
        for i in range(len(matrices)):
            if visible is not None and not visible[i]:
                continue
            items: list[Any] = [Matrix(matrices[i]), InstanceId(i)]
            if colors is not None:
                items.append(Color(colors[i]))
            items.append(shape.shape)
            out.append(Node.transient(items, f"instance{i}"))
        return out
