"""``POVRayEngine``: evaluates a scene graph into POV-Ray 3.7 SDL text.

The engine is the generic state machine with service ``"pov.paint"``; shape
painters (``painters.py``) call :meth:`POVRayEngine.emit` with the geometry
text of one object and the engine adds the texture, interior, model matrix,
clip planes and object-level ``Raw`` text from the rendering context.  Like
the GL engine, a global ambient of 0.2 is added to the lights' ambient terms
and a scene without lights gets a headlight.  Lights,
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

from ..core import Camera, Engine, Technique
from . import sdl
from .attributes import GlobalSettings, Interior, Raw

__all__ = ["POVRayEngine", "camera_sdl"]

_IDENTITY = np.eye(4)
#: OpenGL's global ambient light, added to the lights' ambient terms (as in the GL engine).
GLOBAL_AMBIENT = 0.2
#: Direction towards the headlight in eye space, used when a scene has no light (as in the GL engine).
HEADLIGHT = np.array([-0.25, 0.35, 1.0]) / np.linalg.norm([-0.25, 0.35, 1.0])


def camera_sdl(camera: Camera, view: np.ndarray, size: tuple[int, int]) -> str:
    """A POV-Ray camera with exactly the projection of ``camera.projection_matrix(w / h)``.

    ``view`` is the world-to-eye matrix.  Perspective: the image plane at unit
    distance spans ``2 tan(fov/2)`` vertically and ``aspect`` times that
    horizontally.  Orthographic: the view volume is ``height`` tall.
    """
    w, h = size
    aspect = w / h
    eye_to_world = np.linalg.inv(view)
    axes = eye_to_world[:3, :3]
    right = axes[:, 0] / np.linalg.norm(axes[:, 0])
    up = axes[:, 1] / np.linalg.norm(axes[:, 1])
    forward = -axes[:, 2] / np.linalg.norm(axes[:, 2])
    location = eye_to_world[:3, 3]
    if camera.is_orthographic:
        kind, extent = "orthographic", float(camera.height)
    else:
        kind, extent = "perspective", 2.0 * math.tan(math.radians(camera.fov) / 2.0)
    return (
        f"camera {{\n  {kind}\n  location {sdl.vector(location)}\n  direction {sdl.vector(forward)}\n"
        f"  right {sdl.vector(right * extent * aspect)}\n  up {sdl.vector(up * extent)}\n}}\n"
    )


class POVRayEngine(Engine):
    """Writes POV-Ray SDL for everything evaluated between ``begin`` and ``end``.

    ``size`` (width, height) fixes the camera's aspect.  ``resource_prefix`` is
    the file-name prefix of images the scene needs (textures given as arrays or
    with unsafe paths); :attr:`resources` lists ``(file name, array or path)``
    pairs for the caller to write next to the ``.pov`` file.
    """

    service = "pov.paint"

    def __init__(
        self,
        size: tuple[int, int] = (640, 480),
        *,
        technique: Technique | None = None,
        on_missing: str = "raise",
        mask: str | Callable[[frozenset[str]], bool] | None = None,
        resource_prefix: str = "om_",
    ) -> None:
        super().__init__(technique=technique, on_missing=on_missing, mask=mask)
        w, h = (int(v) for v in size)
        if w <= 0 or h <= 0:
            raise ValueError(f"POVRayEngine: size must be positive, got {size!r}")
        self.size = (w, h)
        self.resource_prefix = sdl.file_name(resource_prefix, "POVRayEngine")[1:-1]
        self.clear()

    # -- output buffers -------------------------------------------------
    def clear(self) -> None:
        """Forget everything written so far."""
        self.objects: list[str] = []
        self.declarations: list[str] = []
        self.lights_sdl: list[str] = []
        self.resources: list[tuple[str, Any]] = []
        self.background: Any = None
        self.fog: Any = None
        self.ambient = np.full(3, GLOBAL_AMBIENT)
        self.light_count = 0
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
            self.declarations.append(f"#declare {name} = {body};\n")
        return name

    def resource(self, key: Any, data: Any, suffix: str = ".png") -> str:
        """A safe file name for an image the scene refers to (written by the caller)."""
        name = self._resource_names.get(key)
        if name is None:
            name = f"{self.resource_prefix}tex{len(self._resource_names)}{suffix}"
            self._resource_names[key] = name
            self.resources.append((name, data))
        return name

    # -- objects --------------------------------------------------------
    def emit(self, geometry: str, texture: str | None = None, *, matrix: np.ndarray | None = None) -> None:
        """Write one object: ``geometry`` plus texture, interior, model matrix, clip planes, raw modifiers."""
        parts = [f"object {{\n  {geometry}\n"]
        if texture:
            parts.append(f"  texture {{ {texture} }}\n")
        interior = self.mono(Interior)
        if interior is not None:
            parts.append(f"  {interior.sdl()}\n")
        m = self.model_matrix() if matrix is None else matrix
        if not np.array_equal(m, _IDENTITY):
            if abs(np.linalg.det(m[:3, :3])) < 1e-300:
                return  # a degenerate (flattened) transform draws nothing; POV-Ray would reject it
            parts.append(f"  {sdl.matrix(m, self._owner())}\n")
        for plane in self._clip_planes():
            parts.append(f"  {plane}\n")
        for raw in self.poly(Raw):
            if raw.placement == "object":
                parts.append(f"  {raw.text}\n")
        path = self.node_path
        head = sdl.comment(path) + "\n" if path else ""
        self.objects.append(head + "".join(parts) + "}\n")

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
    def sdl(self, fog: bool = True) -> str:
        """The complete scene file for what was evaluated (``fog=False`` leaves the fog out)."""
        head = ["// omnirender scene for POV-Ray 3.7\n#version 3.7;\n"]
        settings = "assumed_gamma 1.0 ambient_light " + sdl.color(self.ambient)
        if self.global_settings is not None:
            settings += " " + self.global_settings.body()
        head.append(f"global_settings {{ {settings} }}\n")
        if self.camera_text is not None:
            head.append(self.camera_text)
        else:
            head.append(camera_sdl(Camera(), Camera().view_matrix(), self.size))
        bg = (0.0, 0.0, 0.0) if self.background is None else _rgb(self.background)
        # transmit 1: the background stays transparent in the alpha channel (om.Image.mask)
        head.append(f"background {{ {sdl.color(bg, transmit=1.0)} }}\n")
        if fog and self.fog is not None:
            head.append(self.fog)
        lights = list(self.lights_sdl)
        if self.light_count == 0:
            lights.append(self._headlight())
        return "".join(head + lights + self.declarations + self.objects)

    def _headlight(self) -> str:
        view = self.view_matrix() if self.camera is not None else Camera().view_matrix()
        towards = np.linalg.inv(view)[:3, :3] @ HEADLIGHT
        towards /= np.linalg.norm(towards)
        return f"light_source {{ {sdl.vector(towards * 1e5)} rgb <1,1,1> parallel point_at <0,0,0> }} // headlight\n"


def _rgb(attr: Any) -> tuple[float, float, float]:
    value = getattr(attr, "color", attr)
    if hasattr(value, "rgb"):
        value = value.rgb
    values = [float(v) for v in value][:3]
    return (values[0], values[1], values[2])
