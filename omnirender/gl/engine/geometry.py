"""GPU geometry: vertex and index buffers uploaded once per (shape, version).

A :class:`Geometry` keeps the validated CPU arrays and uploads them lazily on
first draw; :class:`GeometryCache` finds the geometry of a shape by its id and
version (checking a weak reference so a recycled id never aliases), and
releases the GPU buffers of geometries the last compiled draw list no longer
uses.  Unit meshes (sphere, box, cylinder) are shared by every instance of the
native painters.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ...attributes.photometry import srgb_to_linear

__all__ = ["Geometry", "GeometryCache", "unit_mesh", "validate_mesh", "CLOSED"]


class Geometry:
    """Vertex arrays (positions, normals, optional colours, texcoords, sizes) and optional indices."""

    __slots__ = (
        "mode",
        "positions",
        "normals",
        "colors",
        "texcoords",
        "texcoords1",
        "tangent_source",
        "sizes",
        "indices",
        "bounds",
        "buffers",
        "count",
        "persistent",
        "label",
        "translucent",
        "closed",
        "__weakref__",
    )
    #: program features and uniforms of geometry drawn by its own shader stages (NURBS patches); none for meshes
    program_features: tuple = ()
    program_uniforms: tuple = ()

    def __init__(
        self,
        mode: str,
        positions: np.ndarray,
        normals: np.ndarray | None = None,
        colors: np.ndarray | None = None,
        texcoords: np.ndarray | None = None,
        sizes: np.ndarray | None = None,
        indices: np.ndarray | None = None,
        persistent: bool = False,
        label: str = "",
        closed: bool = False,
        texcoords1: np.ndarray | None = None,
        tangents: Any = None,
    ) -> None:
        name = label or "Geometry"
        if mode not in _ARITY:
            raise ValueError(f"{name}: mode {mode!r} is not one of {sorted(_ARITY)}; fix the painter")
        self.mode = mode  # "triangles", "lines" or "points"
        self.positions = _vertex_array(positions, 3, "vertices", name)
        n = len(self.positions)
        normals = None if normals is None else _vertex_array(normals, 3, "normals", name, n)
        if colors is not None:
            colors = _vertex_array(colors, 4, "colours", name, n)
        texcoords = None if texcoords is None else _vertex_array(texcoords, 2, "texture coordinates", name, n)
        if sizes is not None:
            sizes = _vertex_array(np.asarray(sizes).reshape(-1, 1), 1, "sizes", name, n).reshape(-1)
        indices = None if indices is None else _index_array(indices, n, _ARITY[mode], name)
        self.normals = normals
        if colors is not None:
            # per-vertex colours are display (sRGB) values; the GPU gets them linear (alpha unchanged)
            colors = np.array(colors, dtype=np.float32)
            rgb = colors[:, :3]
            colors[:, :3] = srgb_to_linear(rgb)
        self.colors = colors
        self.texcoords = None if texcoords is None else np.ascontiguousarray(texcoords, dtype=np.float32)
        if texcoords1 is not None:
            texcoords1 = _vertex_array(texcoords1, 2, "texture coordinates (set 1)", name, n)
        self.texcoords1 = texcoords1
        #: tangents (N, 4) or a callable computing them, uploaded only for programs that read them (normal maps)
        self.tangent_source = tangents
        self.sizes = None if sizes is None else np.ascontiguousarray(sizes, dtype=np.float32)
        self.indices = indices
        p = self.positions
        self.bounds = (p.min(axis=0).astype(np.float64), p.max(axis=0).astype(np.float64))
        self.buffers: dict[str, Any] | None = None
        self.count = len(self.indices) if self.indices is not None else len(p)
        self.persistent = persistent
        self.label = label
        #: a closed, consistently wound surface (its back faces may be culled when opaque)
        self.closed = closed
        self.translucent = bool(self.colors is not None and len(self.colors) and self.colors[:, 3].min() < 1.0)

    @property
    def uploaded(self) -> bool:
        return self.buffers is not None

    def upload(self, ctx: Any) -> dict[str, Any]:
        """Create the GPU buffers (once); returns name -> moderngl Buffer."""
        if self.buffers is None:
            from .resources import gpu_call

            bufs: dict[str, Any] = {}
            try:
                bufs["in_position"] = gpu_call(ctx.buffer, self.positions, what=f"vertices of {self.label}")
                for name, arr in (
                    ("in_normal", self.normals),
                    ("in_color", self.colors),
                    ("in_texcoord", self.texcoords),
                    ("in_size", self.sizes),
                ):
                    if arr is not None:
                        bufs[name] = gpu_call(ctx.buffer, arr, what=f"{name[3:]}s of {self.label}")
                if self.indices is not None:
                    bufs["index"] = gpu_call(ctx.buffer, self.indices, what=f"indices of {self.label}")
            except Exception:
                for b in bufs.values():
                    b.release()
                raise
            self.buffers = bufs
        return self.buffers

    def adjacency_buffer(self, ctx: Any) -> Any:
        """The ``triangles_adjacency`` index buffer (made on first use: shadow volumes need it)."""
        bufs = self.upload(ctx)
        found = bufs.get("adjacency")
        if found is None:
            from ...geometry.topology import adjacency_indices
            from .resources import gpu_call

            tris = self.indices if self.indices is not None else np.arange(len(self.positions), dtype=np.uint32)
            data = adjacency_indices(self.positions, tris)
            found = bufs["adjacency"] = gpu_call(ctx.buffer, data, what=f"adjacency of {self.label}")
        return found

    def _lazy_buffers(self, program: Any) -> None:
        """Upload the second UV set and the tangents the first time a program reads them."""
        from .resources import gpu_call

        bufs = self.buffers
        assert bufs is not None
        for name, source in (("in_texcoord1", self.texcoords1), ("in_tangent", self.tangent_source)):
            if name in bufs or source is None:
                continue
            try:
                program[name]
            except KeyError:
                continue
            arr = source() if callable(source) else source
            if arr is None:
                continue
            data = np.ascontiguousarray(arr, dtype=np.float32)
            bufs[name] = gpu_call(self._ctx_of(bufs), data, what=f"{name[3:]} of {self.label}")

    @staticmethod
    def _ctx_of(bufs: dict[str, Any]) -> Any:
        return bufs["in_position"].ctx.buffer

    def release(self) -> None:
        """Free the GPU buffers (the CPU arrays stay, so the geometry can upload again)."""
        if self.buffers is not None:
            for b in self.buffers.values():
                b.release()
            self.buffers = None

    def content(self, program: Any) -> list[tuple]:
        """moderngl vertex-array content for the per-vertex attributes ``program`` uses."""
        bufs = self.buffers
        assert bufs is not None
        self._lazy_buffers(program)
        out = []
        for name, fmt in _FORMATS.items():
            if name in bufs:
                try:
                    program[name]
                except KeyError:
                    continue
                out.append((bufs[name], fmt, name))
        return out


_ARITY = {"triangles": 3, "lines": 2, "points": 1}
_FORMATS = {
    "in_position": "3f",
    "in_normal": "3f",
    "in_color": "4f",
    "in_texcoord": "2f",
    "in_texcoord1": "2f",
    "in_tangent": "4f",
    "in_size": "1f",
}


def _vertex_array(values: Any, width: int, what: str, name: str, count: int | None = None) -> np.ndarray:
    """Per-vertex data as a contiguous (N, width) float32 array; ValueError for a bad shape or non-finite values."""
    try:
        arr = np.asarray(values)
        if arr.dtype.kind not in "biuf":
            arr = arr.astype(np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: {what} are not numbers ({exc}); fix the array the painter submits") from None
    if arr.ndim != 2 or arr.shape[1] != width:
        raise ValueError(f"{name}: {what} have shape {arr.shape}, expected (N, {width}); fix the array's shape")
    if count is None and len(arr) == 0:
        raise ValueError(f"{name}: no vertices; give at least one primitive")
    if count is not None and len(arr) != count:
        raise ValueError(f"{name}: {len(arr)} {what} for {count} vertices; give one per vertex")
    finite = np.isfinite(arr).all(axis=1)
    if not finite.all():
        bad = int(np.argmin(finite))
        raise ValueError(f"{name}: {what}[{bad}] = {arr[bad].tolist()} is not finite; fix the {what}")
    return np.ascontiguousarray(arr, dtype=np.float32)


def _index_array(values: Any, count: int, arity: int, name: str) -> np.ndarray:
    """Indices as a flat uint32 array; ValueError (before any cast) for non-integers, negatives, out-of-range."""
    arr = np.asarray(values).reshape(-1)
    if arr.size and arr.dtype.kind not in "iu":
        if arr.dtype.kind != "f" or not np.all(np.isfinite(arr)) or not np.all(arr == np.round(arr)):
            raise ValueError(f"{name}: indices must be whole numbers (got dtype {arr.dtype}); fix the index array")
    if arr.size:
        lo, hi = arr.min(), arr.max()
        if lo < 0:
            raise ValueError(f"{name}: index {int(lo)} is negative; indices must be >= 0; fix the index array")
        if hi >= count:
            raise ValueError(
                f"{name}: index {int(hi)} is out of range for {count} vertices (valid 0..{count - 1}); "
                "indices must be < number of vertices; fix the index array"
            )
    if arr.size % arity:
        raise ValueError(f"{name}: {arr.size} indices is not a multiple of {arity}; fix the index array")
    return np.ascontiguousarray(arr, dtype=np.uint32)


def validate_mesh(positions: np.ndarray, indices: np.ndarray | None, owner: str, path: str, arity: int = 3) -> None:
    """Raise ValueError (naming the shape and node path) for non-finite vertices or out-of-range indices."""
    where = f" in node {path}" if path else ""
    n = len(positions)
    if n == 0:
        raise ValueError(f"{owner}{where}: no vertices; give at least one primitive")
    if not np.all(np.isfinite(positions)):
        bad = int(np.argmax(~np.all(np.isfinite(positions), axis=1)))
        raise ValueError(f"{owner}{where}: vertex {bad} is not finite ({positions[bad].tolist()}); fix the vertex data")
    if indices is not None and indices.size:
        top = int(indices.max())
        if top >= n:
            raise ValueError(
                f"{owner}{where}: index {top} is out of range for {n} vertices (valid 0..{n - 1}); "
                f"fix the indices before rendering"
            )
        if indices.size % arity:
            raise ValueError(f"{owner}{where}: {indices.size} indices is not a multiple of {arity}")


class GeometryCache:
    """Geometry per (shape id, version, variant), verified through a weak reference to the shape."""

    def __init__(self) -> None:
        self._entries: dict[tuple, tuple[Any, Geometry]] = {}

    def get(self, shape: Any, variant: Any = None) -> Geometry | None:
        entry = self._entries.get((id(shape), shape.version, variant))
        if entry is not None and entry[0]() is shape:
            return entry[1]
        return None

    def put(self, shape: Any, geometry: Geometry, variant: Any = None) -> Geometry:
        self._entries[(id(shape), shape.version, variant)] = (weakref.ref(shape), geometry)
        return geometry

    def sweep(self, used: set[int]) -> int:
        """Release geometries whose id is not in ``used`` (ids of geometries in the draw list); returns the count."""
        released = 0
        for key, (ref, geom) in list(self._entries.items()):
            if id(geom) not in used or ref() is None:
                if id(geom) not in used:
                    geom.release()
                    released += 1
                del self._entries[key]
        return released

    def __len__(self) -> int:
        return len(self._entries)

    def geometries(self) -> list[Geometry]:
        return [g for _, g in self._entries.values()]


# -- unit meshes ---------------------------------------------------------------
#: Closed unit meshes: their back faces are never seen when they are opaque.
CLOSED = frozenset({"sphere", "box", "cylinder", "cone"})


def unit_mesh(kind: str, level: int = 3) -> Geometry:
    """The unit shape the native painters scale per instance, from the shared tessellation.

    Sphere radius 1; box edge 1; cylinder and cone radius 1, y in [-1, 1]; disk
    radius 1 and rectangle 1 x 1 in the xz plane facing +y.  ``level`` is the
    Tessellation level: 4 * 2**level segments around (32 at the default 3, the
    simplifiers' density, so wireframes look alike), at least 8, at most 512.
    """
    from ...geometry import tessellate

    seg = min(512, max(8, 4 * 2 ** int(level)))
    if kind == "sphere":
        m = tessellate.sphere(1.0, segments=seg)
    elif kind == "box":
        m = tessellate.box((1.0, 1.0, 1.0))
    elif kind == "cylinder":
        m = tessellate.cylinder(1.0, 2.0, seg)
    elif kind == "cone":
        m = tessellate.cone(1.0, 2.0, seg)
    elif kind == "disk":
        m = tessellate.disk(1.0, seg)
    elif kind == "rectangle":
        m = tessellate.rectangle((1.0, 1.0))
    else:
        raise ValueError(f"unit_mesh: unknown kind {kind!r}")
    from ...geometry.normals import vertex_tangents

    def tangents() -> np.ndarray:
        return vertex_tangents(m.vertices, m.indices, m.normals, m.texcoords)

    return Geometry(
        "triangles",
        m.vertices,
        m.normals,
        texcoords=m.texcoords,
        indices=m.indices,
        persistent=True,
        label=f"unit {kind}",
        closed=kind in CLOSED,
        tangents=tangents if m.texcoords is not None else None,
    )
