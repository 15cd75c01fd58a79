"""The reference 3D Gaussian splatting trainer's ``.ply`` files: read (binary and ASCII) and write.

The trainer (Kerbl et al. 2023, ``gaussian-splatting``'s ``save_ply``) stores
one ``vertex`` element per Gaussian with the properties

- ``x, y, z``: the centre;
- ``nx, ny, nz``: unused (zeros);
- ``f_dc_0..2``: the spherical-harmonics DC coefficient of red, green, blue;
- ``f_rest_0..3*(K-1)-1``: the other ``K - 1`` coefficients, **channel-major**
  (all red coefficients 1..K-1, then the green ones, then the blue ones);
- ``opacity``: the opacity **logit** (the reader applies the sigmoid);
- ``scale_0..2``: the **log** of the standard deviations (the reader applies exp);
- ``rot_0..3``: the rotation quaternion ``(w, x, y, z)``, **not normalised**
  (the reader normalises it).

:func:`read_splat_ply` returns the activated arrays of the
:class:`~omnirender.shapes.GaussianSplats` constructor; :func:`write_splat_ply`
writes them back (log scales, logit opacities).  A file of splats without
``f_dc_*`` but with 8-bit ``red``/``green``/``blue`` colours (some tools write
those) gets the DC coefficient of that colour.

Files are untrusted input: the header must end within :data:`MAX_HEADER`
bytes, the vertex count obeys :data:`omnirender.core.limits.MAX_VERTICES` and
must fit in the file before anything is allocated, and every missing
property, non-finite value, zero quaternion or overflowing scale is an error
naming the file, the property and the row.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from ...core.limits import check_count
from ...fileio import atomic_write

__all__ = ["read_splat_ply", "write_splat_ply", "SplatFileError", "MAX_HEADER", "is_splat_ply"]

#: Largest PLY header read (bytes): a header without ``end_header`` within it is refused.
MAX_HEADER = 1 << 16

#: The spherical-harmonics DC basis constant (the one rule lives in ``omnirender.shapes._sh``; the PLY colour
#: fallback only needs the DC term).
_C0 = 0.28209479177387814

_TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}
_FORMATS = {"binary_little_endian": "<", "binary_big_endian": ">", "ascii": "ascii"}
_SH_COUNTS = {0: 1, 9: 4, 24: 9, 45: 16}  # number of f_rest properties -> K


class SplatFileError(ValueError):
    """A splat file that cannot be read (the message names the file, what is wrong and the row)."""


def _error(path: Any, message: str) -> SplatFileError:
    return SplatFileError(f"load_splats {os.fspath(path)!r}: {message}")


def is_splat_ply(path: str | os.PathLike[str]) -> bool:
    """Whether the PLY file ``path`` holds Gaussian splats (its vertex element has ``scale_0`` and ``rot_0``)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(MAX_HEADER)
    except OSError:
        return False
    end = head.find(b"end_header")
    names = set(re.findall(rb"^property\s+\S+\s+(\S+)\s*$", head[: end if end >= 0 else len(head)], re.MULTILINE))
    return {b"scale_0", b"rot_0"} <= names


