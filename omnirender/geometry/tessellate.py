"""Tessellation of the analytic shapes into triangle meshes.

Every function returns a :class:`Mesh` of float32 vertices (N, 3), uint32
indices (M, 3) counter-clockwise seen from outside, float32 unit normals
(N, 3) pointing outwards and float32 texture coordinates (N, 2).  Closed
shapes (sphere, box, cylinder, cone, torus) are watertight once coincident
vertices are merged; vertices are duplicated only where a seam needs two
texture coordinates or a sharp edge needs two normals (box faces, the caps of
cylinders and cones), so flat parts shade flat.  Conventions match the shape
declarations: +y up, cylinder/cone on the y axis centred at the origin, torus,
disk and rectangle in the xz plane facing +y.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = [
    "Mesh",
    "sphere",
    "box",
    "cylinder",
    "cone",
    "torus",
    "disk",
    "rectangle",
    "heightfield",
    "merge_meshes",
]


class Mesh(NamedTuple):
    """A triangle mesh as plain arrays."""

    vertices: np.ndarray
    indices: np.ndarray
    normals: np.ndarray
    texcoords: np.ndarray | None = None

    @property
    def triangle_count(self) -> int:
        return len(self.indices)


def _mesh(v, i, n, t=None) -> Mesh:
    return Mesh(
        np.ascontiguousarray(v, dtype=np.float32),
        np.ascontiguousarray(i, dtype=np.uint32).reshape(-1, 3),
        np.ascontiguousarray(n, dtype=np.float32),
        None if t is None else np.ascontiguousarray(t, dtype=np.float32),
    )


def _grid(rows: int, cols: int, offset: int = 0) -> np.ndarray:
    """Two triangles per cell of a (rows+1) x (cols+1) vertex grid stored row-major.

    Corner order a=(r,c), b=(r+1,c), c=(r+1,c+1), d=(r,c+1): triangles (a, b, c) and (a, c, d).
    """
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = r * (cols + 1) + c
    b = a + cols + 1
    d = a + 1
    cc = b + 1
    tri = np.stack([np.stack([a, b, cc], -1), np.stack([a, cc, d], -1)], axis=2)
    return tri.reshape(-1, 3) + offset


def _check_segments(segments: int, minimum: int = 3) -> int:
    segments = int(segments)
    if segments < minimum:
        raise ValueError(f"tessellation needs at least {minimum} segments, got {segments}")
    return segments


def sphere(radius: float = 1.0, center=(0.0, 0.0, 0.0), segments: int = 32, rings: int | None = None) -> Mesh:
    """UV sphere: ``segments`` around the y axis, ``rings`` (default segments/2) from pole to pole.

    Texture u runs with longitude, v from 0 at the south pole to 1 at the north pole.
    """
    segments = _check_segments(segments)
    rings = max(2, segments // 2 if rings is None else int(rings))
    theta = np.linspace(0.0, math.pi, rings + 1)  # from +y down to -y
    phi = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    # Longitude increases counter-clockwise seen from +y: x = sin(theta) sin(phi), z = sin(theta) cos(phi).
    n = np.stack([np.sin(th) * np.sin(ph), np.cos(th), np.sin(th) * np.cos(ph)], axis=-1).reshape(-1, 3)
    uv = np.stack([ph / (2 * math.pi), 1.0 - th / math.pi], axis=-1).reshape(-1, 2)
    tri = _grid(rings, segments).reshape(rings, segments, 2, 3)
    # The first row's (a, c, d) and the last row's (a, b, c) touch a pole twice: drop them.
    keep = np.ones((rings, segments, 2), dtype=bool)
    keep[0, :, 1] = False
    keep[-1, :, 0] = False
    # Rows go down from the north pole, columns counter-clockwise seen from +y: (a, b, c) is outward.
    idx = tri[keep]
    v = n * radius + np.asarray(center, dtype=np.float64)
    return _mesh(v, idx, n, uv)


def box(size=(1.0, 1.0, 1.0), center=(0.0, 0.0, 0.0)) -> Mesh:
    """Axis-aligned box: 6 faces of 4 vertices each (flat normals), 12 triangles."""
    half = np.asarray(size, dtype=np.float64) / 2.0
    verts, norms, uvs, idx = [], [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            normal = np.zeros(3)
            normal[axis] = sign
            # Tangent u and bitangent v with u x v = normal (counter-clockwise from outside).
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1.0
            v = np.cross(normal, u)
            base = len(verts)
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                verts.append((normal + du * u + dv * v) * half)
                norms.append(normal)
                uvs.append(((du + 1) / 2, (dv + 1) / 2))
            idx += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    v = np.array(verts) + np.asarray(center, dtype=np.float64)
    return _mesh(v, idx, norms, uvs)


def _ring(segments: int) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of ``segments + 1`` angles (the seam repeated), counter-clockwise seen from +y."""
    phi = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    # Counter-clockwise seen from +y means from +z towards +x: (x, z) = (sin, cos).
    return np.sin(phi), np.cos(phi)


