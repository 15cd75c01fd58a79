"""RenderMan RIB export (``om.export(scene, "scene.rib")``) and ``om.rib.Surface``.

:class:`RIBEngine` (service ``"rib.export"``) writes RIB 3.04 through
handlers: the camera as ``Projection`` + a world-to-camera ``Transform``
(RenderMan's camera space is left-handed, z into the screen: a ``Scale 1 1
-1`` after the GL view matrix), ``Format`` and ``Display``; inside
``WorldBegin``/``WorldEnd`` the lights (``pointlight``, ``distantlight``,
``spotlight``, ``ambientlight``; ``om.RectLight``/``om.DiscLight`` as an
``AreaLightSource "arealight"`` on the light's polygon, of intensity its
radiance) and one ``AttributeBegin``/``AttributeEnd`` block per scene-graph
node with the ``ConcatTransform`` accumulated since its parent. Each shape
gets its own block with its transform relative to the node,
``Color``/``Opacity`` and a ``Surface`` ("plastic" with a specular colour,
"matte" otherwise, or the shader of an active :class:`Surface`). Sphere,
cylinder, cone, torus and disk are RenderMan quadrics (z-up: a rotation turns
them to our y axis), rectangles ``Polygon``, triangle sets ``PointsPolygons``,
line sets ``Curves`` and point sets ``Points``; everything else is simplified.
Matrices are written in RenderMan's row-vector order (our column-major).

Clip planes: RenderMan's ``ClippingPlane x y z nx ny nz`` removes everything on
the side its normal points to, but it is a camera *option* (RI spec 3.2, frozen
at ``WorldBegin``; renderers reject it inside the world block), so it cannot be
scoped to a subgraph as ``om.ClipPlane`` is.  A ``ClipPlane`` that applies to
the whole scene (added in the root node before any shape) is written as a
``ClippingPlane`` before ``WorldBegin``, in world coordinates, with the normal
negated (omnirender keeps the side its normal points to); removing such a
plane by hand before more shapes is refused, as RenderMan cannot end it.  Under any other
``ClipPlane`` the geometry itself is clipped on export
(:mod:`omnirender.geometry.clip`): quadrics and rectangles are simplified to
triangles and cut, curves shortened, points outside dropped; a comment marks
the block where such a plane was added.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..attributes import (
    AmbientLight,
    AreaLight,
    ClipPlane,
    DirectionalLight,
    DrawStyle,
    LightSource,
    Material,
    PBRMaterial,
    PointLight,
    SpotLight,
)
from ..core import AttributePainter, Camera, MonoAttribute, ShapePainter, default_for
from ..fileio import atomic_write
from ..geometry.clip import clip_segments, clip_triangles, keep_points
from ..scene import Node
from ..shapes import Cone, Cylinder, Disk, LineSet, PointSet, Rectangle, Sphere, Torus, TriangleSet
from .walk import NodeTrackingEngine, track_surfaces

__all__ = ["Surface", "RIBEngine", "export", "to_text", "rib_string", "rib_identifier", "rib_numbers"]

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_ ]*$")
_UNSAFE = re.compile(r'["\\\x00-\x1f\x7f]')


def rib_identifier(name: str) -> str:
    """A node name as a RIB string literal: quotes, backslashes and control characters become ``_``.

    Node names are free text and only label the blocks, so an odd name must
    not stop the export; shader names and parameters are still rejected by
    :func:`rib_string`.
    """
    return rib_string(_UNSAFE.sub("_", str(name)), "node name")


def rib_string(value: str, what: str = "string") -> str:
    """A RIB string literal; quotes, backslashes and control characters are rejected."""
    if not isinstance(value, str):
        raise TypeError(f"RIB export: {what} must be a string, got {type(value).__name__}")
    if any(c in value for c in '"\\') or any(ord(c) < 32 for c in value):
        raise ValueError(f"RIB export: {what} {value!r} contains a quote, backslash or control character")
    return f'"{value}"'


def rib_numbers(values: Any) -> str:
    """Numbers as a RIB array ``[1 2.5 ...]`` (%.7g)."""
    a = np.asarray(values, dtype=np.float64).reshape(-1)
    if not np.all(np.isfinite(a)):
        raise ValueError("RIB export: non-finite number")
    if a.size == 0:
        return "[]"
    a = np.where(np.abs(a) < 1e-12, 0.0, a)  # no 6e-17 from rotations
    # one %-format of a repeated template is ~5x faster than formatting number by number
    return "[" + (("%.7g " * a.size) % tuple(a.tolist()))[:-1] + "]"


def _ints(values: np.ndarray) -> str:
    a = np.asarray(values).reshape(-1)
    return "[" + " ".join(map(str, a.tolist())) + "]"


def _matrix(m: np.ndarray) -> str:
    """Our column-vector matrix in RenderMan's row-vector order."""
    return rib_numbers(np.asarray(m, np.float64).T)


