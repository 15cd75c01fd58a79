"""Arrays in scene files: plain lists for small data, compact forms for large data.

Three forms (see docs/scene-files.md):

* ``[[0, 0, 0], [1, 0, 0]]`` or ``{"$array": [...], "dtype": "uint8"}``: plain
  lists, readable and diffable; what small arrays use;
* ``{"$base64": "...", "dtype": "float32", "shape": [N, 3]}``: the array's bytes
  (little-endian) in base64 inside the file; what large arrays use by default;
* ``{"$file": "scene.npz", "key": "array-3"}`` (or a ``.npy`` file without a
  key): the array in a NumPy side-car file next to the scene file
  (``om.save(scene, path, arrays="npz")``).  Side-car paths follow the scene
  files' path policy (inside the scene's folder unless the file is trusted).

Compact forms decode with ``base64``/``numpy.frombuffer``/``numpy.load``
(``allow_pickle=False``): a 5.5-million-point cloud loads at disk speed, where
parsing the same numbers as text takes most of a minute.
"""

from __future__ import annotations

import base64
import binascii
import os
from typing import Any

import numpy as np

__all__ = ["COMPACT_MIN_SIZE", "DTYPES", "encode_base64", "decode_base64", "check_loaded", "SideCar"]

#: Arrays with at least this many elements are written in a compact form (smaller ones as lists).
COMPACT_MIN_SIZE = 1024
#: The dtypes compact arrays may have.
DTYPES = ("uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64", "float32", "float64", "bool")


def encode_base64(arr: np.ndarray) -> dict[str, Any]:
    """``{"$base64", "dtype", "shape"}`` of ``arr`` (little-endian bytes)."""
    data = np.ascontiguousarray(arr, dtype=arr.dtype.newbyteorder("<"))
    return {
        "$base64": base64.b64encode(data.tobytes()).decode("ascii"),
        "dtype": arr.dtype.name,
        "shape": list(arr.shape),
    }


def _dtype(name: Any) -> np.dtype:
    if not isinstance(name, str) or name not in DTYPES:
        raise ValueError(f"dtype must be one of {', '.join(DTYPES)}, got {name!r}")
    return np.dtype(name).newbyteorder("<")


def decode_base64(value: dict[str, Any]) -> np.ndarray:
    """The array of a ``$base64`` entry; ValueError (naming the key) when malformed."""
    extra = set(value) - {"$base64", "dtype", "shape"}
    if extra:
        raise ValueError(f"a $base64 array holds only '$base64', 'dtype' and 'shape', not {sorted(extra)}")
    text = value["$base64"]
    if not isinstance(text, str):
        raise ValueError(f"$base64 must be a base64 string, got {type(text).__name__}")
    dt = _dtype(value.get("dtype"))
    shape = value.get("shape")
    if (
        not isinstance(shape, list)
        or not all(isinstance(n, int) and not isinstance(n, bool) and 0 <= n < 2**48 for n in shape)
        or len(shape) > 8
    ):
        raise ValueError(f"shape must be a list of at most 8 sizes >= 0, got {shape!r}")
    count = 1
    for n in shape:
        count *= n
    try:
        raw = base64.b64decode(text, validate=True)
    except (binascii.Error, ValueError) as exc:
        raise ValueError(f"$base64 is not valid base64 ({exc})") from None
    if len(raw) != count * dt.itemsize:
        raise ValueError(
            f"shape {shape} of {dt.name} needs {count * dt.itemsize} bytes, the $base64 data has {len(raw)}"
        )
    arr = np.frombuffer(raw, dtype=dt).reshape(shape)
    return check_loaded(arr.astype(arr.dtype.newbyteorder("="), copy=False))


def check_loaded(arr: Any) -> np.ndarray:
    """``arr`` if it is a numeric array of finite numbers, else ValueError."""
    if not isinstance(arr, np.ndarray) or arr.dtype.kind not in "biuf":
        raise ValueError(f"expected a numeric array, got {getattr(arr, 'dtype', type(arr).__name__)}")
    if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
        raise ValueError("the array holds non-finite numbers (NaN or infinity)")
    return arr


class SideCar:
    """NumPy side-car files read for one scene file (each opened once, closed at the end)."""

    def __init__(self) -> None:
        self._open: dict[str, Any] = {}

    def load(self, path: str, key: Any) -> np.ndarray:
        """The array at ``path`` (a ``.npy`` file, or ``key`` of a ``.npz`` file); OSError/ValueError."""
        try:
            return self._load(path, key)
        except ValueError as exc:
            if "allow_pickle" in str(exc):  # numpy's refusal of object arrays
                raise ValueError(
                    f"{os.path.basename(path)} holds Python objects (a pickle), which scene files never load; "
                    "save plain numeric arrays"
                ) from None
            raise

    def _load(self, path: str, key: Any) -> np.ndarray:
        lower = path.lower()
        if lower.endswith(".npy"):
            if key is not None:
                raise ValueError("a .npy file holds one array: give no 'key'")
            return check_loaded(np.load(path, allow_pickle=False))
        if not lower.endswith(".npz"):
            raise ValueError(f"side-car arrays are .npy or .npz files, got {path!r}")
        if not isinstance(key, str):
            raise ValueError(f"a .npz side-car needs 'key' naming one of its arrays, got {key!r}")
        archive = self._open.get(path)
        if archive is None:
            archive = self._open[path] = np.load(path, allow_pickle=False)
        if key not in archive.files:
            shown = ", ".join(archive.files[:8]) + (", ..." if len(archive.files) > 8 else "")
            raise ValueError(f"{path} has no array {key!r} (it has: {shown or 'none'})")
        return check_loaded(archive[key])

    def close(self) -> None:
        for archive in self._open.values():
            archive.close()
        self._open.clear()


def numeric_list(value: list[Any]) -> np.ndarray | None:
    """A regular numeric nested list as an array (int64/float64), or None when it is anything else.

    The reader's fast path: one numpy conversion instead of visiting every number.
    """
    first = value[0]
    while isinstance(first, list) and first:
        first = first[0]
    if isinstance(first, bool) or not isinstance(first, (int, float)):
        return None
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError, OverflowError):
        return None
    if arr.dtype.kind not in "if":
        return None
    return arr
