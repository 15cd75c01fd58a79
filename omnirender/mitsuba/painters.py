"""Default handlers of the Mitsuba engine (service ``"mitsuba.paint"``).

Shapes Mitsuba has natively (sphere, cube, cylinder, disk, rectangle) become
shape plugins with ``to_world`` = model matrix times the shape's own frame;
Mitsuba's quadrics are in its own frames (z-up disk and rectangle, cylinder
from p0 to p1, open), so the painters add the rotation and, for the cylinder,
the two cap disks.  Sphere and cylinder refuse non-uniform scaling in Mitsuba:
under such a matrix they fall back to their simplifier (a mesh).  Triangle
sets become in-memory meshes.  Cones, tori and all other shapes reach Mitsuba
through their simplifiers.  Lines and points become thin tubes and small
spheres sized in pixels like the GL engine draws them (see :mod:`.strokes`).

Mitsuba has no clip planes, so under an active ``ClipPlane`` the geometry is
clipped before Mitsuba sees it: native shapes fall back to their simplifiers,
triangle sets are clipped (:func:`omnirender.geometry.clip.clip_triangles`),
segments are shortened and points outside are dropped, as the GL engine's
``gl_ClipDistance`` does; a shape clipped away entirely adds nothing.
"""

from __future__ import annotations

import math

import numpy as np

from ..attributes import Background, ClipPlane, DrawStyle, LightSource
from ..attributes.environment import is_scene_background
from ..attributes.shadowing import check_light_shadows, register_shadowing_warnings
from ..attributes.surface import track_surfaces
from ..core import AttributePainter, ShapePainter, default_for
from ..geometry.clip import clip_segments, clip_triangles, keep_points
from ..shapes import Box, Cylinder, Disk, LineSet, PointSet, Rectangle, Sphere, TriangleSet
from . import convert, strokes
from ._mi import transform
from .attributes import Emitter, Integrator
from .engine import MitsubaEngine
from .mesh import build_mesh, transform_points

__all__ = [
    "SpherePainter",
    "BoxPainter",
    "CylinderPainter",
    "DiskPainter",
    "RectanglePainter",
    "TriangleSetPainter",
    "LineSetPainter",
    "PointSetPainter",
    "LightPainter",
    "EmitterPainter",
    "IntegratorPainter",
    "BackgroundPainter",
    "ClipPlanePainter",
    "is_similarity",
]

SERVICE = MitsubaEngine.service