def _cap(radius: float, y: float, segments: int, up: bool, offset: int) -> tuple:
    """A disk of ``segments`` at height ``y`` facing +y (``up``) or -y: centre vertex + ring."""
    s, c = _ring(segments)
    s, c = s[:-1], c[:-1]
    v = np.concatenate([[[0.0, y, 0.0]], np.stack([radius * s, np.full(segments, y), radius * c], -1)])
    n = np.tile([0.0, 1.0 if up else -1.0, 0.0], (segments + 1, 1))
    uv = np.concatenate([[[0.5, 0.5]], np.stack([0.5 + 0.5 * s, 0.5 + 0.5 * c], -1)])
    k = np.arange(segments)
    ring = 1 + k
    nxt = 1 + (k + 1) % segments
    centre = np.zeros(segments, dtype=np.int64)
    # Ring order is counter-clockwise seen from +y: (centre, ring, next) faces +y.
    tri = np.stack([centre, ring, nxt], -1) if up else np.stack([centre, nxt, ring], -1)
    return v, n, uv, tri + offset


def cylinder(radius: float = 1.0, height: float = 2.0, segments: int = 32, capped: bool = True) -> Mesh:
    """Cylinder on the y axis from -height/2 to +height/2; caps have their own vertices (sharp rims)."""
    segments = _check_segments(segments)
    s, c = _ring(segments)
    h = height / 2.0
    m = segments + 1
    side_v = np.concatenate(
        [np.stack([radius * s, np.full(m, -h), radius * c], -1), np.stack([radius * s, np.full(m, h), radius * c], -1)]
    )
    side_n = np.concatenate([np.stack([s, np.zeros(m), c], -1)] * 2)
    u = np.linspace(0.0, 1.0, m)
    side_uv = np.concatenate([np.stack([u, np.zeros(m)], -1), np.stack([u, np.ones(m)], -1)])
    # Rows: bottom (0), top (1); with b above a, (a, c, b) is outward.
    side_i = _grid(1, segments)[:, [0, 2, 1]]
    parts = [(side_v, side_n, side_uv, side_i)]
    if capped:
        off = len(side_v)
        top = _cap(radius, h, segments, True, off)
        bottom = _cap(radius, -h, segments, False, off + len(top[0]))
        parts += [top, bottom]
    return _join(parts)


def cone(radius: float = 1.0, height: float = 2.0, segments: int = 32, capped: bool = True) -> Mesh:
    """Cone on the y axis: base at y = -height/2, apex at +height/2 (one apex vertex per segment for smooth normals)."""
    segments = _check_segments(segments)
    s, c = _ring(segments)
    h = height / 2.0
    m = segments + 1
    slope = math.hypot(radius, height)
    ny, nr = radius / slope, height / slope
    base_v = np.stack([radius * s, np.full(m, -h), radius * c], -1)
    base_n = np.stack([nr * s, np.full(m, ny), nr * c], -1)
    # Apex copies carry the normal at the middle of their segment.
    mid = np.linspace(0.0, 2.0 * math.pi, m) + math.pi / segments
    apex_v = np.tile([0.0, h, 0.0], (m, 1))
    apex_n = np.stack([nr * np.sin(mid), np.full(m, ny), nr * np.cos(mid)], -1)
    u = np.linspace(0.0, 1.0, m)
    uv = np.concatenate(
        [np.stack([u, np.zeros(m)], -1), np.stack([np.minimum(u + 0.5 / segments, 1.0), np.ones(m)], -1)]
    )
    k = np.arange(segments)
    side_i = np.stack([k, k + 1, m + k], -1)  # base, next base, apex: outward
    parts = [(np.concatenate([base_v, apex_v]), np.concatenate([base_n, apex_n]), uv, side_i)]
    if capped:
        parts.append(_cap(radius, -h, segments, False, 2 * m))
    return _join(parts)


