"""Wavefront OBJ text for ``obj2mesh``, formatted with one ``%``-operation per array.

Vertices are written in world coordinates (any affine model matrix, also
non-uniform scaling and mirroring, whose triangles are turned round so their
normals keep pointing outwards).  Normals become ``vn`` (smooth shading;
``obj2mesh`` rejects zero-length ones, which are replaced by the face's own
normal direction +y, as in the POV-Ray engine), texture coordinates ``vt``
(Radiance's ``Lu``/``Lv``).  Per-face material names (``usemtl``) carry
per-vertex colours: Radiance meshes have no vertex colours, so each triangle
gets the mean colour of its corners.
"""

from __future__ import annotations

import numpy as np

from ..geometry.matrix import transform_normals, transform_points
from . import rad

__all__ = ["obj_text", "transform_mesh", "face_colors"]


def transform_mesh(
    matrix: np.ndarray, vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Vertices, faces and normals in world coordinates (faces reversed under a mirroring matrix)."""
    m = np.asarray(matrix, np.float64)
    f = np.asarray(faces, np.int64)
    if np.linalg.det(m[:3, :3]) < 0.0:
        f = f[:, ::-1]
    n = None if normals is None else transform_normals(m, normals)
    return transform_points(m, vertices), f, n


def face_colors(colors: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distinct RGBA colours, per-face index into them): each face's mean corner colour, to 1/1000."""
    mean = np.asarray(colors, np.float64)[faces].mean(axis=1)
    mean = np.round(mean, 3)
    unique, inverse = np.unique(mean, axis=0, return_inverse=True)
    return unique, inverse.reshape(-1)


def _lines(prefix: str, array: np.ndarray, fmt: str, owner: str, what: str) -> str:
    array = np.asarray(array, np.float64)
    if array.size and not np.all(np.isfinite(array)):
        raise rad.RadError(f"{owner}: mesh {what} contain non-finite values")
    n, k = array.shape
    if n == 0:
        return ""
    line = prefix + " " + " ".join([fmt] * k) + "\n"
    return (line * n) % tuple(array.ravel().tolist())


def obj_text(
    vertices: np.ndarray,
    faces: np.ndarray,
    normals: np.ndarray | None = None,
    texcoords: np.ndarray | None = None,
    groups: np.ndarray | None = None,
    names: list[str] | None = None,
    owner: str = "Radiance",
) -> str:
    """OBJ text of a triangle mesh; ``groups`` (per face) index ``names``, the ``usemtl`` of each face."""
    vertices = np.asarray(vertices, np.float64)
    faces = np.asarray(faces, np.int64).reshape(-1, 3)
    n = len(vertices)
    if faces.size and (faces.min() < 0 or faces.max() >= n):
        raise rad.RadError(f"{owner}: triangle indices out of range 0..{n - 1}")
    parts = [_lines("v", vertices, "%.9g", owner, "vertices")]
    if normals is not None:
        normals = np.asarray(normals, np.float64).copy()
        bad = ~np.any(normals != 0.0, axis=1)
        normals[bad] = (0.0, 1.0, 0.0)
        parts.append(_lines("vn", normals, "%.7g", owner, "normals"))
    if texcoords is not None:
        parts.append(_lines("vt", np.asarray(texcoords, np.float64)[:, :2], "%.7g", owner, "texture coordinates"))
    one = faces + 1
    if normals is not None and texcoords is not None:
        corner, per = "%d/%d/%d", np.repeat(one, 3, axis=1)
    elif normals is not None:
        corner, per = "%d//%d", np.repeat(one, 2, axis=1)
    elif texcoords is not None:
        corner, per = "%d/%d", np.repeat(one, 2, axis=1)
    else:
        corner, per = "%d", one
    line = "f " + " ".join([corner] * 3) + "\n"
    if groups is None:
        parts.append((line * len(faces)) % tuple(per.ravel().tolist()))
        return "".join(parts)
    assert names is not None
    order = np.argsort(groups, kind="stable")
    groups, per = np.asarray(groups)[order], per[order]
    starts = np.flatnonzero(np.r_[True, groups[1:] != groups[:-1]])
    ends = np.r_[starts[1:], len(groups)]
    for a, b in zip(starts, ends, strict=True):
        parts.append(f"usemtl {rad.identifier(names[groups[a]], owner)}\n")
        parts.append((line * (b - a)) % tuple(per[a:b].ravel().tolist()))
    return "".join(parts)