def _translate(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def _scale(x: float, y: float, z: float) -> np.ndarray:
    return np.diag([x, y, z, 1.0])


def _rot_x(degrees: float) -> np.ndarray:
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    m = np.eye(4)
    m[1, 1], m[1, 2], m[2, 1], m[2, 2] = c, -s, s, c
    return m


#: Mitsuba's z-up frame (disk, rectangle) to ours: z -> +y, y -> -z.
Z_TO_Y = _rot_x(-90.0)
#: z -> -y (the bottom cap of a cylinder faces down).
Z_TO_MINUS_Y = _rot_x(90.0)


def is_similarity(matrix: np.ndarray, tol: float = 1e-6) -> bool:
    """Whether the linear part is a rotation (or mirror) times a uniform scale."""
    m = np.asarray(matrix, np.float64)[:3, :3]
    g = m.T @ m
    s = np.trace(g) / 3.0
    return s > 0.0 and bool(np.allclose(g, s * np.eye(3), atol=tol * s))


def _clipped_natively(shape, engine: MitsubaEngine) -> bool:
    """Under active clip planes a native Mitsuba shape cannot be cut: draw its simplification instead."""
    if engine.clip_planes():
        engine.simplify(shape)
        return True
    return False


def _local_planes(engine: MitsubaEngine, matrix: np.ndarray) -> list[np.ndarray]:
    """The active world clip planes in the coordinates of ``matrix`` (plane rows transform by M^T)."""
    m = np.asarray(matrix, np.float64)
    return [m.T @ row for row in engine.clip_planes()]


@default_for(MitsubaEngine)
class SpherePainter(ShapePainter):
    """``Sphere`` -> Mitsuba ``sphere`` (mesh fallback under non-uniform scaling)."""

    __slots__ = ()
    service = SERVICE
    target = Sphere

    def exec(self, shape: Sphere, engine: MitsubaEngine) -> None:
        if _clipped_natively(shape, engine):
            return
        m = engine.model_matrix()
        if not is_similarity(m):
            engine.simplify(shape)
            return
        r = float(shape.radius)
        to_world = m @ _translate(*shape.center) @ _scale(r, r, r)
        engine.add_shape({"type": "sphere", "to_world": transform(to_world)}, "sphere")


@default_for(MitsubaEngine)
class BoxPainter(ShapePainter):
    """``Box`` -> Mitsuba ``cube`` ([-1, 1]^3) scaled to the box."""

    __slots__ = ()
    service = SERVICE
    target = Box

    def exec(self, shape: Box, engine: MitsubaEngine) -> None:
        if _clipped_natively(shape, engine):
            return
        sx, sy, sz = (float(v) / 2.0 for v in shape.size)
        to_world = engine.model_matrix() @ _translate(*shape.center) @ _scale(sx, sy, sz)
        engine.add_shape({"type": "cube", "to_world": transform(to_world)}, "box")


@default_for(MitsubaEngine)
class CylinderPainter(ShapePainter):
    """``Cylinder`` (axis +y, centred, capped) -> open Mitsuba ``cylinder`` plus two ``disk`` caps."""

    __slots__ = ()
    service = SERVICE
    target = Cylinder

    def exec(self, shape: Cylinder, engine: MitsubaEngine) -> None:
        if _clipped_natively(shape, engine):
            return
        m = engine.model_matrix()
        if not is_similarity(m):
            engine.simplify(shape)
            return
        r, h = float(shape.radius), float(shape.height)
        bsdf = engine.current_bsdf()
        body = m @ _translate(0.0, -h / 2.0, 0.0) @ Z_TO_Y @ _scale(r, r, h)
        engine.add_shape({"type": "cylinder", "to_world": transform(body), "bsdf": bsdf}, "cylinder")
        top = m @ _translate(0.0, h / 2.0, 0.0) @ Z_TO_Y @ _scale(r, r, 1.0)
        bottom = m @ _translate(0.0, -h / 2.0, 0.0) @ Z_TO_MINUS_Y @ _scale(r, r, 1.0)
        engine.add_shape({"type": "disk", "to_world": transform(top), "bsdf": bsdf}, "cap")
        engine.add_shape({"type": "disk", "to_world": transform(bottom), "bsdf": bsdf}, "cap")


@default_for(MitsubaEngine)
class DiskPainter(ShapePainter):
    """``Disk`` (xz plane, facing +y) -> Mitsuba ``disk`` (xy plane, facing +z)."""

    __slots__ = ()
    service = SERVICE
    target = Disk

    def exec(self, shape: Disk, engine: MitsubaEngine) -> None:
        if _clipped_natively(shape, engine):
            return
        r = float(shape.radius)
        to_world = engine.model_matrix() @ Z_TO_Y @ _scale(r, r, 1.0)
        engine.add_shape({"type": "disk", "to_world": transform(to_world)}, "disk")


@default_for(MitsubaEngine)
class RectanglePainter(ShapePainter):
    """``Rectangle`` (xz plane, facing +y) -> Mitsuba ``rectangle`` ([-1, 1]^2 in xy, facing +z)."""

    __slots__ = ()
    service = SERVICE
    target = Rectangle

    def exec(self, shape: Rectangle, engine: MitsubaEngine) -> None:
        if _clipped_natively(shape, engine):
            return
        sx, sz = (float(v) / 2.0 for v in shape.size)
        to_world = engine.model_matrix() @ Z_TO_Y @ _scale(sx, sz, 1.0)
        engine.add_shape({"type": "rectangle", "to_world": transform(to_world)}, "rectangle")


@default_for(MitsubaEngine)
class TriangleSetPainter(ShapePainter):
    """``TriangleSet`` -> an in-memory Mitsuba mesh in world coordinates.

    Normals are passed unless ``DrawStyle(shading="flat")`` is active; colours
    (sRGB) become the linear ``vertex_color`` attribute the BSDF reads.
    """

    __slots__ = ()
    service = SERVICE
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: MitsubaEngine) -> None:
        faces = shape.index_array()
        if len(faces) == 0:
            return
        style = engine.mono(DrawStyle)
        if style is not None and style.mode in ("wireframe", "points"):
            _edges_or_points(shape, engine, style)
            return
        flat = style is not None and getattr(style, "shading", "smooth") == "flat"
        matrix = engine.model_matrix()
        vertices = shape.vertex_array()
        normals = None if flat else shape.normal_array()
        colors = shape.color_array()
        texcoords = shape.texcoord_array()
        if engine.clip_planes():
            planes = _local_planes(engine, matrix)
            vertices, faces, normals, texcoords, colors = clip_triangles(
                vertices, faces, planes, normals, texcoords, colors
            )
            if len(faces) == 0:
                return
        uv = texcoords is not None
        linear = glow = None
        if colors is not None:
            linear = engine.vertex_colors(convert.srgb_to_linear(colors[:, :3]), uv)
            glow = engine.vertex_glow(linear, uv)
        bsdf = engine.current_bsdf(vertex_colors=colors is not None, texcoords=uv)
        if glow is not None and len(faces) > 1:
            # each group of faces of about the same colour emits its own ambient glow (per-face colours exact)
            for group in _glow_groups(glow, faces):
                keep = np.unique(faces[group])
                remap = np.full(len(vertices), -1, np.int64)
                remap[keep] = np.arange(len(keep))
                name = engine.unique_name("mesh")
                engine.shapes[name] = build_mesh(
                    name,
                    vertices[keep],
                    remap[faces[group]],
                    matrix=matrix,
                    normals=None if normals is None else normals[keep],
                    texcoords=None if texcoords is None else texcoords[keep],
                    colors=linear[keep],
                    bsdf=bsdf,
                    emitter=engine.current_area_emitter(uv, glow=glow[keep], share=len(group) / len(faces)),
                )
            return
        name = engine.unique_name("mesh")
        mesh = build_mesh(
            name,
            vertices,
            faces,
            matrix=matrix,
            normals=normals,
            texcoords=texcoords,
            colors=linear,
            bsdf=bsdf,
            emitter=engine.current_area_emitter(uv, glow=glow),
        )
        engine.shapes[name] = mesh


