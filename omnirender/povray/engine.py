"""``POVRayEngine``: evaluates a scene graph into POV-Ray 3.7 SDL text.

The engine is the generic state machine with service ``"pov.paint"``; shape
painters (``painters.py``) call :meth:`POVRayEngine.emit` with the geometry
text of one object and the engine adds the texture, interior, model matrix,
clip planes and object-level ``Raw`` text from the rendering context.  Like
the GL engine, a global ambient of 0.2 is added to the lights' ambient terms
and a scene without lights gets a headlight.  Objects under a ``LightSwitch``
that leaves only some lights on are wrapped in a ``light_group`` with copies
of those lights (``global_lights off``).  Lights,
background, fog and global settings are recorded by attribute painters;
:meth:`POVRayEngine.sdl` assembles the file.  The engine writes the scene in
omnirender's right-handed world coordinates unchanged and gives the camera
explicit ``direction``/``right``/``up`` vectors taken from the GL view matrix,
so no handedness flip is needed anywhere: POV-Ray shoots the ray
``direction + x*right + y*up`` through image position (x, y), which is exactly
the GL projection.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..attributes import Mirror, Shadowing
from ..attributes.conversion import native_to
from ..core import Camera, Engine, LightSwitch, Technique
from . import sdl
from .attributes import Finish, GlobalSettings, Interior, Pigment, Raw

__all__ = ["POVRayEngine", "camera_sdl", "depth_texture", "decode_depth", "coverage"]

_IDENTITY = np.eye(4)
#: OpenGL's global ambient light, added to the lights' ambient terms (as in the GL engine).
GLOBAL_AMBIENT = 0.2
#: Direction towards the headlight in eye space, used when a scene has no light (as in the GL engine).
HEADLIGHT = np.array([-0.25, 0.35, 1.0]) / np.linalg.norm([-0.25, 0.35, 1.0])


def camera_sdl(camera: Camera, view: np.ndarray, size: tuple[int, int]) -> str:
    """A POV-Ray camera with exactly the projection of ``camera.projection_matrix(w / h)``.

    ``view`` is the world-to-eye matrix.  Perspective: the image plane at unit
    distance spans ``2 tan(fov/2)`` vertically and ``aspect`` times that
    horizontally.  Orthographic: the view volume is ``height`` tall.  An
    off-axis camera (``camera.shift``) moves the window's centre.
    """
    w, h = size
    aspect = w / h
    eye_to_world = np.linalg.inv(view)
    axes = eye_to_world[:3, :3]
    right = axes[:, 0] / np.linalg.norm(axes[:, 0])
    up = axes[:, 1] / np.linalg.norm(axes[:, 1])
    forward = -axes[:, 2] / np.linalg.norm(axes[:, 2])
    location = eye_to_world[:3, 3]
    sx, sy = camera.shift
    if camera.is_orthographic:
        kind, extent = "orthographic", float(camera.height)
        location = location + extent * (sx * right + sy * up)  # parallel rays: the window moves with the eye
    else:
        kind, extent = "perspective", 2.0 * math.tan(math.radians(camera.fov) / 2.0)
        # off-axis: POV-Ray's ray is direction + x right + y up (x, y in [-1/2, 1/2]), so pointing ``direction`` at
        # the shifted window's centre gives glFrustum's asymmetric window (POV-Ray then warns that the camera
        # vectors are not perpendicular, and renders exactly that)
        forward = forward + extent * (sx * right + sy * up)

    # the axes at full precision: POV-Ray warns "Camera vectors are not perpendicular" when a dot product of
    # the parsed vectors exceeds 1e-10, which 9 significant digits do not guarantee
    def exact(v: np.ndarray) -> str:
        sdl.vector(v)  # finite check
        return "<" + ",".join("0" if x == 0.0 else f"{float(x):.17g}" for x in v) + ">"

    return (
        f"camera {{\n  {kind}\n  location {sdl.vector(location)}\n  direction {exact(forward)}\n"
        f"  right {exact(right * extent * aspect)}\n  up {exact(up * extent)}\n}}\n"
    )


class POVRayEngine(Engine):
    """Writes POV-Ray SDL for everything evaluated between ``begin`` and ``end``.

    ``size`` (width, height) fixes the camera's aspect.  ``resource_prefix`` is
    the file-name prefix of images the scene needs (textures given as arrays or
    with unsafe paths); :attr:`resources` lists ``(file name, array or path)``
    pairs for the caller to write next to the ``.pov`` file.
    """

    service = "pov.paint"
    uses_camera_mask = True

    def __init__(
        self,
        size: tuple[int, int] = (640, 480),
        *,
        technique: Technique | None = None,
        on_missing: str = "raise",
        mask: str | Callable[[frozenset[str]], bool] | None = None,
        resource_prefix: str = "om_",
        resource_dir: str | None = None,
    ) -> None:
        super().__init__(technique=technique, on_missing=on_missing, mask=mask)
        w, h = (int(v) for v in size)
        if w <= 0 or h <= 0:
            raise ValueError(f"POVRayEngine: size must be positive, got {size!r}")
        self.size = (w, h)
        self.resource_prefix = sdl.file_name(resource_prefix, "POVRayEngine")[1:-1]
        #: the folder the resources are written to, named in the SDL (so the file renders from any folder)
        self.resource_dir = None if resource_dir is None else sdl.file_name(resource_dir, "POVRayEngine")[1:-1]
        self.clear()

    # -- output buffers -------------------------------------------------
    def clear(self) -> None:
        """Forget everything written so far."""
        self.objects: list[str | _Object] = []
        #: Color / Material / PBRMaterial in the order they became active (the one appearance model)
        self.surface_stack: list[Any] = []
        self.declarations: list[str] = []
        self.lights_sdl: list[str] = []
        self.resources: list[tuple[str, Any]] = []
        self.background: Any = None
        self.fog: Any = None
        self.ambient = np.full(3, GLOBAL_AMBIENT)
        self.light_count = 0
        #: id(light) -> its light_source text (for light groups under a LightSwitch)
        self.light_texts: dict[int, str] = {}
        self.global_settings: GlobalSettings | None = None
        self.camera_text: str | None = None
        self._declared: dict[Any, str] = {}
        self._resource_names: dict[Any, str] = {}
        self._clip_matrices: dict[int, np.ndarray] = {}

    def begin(self, root: Any) -> None:
        self.clear()
        super().begin(root)
        if self.camera is not None:
            camera, _ = self.camera
            self.camera_text = camera_sdl(camera, self.view_matrix(), self.size)

    def declare(self, key: Any, kind: str, body: str) -> str:
        """``#declare`` ``body`` once per ``key`` and return its identifier (``OM_<kind><n>``)."""
        name = self._declared.get(key)
        if name is None:
            name = f"OM_{kind}{len(self._declared)}"
            self._declared[key] = name
            where = sdl.comment(self.node_path) + "\n" if self.node_path else ""  # for error locations
            self.declarations.append(f"{where}#declare {name} = {body};\n")
        return name

    def resource(self, key: Any, data: Any, suffix: str = ".png") -> str:
        """A safe file name for an image the scene refers to (written by the caller)."""
        name = self._resource_names.get(key)
        if name is None:
            name = f"{self.resource_prefix}tex{len(self._resource_names)}{suffix}"
            self.resources.append((name, data))
            if self.resource_dir is not None:
                name = f"{self.resource_dir.rstrip('/')}/{name}"
            self._resource_names[key] = name
        return name

    # -- objects --------------------------------------------------------
    def emit(
        self,
        geometry: str,
        texture: str | None = None,
        *,
        matrix: np.ndarray | None = None,
        plain: Callable[[], str] | None = None,
    ) -> None:
        """Write one object: ``geometry`` plus texture, interior, model matrix, clip planes, raw modifiers.

        ``plain`` returns the geometry without embedded textures (per-vertex
        colours), for the depth pass; by default ``geometry`` is used.
        """
        m = self.model_matrix() if matrix is None else matrix
        placement = []
        if not np.array_equal(m, _IDENTITY):
            if abs(np.linalg.det(m[:3, :3])) < 1e-300:
                return  # a degenerate (flattened) transform draws nothing; POV-Ray would reject it
            placement.append(f"  {sdl.matrix(m, self._owner())}\n")
        for plane in self._clip_planes():
            placement.append(f"  {plane}\n")
        placement.extend(self._shadow_and_mirror())
        for raw in self.poly(Raw):
            if raw.placement == "object":
                placement.append(f"  {raw.text}\n")
        interior = self.mono(Interior)
        path = self.node_path
        obj = _Object(
            sdl.comment(path) + "\n" if path else "",
            geometry,
            f"  texture {{ {texture} }}\n" if texture else "",
            f"  {interior.sdl()}\n" if interior is not None else "",
            "".join(placement),
            plain,
        )
        shadowing = self.mono(Shadowing)
        receives = shadowing is None or shadowing.receive
        if self.mono(LightSwitch) is not None or not receives:
            lit = [id(light) for light, _ in self.lights()]
            if not receives or len(lit) != len(self.light_texts) or any(i not in self.light_texts for i in lit):
                # only some lights reach this object, or no shadow may fall on it: a light group with
                # copies of its lights (shadowless copies for an object that receives no shadows)
                texts = [self.light_texts[i] for i in lit if i in self.light_texts]
                if not receives:
                    texts = [_shadowless(t) for t in texts]
                obj.group = "".join(texts)
        self.objects.append(obj)

    def _shadow_and_mirror(self) -> list[str]:
        """Object modifiers of the generic ``Shadowing`` (``no_shadow``) and ``Mirror`` (a reflecting finish)."""
        out = []
        shadowing = self.mono(Shadowing)
        if shadowing is not None and not shadowing.cast:
            out.append("  no_shadow\n")
        mirror = self.mono(Mirror)
        if mirror is not None and mirror.reflectance > 0.0:
            # added to the texture's finish; conserve_energy dims the surface's own colour by the reflected part
            out.append(f"  finish {{ reflection {{ {sdl.number(mirror.reflectance)} }} conserve_energy }}\n")
        return out

    def _owner(self) -> str:
        path = self.node_path
        return f"POV-Ray (node {path})" if path else "POV-Ray"

    def _clip_planes(self) -> list[str]:
        from ..attributes import ClipPlane

        out = []
        for plane in self.poly(ClipPlane):
            a, b, c, d = plane.world_plane(self._clip_matrices.get(id(plane), _IDENTITY))
            # keeps a x + b y + c z + d >= 0; POV-Ray keeps the inside of plane {N, D}: N.p <= D
            out.append(f"clipped_by {{ plane {{ {sdl.vector((-a, -b, -c))}, {sdl.number(d)} }} }}")
        return out

    # -- the file -------------------------------------------------------
    def sdl(self, fog: bool = True, depth: bool = False, standalone: bool = False) -> str:
        """The complete scene file for what was evaluated.

        ``fog=False`` leaves the fog out; ``depth=True`` writes the depth pass:
        no lights, every object self-lit by a world-space pigment that encodes
        the eye-space depth (see :func:`depth_texture`).  ``standalone=True``
        writes an opaque background (the scene's, else the shared default), for
        a file rendered by ``povray`` directly rather than composited by omnirender.
        """
        head = ["// omnirender scene for POV-Ray 3.7\n#version 3.7;\n"]
        settings = "assumed_gamma 1.0 ambient_light " + sdl.color(self.ambient)
        if self.global_settings is not None and not depth:
            settings += " " + self.global_settings.body()
        head.append(f"global_settings {{ {settings} }}\n")
        head.append(self.camera_text if self.camera_text is not None else self._default_camera())
        bg = (0.0, 0.0, 0.0) if self.background is None else _rgb(self.background)
        if depth:  # blue marks the background; objects have none
            head.append("background { rgb <0,0,1> }\n")
        elif standalone:
            from ..attributes.environment import DEFAULT_BACKGROUND
            from .appearance import srgb_to_linear

            shown = DEFAULT_BACKGROUND[:3] if self.background is None else bg
            head.append(f"background {{ {sdl.color(srgb_to_linear(shown))} }}\n")
        else:  # transmit 1: the background stays transparent in the alpha channel (om.Image.mask)
            head.append(f"background {{ {sdl.color(bg, transmit=1.0)} }}\n")
        if depth:
            head.append(f"#declare OM_DEPTH = {depth_texture(self.depth_view(), self.depth_range())};\n")
            body = [o.depth_sdl() if isinstance(o, _Object) else o for o in self.objects]
            return "".join(head + body)
        if fog and self.fog is not None:
            head.append(self.fog)
        lights = list(self.lights_sdl)
        if self.light_count == 0:
            lights.append(self._headlight())
        body = [o.sdl() if isinstance(o, _Object) else o for o in self.objects]
        return "".join(head + lights + self.declarations + body)

    def _default_camera(self) -> str:
        return camera_sdl(Camera(), Camera().view_matrix(), self.size)

    def depth_view(self) -> np.ndarray:
        """The world-to-eye matrix the depth pass measures with."""
        return self.view_matrix() if self.camera is not None else Camera().view_matrix()

    def depth_range(self) -> float:
        """The depth that maps to the largest encoded value: the camera's far distance."""
        return float(self.camera[0].far) if self.camera is not None else Camera().far

    def _headlight(self) -> str:
        view = self.depth_view()
        towards = np.linalg.inv(view)[:3, :3] @ HEADLIGHT
        towards /= np.linalg.norm(towards)
        # shadowless, as the GL engine's headlight (it sits at the eye, where shadows hide behind their casters)
        return (
            f"light_source {{ {sdl.vector(towards * 1e5)} rgb <1,1,1> parallel point_at <0,0,0> shadowless }}"
            " // headlight\n"
        )