def _param_value(owner: str, name: str, value: Any) -> str:
    if isinstance(value, str):
        return "[" + rib_string(value, f"{owner} parameter {name!r}") + "]"
    if isinstance(value, (list, tuple)) and value and all(isinstance(v, str) for v in value):
        return "[" + " ".join(rib_string(v, f"{owner} parameter {name!r}") for v in value) + "]"
    try:
        return rib_numbers(value)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: parameter {name!r} must be numbers or strings, got {value!r}") from None


class Surface(MonoAttribute):
    """A RenderMan surface shader with its parameters, passed through: ``Surface("wood", Kd=0.8, ringscale=10)``.

    Overrides the surface converted from materials for the following shapes;
    other engines ignore it.  Parameter names may carry an inline declaration
    (``**{"uniform float grain": 3}``).
    """

    __slots__ = ("_name", "_params")

    def __init__(self, name: str, **params: Any) -> None:
        super().__init__()
        rib_string(name, "Surface name")
        if not name:
            raise ValueError("Surface: the shader name must not be empty")
        for key, value in params.items():
            if not _NAME.match(key):
                raise ValueError(f"Surface: parameter name {key!r} must be letters, digits, spaces and underscores")
            _param_value("Surface", key, value)
        object.__setattr__(self, "_name", name)
        object.__setattr__(self, "_params", dict(params))

    @property
    def name(self) -> str:
        return self._name

    @property
    def params(self) -> dict[str, Any]:
        return dict(self._params)

    def parameters(self) -> dict[str, Any]:
        return {"name": self._name, **self._params}

    def rib(self) -> str:
        """The ``Surface`` request."""
        parts = [f"Surface {rib_string(self._name)}"]
        for key, value in self._params.items():
            parts.append(f"{rib_string(key)} {_param_value('Surface', key, value)}")
        return " ".join(parts)


def _rot_x(degrees: float) -> np.ndarray:
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    m = np.eye(4)
    m[1, 1], m[1, 2], m[2, 1], m[2, 2] = c, -s, s, c
    return m


