"""Default simplifiers: every shape ends in TriangleSets (or LineSets/PointSets) on every engine.

They are registered for :class:`omnirender.Engine`, so any engine without a
painter for a shape still shows it; painters are optional speed-ups.  Curved
shapes read the density from the context's ``Tessellation`` mono attribute
(``Tessellation.segments(base)``; base 4 around a full circle, i.e. 32 at the
default level 3).  Results are cached per (shape, version, level) in a
weak-keyed table, so evaluating a scene again neither re-tessellates nor hands
the engine new objects (engines that upload per (shape, version) reuse theirs).

Dependency rule exception (deliberate, decided by the lead, who documents it in
DESIGN.md): shapes import only core/data/geometry, but two simplifiers need
attribute classes: ``Tessellation`` (to read the density) and
``Material``/``PBRMaterial``/``Texture`` (MeshFile parts).  They are imported
LAZILY inside the functions that need them, never at module level, so
importing ``omnirender.shapes`` does not import ``omnirender.attributes``.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np

from ..core import Engine, Matrix, Shape, ShapeSimplifier, Translation, default_for
from ..geometry import tessellate
from ..geometry.isosurface import isosurface
from ..geometry.matrix import align_y_matrix
from .files import MeshFile
from .grids import Heightfield, Volume
from .meshes import Polygon, Polyline, TriangleSet
from .primitives import Arrow, Box, Cone, Cylinder, Disk, Rectangle, Sphere, Torus
from .text import Text

__all__ = [
    "tessellation_level",
    "segments",
    "clear_cache",
    "SphereSimplifier",
    "BoxSimplifier",
    "CylinderSimplifier",
    "ConeSimplifier",
    "TorusSimplifier",
    "DiskSimplifier",
    "RectangleSimplifier",
    "ArrowSimplifier",
    "PolygonSimplifier",
    "PolylineSimplifier",
    "HeightfieldSimplifier",
    "VolumeSimplifier",
    "MeshFileSimplifier",
    "MeshPart",
    "MeshPartSimplifier",
    "TextSimplifier",
]

#: Level used when the context has no Tessellation (same as Tessellation.DEFAULT_LEVEL).
DEFAULT_LEVEL = 3

_tessellation_class: Any = None


def _tessellation() -> Any:
    """The Tessellation attribute class (imported lazily: attributes are a sibling declaration package)."""
    global _tessellation_class
    if _tessellation_class is None:
        # Deliberate exception to the dependency rule: lazy import of an attribute class (see the module docstring).
        try:
            from ..attributes import Tessellation
        except ImportError:  # pragma: no cover - attributes always ship with shapes
            return None
        _tessellation_class = Tessellation
    return _tessellation_class


def tessellation_level(engine: Engine) -> int:
    """The active ``Tessellation.level`` of ``engine`` (:data:`DEFAULT_LEVEL` without one)."""
    cls = _tessellation()
    t = None if cls is None else engine.mono(cls)
    return DEFAULT_LEVEL if t is None else int(t.level)


def segments(level: int, base: int = 4) -> int:
    """Segments for a quantity that has ``base`` segments at level 0: ``max(3, base * 2**level)``."""
    return max(3, int(base) * 2 ** int(level))


# -- cache --------------------------------------------------------------------
_cache: weakref.WeakKeyDictionary[Any, tuple[int, int, list[Any]]] = weakref.WeakKeyDictionary()
_lock = threading.Lock()


def clear_cache() -> None:
    """Forget every cached simplification."""
    with _lock:
        _cache.clear()


def cached(shape: Any, level: int, build: Callable[[], list[Any]]) -> list[Any]:
    """``build()`` once per (shape, version, level)."""
    entry = _cache.get(shape)
    version = shape.version
    if entry is not None and entry[0] == version and entry[1] == level:
        return entry[2]
    result = build()
    with _lock:
        _cache[shape] = (version, level, result)
    return result


def _triangles(mesh: tessellate.Mesh, colors: Any = None) -> TriangleSet:
    return TriangleSet(mesh.vertices, mesh.indices, normals=mesh.normals, colors=colors, texcoords=mesh.texcoords)


class _Tessellated(ShapeSimplifier):
    """Base of simplifiers whose result depends on the tessellation level."""

    __slots__ = ()

    def exec(self, shape: Any, engine: Engine) -> list[Any]:
        level = tessellation_level(engine)
        return cached(shape, level, lambda: self.build(shape, level))

    def build(self, shape: Any, level: int) -> list[Any]:  # pragma: no cover - abstract
        raise NotImplementedError


class _Fixed(ShapeSimplifier):
    """Base of simplifiers whose result depends on the shape only."""

    __slots__ = ()

    def exec(self, shape: Any, engine: Engine) -> list[Any]:
        return cached(shape, -1, lambda: self.build(shape))

    def build(self, shape: Any) -> list[Any]:  # pragma: no cover - abstract
        raise NotImplementedError


@default_for(Engine)
class SphereSimplifier(_Tessellated):
    """Sphere -> UV-sphere TriangleSet (``segments(level)`` around, half as many rings)."""

    __slots__ = ()
    target = Sphere

    def build(self, shape: Sphere, level: int) -> list[Any]:
        return [_triangles(tessellate.sphere(shape.radius, shape.center, segments(level)))]


@default_for(Engine)
class BoxSimplifier(_Fixed):
    """Box -> 12 triangles with flat faces."""

    __slots__ = ()
    target = Box

    def build(self, shape: Box) -> list[Any]:
        return [_triangles(tessellate.box(shape.size, shape.center))]


@default_for(Engine)
class CylinderSimplifier(_Tessellated):
    """Cylinder -> capped TriangleSet with sharp rims."""

    __slots__ = ()
    target = Cylinder

    def build(self, shape: Cylinder, level: int) -> list[Any]:
        return [_triangles(tessellate.cylinder(shape.radius, shape.height, segments(level)))]


@default_for(Engine)
class ConeSimplifier(_Tessellated):
    """Cone -> TriangleSet with a flat base."""

    __slots__ = ()
    target = Cone

    def build(self, shape: Cone, level: int) -> list[Any]:
        return [_triangles(tessellate.cone(shape.radius, shape.height, segments(level)))]


@default_for(Engine)
class TorusSimplifier(_Tessellated):
    """Torus -> TriangleSet (``segments(level)`` around the ring, half as many around the tube)."""

    __slots__ = ()
    target = Torus

    def build(self, shape: Torus, level: int) -> list[Any]:
        n = segments(level)
        return [_triangles(tessellate.torus(shape.major_radius, shape.minor_radius, n, max(3, n // 2)))]


@default_for(Engine)
class DiskSimplifier(_Tessellated):
    """Disk -> triangle fan facing +y."""

    __slots__ = ()
    target = Disk

    def build(self, shape: Disk, level: int) -> list[Any]:
        return [_triangles(tessellate.disk(shape.radius, segments(level)))]


@default_for(Engine)
class RectangleSimplifier(_Fixed):
    """Rectangle -> two triangles facing +y."""

    __slots__ = ()
    target = Rectangle

    def build(self, shape: Rectangle) -> list[Any]:
        return [_triangles(tessellate.rectangle(shape.size))]


@default_for(Engine)
class ArrowSimplifier(_Fixed):
    """Arrow -> [Matrix (start, turned to the arrow), Cylinder (shaft), Translation (along it), Cone (head)].

    The pushed transforms are scoped to the arrow (the engine pops them after
    the result).  The shaft is left out when the head takes the whole length.
    """

    __slots__ = ()
    target = Arrow

    def build(self, shape: Arrow) -> list[Any]:
        start = np.asarray(shape.start)
        direction = np.asarray(shape.end) - start
        length = float(np.linalg.norm(direction))
        head_radius, head_length = shape.effective_head()
        shaft = length - head_length
        out: list[Any] = []
        if shaft > 1e-9 * length:
            out.append(Matrix(align_y_matrix(start + direction / length * (shaft / 2.0), direction)))
            out.append(Cylinder(shape.radius, shaft))
            out.append(Translation(0.0, (shaft + head_length) / 2.0, 0.0))
        else:
            out.append(Matrix(align_y_matrix(start + direction / length * (head_length / 2.0), direction)))
        out.append(Cone(head_radius, head_length))
        return out


@default_for(Engine)
class PolygonSimplifier(_Fixed):
    """Polygon -> TriangleSet by ear clipping; normals given per vertex or the plane's normal."""

    __slots__ = ()
    target = Polygon

    def build(self, shape: Polygon) -> list[Any]:
        from ..geometry.triangulate import newell_normal

        v = shape.vertex_array()
        normals = shape.normal_array()
        if normals is None:
            n = newell_normal(v)
            normals = np.tile(n / np.linalg.norm(n), (len(v), 1))
        return [TriangleSet(v, shape.triangle_indices(), normals=normals, colors=shape.color_array())]


