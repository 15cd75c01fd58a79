"""Default handlers of the POV-Ray engine (service ``"pov.paint"``).

Shape painters write native POV-Ray primitives (sphere, box, cylinder, cone,
torus, disc, polygon; textured ones are tessellated by their simplifier so the
texture coordinates are those of every other engine) and ``mesh2`` for
triangle sets; every other shape
reaches these through the shapes' default simplifiers.  Line and point sets
become thin cylinders and small spheres whose radius corresponds to the
style's line width / point size in pixels at the shape's distance from the
camera.  Attribute painters record lights, background, fog, global settings,
clip planes and scene-level ``Raw`` text in the engine.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..attributes import (
    AmbientLight,
    AreaLight,
    Background,
    ClipPlane,
    DirectionalLight,
    DiscLight,
    DrawStyle,
    Fog,
    PointLight,
    RectLight,
    SpotLight,
)
from ..attributes.environment import is_scene_background
from ..attributes.photometry import area_radiance
from ..attributes.surface import engine_appearance, track_surfaces
from ..core import SIMPLIFY, AttributePainter, ShapePainter, default_for
from ..shapes import (
    CSG,
    Box,
    Cone,
    Cylinder,
    Disk,
    LineSet,
    NURBSSurface,
    PointSet,
    Rectangle,
    Sphere,
    Torus,
    TriangleSet,
)
from . import sdl
from .appearance import finish_name, srgb_to_linear, texture_name, vertex_colors
from .attributes import GlobalSettings, Raw
from .engine import POVRayEngine
from .mesh import mesh2_text

__all__ = [
    "SpherePainter",
    "BoxPainter",
    "CylinderPainter",
    "ConePainter",
    "TorusPainter",
    "DiskPainter",
    "RectanglePainter",
    "TriangleSetPainter",
    "LineSetPainter",
    "PointSetPainter",
    "LightPainter",
]

PAINT = "pov.paint"


def _n(value: float) -> str:
    return sdl.number(value)


def _simplify(shape: Any, engine: POVRayEngine) -> bool:
    """Evaluate the shape's default simplification instead (True when there is one).

    Textured primitives are tessellated so that they carry the same texture
    coordinates as in every other engine; POV-Ray's own uv mappings differ.
    """
    for cls in type(shape).__mro__:
        simplifier = engine.find_handler(SIMPLIFY, cls)
        if simplifier is not None:
            result = simplifier.exec(shape, engine)
            if result is not None:
                engine.evaluate(result)
            return True
    return False


class _Primitive(ShapePainter):
    __slots__ = ()
    service = PAINT

    def exec(self, shape: Any, engine: POVRayEngine) -> None:
        if engine_appearance(engine).textures and _simplify(shape, engine):
            return
        engine.emit(self.geometry(shape), texture_name(engine))

    def geometry(self, shape: Any) -> str:  # pragma: no cover - abstract
        raise NotImplementedError


@default_for(POVRayEngine)
class SpherePainter(_Primitive):
    __slots__ = ()
    target = Sphere

    def geometry(self, shape: Sphere) -> str:
        return f"sphere {{ {sdl.vector(shape.center)}, {_n(shape.radius)} }}"


@default_for(POVRayEngine)
class BoxPainter(_Primitive):
    __slots__ = ()
    target = Box

    def geometry(self, shape: Box) -> str:
        c, s = np.asarray(shape.center), np.asarray(shape.size) / 2.0
        return f"box {{ {sdl.vector(c - s)}, {sdl.vector(c + s)} }}"


@default_for(POVRayEngine)
class CylinderPainter(_Primitive):
    __slots__ = ()
    target = Cylinder

    def geometry(self, shape: Cylinder) -> str:
        h = shape.height / 2.0
        return f"cylinder {{ <0,{_n(-h)},0>, <0,{_n(h)},0>, {_n(shape.radius)} }}"


@default_for(POVRayEngine)
class ConePainter(_Primitive):
    __slots__ = ()
    target = Cone

    def geometry(self, shape: Cone) -> str:
        h = shape.height / 2.0
        return f"cone {{ <0,{_n(-h)},0>, {_n(shape.radius)}, <0,{_n(h)},0>, 0 }}"


@default_for(POVRayEngine)
class TorusPainter(_Primitive):
    __slots__ = ()
    target = Torus

    def geometry(self, shape: Torus) -> str:
        # POV-Ray's torus lies in the xz plane around the y axis, like ours.
        return f"torus {{ {_n(shape.major_radius)}, {_n(shape.minor_radius)} }}"


@default_for(POVRayEngine)
class DiskPainter(_Primitive):
    __slots__ = ()
    target = Disk

    def geometry(self, shape: Disk) -> str:
        return f"disc {{ <0,0,0>, <0,1,0>, {_n(shape.radius)} }}"


@default_for(POVRayEngine)
class RectanglePainter(_Primitive):
    __slots__ = ()
    target = Rectangle

    def geometry(self, shape: Rectangle) -> str:
        a, b = shape.size[0] / 2.0, shape.size[1] / 2.0
        corners = [(-a, 0, -b), (a, 0, -b), (a, 0, b), (-a, 0, b)]
        return "polygon { 4, " + ", ".join(sdl.vector(c) for c in corners) + " }"


@default_for(POVRayEngine)
class TriangleSetPainter(ShapePainter):
    """``mesh2`` with vertices, normals (unless flat shading), uvs (with a texture) and per-vertex colours."""

    __slots__ = ()
    service = PAINT
    target = TriangleSet

    def exec(self, shape: TriangleSet, engine: POVRayEngine) -> None:
        vertices = shape.vertex_array()
        indices = shape.index_array()
        if len(vertices) == 0 or len(indices) == 0:
            return
        style = engine.mono(DrawStyle)
        if style is not None and style.mode != "filled":
            _edges_or_points(shape, engine, style)
            return
        normals = None if style is not None and style.shading == "flat" else shape.normal_array()
        has_texture = bool(engine_appearance(engine).textures)
        uvs = shape.texcoord_array() if has_texture else None
        colors = None if has_texture else shape.color_array()
        if colors is not None:
            lin = vertex_colors(engine, colors)
            text = mesh2_text(vertices, indices, normals, uvs, lin, finish_name(engine), engine._owner())
            engine.emit(text, None, plain=lambda: mesh2_text(vertices, indices))
        else:
            text = mesh2_text(vertices, indices, normals, uvs, None, None, engine._owner())
            engine.emit(text, texture_name(engine, uv=uvs is not None))


@default_for(POVRayEngine)
class NURBSSurfacePainter(ShapePainter):
    """Untrimmed polynomial bicubic NURBS surfaces as POV-Ray ``bicubic_patch``es (one per Bézier patch).

    Trimmed, rational, other-degree or textured surfaces (whose texture coordinates are the surface's
    (u, v), not POV-Ray's per-patch ones) and wireframes go through the simplifier's mesh.
    """

    __slots__ = ()
    service = PAINT
    target = NURBSSurface

    def exec(self, shape: NURBSSurface, engine: POVRayEngine) -> None:
        style = engine.mono(DrawStyle)
        native = shape.degrees == (3, 3) and not shape.trim_loops() and not shape.rational
        if not native or engine_appearance(engine).textures or (style is not None and style.mode != "filled"):
            _simplify(shape, engine)
            return
        patches, _ = shape.bezier_patches()
        body = []
        for patch in patches:  # (4, 4, 4) homogeneous control points, weights all equal
            points = patch[..., :3] / patch[..., 3:]
            rows = ",\n  ".join(", ".join(sdl.vector(points[i, j]) for j in range(4)) for i in range(4))
            body.append(f"bicubic_patch {{ type 1 flatness 0 u_steps 5 v_steps 5\n  {rows}\n}}\n")
        engine.emit(_union("".join(body)), texture_name(engine))


def _pixel_radius(engine: POVRayEngine, points: np.ndarray, pixels: float) -> float:
    """World-space radius that covers ``pixels`` pixels (diameter) near ``points`` (model coordinates)."""
    m = engine.model_matrix()
    centre = m[:3, :3] @ points.mean(axis=0) + m[:3, 3]
    scale = float(np.cbrt(abs(np.linalg.det(m[:3, :3])))) or 1.0
    if engine.camera is None:
        return 0.005 * pixels
    camera, _ = engine.camera
    view = engine.view_matrix()
    h = engine.size[1]
    if camera.is_orthographic:
        per_pixel = camera.height / h
    else:
        depth = max(-(view[:3, :3] @ centre + view[:3, 3])[2], camera.near)
        per_pixel = 2.0 * depth * math.tan(math.radians(camera.fov) / 2.0) / h
    return 0.5 * pixels * per_pixel / scale


def _cylinders(vertices: np.ndarray, segments: np.ndarray, radius: float) -> str:
    a, b = vertices[segments[:, 0]], vertices[segments[:, 1]]
    # POV-Ray refuses a cylinder whose ends are equal *as written* (%.7g), a fatal "Degenerate cylinder":
    # drop segments shorter than 1e-5 of their coordinates' magnitude (they round to one point; invisible anyway)
    scale = np.maximum(np.abs(a).max(axis=1, initial=0.0), np.abs(b).max(axis=1, initial=0.0))
    keep = np.linalg.norm(a - b, axis=1) > 1e-5 * scale
    keep &= np.any(a != b, axis=1)
    a, b = a[keep], b[keep]
    if len(a) == 0:
        return ""
    r = _n(radius)
    line = "cylinder { <%.7g,%.7g,%.7g>, <%.7g,%.7g,%.7g>, " + r + " }\n"
    return (line * len(a)) % tuple(np.column_stack([a, b]).ravel().tolist())


def _spheres(vertices: np.ndarray, radii: np.ndarray) -> str:
    line = "sphere { <%.7g,%.7g,%.7g>, %.7g }\n"
    return (line * len(vertices)) % tuple(np.column_stack([vertices, radii]).ravel().tolist())


def _union(body: str) -> str:
    # a union needs two members: a degenerate one is added for single-member sets
    return "union {\n" + body + "sphere { <0,0,0>, 0 }\n}"


def _edges_or_points(shape: Any, engine: POVRayEngine, style: Any) -> None:
    vertices = np.asarray(shape.vertex_array(), dtype=np.float64)
    if style.mode == "points":
        radius = _pixel_radius(engine, vertices, style.point_size)
        body = _spheres(vertices, np.full(len(vertices), radius))
    else:
        tri = shape.index_array()
        edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
        edges = np.unique(np.sort(edges, axis=1), axis=0)
        body = _cylinders(vertices, edges, _pixel_radius(engine, vertices, style.line_width))
    if body:
        engine.emit(_union(body), texture_name(engine))


@default_for(POVRayEngine)
class LineSetPainter(ShapePainter):
    """Segments as cylinders ``DrawStyle.line_width`` pixels thick (1 by default)."""

    __slots__ = ()
    service = PAINT
    target = LineSet

    def exec(self, shape: LineSet, engine: POVRayEngine) -> None:
        vertices = np.asarray(shape.vertex_array(), dtype=np.float64)
        segments = np.asarray(shape.index_array()).reshape(-1, 2)
        if len(vertices) == 0 or len(segments) == 0:
            return
        style = engine.mono(DrawStyle)
        width = style.line_width if style is not None else 1.0
        body = _cylinders(vertices, segments, _pixel_radius(engine, vertices, width))
        if body:
            engine.emit(_union(body), texture_name(engine))


@default_for(POVRayEngine)
class PointSetPainter(ShapePainter):
    """Points as spheres of ``sizes`` or ``DrawStyle.point_size`` pixels (1 by default)."""

    __slots__ = ()
    service = PAINT
    target = PointSet

    def exec(self, shape: PointSet, engine: POVRayEngine) -> None:
        vertices = np.asarray(shape.vertex_array(), dtype=np.float64)
        if len(vertices) == 0:
            return
        style = engine.mono(DrawStyle)
        size = style.point_size if style is not None else 1.0
        unit = _pixel_radius(engine, vertices, 1.0)
        sizes = shape.size_array()
        radii = unit * (
            np.asarray(sizes, dtype=np.float64).reshape(-1) if sizes is not None else np.full(len(vertices), size)
        )
        engine.emit(_union(_spheres(vertices, radii)), texture_name(engine))


@default_for(POVRayEngine)
class CSGPainter(ShapePainter):
    """``CSG`` -> POV-Ray's native ``union`` / ``intersection`` / ``difference`` of the operands.

    The operands are evaluated in place (their objects, with world matrices
    and without textures, become the children); the CSG object gets the
    texture active where it is evaluated.
    """

    __slots__ = ()
    service = PAINT
    target = CSG

    def exec(self, shape: CSG, engine: POVRayEngine) -> None:
        children = []
        for operand in shape.operands():
            saved = engine.objects
            engine.objects = []
            try:
                engine.evaluate(operand if hasattr(operand, "local_program") else [operand])
                made = engine.objects
            finally:
                engine.objects = saved
            for obj in made:
                if isinstance(obj, str):  # scene-level text met inside an operand stays at the top level
                    engine.objects.append(obj)
                else:
                    children.append(f"object {{\n  {obj.geometry}\n{obj.placement}}}")
            if not any(not isinstance(obj, str) for obj in made):
                children.append("sphere { <0,0,0>, 0 }")  # an empty operand: POV-Ray needs an object
        body = "\n".join(children)
        engine.emit(f"{shape.operation} {{\n{body}\n}}", texture_name(engine), matrix=np.eye(4))


track_surfaces(POVRayEngine)  # Color / Material / PBRMaterial in activation order (the one appearance model)


# -- attributes -------------------------------------------------------------
def _light_matrix(light: Any, engine: POVRayEngine) -> np.ndarray:
    for other, matrix in engine.lights():
        if other is light:
            return matrix
    return engine.model_matrix()


def _fade(light: Any) -> tuple[float, str]:
    """(colour scale, fade items) approximating OpenGL's 1 / (C + L d + Q d^2).

    POV-Ray attenuates by 2 / (1 + (d / D)^P).  With scale 1 / (2 C),
    P = 2 and D = sqrt(C / Q) this is exactly 1 / (C + Q d^2); with P = 1 and
    D = C / L exactly 1 / (C + L d).  When both L and Q are set the quadratic
    term decides (it dominates far away).
    """
    c, lin, q = float(light.constant), float(light.linear), float(light.quadratic)
    if lin == 0.0 and q == 0.0:
        return 1.0 / c, ""
    c = max(c, 1e-3)
    if q > 0.0:
        return 1.0 / (2.0 * c), f" fade_distance {_n(math.sqrt(c / q))} fade_power 2"
    return 1.0 / (2.0 * c), f" fade_distance {_n(c / lin)} fade_power 1"


@default_for(POVRayEngine)
class LightPainter(AttributePainter):
    """Point -> ``light_source``, spot -> ``spotlight``, directional -> ``parallel``, ambient -> ``ambient_light``."""

    __slots__ = ()
    service = PAINT
    target = PointLight

    def exec(self, light: Any, engine: POVRayEngine) -> None:
        engine.ambient = engine.ambient + np.asarray(light.ambient, dtype=np.float64)
        engine.light_count += 1  # any light (even ambient) turns the headlight off, as in GL
        if isinstance(light, AmbientLight):
            return
        world = _light_matrix(light, engine)
        color = np.asarray(light.diffuse, dtype=np.float64)
        if isinstance(light, DirectionalLight):
            d = light.world_direction(world)
            text = f"light_source {{ {sdl.vector(-d * 1e5)} {sdl.color(color)} parallel point_at <0,0,0>"
        else:
            p = light.world_position(world)
            scale, fade = _fade(light)
            text = f"light_source {{ {sdl.vector(p)} {sdl.color(color * scale)}{fade}"
            if isinstance(light, SpotLight):
                axis = light.world_direction(world)
                cutoff = float(light.cutoff)
                radius = cutoff
                if light.exponent > 0:  # full beam where cos^exponent is above one half
                    radius = min(cutoff, math.degrees(math.acos(0.5 ** (1.0 / light.exponent))))
                text += (
                    f" spotlight point_at {sdl.vector(p + axis)} radius {_n(radius * 0.999)}"
                    f" falloff {_n(cutoff)} tightness {_n(light.exponent)}"
                )
        if not light.casts_shadows:
            text += " shadowless"
        text += " }\n"
        engine.lights_sdl.append(text)
        engine.light_texts[id(light)] = text


for _cls in (SpotLight, DirectionalLight, AmbientLight):
    _painter = type(f"{_cls.__name__}Painter", (LightPainter,), {"__slots__": (), "target": _cls})
    default_for(POVRayEngine)(_painter)


#: Points along the longer side of a rectangle or disc light in POV-Ray (the shorter side proportionally fewer,
#: >= 3).
AREA_SAMPLES = 12  # made odd: 13
#: POV-Ray's fade distance for an area light's samples, as a fraction of the light's larger half extent: each
#: sample falls off as ``2 / (1 + (d / D)^2)``, within ``(D / d)^2`` of ``2 D^2 / d^2`` (0.04 % at one size).
AREA_FADE_FRACTION = 0.01


def area_light_points(light: Any, world: np.ndarray) -> np.ndarray:
    """World points standing for the light: the centres of an ``nu`` x ``nv`` grid of equal cells over the
    rectangle (odd counts, the longer side :data:`AREA_SAMPLES` + 1), for a disc those inside its ellipse."""
    centre, hu, hv, _ = light.world_frame(world)
    lu, lv = float(np.linalg.norm(hu)), float(np.linalg.norm(hv))
    longest = max(lu, lv)
    # odd counts: an even grid has a plateau at exactly half the samples visible across the shadow's edge
    nu = max(3, 2 * round(AREA_SAMPLES * lu / longest / 2.0) + 1)
    nv = max(3, 2 * round(AREA_SAMPLES * lv / longest / 2.0) + 1)
    if isinstance(light, DiscLight):
        nu = nv = max(nu, nv)
    a, b = (g.ravel() for g in np.meshgrid((np.arange(nu) + 0.5) / nu * 2 - 1, (np.arange(nv) + 0.5) / nv * 2 - 1))
    keep = a * a + b * b <= 1.0 if isinstance(light, DiscLight) else np.ones(a.shape, bool)
    return centre + a[keep, None] * hu + b[keep, None] * hv


def area_light_text(light: Any, world: np.ndarray) -> list[str]:
    """POV-Ray ``light_source`` text for a rectangle or disc light: one ``spotlight`` per point of
    :func:`area_light_points` (per lit side).

    Each is a Lambertian emitter's piece (``radius 90 falloff 90 tightness 1``: the factor
    ``cos(angle to the normal)``) with ``fade_power 2`` for the ``1 / d^2`` falloff, and the colour makes
    their sum the form factor of :func:`omnirender.attributes.photometry.area_form_factor`: each point's
    colour is ``L * area / (2 pi D^2 n)`` with ``D`` the fade distance and ``n`` the points.

    Not POV-Ray's ``area_light``: it averages its samples' *visibility* with equal weights and shades
    with that share (``area_illumination`` or not), where a surface's irradiance weights each point of
    the light by ``cos cos / r^2``; its shadows came out about a pixel wider than the analytic ones and
    than Mitsuba's, Radiance's and GL's (IoU 0.93-0.95; with a spotlight per point 0.96-0.99, at the
    same number of shadow rays: ``tests/test_area_light_agreement.py``).  The points are the same in
    every frame (animations do not flicker).
    """
    _, hu, hv, normal = light.world_frame(world)
    points = area_light_points(light, world)
    fade = AREA_FADE_FRACTION * max(float(np.linalg.norm(hu)), float(np.linalg.norm(hv)))
    color = area_radiance(light) * light.world_area(world) / (2.0 * math.pi * fade * fade * len(points))
    extra = " shadowless" if not light.casts_shadows else ""
    out = []
    for side in (1.0, -1.0) if light.two_sided else (1.0,):
        for p in points:
            out.append(
                f"light_source {{ {sdl.vector(p)} {sdl.color(color)} fade_distance {_n(fade)} fade_power 2"
                f" spotlight point_at {sdl.vector(p + side * normal)} radius 90 falloff 90 tightness 1{extra} }}\n"
            )
    return out


@default_for(POVRayEngine)
class AreaLightPainter(AttributePainter):
    """Rectangle and disc lights -> a spotlight per point of the light (see :func:`area_light_text`)."""

    __slots__ = ()
    service = PAINT
    target = RectLight

    def exec(self, light: AreaLight, engine: POVRayEngine) -> None:
        engine.ambient = engine.ambient + np.asarray(light.ambient, dtype=np.float64)
        engine.light_count += 1
        text = "".join(area_light_text(light, _light_matrix(light, engine)))
        engine.lights_sdl.append(text)
        engine.light_texts[id(light)] = text


default_for(POVRayEngine)(type("DiscLightPainter", (AreaLightPainter,), {"__slots__": (), "target": DiscLight}))


@default_for(POVRayEngine)
class BackgroundPainter(AttributePainter):
    __slots__ = ()
    service = PAINT
    target = Background

    def exec(self, attribute: Background, engine: POVRayEngine) -> None:
        if is_scene_background(attribute, engine):
            engine.background = attribute


@default_for(POVRayEngine)
class FogPainter(AttributePainter):
    """POV-Ray's constant fog is exponential; linear and exp2 fog are matched at half strength."""

    __slots__ = ()
    service = PAINT
    target = Fog

    def exec(self, fog: Fog, engine: POVRayEngine) -> None:
        if fog.mode == "exp":
            distance = 1.0 / max(fog.density, 1e-9)
        elif fog.mode == "exp2":
            distance = math.sqrt(math.log(2.0)) / max(fog.density, 1e-9) / math.log(2.0)
        else:
            distance = (fog.start + fog.end) / 2.0 / math.log(2.0)
        colour = srgb_to_linear(fog.color)
        engine.fog = f"fog {{ fog_type 1 distance {_n(distance)} {sdl.color(colour)} }}\n"


@default_for(POVRayEngine)
class GlobalSettingsPainter(AttributePainter):
    __slots__ = ()
    service = PAINT
    target = GlobalSettings

    def exec(self, attribute: GlobalSettings, engine: POVRayEngine) -> None:
        engine.global_settings = attribute


@default_for(POVRayEngine)
class RawPainter(AttributePainter):
    __slots__ = ()
    service = PAINT
    target = Raw

    def exec(self, raw: Raw, engine: POVRayEngine) -> None:
        if raw.placement == "scene":  # the node comment lets errors in the text name the node
            engine.objects.append(sdl.comment(engine.node_path or "/") + "\n" + raw.text.rstrip("\n") + "\n")


@default_for(POVRayEngine)
class ClipPlanePainter(AttributePainter):
    """Remembers the model matrix the plane was added under (its coordinates)."""

    __slots__ = ()
    service = PAINT
    target = ClipPlane

    def exec(self, plane: ClipPlane, engine: POVRayEngine) -> None:
        engine._clip_matrices[id(plane)] = engine.model_matrix()


from . import splats as _splats  # noqa: E402,F401  (registers the Gaussian splats handler)