def _translate(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


#: RenderMan quadrics are z-up; ours are y-up: z -> +y.
Z_TO_Y = _rot_x(-90.0)


class RIBEngine(NodeTrackingEngine):
    """Evaluates a scene into RIB text (see the module docstring)."""

    service = "rib.export"

    def __init__(self, size: tuple[int, int] = (640, 480), display: str = "omnirender.tif", **options: Any) -> None:
        super().__init__(**options)
        self.size = (int(size[0]), int(size[1]))
        if min(self.size) <= 0:
            raise ValueError(f"RIB export: size must be positive (width, height), got {size!r}")
        rib_string(display, "Display name")
        self.display = display
        self.lines: list[str] = []
        self._depth = 1  # inside WorldBegin
        self._stack: list[np.ndarray] = []
        self._lights: list[tuple[Any, np.ndarray]] = []
        #: active clip planes: (ClipPlane, world plane row (a, b, c, d), written as a frame option?)
        self._clips: list[tuple[Any, np.ndarray, bool]] = []
        #: world plane rows of the clip planes written as ``ClippingPlane`` options
        self.global_clips: list[np.ndarray] = []
        self._shapes_written = 0
        self._options_removed = 0  # whole-scene clip planes removed before the end of the scene

    # -- output -------------------------------------------------------------
    def emit(self, line: str) -> None:
        """Append one RIB request at the current block indentation."""
        self.lines.append("  " * self._depth + line)

    def begin_block(self, name: str = "Attribute") -> None:
        self.emit(f"{name}Begin")
        self._depth += 1

    def end_block(self, name: str = "Attribute") -> None:
        self._depth -= 1
        self.emit(f"{name}End")

    # -- structure ----------------------------------------------------------
    def enter_node(self, node: Any, world: np.ndarray) -> None:
        parent = self._stack[-1] if self._stack else np.eye(4)
        self.begin_block()
        self.emit(f'Attribute "identifier" "name" [{rib_identifier(node.name)}]')
        local = np.linalg.solve(parent, world)
        if not np.allclose(local, np.eye(4), atol=1e-12):
            self.emit(f"ConcatTransform {_matrix(local)}")
        self._stack.append(np.array(world))

    def leave_node(self, node: Any) -> None:
        self._stack.pop()
        self.end_block()

    # -- clip planes ------------------------------------------------------------
    def add_clip(self, plane: ClipPlane) -> None:
        """Record an added ``ClipPlane``; one for the whole scene becomes a ``ClippingPlane`` option."""
        row = plane.world_plane(self.model_matrix())
        whole_scene = len(self._stack) <= 1 and self._shapes_written == 0
        self._clips.append((plane, row, whole_scene))
        if whole_scene:
            self.global_clips.append(row)
        else:
            normal = " ".join(f"{v:.7g}" for v in np.where(np.abs(row[:3]) < 1e-12, 0.0, row[:3]))
            self.emit(
                f"# ClipPlane normal [{normal}] offset {-float(row[3]):.7g} (world): applied to the geometry "
                "below, as RenderMan's ClippingPlane is a frame option"
            )

    def remove_clip(self, plane: ClipPlane) -> None:
        """Forget the most recent record of ``plane``."""
        for i in range(len(self._clips) - 1, -1, -1):
            if self._clips[i][0] is plane:
                self._options_removed += self._clips[i][2]
                del self._clips[i]
                return

    def local_clips(self) -> list[np.ndarray]:
        """Plane rows in the current model coordinates of the active clip planes the geometry must apply itself."""
        m = self.model_matrix()
        return [m.T @ row for _, row, option in self._clips if not option]

    def clipping_plane_lines(self) -> list[str]:
        """``ClippingPlane`` requests for the whole-scene clip planes (world coordinates, normal negated)."""
        out = []
        for row in self.global_clips:
            normal, d = row[:3], float(row[3])  # |normal| = 1: the plane is normal . p + d = 0
            values = np.concatenate([-d * normal, -normal])  # a point on the plane; the clipped side's normal
            values = np.where(np.abs(values) < 1e-12, 0.0, values)
            out.append("ClippingPlane " + " ".join(f"{v:.7g}" for v in values))
        return out

    def shape_block(self, local: np.ndarray | None = None) -> None:
        """Open a shape's attribute block: transform relative to the node (times ``local``) and appearance."""
        if self._options_removed:
            raise ValueError(
                f"RIB export: a shape in node {self.node_path or '/'} follows the removal of a ClipPlane that was "
                "written as a ClippingPlane option for the whole scene (RenderMan cannot end it); put that "
                "ClipPlane in a node around the shapes it clips instead of removing it by hand"
            )
        self._shapes_written += 1
        self.begin_block()
        node_world = self._stack[-1] if self._stack else np.eye(4)
        m = np.linalg.solve(node_world, self.model_matrix())
        if local is not None:
            m = m @ local
        if not np.allclose(m, np.eye(4), atol=1e-12):
            self.emit(f"ConcatTransform {_matrix(m)}")
        self.appearance()

    def appearance(self) -> None:
        """``Color``, ``Opacity`` and ``Surface`` from the active attributes."""
        surface = self.mono(Surface)
        material, col = self.surface()
        pbr = material if isinstance(material, PBRMaterial) else None
        mat = material if isinstance(material, Material) else None
        if pbr is not None:
            self.emit(f"Color {rib_numbers(pbr.base_color)}")
            opacity = pbr.opacity
            ks = 0.04 + 0.96 * pbr.metallic
            converted = (
                f'Surface "plastic" "Ka" [1] "Kd" {rib_numbers(1.0 - pbr.metallic)} "Ks" {rib_numbers(ks)} '
                f'"roughness" {rib_numbers(max(pbr.roughness**2, 0.001))} "specularcolor" '
                f"{rib_numbers(pbr.base_color if pbr.metallic > 0.5 else (1.0, 1.0, 1.0))}"
            )
        elif mat is not None:
            self.emit(f"Color {rib_numbers(mat.diffuse)}")
            opacity = mat.opacity
            ka = float(np.mean(mat.ambient)) / max(float(np.mean(mat.diffuse)), 1e-6)
            if max(mat.specular) > 0.0:
                converted = (
                    f'Surface "plastic" "Ka" {rib_numbers(min(ka, 1.0))} "Kd" [1] "Ks" [1] '
                    f'"roughness" {rib_numbers(1.0 / max(mat.shininess, 1.0))} '
                    f'"specularcolor" {rib_numbers(mat.specular)}'
                )
            else:
                converted = f'Surface "matte" "Ka" {rib_numbers(min(ka, 1.0))} "Kd" [1]'
        else:
            self.emit(f"Color {rib_numbers((0.8, 0.8, 0.8))}")
            opacity = 1.0
            converted = 'Surface "matte"'
        if col is not None:  # a Color after the material replaces its colour (as in the GL engine)
            self.lines[-1] = self.lines[-1].rsplit("Color ", 1)[0] + f"Color {rib_numbers(col.rgb)}"
            opacity *= col.a
        if opacity < 1.0:
            self.emit(f"Opacity {rib_numbers((opacity,) * 3)}")
        self.emit(surface.rib() if surface is not None else converted)

    # -- lights and camera ----------------------------------------------------
    def add_light(self, light: Any) -> None:
        for other, m in self.lights():
            if other is light:
                self._lights.append((light, np.array(m)))
                return
        self._lights.append((light, self.model_matrix()))

    def reference_point(self) -> np.ndarray:
        if self.camera is None:
            return np.zeros(3)
        camera, world = self.camera
        return (np.asarray(world) @ np.array([*camera.center, 1.0]))[:3]

    def light_lines(self) -> list[str]:
        """``LightSource`` requests for the collected lights (world coordinates)."""
        out = []
        reference = self.reference_point()
        for handle, (light, world) in enumerate(self._lights, start=1):
            color = rib_numbers(light.color)
            if isinstance(light, AmbientLight):
                out.append(
                    f'LightSource "ambientlight" {handle} "intensity" {rib_numbers(light.intensity)} '
                    f'"lightcolor" {color}'
                )
            elif isinstance(light, DirectionalLight):
                d = light.world_direction(world)
                out.append(
                    f'LightSource "distantlight" {handle} "from" [0 0 0] "to" {rib_numbers(d)} '
                    f'"intensity" {rib_numbers(light.intensity)} "lightcolor" {color}'
                )
            elif isinstance(light, AreaLight):
                # RI 3.04's area light: the standard "arealight" shader on the light's polygon (world
                # coordinates; a disc as a 32-gon of its area), radiance L; the renderer samples the shape
                pts = light.world_polygon(world, 32)
                sides = "Sides 2" if light.two_sided else "Sides 1"
                out.append(
                    f"AttributeBegin  # {type(light).__name__}, radiance {float(light.intensity):g}\n"
                    f'  {sides}\n  AreaLightSource "arealight" {handle} "intensity" {rib_numbers(light.intensity)} '
                    f'"lightcolor" {color}\n'
                    f'  Polygon "P" {rib_numbers(pts.reshape(-1))}\nAttributeEnd\nIlluminate {handle} 1'
                )
            elif isinstance(light, (PointLight, SpotLight)):
                p = light.world_position(world)
                # RenderMan lights fall off as 1/d^2; match GL's attenuation at the centre of interest.
                dist = max(float(np.linalg.norm(reference - p)), 1e-6)
                intensity = light.intensity * dist * dist * float(light.attenuation(dist))
                if isinstance(light, PointLight):
                    out.append(
                        f'LightSource "pointlight" {handle} "from" {rib_numbers(p)} '
                        f'"intensity" {rib_numbers(intensity)} "lightcolor" {color}'
                    )
                else:
                    to = p + light.world_direction(world)
                    cone = math.radians(light.cutoff)
                    out.append(
                        f'LightSource "spotlight" {handle} "from" {rib_numbers(p)} "to" {rib_numbers(to)} '
                        f'"coneangle" {rib_numbers(cone)} "conedeltaangle" {rib_numbers(min(cone, math.radians(5)))} '
                        f'"beamdistribution" {rib_numbers(light.exponent)} "intensity" {rib_numbers(intensity)} '
                        f'"lightcolor" {color}'
                    )
        return out

    def camera_lines(self) -> list[str]:
        """``Format``, ``Projection``, clipping and the world-to-camera ``Transform``."""
        w, h = self.size
        camera, world = self.camera if self.camera is not None else (Camera(), np.eye(4))
        aspect = w / h
        out = [f"Format {w} {h} 1"]
        if camera.is_orthographic:
            left, right, bottom, top = camera.window(aspect)
            out.append('Projection "orthographic"')
            out.append(f"ScreenWindow {left:.7g} {right:.7g} {bottom:.7g} {top:.7g}")
        else:
            fov = camera.fov  # RenderMan's fov spans the smaller image side
            if aspect < 1.0:
                fov = math.degrees(2.0 * math.atan(math.tan(math.radians(camera.fov) / 2.0) * aspect))
            out.append(f'Projection "perspective" "fov" {rib_numbers(fov)}')
            if camera.is_off_axis:  # the window in units where the smaller side spans [-1, 1], moved off-axis
                unit = math.tan(math.radians(fov) / 2.0)
                left, right, bottom, top = (v / unit for v in camera.window(aspect))
                out.append(f"ScreenWindow {left:.7g} {right:.7g} {bottom:.7g} {top:.7g}")
        out.append(f"Clipping {camera.near:.7g} {camera.far:.7g}")
        view = np.diag([1.0, 1.0, -1.0, 1.0]) @ camera.view_matrix() @ np.linalg.inv(np.asarray(world, np.float64))
        out.append(f"Transform {_matrix(view)}")
        out += self.clipping_plane_lines()  # after the Transform: world coordinates
        return out

    def document(self, name: str = "scene") -> str:
        """The whole RIB file after a traversal."""
        head = ["##RenderMan RIB", f"# {_UNSAFE.sub('_', str(name))}: written by omnirender", "version 3.04"]
        head.append(f'Display {rib_string(self.display)} "file" "rgba"')
        head += self.camera_lines()
        head.append("WorldBegin")
        body = ["  " + line for line in self.light_lines()]
        return "\n".join([*head, *body, *self.lines, "WorldEnd", ""])


# -- shape handlers ---------------------------------------------------------------
SERVICE = RIBEngine.service
track_surfaces(RIBEngine)


#: shapes whose writers clip their own geometry; the others are simplified under a scoped clip plane
_CLIPS_ITSELF = (TriangleSet, LineSet, PointSet)


def _painter(target: type):
    def decorate(fn):
        def exec_(self: Any, shape: Any, engine: RIBEngine) -> None:
            if target not in _CLIPS_ITSELF and engine.local_clips():
                engine.simplify(shape)
                return
            fn(self, shape, engine)

        cls = type(
            f"{target.__name__}RIBWriter",
            (ShapePainter,),
            {"__slots__": (), "service": SERVICE, "target": target, "exec": exec_, "__doc__": fn.__doc__},
        )
        default_for(RIBEngine)(cls)
        return cls

    return decorate


@_painter(Sphere)
def _sphere(self: Any, shape: Sphere, engine: RIBEngine) -> None:
    """``Sphere r -r r 360`` at the centre."""
    r = float(shape.radius)
    engine.shape_block(_translate(*shape.center))
    engine.emit(f"Sphere {r:.7g} {-r:.7g} {r:.7g} 360")
    engine.end_block()


@_painter(Cylinder)
def _cylinder(self: Any, shape: Cylinder, engine: RIBEngine) -> None:
    """``Cylinder`` (open, z-up) rotated to +y plus two ``Disk`` caps."""
    r, h = float(shape.radius), float(shape.height)
    engine.shape_block(Z_TO_Y)
    engine.emit(f"Cylinder {r:.7g} {-h / 2:.7g} {h / 2:.7g} 360")
    engine.emit(f"Disk {h / 2:.7g} {r:.7g} 360")
    engine.emit(f"Disk {-h / 2:.7g} {r:.7g} 360")
    engine.end_block()


@_painter(Cone)
def _cone(self: Any, shape: Cone, engine: RIBEngine) -> None:
    """``Cone`` (base at z = 0, apex at z = h) moved to base y = -h/2, plus the base ``Disk``."""
    r, h = float(shape.radius), float(shape.height)
    engine.shape_block(_translate(0.0, -h / 2, 0.0) @ Z_TO_Y)
    engine.emit(f"Cone {h:.7g} {r:.7g} 360")
    engine.emit(f"Disk 0 {r:.7g} 360")
    engine.end_block()


@_painter(Torus)
def _torus(self: Any, shape: Torus, engine: RIBEngine) -> None:
    """``Torus`` (ring in xy around z) rotated to the xz plane around +y."""
    engine.shape_block(Z_TO_Y)
    engine.emit(f"Torus {float(shape.major_radius):.7g} {float(shape.minor_radius):.7g} 0 360 360")
    engine.end_block()


@_painter(Disk)
def _disk(self: Any, shape: Disk, engine: RIBEngine) -> None:
    """``Disk`` at height 0 rotated to face +y."""
    engine.shape_block(Z_TO_Y)
    engine.emit(f"Disk 0 {float(shape.radius):.7g} 360")
    engine.end_block()


@_painter(Rectangle)
def _rectangle(self: Any, shape: Rectangle, engine: RIBEngine) -> None:
    """``Polygon`` with the four corners (xz plane, counter-clockwise seen from +y)."""
    sx, sz = (float(v) / 2.0 for v in shape.size)
    corners = [(-sx, 0, sz), (sx, 0, sz), (sx, 0, -sz), (-sx, 0, -sz)]
    engine.shape_block()
    engine.emit(f'Polygon "P" {rib_numbers(corners)} "N" {rib_numbers([(0, 1, 0)] * 4)}')
    engine.end_block()


@_painter(TriangleSet)
def _triangles(self: Any, shape: TriangleSet, engine: RIBEngine) -> None:
    """``PointsPolygons`` with "P", "N" (unless flat shading), "Cs" and "st" (t flipped: RenderMan's t points down)."""
    faces = shape.index_array()
    if len(faces) == 0:
        return
    style = engine.mono(DrawStyle)
    smooth = style is None or getattr(style, "shading", "smooth") != "flat"
    vertices, normals = shape.vertex_array(), shape.normal_array() if smooth else None
    colors, uv = shape.color_array(), shape.texcoord_array()
    planes = engine.local_clips()
    if planes:
        vertices, faces, normals, uv, colors = clip_triangles(vertices, faces, planes, normals, uv, colors)
        if len(faces) == 0:
            return
    engine.shape_block()
    parts = [
        f"PointsPolygons {_ints(np.full(len(faces), 3))} {_ints(faces)}",
        f'"P" {rib_numbers(vertices)}',
    ]
    if normals is not None:
        parts.append(f'"N" {rib_numbers(normals)}')
    if colors is not None:
        parts.append(f'"Cs" {rib_numbers(colors[:, :3])}')
    if uv is not None:
        st = np.array(uv, np.float64)
        st[:, 1] = 1.0 - st[:, 1]
        parts.append(f'"st" {rib_numbers(st)}')
    engine.emit(" ".join(parts))
    engine.end_block()


@_painter(LineSet)
def _lines(self: Any, shape: LineSet, engine: RIBEngine) -> None:
    """``Curves "linear"``: one two-vertex curve per segment."""
    segments = shape.index_array()
    if len(segments) == 0:
        return
    style = engine.mono(DrawStyle)
    width = 0.01 * (getattr(style, "line_width", 1.0) if style is not None else 1.0)
    vertices = shape.vertex_array()
    a, b = vertices[segments[:, 0]], vertices[segments[:, 1]]
    planes = engine.local_clips()
    if planes:
        a, b, _ = clip_segments(a, b, planes)
        if len(a) == 0:
            return
    points = np.stack([a, b], axis=1).reshape(-1, 3)
    engine.shape_block()
    engine.emit(
        f'Curves "linear" {_ints(np.full(len(a), 2))} "nonperiodic" "P" {rib_numbers(points)} '
        f'"constantwidth" {rib_numbers(width)}'
    )
    engine.end_block()


@_painter(PointSet)
def _points(self: Any, shape: PointSet, engine: RIBEngine) -> None:
    """``Points`` with a constant width."""
    vertices = shape.vertex_array()
    if len(vertices) == 0:
        return
    style = engine.mono(DrawStyle)
    width = 0.02 * (getattr(style, "point_size", 1.0) if style is not None else 1.0)
    planes = engine.local_clips()
    if planes:
        vertices = vertices[keep_points(vertices, planes)]
        if len(vertices) == 0:
            return
    engine.shape_block()
    engine.emit(f'Points "P" {rib_numbers(vertices)} "constantwidth" {rib_numbers(width)}')
    engine.end_block()


@default_for(RIBEngine)
class LightWriter(AttributePainter):
    """Lights -> ``LightSource`` requests at the start of the world block."""

    __slots__ = ()
    service = SERVICE
    target = LightSource

    def exec(self, light: LightSource, engine: RIBEngine) -> None:
        engine.add_light(light)


@default_for(RIBEngine)
class ClipPlaneWriter(AttributePainter):
    """``ClipPlane``: a ``ClippingPlane`` option for the whole scene, else clipped geometry (module docstring)."""

    __slots__ = ()
    service = SERVICE
    target = ClipPlane

    def exec(self, plane: ClipPlane, engine: RIBEngine) -> None:
        engine.add_clip(plane)

    def unexec(self, plane: ClipPlane, engine: RIBEngine) -> None:
        engine.remove_clip(plane)


def to_text(
    scene: Any,
    *,
    size: Sequence[int] = (640, 480),
    display: str | None = None,
    on_missing: str = "raise",
    mask: str | None = None,
) -> str:
    """The RIB text of ``scene`` (``display``: the image file name RenderMan writes).

    ``on_missing``: what a shape without a handler does — ``"raise"`` (the
    default, as in every engine: an export must not silently lose geometry),
    ``"warn"`` or ``"skip"``.
    """
    if not isinstance(scene, Node):
        scene = Node("scene", scene)
    engine = RIBEngine(tuple(size), display or f"{_UNSAFE.sub('_', scene.name)}.tif", on_missing=on_missing, mask=mask)
    engine.run(scene)
    return engine.document(scene.name)


def export(scene: Any, path: str | os.PathLike[str], **options: Any) -> None:
    """Write ``scene`` as RenderMan RIB to ``path`` atomically (options: see :func:`to_text`)."""
    options.setdefault("display", Path(path).with_suffix(".tif").name)
    text = to_text(scene, **options)
    with atomic_write(path, "w") as fh:
        fh.write(text)