def _shadowless(light_text: str) -> str:
    """A ``light_source`` text made ``shadowless`` (once)."""
    if " shadowless" in light_text:
        return light_text
    if light_text.count("light_source") > 1:  # a two-sided area light: one light_source per side
        return "".join(
            _shadowless(part) for part in light_text.replace("light_source", "\0light_source").split("\0")[1:]
        )
    end = light_text.rindex("}")
    return f"{light_text[:end]}shadowless {light_text[end:]}"


def _rgb(attr: Any) -> tuple[float, float, float]:
    value = getattr(attr, "color", attr)
    if hasattr(value, "rgb"):
        value = value.rgb
    values = [float(v) for v in value][:3]
    return (values[0], values[1], values[2])


class _Object:
    """One object of the scene file, kept in parts so the depth pass can re-texture it."""

    __slots__ = ("head", "geometry", "texture", "interior", "placement", "plain", "group")

    def __init__(
        self, head: str, geometry: str, texture: str, interior: str, placement: str, plain: Callable[[], str] | None
    ) -> None:
        self.head, self.geometry, self.texture = head, geometry, texture
        self.interior, self.placement, self.plain = interior, placement, plain
        self.group: str | None = None  # light_source texts when a LightSwitch leaves only some lights on

    def sdl(self) -> str:
        text = f"object {{\n  {self.geometry}\n{self.texture}{self.interior}{self.placement}}}\n"
        if self.group is not None:
            text = f"light_group {{\n{self.group}{text}global_lights off\n}}\n"
        return self.head + text

    def depth_sdl(self) -> str:
        geometry = self.plain() if self.plain is not None else self.geometry
        # the texture comes after the matrix, so its pattern is evaluated in world coordinates
        return f"object {{\n  {geometry}\n{self.placement}  texture {{ OM_DEPTH }}\n}}\n"