class _Header:
    """The parsed header: format, the elements (name, count, [(property, dtype) or list]) and the data offset."""

    def __init__(self, path: Any, data: bytes) -> None:
        end = data.find(b"end_header")
        if not data.startswith(b"ply") or end < 0:
            if not data.startswith(b"ply"):
                raise _error(path, "not a PLY file (it does not start with 'ply')")
            raise _error(
                path, f"the PLY header does not end ('end_header') within {MAX_HEADER:,} bytes (truncated or corrupt)"
            )
        newline = data.find(b"\n", end)
        if newline < 0:
            raise _error(path, "the PLY header's 'end_header' line has no line end (truncated file)")
        self.offset = newline + 1
        self.format = ""
        self.elements: list[tuple[str, int, list[tuple[str, str | None]]]] = []
        for number, raw in enumerate(data[:end].decode("ascii", errors="replace").splitlines()[1:], start=2):
            words = raw.split()
            if not words or words[0] in ("comment", "obj_info"):
                continue
            if words[0] == "format":
                if len(words) < 2 or words[1] not in _FORMATS:
                    raise _error(path, f"header line {number}: unknown PLY format {raw.strip()!r}")
                self.format = _FORMATS[words[1]]
            elif words[0] == "element":
                if len(words) != 3 or not words[2].isdigit():
                    raise _error(path, f"header line {number}: malformed element line {raw.strip()!r}")
                self.elements.append((words[1], int(words[2]), []))
            elif words[0] == "property":
                if not self.elements:
                    raise _error(path, f"header line {number}: a property before any element")
                if len(words) == 5 and words[1] == "list":
                    self.elements[-1][2].append((words[4], None))
                elif len(words) == 3 and words[1] in _TYPES:
                    self.elements[-1][2].append((words[2], _TYPES[words[1]]))
                else:
                    raise _error(path, f"header line {number}: malformed property line {raw.strip()!r}")
            else:
                raise _error(path, f"header line {number}: unknown PLY header keyword {words[0]!r}")
        if not self.format:
            raise _error(path, "the PLY header has no 'format' line")


