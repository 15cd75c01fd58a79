"""The glTF 2.0 binary container: one JSON chunk and one BIN chunk, built with numpy.

:class:`GLBBuilder` collects arrays into a single buffer (each view 4-byte
aligned) and creates accessors with the ``min``/``max`` the specification
requires for positions; :meth:`GLBBuilder.to_bytes` packs the GLB.
"""

from __future__ import annotations

import hashlib
import json
import struct
from typing import Any

import numpy as np

__all__ = ["GLBBuilder", "FLOAT", "UNSIGNED_INT", "UNSIGNED_BYTE", "ARRAY_BUFFER", "ELEMENT_ARRAY_BUFFER"]

FLOAT = 5126
UNSIGNED_INT = 5125
UNSIGNED_BYTE = 5121
ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963

_COMPONENT = {np.dtype(np.float32): FLOAT, np.dtype(np.uint32): UNSIGNED_INT, np.dtype(np.uint8): UNSIGNED_BYTE}
_TYPE = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}
_MAGIC = 0x46546C67  # "glTF"
_JSON = 0x4E4F534A
_BIN = 0x004E4942


class GLBBuilder:
    """Accumulates the glTF JSON document and its binary buffer."""

    def __init__(self, generator: str = "omnirender") -> None:
        self.doc: dict[str, Any] = {"asset": {"version": "2.0", "generator": generator}}
        self._chunks: list[bytes] = []
        self._length = 0
        #: while a dict (set by the writer for a while): accessors of equal arrays are written once, keyed by content
        self.shared: dict[tuple, int] | None = None

    def _list(self, key: str) -> list[Any]:
        return self.doc.setdefault(key, [])

    def append(self, key: str, item: dict[str, Any]) -> int:
        """Append ``item`` to the top-level array ``key``; returns its index."""
        items = self._list(key)
        items.append(item)
        return len(items) - 1

    def buffer_view(self, data: bytes, target: int | None = None) -> int:
        """Add raw bytes as a buffer view (4-byte aligned); returns the view index."""
        pad = (-self._length) % 4
        if pad:
            self._chunks.append(b"\0" * pad)
            self._length += pad
        view: dict[str, Any] = {"buffer": 0, "byteOffset": self._length, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self._chunks.append(data)
        self._length += len(data)
        return self.append("bufferViews", view)

    def accessor(self, array: np.ndarray, target: int | None = None, *, bounds: bool = False, normalized=False) -> int:
        """Add an (N,) or (N, k) array as a tightly packed accessor; returns its index."""
        a = np.ascontiguousarray(array)
        if a.dtype not in _COMPONENT:
            raise ValueError(f"glTF export: unsupported array type {a.dtype}")
        width = 1 if a.ndim == 1 else a.shape[1]
        data = a.tobytes()
        key = None
        if self.shared is not None:
            key = (hashlib.blake2b(data, digest_size=16).digest(), a.dtype.str, a.shape, target, bounds, normalized)
            found = self.shared.get(key)
            if found is not None:
                return found
        view = self.buffer_view(data, target)
        acc: dict[str, Any] = {
            "bufferView": view,
            "componentType": _COMPONENT[a.dtype],
            "count": int(a.shape[0]),
            "type": _TYPE[width],
        }
        if normalized:
            acc["normalized"] = True
        if bounds and len(a):
            flat = a.reshape(len(a), width)
            acc["min"] = [_num(v) for v in flat.min(axis=0)]
            acc["max"] = [_num(v) for v in flat.max(axis=0)]
        index = self.append("accessors", acc)
        if key is not None:
            self.shared[key] = index  # type: ignore[index]
        return index

    def checkpoint(self) -> tuple[Any, ...]:
        """The document's state now, for :meth:`rollback` (an attempt that may be abandoned)."""
        lists = {k: len(v) for k, v in self.doc.items() if isinstance(v, list)}
        shared = None if self.shared is None else dict(self.shared)
        return len(self._chunks), self._length, lists, shared

    def rollback(self, mark: tuple[Any, ...]) -> None:
        """Forget everything added since :meth:`checkpoint` returned ``mark``."""
        chunks, length, lists, shared = mark
        del self._chunks[chunks:]
        self._length = length
        for key in [k for k, v in self.doc.items() if isinstance(v, list)]:
            if key in lists:
                del self.doc[key][lists[key] :]
            else:
                del self.doc[key]
        self.shared = shared

    def use_extension(self, name: str) -> None:
        used = self._list("extensionsUsed")
        if name not in used:
            used.append(name)

    def to_bytes(self) -> bytes:
        """The complete GLB file."""
        binary = b"".join(self._chunks)
        binary += b"\0" * ((-len(binary)) % 4)
        doc = dict(self.doc)
        if binary:
            doc["buffers"] = [{"byteLength": len(binary)}]
        text = json.dumps(doc, separators=(",", ":"), allow_nan=False).encode("utf-8")
        text += b" " * ((-len(text)) % 4)
        total = 12 + 8 + len(text) + (8 + len(binary) if binary else 0)
        parts = [struct.pack("<III", _MAGIC, 2, total), struct.pack("<II", len(text), _JSON), text]
        if binary:
            parts += [struct.pack("<II", len(binary), _BIN), binary]
        return b"".join(parts)


def _num(v: Any) -> float | int:
    return int(v) if isinstance(v, (np.integer, int)) else float(v)