#: At most this many groups of faces of one ambient glow per vertex-coloured mesh.
MAX_GLOW_GROUPS = 256


def _glow_groups(glow: np.ndarray, faces: np.ndarray) -> list[np.ndarray]:
    """Face indices grouped by their mean glow (quantised; coarser until at most MAX_GLOW_GROUPS groups)."""
    face_glow = glow[faces].mean(axis=1)
    top = max(float(face_glow.max()), 1e-12)
    for levels in (32, 16, 8, 4, 2):
        keys = np.round(face_glow / top * levels).astype(np.int64)
        unique, inverse = np.unique(keys, axis=0, return_inverse=True)
        if len(unique) <= MAX_GLOW_GROUPS:
            break
    inverse = inverse.reshape(-1)
    order = np.argsort(inverse, kind="stable")
    bounds = np.searchsorted(inverse[order], np.arange(len(unique) + 1))
    return [order[bounds[i] : bounds[i + 1]] for i in range(len(unique))]


#: Above this many points a PointSet becomes one mesh of octahedra instead of Mitsuba spheres.
MAX_SPHERES = 2000


def _world_pixel(engine: MitsubaEngine, world_points: np.ndarray) -> float:
    camera, _ = engine.camera_or_default()
    view = engine.view_matrix()
    if view is None:
        view = camera.view_matrix()
    return strokes.pixel_size(camera, view, engine.size[1], world_points.mean(axis=0))


def _edges_or_points(shape: TriangleSet, engine: MitsubaEngine, style: DrawStyle) -> None:
    """A triangle set drawn as ``DrawStyle(mode="wireframe")`` tubes or ``mode="points"`` spheres."""
    points = transform_points(engine.model_matrix(), np.asarray(shape.vertex_array(), np.float64)).astype(np.float64)
    unit = _world_pixel(engine, points)
    bsdf = engine.current_bsdf(texcoords=False)
    planes = engine.clip_planes()
    if style.mode == "points":
        if planes:
            points = points[keep_points(points, planes)]
        vertices, faces = strokes.octahedra(points, np.full(len(points), 0.5 * style.point_size * unit))
    else:
        tri = shape.index_array()
        edges = np.unique(np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1), axis=0)
        a, b = points[edges[:, 0]], points[edges[:, 1]]
        if planes:
            a, b, _ = clip_segments(a, b, planes)
        vertices, faces = strokes.tubes(a, b, 0.5 * style.line_width * unit)
    if len(faces):
        name = engine.unique_name(style.mode)
        engine.shapes[name] = build_mesh(name, vertices, faces, bsdf=bsdf)


@default_for(MitsubaEngine)
class LineSetPainter(ShapePainter):
    """``LineSet`` -> one mesh of thin tubes ``DrawStyle.line_width`` pixels wide (1 by default)."""

    __slots__ = ()
    service = SERVICE
    target = LineSet

    def exec(self, shape: LineSet, engine: MitsubaEngine) -> None:
        segments = np.asarray(shape.index_array()).reshape(-1, 2)
        if len(segments) == 0:
            return
        m = engine.model_matrix()
        points = transform_points(m, np.asarray(shape.vertex_array(), np.float64)).astype(np.float64)
        style = engine.mono(DrawStyle)
        width = style.line_width if style is not None else 1.0
        radius = 0.5 * width * _world_pixel(engine, points)
        a, b = points[segments[:, 0]], points[segments[:, 1]]
        if engine.clip_planes():
            a, b, _ = clip_segments(a, b, engine.clip_planes())
        vertices, faces = strokes.tubes(a, b, radius)
        if len(faces) == 0:
            return
        name = engine.unique_name("lines")
        engine.shapes[name] = build_mesh(name, vertices, faces, bsdf=engine.current_bsdf(texcoords=False))