def torus(major_radius: float = 1.0, minor_radius: float = 0.25, segments: int = 32, sides: int | None = None) -> Mesh:
    """Torus around the y axis: ``segments`` around the ring, ``sides`` (default segments/2, >= 3) around the tube."""
    segments = _check_segments(segments)
    sides = max(3, segments // 2 if sides is None else int(sides))
    phi = np.linspace(0.0, 2.0 * math.pi, segments + 1)  # around the ring
    psi = np.linspace(0.0, 2.0 * math.pi, sides + 1)  # around the tube
    ps, ph = np.meshgrid(psi, phi, indexing="ij")  # rows: tube angle, columns: ring angle
    ring = np.stack([np.sin(ph), np.zeros_like(ph), np.cos(ph)], -1)
    up = np.array([0.0, 1.0, 0.0])
    n = np.cos(ps)[..., None] * ring + np.sin(ps)[..., None] * up
    v = major_radius * ring + minor_radius * n
    uv = np.stack([ph / (2 * math.pi), ps / (2 * math.pi)], -1)
    # Rows turn outward-then-up around the tube, columns counter-clockwise around y: (a, c, b) is outward.
    idx = _grid(sides, segments)[:, [0, 2, 1]]
    return _mesh(v.reshape(-1, 3), idx, n.reshape(-1, 3), uv.reshape(-1, 2))


def disk(radius: float = 1.0, segments: int = 32) -> Mesh:
    """Disk in the xz plane facing +y (one layer; engines light both sides)."""
    segments = _check_segments(segments)
    v, n, uv, tri = _cap(radius, 0.0, segments, True, 0)
    return _mesh(v, tri, n, uv)


def rectangle(size=(1.0, 1.0)) -> Mesh:
    """Rectangle of (x extent, z extent) in the xz plane facing +y: 4 vertices, 2 triangles."""
    hx, hz = size[0] / 2.0, size[1] / 2.0
    v = [(-hx, 0, hz), (hx, 0, hz), (hx, 0, -hz), (-hx, 0, -hz)]
    uv = [(0, 0), (1, 0), (1, 1), (0, 1)]
    n = np.tile([0.0, 1.0, 0.0], (4, 1))
    return _mesh(v, [(0, 1, 2), (0, 2, 3)], n, uv)


def heightfield(heights: np.ndarray, spacing=(1.0, 1.0)) -> Mesh:
    """Grid mesh of ``heights`` (R, C): x along columns, z along rows, centred, y = height, facing +y.

    Normals from central differences of the height function; u along x, v along z in [0, 1].
    """
    h = np.asarray(heights, dtype=np.float64)
    rows, cols = h.shape
    dx, dz = float(spacing[0]), float(spacing[1])
    x = (np.arange(cols) - (cols - 1) / 2.0) * dx
    z = (np.arange(rows) - (rows - 1) / 2.0) * dz
    xx, zz = np.meshgrid(x, z)
    v = np.stack([xx, h, zz], -1).reshape(-1, 3)
    gz, gx = np.gradient(h, dz, dx)
    n = np.stack([-gx, np.ones_like(h), -gz], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    uu, vv = np.meshgrid(np.linspace(0, 1, cols), np.linspace(0, 1, rows))
    uv = np.stack([uu, vv], -1).reshape(-1, 2)
    # Rows advance along +z, columns along +x: (a, b, c) = (x, z) -> (x, z+1) -> (x+1, z+1) faces +y.
    idx = _grid(rows - 1, cols - 1)
    return _mesh(v, idx, n.reshape(-1, 3), uv)


def _join(parts: list[tuple]) -> Mesh:
    v = np.concatenate([p[0] for p in parts])
    n = np.concatenate([p[1] for p in parts])
    uv = np.concatenate([p[2] for p in parts])
    i = np.concatenate([p[3] for p in parts])
    return _mesh(v, i, n, uv)


def merge_meshes(meshes: list[Mesh]) -> Mesh:
    """One mesh holding all of ``meshes`` (indices offset; texcoords kept only if all have them)."""
    offset = 0
    idx = []
    for m in meshes:
        idx.append(m.indices.astype(np.int64) + offset)
        offset += len(m.vertices)
    uv = None if any(m.texcoords is None for m in meshes) else np.concatenate([m.texcoords for m in meshes])
    return _mesh(
        np.concatenate([m.vertices for m in meshes]),
        np.concatenate(idx),
        np.concatenate([m.normals for m in meshes]),
        uv,
    )