def read_splat_ply(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """The splats of a trainer ``.ply`` file as the activated arrays of ``om.GaussianSplats``.

    Returns ``{"positions" (N, 3), "rotations" (N, 4) unit (w, x, y, z),
    "scales" (N, 3) linear, "opacities" (N,) in [0, 1], "sh" (N, K, 3)}``,
    float32.  Raises :class:`SplatFileError` (a ValueError) naming the file
    and the problem, :class:`~omnirender.core.limits.ResourceLimitError` when
    the header announces more splats than the limits allow, FileNotFoundError
    when there is no such file.
    """
    path = Path(os.fspath(path))
    if not path.is_file():
        raise FileNotFoundError(f"load_splats: no such file {os.fspath(path)!r}")
    size = path.stat().st_size
    with open(path, "rb") as fh:
        header = _Header(path, fh.read(MAX_HEADER))
        skip = 0  # bytes of the elements before the vertex element (binary files)
        skip_lines = 0
        for name, count, props in header.elements:
            if name == "vertex":
                break
            if any(t is None for _, t in props):
                raise _error(path, f"the element {name!r} before the splats holds list properties; not supported")
            skip += count * sum(np.dtype(t).itemsize for _, t in props)  # type: ignore[arg-type]
            skip_lines += count
        else:
            raise _error(path, "the file has no 'vertex' element (the splats)")
        _, count, props = header.elements[[e[0] for e in header.elements].index("vertex")]
        source = f"load_splats {os.fspath(path)!r}"
        check_count(source, "the PLY 'vertex' element", count, "vertices")
        lists = [p for p, t in props if t is None]
        if lists:
            raise _error(path, f"the vertex element holds list properties ({', '.join(lists)}); a splat file has none")
        dtype = np.dtype([(p, (header.format if header.format != "ascii" else "<") + t) for p, t in props])  # type: ignore[operator]
        names = [p for p, _ in props]
        if len(set(names)) != len(names):
            raise _error(path, "the vertex element names a property twice")
        _layout(path, names)  # a file of something else is refused before its data is read
        if header.format == "ascii":
            table = _read_ascii(path, fh, header.offset, skip_lines, count, dtype, size)
        else:
            need = header.offset + skip + count * dtype.itemsize
            if need > size:
                raise _error(
                    path,
                    f"the header announces {count:,} splats of {dtype.itemsize} bytes, {need:,} bytes in all, but the "
                    f"file holds only {size:,} bytes (truncated or corrupt)",
                )
            fh.seek(header.offset + skip)
            table = np.frombuffer(fh.read(count * dtype.itemsize), dtype=dtype, count=count)
    return _activate(path, table, names)


def _read_ascii(
    path: Path, fh: Any, offset: int, skip_lines: int, count: int, dtype: np.dtype, size: int
) -> np.ndarray:
    if count * len(dtype.names or ()) * 2 > size:  # every value takes at least a digit and a separator
        raise _error(path, f"the header announces {count:,} splats but the file holds only {size:,} bytes")
    fh.seek(offset)
    lines = fh.read().decode("ascii", errors="replace").splitlines()
    rows = [ln for ln in lines if ln.strip()][skip_lines : skip_lines + count]
    if len(rows) < count:
        raise _error(path, f"the header announces {count:,} splats but the file holds {len(rows):,} rows (truncated)")
    width = len(dtype.names or ())
    try:
        values = np.array([r.split() for r in rows], dtype=np.float64) if count else np.zeros((0, width))
    except ValueError:
        bad = next(i for i, r in enumerate(rows) if len(r.split()) != width or not _numbers(r))
        raise _error(path, f"splat row {bad} is not {width} numbers: {rows[bad][:80]!r}") from None
    if values.ndim != 2 or values.shape[1] != width:
        bad = next(i for i, r in enumerate(rows) if len(r.split()) != width)
        raise _error(path, f"splat row {bad} holds {len(rows[bad].split())} values, the header names {width}")
    table = np.zeros(count, dtype=dtype)
    for i, name in enumerate(dtype.names or ()):
        table[name] = values[:, i]
    return table


def _numbers(row: str) -> bool:
    try:
        [float(v) for v in row.split()]
    except ValueError:
        return False
    return True


def _layout(path: Path, names: list[str]) -> tuple[list[str], list[str]]:
    """The colour and ``f_rest_*`` properties of a splat file's vertex element; SplatFileError when it is not one."""
    present = set(names)
    rest = sorted((n for n in names if n.startswith("f_rest_")), key=lambda n: int(n[7:]) if n[7:].isdigit() else -1)
    need = ["x", "y", "z", "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
    colour = ["f_dc_0", "f_dc_1", "f_dc_2"]
    if not set(colour) <= present and {"red", "green", "blue"} <= present:
        colour = ["red", "green", "blue"]
    missing = [n for n in need + colour if n not in present]
    if missing:
        raise _error(
            path,
            f"the vertex element lacks the splat properties {', '.join(missing)}; a Gaussian splat file "
            "(the reference trainer's layout) has x y z, f_dc_0..2, f_rest_*, opacity, scale_0..2 and rot_0..3",
        )
    if len(rest) not in _SH_COUNTS or rest != [f"f_rest_{i}" for i in range(len(rest))]:
        raise _error(
            path,
            f"the file has {len(rest)} f_rest_* properties; spherical harmonics of degree 0..3 need 0, 9, 24 or 45 "
            "numbered from f_rest_0",
        )
    return colour, rest


def _activate(path: Path, table: np.ndarray, names: list[str]) -> dict[str, np.ndarray]:
    colour, rest = _layout(path, names)
    k = _SH_COUNTS[len(rest)]
    n = len(table)

    def stack(columns: list[str]) -> np.ndarray:
        out = np.empty((n, len(columns)), np.float64)
        for i, c in enumerate(columns):
            out[:, i] = np.asarray(table[c], dtype=np.float64)
        return out

    raw = {
        "x y z": stack(["x", "y", "z"]),
        "opacity": stack(["opacity"]),
        "scale_0..2": stack(["scale_0", "scale_1", "scale_2"]),
        "rot_0..3": stack(["rot_0", "rot_1", "rot_2", "rot_3"]),
        "colour": stack(colour),
        "f_rest_*": stack(rest) if rest else np.zeros((n, 0)),
    }
    for what, values in raw.items():
        finite = np.isfinite(values).all(axis=1)
        if not finite.all():
            row = int(np.argmin(finite))
            label = "f_dc_0..2" if what == "colour" else what
            raise _error(path, f"splat row {row}: {label} are not finite: {values[row].tolist()}")
    sh = np.zeros((n, k, 3), np.float64)
    if colour[0] == "red":
        scale = 255.0 if np.asarray(table["red"]).dtype.kind in "iu" else 1.0
        sh[:, 0, :] = (raw["colour"] / scale - 0.5) / _C0
    else:
        sh[:, 0, :] = raw["colour"]
    if k > 1:  # channel-major: f_rest_[c * (K - 1) + (j - 1)] is coefficient j of channel c
        sh[:, 1:, :] = raw["f_rest_*"].reshape(n, 3, k - 1).transpose(0, 2, 1)
    log_scales = raw["scale_0..2"]
    big = (log_scales > 80.0).any(axis=1) | (log_scales < -80.0).any(axis=1)
    if big.any():
        row = int(np.argmax(big))
        raise _error(
            path,
            f"splat row {row}: the log scales {log_scales[row].tolist()} give standard deviations of "
            f"exp({log_scales[row].max():.4g}) (beyond e^80 or below e^-80); the file is corrupt or not in log units",
        )
    q = raw["rot_0..3"]
    length = np.linalg.norm(q, axis=1)
    zero = length < 1e-12
    if zero.any():
        row = int(np.argmax(zero))
        raise _error(path, f"splat row {row}: the rotation quaternion rot_0..3 is zero; it has no orientation")
    logit = raw["opacity"][:, 0]
    opacities = np.where(logit >= 0, 1.0 / (1.0 + np.exp(-np.abs(logit))), 1.0 - 1.0 / (1.0 + np.exp(-np.abs(logit))))
    return {
        "positions": raw["x y z"].astype(np.float32),
        "rotations": (q / length[:, None]).astype(np.float32),
        "scales": np.exp(log_scales).astype(np.float32),
        "opacities": opacities.astype(np.float32),
        "sh": sh.astype(np.float32),
    }


def write_splat_ply(
    path: str | os.PathLike[str],
    positions: Any,
    rotations: Any,
    scales: Any,
    opacities: Any,
    sh: Any,
    *,
    binary: bool = True,
) -> None:
    """Write splats in the reference trainer's ``.ply`` layout (log scales, logit opacities, channel-major SH).

    The arrays are those of ``om.GaussianSplats`` (linear scales, opacities in
    [0, 1], ``sh`` (N, K, 3)); ``binary=False`` writes ASCII.  Opacities are
    clipped to [1e-7, 1 - 1e-7] so that their logits stay finite.  The file
    is written atomically.
    """
    p = np.asarray(positions, np.float64).reshape(-1, 3)
    n = len(p)
    q = np.asarray(rotations, np.float64).reshape(n, 4)
    s = np.asarray(scales, np.float64).reshape(n, 3)
    o = np.clip(np.asarray(opacities, np.float64).reshape(n), 1e-7, 1.0 - 1e-7)
    c = np.asarray(sh, np.float64).reshape(n, -1, 3)
    k = c.shape[1]
    if k not in (1, 4, 9, 16):
        raise ValueError(f"write_splat_ply: sh must hold 1, 4, 9 or 16 coefficients per splat, got {k}")
    columns = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
    columns += [f"f_rest_{i}" for i in range(3 * (k - 1))]
    columns += ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
    rest = c[:, 1:, :].transpose(0, 2, 1).reshape(n, 3 * (k - 1))
    values = np.concatenate(
        [p, np.zeros((n, 3)), c[:, 0, :], rest, np.log(o / (1.0 - o))[:, None], np.log(s), q], axis=1
    ).astype(np.float32)
    head = "ply\nformat {} 1.0\nelement vertex {}\n{}end_header\n".format(
        "binary_little_endian" if binary else "ascii", n, "".join(f"property float {c}\n" for c in columns)
    )
    with atomic_write(path, "wb") as fh:
        fh.write(head.encode("ascii"))
        if binary:
            fh.write(values.astype("<f4").tobytes())
        else:
            fh.write("".join(" ".join(repr(float(v)) for v in row) + "\n" for row in values).encode("ascii"))