def depth_texture(view: np.ndarray, far: float) -> str:
    """A self-lit texture whose red channel is depth / far and green channel frac(256 depth / far).

    Depth is the eye-space distance along the viewing axis,
    ``-(view @ p).z``.  Two pigments are averaged, so each colour map goes
    to 2 (the average halves it).  Decoded by :func:`decode_depth`.
    """
    row = -np.asarray(view, dtype=np.float64)[2]  # depth = row . (x, y, z, 1)
    a, b, c, d = (sdl.number(v / far) for v in row)
    f = f"({a})*x + ({b})*y + ({c})*z + ({d})"
    coarse = f"function {{ min(max({f}, 0), 1) }} color_map {{ [0 rgb 0] [1 rgb <2,0,0>] }}"
    fine = f"function {{ mod(max({f}, 0) * 256, 1) }} color_map {{ [0 rgb 0] [1 rgb <0,2,0>] }}"
    return (
        f"texture {{ pigment {{ average pigment_map {{ [1 {coarse}] [1 {fine}] }} }}"
        " finish { ambient 0 diffuse 0 emission 1 } }"
    )


def decode_depth(rgb16: np.ndarray, far: float) -> np.ndarray:
    """Depth from the 16-bit RGB depth-pass image (inf where the blue background shows)."""
    r = rgb16[:, :, 0].astype(np.float64) / 65535.0
    g = rgb16[:, :, 1].astype(np.float64) / 65535.0
    coarse = r * 256.0
    n = np.floor(coarse)
    best = n + g
    for k in (-1.0, 1.0):  # the fine digit decides between neighbouring coarse steps
        cand = n + k + g
        better = np.abs(cand - coarse) < np.abs(best - coarse)
        best = np.where(better, cand, best)
    depth = (best / 256.0 * far).astype(np.float32)
    depth[coverage(rgb16) == 0] = np.inf
    return depth


def coverage(rgb16: np.ndarray) -> np.ndarray:
    """(H, W) uint8 alpha of the depth pass: 255 on objects, 0 on the (blue) background."""
    return np.where(rgb16[:, :, 2] < 32768, 255, 0).astype(np.uint8)


# Its own renderer-specific attributes stay on their stacks here (other engines convert them to generic ones).
native_to(POVRayEngine, "pov.paint", Finish, Pigment)
