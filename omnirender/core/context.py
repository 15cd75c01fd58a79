"""The rendering context: attribute stacks, attribute sets and handler stacks.

Containers are created on first use, so a context costs nothing for categories
it never sees.  The ``Transform`` category is special: its entry is the
accumulated model matrix, composed lazily (only when somebody asks for it), so
pushing and popping transforms during a traversal is a plain list operation.
"""

from __future__ import annotations

from collections import defaultdict
from typing import Any

import numpy as np

from .limits import MAX_MAGNITUDE
from .transform import Matrix, Rotation, Scaling, Transform, Translation

__all__ = ["RenderingContext"]

_IDENTITY = np.eye(4)
_IDENTITY.setflags(write=False)
_F64 = np.dtype(np.float64)
#: transforms whose own matrix is within the magnitude limit by the checks of their parameters
_BOUNDED = frozenset((Translation, Rotation, Scaling, Matrix))


class RenderingContext:
    """Per-category mono stacks, per-category poly sets and the handler table."""

    __slots__ = ("_mono", "_poly", "_handlers", "_matrices", "_transforms")

    def __init__(self) -> None:
        self._mono: defaultdict[type, list[Any]] = defaultdict(list)
        self._poly: dict[type, list[Any]] = {}
        self._handlers: dict[tuple[str, type], list[Any]] = {}
        self._transforms: list[Transform] = []
        self._mono[Transform] = self._transforms
        # _matrices[i] = (transform i-1, accumulated matrix of the first i transforms).
        self._matrices: list[tuple[Transform | None, np.ndarray, int]] = [(None, _IDENTITY, 0)]

    # -- mono stacks -------------------------------------------------------
    def mono_stack(self, category: type) -> list[Any]:
        """The stack of ``category`` (created empty on first use)."""
        return self._mono[category]

    def mono(self, category: type, default: Any = None) -> Any:
        """The active (top) attribute of ``category``, or ``default``.

        For the ``Transform`` category this is the accumulated model matrix.
        """
        if category is Transform:
            return self.model_matrix()
        stack = self._mono.get(category)
        if stack:
            return stack[-1]
        return default

    def model_matrix(self) -> np.ndarray:
        """The accumulated model matrix (4x4 float64, read-only).

        Composed lazily: ``_matrices[i]`` caches the product of the first ``i``
        transforms together with the transform it was made from and its
        version, and is trusted only while that transform, unchanged, is still
        at position ``i - 1``.  Push and pop
        therefore stay plain list operations.
        """
        transforms = self._transforms
        matrices = self._matrices
        n = len(transforms)
        valid = 1
        limit = min(n + 1, len(matrices))
        while valid < limit:
            entry = matrices[valid]
            t = transforms[valid - 1]
            if entry[0] is not t or entry[2] != t.version:  # (a TranslationArray's translation: its array's too)
                break
            valid += 1
        if valid == n + 1:
            return matrices[n][1] if n else _IDENTITY
        del matrices[valid:]
        current = matrices[valid - 1][1] if valid > 1 else _IDENTITY
        for i in range(valid - 1, n):
            t = transforms[i]
            m = t.matrix
            if current is _IDENTITY and m.dtype == _F64 and not m.flags.writeable:
                current = m  # the first transform's own (read-only) matrix is the product: no multiplication
                if t.__class__ in _BOUNDED:
                    matrices.append((t, current, t.version))
                    continue
            else:
                current = current @ m
            if not np.abs(current).max() <= MAX_MAGNITUDE:  # NaN fails too
                raise ValueError(
                    f"{type(t).__name__}: the accumulated model matrix exceeds {MAX_MAGNITUDE:.0e} here ({i + 1} "
                    "transforms deep), which overflows the engines' float32 arithmetic; rescale the scene"
                )
            current.setflags(write=False)
            matrices.append((t, current, t.version))
        return current

    # -- poly sets ---------------------------------------------------------
    def poly_set(self, category: type) -> list[Any]:
        """The ordered set of ``category`` (created empty on first use)."""
        items = self._poly.get(category)
        if items is None:
            items = self._poly[category] = []
        return items

    def poly(self, category: type) -> tuple[Any, ...]:
        """The active attributes of ``category`` in the order they were added."""
        items = self._poly.get(category)
        return tuple(items) if items else ()

    # -- handlers ----------------------------------------------------------
    def handler_stack(self, service: str, target: type) -> list[Any]:
        key = (service, target)
        stack = self._handlers.get(key)
        if stack is None:
            stack = self._handlers[key] = []
        return stack

    def handler(self, service: str, target: type) -> Any:
        """The top installed handler for (service, target), or None."""
        stack = self._handlers.get((service, target))
        return stack[-1] if stack else None

    # -- inspection --------------------------------------------------------
    def categories(self) -> list[type]:
        """Categories that currently have at least one active attribute."""
        cats = [c for c, s in self._mono.items() if s]
        cats += [c for c, s in self._poly.items() if s and c not in cats]
        return cats

    def is_empty(self) -> bool:
        """True when no attribute is pushed or added and no handler installed."""
        return not any(self._mono.values()) and not any(self._poly.values()) and not any(self._handlers.values())