@default_for(MitsubaEngine)
class PointSetPainter(ShapePainter):
    """``PointSet`` -> spheres of ``sizes`` or ``DrawStyle.point_size`` pixels (1 by default)."""

    __slots__ = ()
    service = SERVICE
    target = PointSet

    def exec(self, shape: PointSet, engine: MitsubaEngine) -> None:
        vertices = np.asarray(shape.vertex_array(), np.float64)
        if len(vertices) == 0:
            return
        points = transform_points(engine.model_matrix(), vertices).astype(np.float64)
        style = engine.mono(DrawStyle)
        size = style.point_size if style is not None else 1.0
        sizes = shape.size_array()
        pixels = np.asarray(sizes, np.float64).reshape(-1) if sizes is not None else np.full(len(points), size)
        radii = 0.5 * pixels * _world_pixel(engine, points)
        if engine.clip_planes():  # GL clips a point by its vertex: drop the points outside
            inside = keep_points(points, engine.clip_planes())
            points, radii = points[inside], radii[inside]
            if len(points) == 0:
                return
        bsdf = engine.current_bsdf(texcoords=False)
        if len(points) > MAX_SPHERES:
            vertices, faces = strokes.octahedra(points, radii)
            name = engine.unique_name("points")
            engine.shapes[name] = build_mesh(name, vertices, faces, bsdf=bsdf)
            return
        for p, r in zip(points, radii, strict=True):
            engine.add_shape(
                {"type": "sphere", "center": [float(c) for c in p], "radius": float(r), "bsdf": bsdf}, "point"
            )


track_surfaces(MitsubaEngine)  # Color / Material / PBRMaterial in activation order
# a path tracer: every light casts shadows and every shape casts and receives them (a warning says so)
register_shadowing_warnings(MitsubaEngine, "Mitsuba", mirror=True)


@default_for(MitsubaEngine)
class LightPainter(AttributePainter):
    """Generic lights -> queued for conversion to Mitsuba emitters (see :func:`convert.light_emitter`)."""

    __slots__ = ()
    service = SERVICE
    target = LightSource

    def exec(self, light: LightSource, engine: MitsubaEngine) -> None:
        check_light_shadows(engine, light, "Mitsuba")
        engine.add_light(light)


@default_for(MitsubaEngine)
class EmitterPainter(AttributePainter):
    """``om.mitsuba.Emitter``: non-area emitters join the scene once (area ones are read by shapes)."""

    __slots__ = ()
    service = SERVICE
    target = Emitter

    def exec(self, emitter: Emitter, engine: MitsubaEngine) -> None:
        if emitter.is_area or id(emitter) in engine._emitter_ids:
            return
        engine._emitter_ids.add(id(emitter))
        plugin = emitter.plugin_dict()
        m = engine.model_matrix()
        if "to_world" not in plugin and not np.array_equal(m, np.eye(4)):
            plugin["to_world"] = transform(m)
        engine.add_emitter(plugin, emitter.kind)


@default_for(MitsubaEngine)
class IntegratorPainter(AttributePainter):
    """``om.mitsuba.Integrator``: the last one met is the render's integrator."""

    __slots__ = ()
    service = SERVICE
    target = Integrator

    def exec(self, integrator: Integrator, engine: MitsubaEngine) -> None:
        engine.integrator = integrator.plugin_dict()


@default_for(MitsubaEngine)
class BackgroundPainter(AttributePainter):
    """``Background``: the scene's (see ``is_scene_background``) is composited behind the image."""

    __slots__ = ()
    service = SERVICE
    target = Background

    def exec(self, background: Background, engine: MitsubaEngine) -> None:
        if engine.background is None and is_scene_background(background, engine):
            engine.background = tuple(float(c) for c in background.color)


@default_for(MitsubaEngine)
class ClipPlanePainter(AttributePainter):
    """``ClipPlane``: remembered in world coordinates while active; the shape painters clip against it."""

    __slots__ = ()
    service = SERVICE
    target = ClipPlane

    def exec(self, plane: ClipPlane, engine: MitsubaEngine) -> None:
        engine.add_clip(plane)

    def unexec(self, plane: ClipPlane, engine: MitsubaEngine) -> None:
        engine.remove_clip(plane)


from . import splats as _splats  # noqa: E402,F401  (registers the Gaussian splats painter)
