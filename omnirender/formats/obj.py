"""A small reader for plain Wavefront OBJ files, so that a simple mesh needs no trimesh.

Importing trimesh takes over a second; a 5-vertex OBJ file should not pay
that.  This reader handles the plain subset most scanned and exported
meshes use: ``v x y z`` positions, ``vn`` normals and ``f`` polygons (``v``,
``v//vn``; fan-triangulated, negative indices allowed), with ``o``/``g``/``s``
lines ignored.  Anything else (materials, texture coordinates, vertex colours,
lines, free-form geometry) returns None and :class:`~omnirender.shapes.MeshFile`
uses trimesh, which reads the full format.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

__all__ = ["read_plain_obj", "PLAIN_OBJ_MAX_BYTES"]

#: Larger files go to trimesh (its parser is vectorised; the import is then a small part of the time).
PLAIN_OBJ_MAX_BYTES = 4 << 20
_IGNORED = ("#", "o ", "g ", "s ", "o\t", "g\t", "s\t")


def read_plain_obj(path: str) -> dict[str, Any] | None:
    """``{"vertices", "indices", "normals"}`` of a plain OBJ file, or None when trimesh must read it.

    Raises ValueError for a malformed plain file (bad numbers, indices out of range, no faces).
    """
    if os.path.getsize(path) > PLAIN_OBJ_MAX_BYTES:
        return None
    with open(path, encoding="utf-8", errors="replace") as fh:
        lines = fh.read().splitlines()
    positions: list[str] = []
    normals: list[str] = []
    faces: list[list[str]] = []
    for raw in lines:
        line = raw.strip()
        if not line or line.startswith(_IGNORED):
            continue
        head, _, rest = line.partition(" ")
        if head == "v":
            positions.append(rest)
        elif head == "vn":
            normals.append(rest)
        elif head == "f":
            faces.append(rest.split())
        else:
            return None  # materials, texture coordinates, lines...: trimesh's job
    if not faces:
        return None
    v = _numbers(positions, "v", lines)
    if v is None:
        return None
    vn = _numbers(normals, "vn", lines) if normals else np.zeros((0, 3))
    if vn is None:
        return None
    corners: list[tuple[int, int]] = []
    triangles: list[tuple[int, int, int]] = []
    index: dict[tuple[int, int], int] = {}
    for number, face in enumerate(faces):
        if len(face) < 3:
            raise ValueError(f"face {number + 1} has {len(face)} corners (at least 3)")
        ids = []
        for token in face:
            parts = token.split("/")
            if len(parts) > 3 or (len(parts) >= 2 and parts[1]):
                return None  # texture coordinates
            key = (_index(parts[0], len(v), number), _index(parts[2], len(vn), number) if len(parts) == 3 else -1)
            at = index.get(key)
            if at is None:
                at = index[key] = len(corners)
                corners.append(key)
            ids.append(at)
        triangles.extend((ids[0], ids[i], ids[i + 1]) for i in range(1, len(ids) - 1))
    keys = np.array(corners, dtype=np.int64)
    with_normals = bool(len(vn)) and bool(np.all(keys[:, 1] >= 0))
    return {
        "vertices": v[keys[:, 0]],
        "indices": np.array(triangles, dtype=np.int64),
        "normals": vn[keys[:, 1]].astype(np.float32) if with_normals else None,
    }


def _numbers(rows: list[str], kind: str, lines: list[str]) -> np.ndarray | None:
    try:
        values = [[float(x) for x in row.split()] for row in rows]
    except ValueError:
        for number, line in enumerate(lines, 1):  # find the line to name it (only on this error path)
            head, _, rest = line.strip().partition(" ")
            if head == kind and any(not _is_number(x) for x in rest.split()):
                bad = next(x for x in rest.split() if not _is_number(x))
                raise ValueError(f"line {number}: {bad!r} in a '{kind}' line is not a number") from None
        raise ValueError(f"a '{kind}' line holds something that is not a number") from None
    if any(len(row) != 3 for row in values):
        return None  # homogeneous coordinates or vertex colours: trimesh reads them
    arr = np.array(values, dtype=np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"a '{kind}' line holds a non-finite number")
    return arr


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _index(token: str, count: int, face: int) -> int:
    try:
        i = int(token)
    except ValueError:
        raise ValueError(f"face {face + 1}: {token!r} is not a vertex index") from None
    j = i - 1 if i > 0 else count + i
    if i == 0 or not 0 <= j < count:
        raise ValueError(f"face {face + 1}: index {i} is out of range for {count} entries")
    return j
