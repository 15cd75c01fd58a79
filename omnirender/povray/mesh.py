"""``mesh2`` text for triangle sets, formatted with one ``%``-operation per array.

A million triangles format in about a second: each array is turned into one
long format string and one tuple, so the per-vertex work happens in C.  Per
vertex colours become a ``texture_list`` of the distinct colours with three
texture indices per face (POV-Ray interpolates them across the triangle).
"""

from __future__ import annotations

import numpy as np

from . import sdl

__all__ = ["mesh2_text"]


def mesh2_text(
    vertices: np.ndarray,
    indices: np.ndarray,
    normals: np.ndarray | None = None,
    texcoords: np.ndarray | None = None,
    colors: np.ndarray | None = None,
    finish: str | None = None,
    owner: str = "POV-Ray",
) -> str:
    """A ``mesh2 { ... }`` block.

    ``vertices`` (N, 3), ``indices`` (M, 3) into the vertices, optional
    ``normals`` (N, 3), ``texcoords`` (N, 2) and linear ``colors`` (N, 3 or 4;
    alpha becomes transmit) with ``finish`` the identifier of a declared
    finish for the per-vertex textures.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    indices = np.asarray(indices, dtype=np.int64)
    n = len(vertices)
    if indices.size and (indices.min() < 0 or indices.max() >= n):
        raise sdl.SDLError(f"{owner}: triangle indices out of range 0..{n - 1}")
    parts = ["mesh2 {\n", f"vertex_vectors {{ {n},\n", sdl.vectors_text(vertices, owner, "vertices"), "}\n"]
    if normals is not None:
        normals = np.asarray(normals, dtype=np.float64)
        # POV-Ray rejects zero-length normals; replace them by +y (the triangle keeps its own normal).
        bad = ~np.any(normals != 0.0, axis=1)
        if bad.any():
            normals = normals.copy()
            normals[bad] = (0.0, 1.0, 0.0)
        parts += [f"normal_vectors {{ {n},\n", sdl.vectors_text(normals, owner, "normals", "%.6g"), "}\n"]
    if texcoords is not None:
        parts += [f"uv_vectors {{ {n},\n", sdl.vectors_text(np.asarray(texcoords)[:, :2], owner, "uvs", "%.7g"), "}\n"]
    if colors is not None:
        colors = np.asarray(colors, dtype=np.float64)
        if colors.shape[1] == 4:
            colors = np.column_stack([colors[:, :3], 1.0 - colors[:, 3]])
        else:
            colors = np.column_stack([colors[:, :3], np.zeros(n)])
        colors = np.round(colors, 5)
        unique, inverse = np.unique(colors, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        fin = f" finish {{ {finish} }}" if finish else ""
        line = "texture { pigment { rgbt <%.5g,%.5g,%.5g,%.5g> }" + fin + " }\n"
        parts += [f"texture_list {{ {len(unique)},\n", (line * len(unique)) % tuple(unique.ravel().tolist()), "}\n"]
        faces = np.column_stack([indices, inverse[indices]])
        parts += [f"face_indices {{ {len(indices)},\n", sdl.sextuples_text(faces), "}\n"]
    else:
        parts += [f"face_indices {{ {len(indices)},\n", sdl.triples_text(indices), "}\n"]
    parts.append("}")
    return "".join(parts)
