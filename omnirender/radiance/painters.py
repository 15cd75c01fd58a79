"""Default handlers of the Radiance engine (service ``"rad.paint"``).

Shapes Radiance has natively become its surfaces in world coordinates:
``Sphere`` a ``sphere``, ``Cylinder`` a ``cylinder`` with two ``ring`` caps,
``Cone`` a ``cone`` with a ``ring`` base, ``Disk`` a ``ring``, ``Rectangle``,
``Box`` (six) and plain ``Polygon`` outlines ``polygon``.  Round shapes need a
similarity transform (rotation, uniform scale, translation); under any other
matrix, with an active texture (for its texture coordinates) or under clip
planes they fall back to their simplifier, a triangle mesh.  Triangle sets
become ``obj2mesh`` meshes with a real modifier; clip planes cut them on the
CPU (:func:`omnirender.geometry.clip.clip_triangles`), as in the Mitsuba
engine.  Lines and points (also ``DrawStyle`` wireframe/points) become thin
``cylinder``\\ s and small ``sphere``\\ s sized in pixels like the GL engine draws
them.  Everything else reaches Radiance through the shapes' simplifiers.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..attributes import Background, ClipPlane, DrawStyle, Fog, LightSource
from ..attributes.environment import is_scene_background
from ..attributes.photometry import linear_to_srgb
from ..attributes.shadowing import check_light_shadows, register_shadowing_warnings
from ..attributes.surface import engine_appearance, track_surfaces, vertex_rgba
from ..core import AttributePainter, LightSwitch, ShapePainter, default_for, version_key
from ..geometry.clip import clip_segments, clip_triangles, keep_points
from ..geometry.pixels import pixel_size
from ..shapes import Box, Cone, Cylinder, Disk, LineSet, PointSet, Polygon, Rectangle, Sphere, TriangleSet
from . import rad
from .appearance import modifier
from .attributes import Options, Raw, Sky
from .engine import RadianceEngine
from .mesh import face_colors, obj_text, transform_mesh

__all__ = [
    "SpherePainter",
    "BoxPainter",
    "CylinderPainter",
    "ConePainter",
    "DiskPainter",
    "RectanglePainter",
    "PolygonPainter",
    "TriangleSetPainter",
    "LineSetPainter",
    "PointSetPainter",
    "LightPainter",
    "similarity_scale",
]

SERVICE = RadianceEngine.service

#: The eight corners of the unit box and its six faces (outward, counter-clockwise).
_BOX_CORNERS = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
_BOX_FACES = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])


def similarity_scale(matrix: np.ndarray, tol: float = 1e-6) -> float | None:
    """The uniform scale of a rotation-times-scale matrix (mirrors allowed), or None for any other matrix."""
    m = np.asarray(matrix, np.float64)[:3, :3]
    g = m.T @ m
    s = np.trace(g) / 3.0
    if s > 0.0 and bool(np.allclose(g, s * np.eye(3), atol=tol * s)):
        return float(np.sqrt(s))
    return None


def _point(m: np.ndarray, p: Any) -> np.ndarray:
    return m[:3, :3] @ np.asarray(p, np.float64) + m[:3, 3]


def _direction(m: np.ndarray, d: Any) -> np.ndarray:
    n = np.linalg.inv(m[:3, :3]).T @ np.asarray(d, np.float64)
    return n / np.linalg.norm(n)


def _model(engine: RadianceEngine) -> np.ndarray | None:
    """The model matrix; None when it squashes space flat (nothing is drawn, as in the POV-Ray engine).

    A matrix whose numbers overflowed is refused with the node, before anything is written.
    """
    m = engine.model_matrix()
    if not np.all(np.isfinite(m)):
        raise rad.RadError(
            f"{engine.owner()}: the accumulated transform is not finite (its numbers overflow); "
            "check the Translation/Scaling/Matrix attributes above this shape"
        )
    if abs(float(np.linalg.det(m[:3, :3]))) < 1e-300:
        return None
    return m


def _fallback(shape: Any, engine: RadianceEngine, needs_similarity: bool) -> tuple[np.ndarray, float] | None:
    """(model matrix, uniform scale) when ``shape`` can be written natively, else evaluate its simplification.

    None also when the matrix is flattened: nothing is drawn.
    """
    m = _model(engine)
    if m is None:
        return None
    scale = similarity_scale(m) if needs_similarity else 1.0
    if engine.clip_planes() or _textured(engine) or scale is None or _drawn_as_lines(engine):
        engine.simplify(shape)
        return None
    return m, scale


def _drawn_as_lines(engine: RadianceEngine) -> bool:
    style = engine.mono(DrawStyle)
    return style is not None and style.mode != "filled"


@default_for(RadianceEngine)
class SpherePainter(ShapePainter):
    """``Sphere`` -> ``sphere``."""

    __slots__ = ()
    service = SERVICE
    target = Sphere

    def exec(self, shape: Sphere, engine: RadianceEngine) -> None:
        found = _fallback(shape, engine, True)
        if found is not None:
            m, s = found
            engine.surface("sphere", [*_point(m, shape.center), shape.radius * s], modifier(engine))


@default_for(RadianceEngine)
class CylinderPainter(ShapePainter):
    """``Cylinder`` (axis +y, centred, capped) -> ``cylinder`` and two ``ring`` caps."""

    __slots__ = ()
    service = SERVICE
    target = Cylinder

    def exec(self, shape: Cylinder, engine: RadianceEngine) -> None:
        found = _fallback(shape, engine, True)
        if found is None:
            return
        m, s = found
        h, r = shape.height / 2.0, shape.radius * s
        bottom, top = _point(m, (0, -h, 0)), _point(m, (0, h, 0))
        up = _direction(m, (0, 1, 0))
        mod = modifier(engine)
        engine.surface("cylinder", [*bottom, *top, r], mod)
        engine.surface("ring", [*top, *up, 0, r], mod)
        engine.surface("ring", [*bottom, *(-up), 0, r], mod)


@default_for(RadianceEngine)
class ConePainter(ShapePainter):
    """``Cone`` (base at y = -height/2, apex at +height/2) -> ``cone`` and a ``ring`` base."""

    __slots__ = ()
    service = SERVICE
    target = Cone

    def exec(self, shape: Cone, engine: RadianceEngine) -> None:
        found = _fallback(shape, engine, True)
        if found is None:
            return
        m, s = found
        h, r = shape.height / 2.0, shape.radius * s
        base, apex = _point(m, (0, -h, 0)), _point(m, (0, h, 0))
        mod = modifier(engine)
        engine.surface("cone", [*base, *apex, r, 0], mod)
        engine.surface("ring", [*base, *(-_direction(m, (0, 1, 0))), 0, r], mod)


@default_for(RadianceEngine)
class DiskPainter(ShapePainter):
    """``Disk`` (xz plane, facing +y) -> ``ring`` with inner radius 0."""

    __slots__ = ()
    service = SERVICE
    target = Disk

    def exec(self, shape: Disk, engine: RadianceEngine) -> None:
        found = _fallback(shape, engine, True)
        if found is not None:
            m, s = found
            engine.surface(
                "ring", [*_point(m, (0, 0, 0)), *_direction(m, (0, 1, 0)), 0, shape.radius * s], modifier(engine)
            )


def _polygons(engine: RadianceEngine, m: np.ndarray, outlines: np.ndarray) -> None:
    """Write (K, N, 3) model-space outlines as polygons (reversed under a mirroring matrix)."""
    world = outlines @ m[:3, :3].T + m[:3, 3]
    if np.linalg.det(m[:3, :3]) < 0.0:
        world = world[:, ::-1]
    mod = modifier(engine)
    for outline in world:
        engine.surface("polygon", rad.rows_text(outline, engine.owner(), "polygon vertices"), mod, count=outline.size)


@default_for(RadianceEngine)
class BoxPainter(ShapePainter):
    """``Box`` -> six ``polygon``\\ s (any affine matrix)."""

    __slots__ = ()
    service = SERVICE
    target = Box

    def exec(self, shape: Box, engine: RadianceEngine) -> None:
        found = _fallback(shape, engine, False)
        if found is not None:
            corners = np.asarray(shape.center) + _BOX_CORNERS * np.asarray(shape.size)
            _polygons(engine, found[0], corners[_BOX_FACES])


@default_for(RadianceEngine)
class RectanglePainter(ShapePainter):
    """``Rectangle`` (xz plane, facing +y) -> ``polygon``."""

    __slots__ = ()
    service = SERVICE
    target = Rectangle

    def exec(self, shape: Rectangle, engine: RadianceEngine) -> None:
        found = _fallback(shape, engine, False)
        if found is not None:
            a, b = shape.size[0] / 2.0, shape.size[1] / 2.0
            outline = np.array([[[-a, 0, b], [a, 0, b], [a, 0, -b], [-a, 0, -b]]])
            _polygons(engine, found[0], outline)


@default_for(RadianceEngine)
class PolygonPainter(ShapePainter):
    """A plain ``Polygon`` -> ``polygon``; with per-vertex normals or colours its triangles are used."""

    __slots__ = ()
    service = SERVICE
    target = Polygon

    def exec(self, shape: Polygon, engine: RadianceEngine) -> None:
        if shape.color_array() is not None or shape.normal_array() is not None:
            engine.simplify(shape)
            return
        found = _fallback(shape, engine, False)
        if found is not None:
            _polygons(engine, found[0], np.asarray(shape.vertex_array(), np.float64)[None])


@default_for(RadianceEngine)
class TriangleSetPainter(ShapePainter):
    """``TriangleSet`` -> an ``obj2mesh`` mesh in world coordinates, with a real modifier.

    Normals are written unless ``DrawStyle(shading="flat")``; texture
    coordinates when a ``Texture`` is active.  Per-vertex colours become one
    material per distinct face colour stored in the mesh (each face names its
    own, so the mesh is used with the ``void`` modifier that selects them).
    """

    __slots__ = ()
    service = SERVICE
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: RadianceEngine) -> None:
        faces = shape.index_array()
        if len(faces) == 0:
            return
        style = engine.mono(DrawStyle)
        if style is not None and style.mode != "filled":
            _edges_or_points(shape, engine, style)
            return
        flat = style is not None and style.shading == "flat"
        textured = _textured(engine) and shape.texcoord_array() is not None
        colors = shape.color_array()
        m = _model(engine)
        if m is None:
            return
        planes = engine.clip_planes()
        key = (version_key(shape), m.tobytes(), flat, textured, tuple(r.tobytes() for r in planes))
        if colors is None:
            name = engine.add_mesh(key, lambda: _mesh_obj(shape, engine, m, planes, flat, textured))
            if name is not None:
                _mesh_surface(engine, name, modifier(engine, uv=textured))
            return
        # the colours' materials are stored in the mesh: its faces name them, selected by the void modifier
        key += (_appearance_key(engine), engine.coverage)
        name = engine.add_mesh(key, lambda: _mesh_obj(shape, engine, m, planes, flat, textured, with_colors=True))
        if name is not None:
            _mesh_surface(engine, name, "void")


def _textured(engine: RadianceEngine) -> bool:
    """Whether the appearance samples a texture Radiance draws (base colour, an ``om.Texture``, emissive)."""
    app = engine_appearance(engine)
    return app.texture is not None or app.emissive_texture is not None


def _appearance_key(engine: RadianceEngine) -> tuple:
    from .attributes import Material as RadMaterial

    material, color = engine.appearance()
    items = (engine.mono(RadMaterial), engine_appearance(engine).texture, material, color)
    return tuple(version_key(a) for a in items)


def _mesh_surface(engine: RadianceEngine, file_name: str, mod: str) -> None:
    ident = engine.new_id("o")
    path = engine.node_path
    head = rad.comment(path) + "\n" if path else ""
    engine.body.append(head + f"{rad.identifier(mod)} mesh {ident}\n1 {rad.token(file_name)}\n0\n0\n")


def _mesh_obj(
    shape: TriangleSet,
    engine: RadianceEngine,
    m: np.ndarray,
    planes: list[np.ndarray],
    flat: bool,
    textured: bool,
    with_colors: bool = False,
) -> tuple[str, str | None] | None:
    """(OBJ text, material text or None) of the shape in world coordinates, clipped; None if nothing is left."""
    vertices, faces, normals = transform_mesh(
        m, shape.vertex_array(), shape.index_array(), None if flat else shape.normal_array()
    )
    texcoords = shape.texcoord_array() if textured else None
    colors = shape.color_array() if with_colors else None
    if planes:
        vertices, faces, normals, texcoords, colors = clip_triangles(
            vertices, faces, planes, normals, texcoords, colors
        )
        if len(faces) == 0:
            return None
    faces = _with_area(vertices, faces)
    if len(faces) == 0:
        return None  # only degenerate triangles: obj2mesh would refuse a mesh without polygons
    if not with_colors:
        return obj_text(vertices, faces, normals, texcoords, owner=engine.owner()), None
    materials: list[str] = []
    # the appearance model's vertex colours (multiplied into a PBR base, alpha by the alpha mode), as display
    # values: the look of each face replaces the base colour with them
    rgba = vertex_rgba(engine_appearance(engine, texcoords=textured), colors)
    rgba[:, :3] = linear_to_srgb(rgba[:, :3])
    unique, groups = face_colors(rgba, faces)
    names = [modifier(engine, uv=textured, vertex_rgba=c, sink=materials) for c in unique]
    return obj_text(vertices, faces, normals, texcoords, groups, names, engine.owner()), "".join(materials)


def _with_area(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``faces`` without the triangles of zero area (collinear or repeated corners), which draw nothing."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces)
    cross = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    scale = np.abs(v).max(initial=1.0)
    return f[np.einsum("ij,ij->i", cross, cross) > (1e-12 * scale * scale) ** 2]


def _pixel(engine: RadianceEngine, world_points: np.ndarray) -> float:
    camera, _ = engine.camera_or_default()
    return pixel_size(camera, engine.world_view(), engine.size[1], world_points.mean(axis=0))


def _cylinders(engine: RadianceEngine, a: np.ndarray, b: np.ndarray, radius: float) -> None:
    keep = np.linalg.norm(b - a, axis=1) > 1e-9 * np.maximum(np.abs(a).max(axis=1, initial=1.0), 1.0)
    a, b = a[keep], b[keep]
    if len(a):
        engine.surfaces("cylinder", np.column_stack([a, b, np.full(len(a), radius)]), modifier(engine))


def _spheres(engine: RadianceEngine, centres: np.ndarray, radii: np.ndarray) -> None:
    if len(centres):
        engine.surfaces("sphere", np.column_stack([centres, radii]), modifier(engine))


def _world(engine: RadianceEngine, points: Any) -> np.ndarray:
    m = _model(engine)
    if m is None:
        m = engine.model_matrix()  # flattened: lines and points still have a place
    return np.asarray(points, np.float64) @ m[:3, :3].T + m[:3, 3]


def _edges_or_points(shape: TriangleSet, engine: RadianceEngine, style: DrawStyle) -> None:
    """A triangle set drawn as ``DrawStyle(mode="wireframe")`` cylinders or ``mode="points"`` spheres."""
    points = _world(engine, shape.vertex_array())
    unit = _pixel(engine, points)
    planes = engine.clip_planes()
    if style.mode == "points":
        if planes:
            points = points[keep_points(points, planes)]
        _spheres(engine, points, np.full(len(points), 0.5 * style.point_size * unit))
        return
    tri = shape.index_array()
    edges = np.unique(np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1), axis=0)
    a, b = points[edges[:, 0]], points[edges[:, 1]]
    if planes:
        a, b, _ = clip_segments(a, b, planes)
    _cylinders(engine, a, b, 0.5 * style.line_width * unit)


@default_for(RadianceEngine)
class LineSetPainter(ShapePainter):
    """``LineSet`` -> ``cylinder``\\ s ``DrawStyle.line_width`` pixels thick (1 by default)."""

    __slots__ = ()
    service = SERVICE
    target = LineSet

    def exec(self, shape: LineSet, engine: RadianceEngine) -> None:
        segments = np.asarray(shape.index_array()).reshape(-1, 2)
        if len(segments) == 0:
            return
        points = _world(engine, shape.vertex_array())
        style = engine.mono(DrawStyle)
        width = style.line_width if style is not None else 1.0
        a, b = points[segments[:, 0]], points[segments[:, 1]]
        if engine.clip_planes():
            a, b, _ = clip_segments(a, b, engine.clip_planes())
        _cylinders(engine, a, b, 0.5 * width * _pixel(engine, points))


@default_for(RadianceEngine)
class PointSetPainter(ShapePainter):
    """``PointSet`` -> ``sphere``\\ s of ``sizes`` or ``DrawStyle.point_size`` pixels (1 by default)."""

    __slots__ = ()
    service = SERVICE
    target = PointSet

    def exec(self, shape: PointSet, engine: RadianceEngine) -> None:
        points = _world(engine, shape.vertex_array())
        if len(points) == 0:
            return
        style = engine.mono(DrawStyle)
        size = style.point_size if style is not None else 1.0
        sizes = shape.size_array()
        pixels = np.asarray(sizes, np.float64).reshape(-1) if sizes is not None else np.full(len(points), size)
        radii = 0.5 * pixels * _pixel(engine, points)
        if engine.clip_planes():
            inside = keep_points(points, engine.clip_planes())
            points, radii = points[inside], radii[inside]
        _spheres(engine, points, radii)


# -- attributes -------------------------------------------------------------
track_surfaces(RadianceEngine)  # Color / Material / PBRMaterial in activation order


def _light_matrix(light: Any, engine: RadianceEngine) -> np.ndarray:
    for other, matrix in engine.lights():
        if other is light:
            return matrix
    return engine.model_matrix()


@default_for(RadianceEngine)
class LightPainter(AttributePainter):
    """Generic lights (and ``om.radiance.Sky``) -> queued for conversion (see :mod:`.lights`)."""

    __slots__ = ()
    service = SERVICE
    target = LightSource

    def exec(self, light: Any, engine: RadianceEngine) -> None:
        check_light_shadows(engine, light, "Radiance")
        if not any(light is other for other, _ in engine.pending_lights):
            engine.pending_lights.append((light, np.array(_light_matrix(light, engine))))


default_for(RadianceEngine)(type("SkyPainter", (LightPainter,), {"__slots__": (), "target": Sky}))
# every Radiance source casts shadows onto every surface, and mirrors are not converted: warnings say so
register_shadowing_warnings(RadianceEngine, "Radiance", mirror=False)


def _recorder(target: type, attribute: str, accept: Any = None) -> type:
    def exec(self: Any, value: Any, engine: RadianceEngine) -> None:
        if accept is None or (getattr(engine, attribute) is None and accept(value, engine)):
            setattr(engine, attribute, value)

    cls = type(
        f"{target.__name__}Painter",
        (AttributePainter,),
        {"__slots__": (), "service": SERVICE, "target": target, "exec": exec},
    )
    return default_for(RadianceEngine)(cls)


BackgroundPainter = _recorder(Background, "background", is_scene_background)  # the scene's background
FogPainter = _recorder(Fog, "fog")
OptionsPainter = _recorder(Options, "options")  # the last one met applies


@default_for(RadianceEngine)
class LightSwitchPainter(AttributePainter):
    """``LightSwitch`` cannot be expressed in Radiance (no light linking): a warning names the node, once."""

    __slots__ = ()
    service = SERVICE
    target = LightSwitch

    def exec(self, switch: LightSwitch, engine: RadianceEngine) -> None:
        if not engine.warned_light_switch:
            engine.warned_light_switch = True
            warnings.warn(
                f"Radiance: the LightSwitch in node {engine.node_path or '/'} is ignored: Radiance lights every "
                "surface with every source (render with another engine for per-subgraph lights)",
                stacklevel=2,
            )


@default_for(RadianceEngine)
class RawPainter(AttributePainter):
    """``om.radiance.Raw``: trusted text written where it is met."""

    __slots__ = ()
    service = SERVICE
    target = Raw

    def exec(self, raw: Raw, engine: RadianceEngine) -> None:
        engine.raw(raw.text)


@default_for(RadianceEngine)
class ClipPlanePainter(AttributePainter):
    """``ClipPlane``: remembered in world coordinates while active; the shape painters clip against it."""

    __slots__ = ()
    service = SERVICE
    target = ClipPlane

    def exec(self, plane: ClipPlane, engine: RadianceEngine) -> None:
        engine.add_clip(plane)

    def unexec(self, plane: ClipPlane, engine: RadianceEngine) -> None:
        engine.remove_clip(plane)


from . import splats as _splats  # noqa: E402,F401  (registers the Gaussian splats handler)