@default_for(Engine)
class PolylineSimplifier(_Fixed):
    """Polyline -> LineSet of its segments."""

    __slots__ = ()
    target = Polyline

    def build(self, shape: Polyline) -> list[Any]:
        from .meshes import LineSet

        return [LineSet(shape.vertex_array(), shape.index_array(), colors=shape.color_array())]


@default_for(Engine)
class HeightfieldSimplifier(_Fixed):
    """Heightfield -> grid TriangleSet facing +y (two triangles per cell)."""

    __slots__ = ()
    target = Heightfield

    def build(self, shape: Heightfield) -> list[Any]:
        return [_triangles(tessellate.heightfield(shape.height_array(), shape.spacing))]


@default_for(Engine)
class VolumeSimplifier(_Fixed):
    """Volume -> its isosurface at ``iso_level()`` (marching cubes, capped at the grid boundary).

    The surface is coloured with the transfer function's colour at the level
    (opaque).  Nothing when the level lies outside the data.
    """

    __slots__ = ()
    target = Volume

    def build(self, shape: Volume) -> list[Any]:
        level = shape.iso_level()
        mesh = isosurface(shape.data_array(), level, shape.spacing)
        if mesh is None:
            return []
        rgba = shape.transfer_function.lookup(level)
        rgba[3] = 1.0
        return [_triangles(mesh, colors=rgba)]


@default_for(Engine)
class MeshFileSimplifier(_Fixed):
    """MeshFile -> per part: its material (om.Material / om.PBRMaterial, and om.Texture) then its TriangleSet.

    Each part's attributes are scoped to the part.  Loading errors
    (malformed file) propagate as ValueError naming the path.
    """

    __slots__ = ()
    target = MeshFile

    def exec(self, shape: MeshFile, engine: Engine) -> list[Any]:
        try:
            return super().exec(shape, engine)
        except (ValueError, FileNotFoundError) as exc:
            raise type(exc)(f"{exc} (MeshFile in node {engine.node_path!r}; fix or replace the file)") from None

    def build(self, shape: MeshFile) -> list[Any]:
        out: list[Any] = []
        for material, triangles in shape.parts():
            attrs = _material_attributes(material, triangles.texcoord_array() is not None)
            out.append(MeshPart([*attrs, triangles]) if attrs else triangles)
        return out


class MeshPart(Shape):
    """A part of a MeshFile with its own attributes: simplifies to them and its TriangleSet, scoped.

    (The engine pops what a simplifier's result pushed, so one part's material
    never leaks onto the next part.)
    """

    __slots__ = ("items",)

    def __init__(self, items: list[Any]) -> None:
        super().__init__()
        self.items = tuple(items)


@default_for(Engine)
class MeshPartSimplifier(ShapeSimplifier):
    """MeshPart -> its attributes and triangles."""

    __slots__ = ()
    target = MeshPart

    def exec(self, shape: MeshPart, engine: Engine) -> list[Any]:
        return list(shape.items)


def _material_attributes(material: dict[str, Any] | None, has_texcoords: bool) -> list[Any]:
    if material is None:
        return []
    # Deliberate exception to the dependency rule: lazy import of attribute classes (see the module docstring).
    try:
        from .. import attributes
    except ImportError:  # pragma: no cover
        return []
    params = dict(material)
    kind = params.pop("kind", "phong")
    if kind == "attributes":  # a glTF part: the importer's attributes as they are
        return list(params["attributes"])
    texture = params.pop("texture", None)
    out: list[Any] = []
    try:
        if kind == "pbr" and hasattr(attributes, "PBRMaterial"):
            out.append(attributes.PBRMaterial(**params))
        elif hasattr(attributes, "Material"):
            out.append(attributes.Material(**params))
        if texture is not None and has_texcoords and hasattr(attributes, "Texture"):
            out.append(attributes.Texture(texture))
    except (TypeError, ValueError):
        return out
    return out


@default_for(Engine)
class TextSimplifier(ShapeSimplifier):
    """Text -> nothing: 3D engines without a text painter skip labels quietly."""

    __slots__ = ()
    target = Text

    def exec(self, shape: Text, engine: Engine) -> list[Any]:
        return []
