"""What the pass being drawn sees: its camera, its target and the GL state applier.

One :class:`FrameState` per engine.  The frame runner (:mod:`.frame`) writes
it when a frame starts and whenever a pass changes camera or target; the batch
drawer (:mod:`.drawer`) reads it for every draw; the engine's public frame
properties (``frame_view``, ``target_size``, ``linear_output``, ...) are views
of it.  Nothing else writes it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["FrameState", "ProjectionInfo"]

#: cameras whose uniforms are kept (the frame's, shadow maps', mirrors') before they are all dropped
_CAMERAS_KEPT = 8


class ProjectionInfo:
    """Near, far and kind of a projection given as a matrix (what depth read-back needs of a camera)."""

    __slots__ = ("near", "far", "is_orthographic")

    def __init__(self, near: float, far: float, is_orthographic: bool) -> None:
        self.near, self.far, self.is_orthographic = near, far, is_orthographic

    @classmethod
    def of(cls, proj: np.ndarray) -> ProjectionInfo:
        """The near and far planes of an OpenGL perspective or orthographic projection matrix."""
        a, b = float(proj[2, 2]), float(proj[2, 3])
        if abs(proj[3, 3] - 1.0) < 1e-9:  # orthographic: ndc z = a z + b
            return cls((b + 1.0) / a, (b - 1.0) / a, True)
        return cls(b / (a - 1.0), b / (a + 1.0), False)


class FrameState:
    """The camera, target and applier of the pass being drawn, and the frame's own camera."""

    __slots__ = (
        "camera",
        "_cameras",
        "view",
        "proj",
        "ortho",
        "view_key",
        "uniforms",
        "lights",
        "frame_view",
        "frame_view_key",
        "target_size",
        "linear_output",
        "shading",
        "applier",
        "shadow_plan",
        "background",
        "drawing",
        "recorder",
    )

    def __init__(self, size: tuple[int, int]) -> None:
        #: the frame's ``om.Camera`` (or a :class:`ProjectionInfo` for a camera given as matrices)
        self.camera: Any = None
        self.view = np.eye(4)
        self.proj = np.eye(4)
        self.ortho = False
        #: bytes identifying (view, projection) of the pass: batches are sorted and culled per key
        self.view_key = b""
        #: u_view, u_proj, u_eye_to_world of the pass as float32 bytes (transposed for GL)
        self.uniforms: dict[str, bytes] = {}
        #: (view, projection) bytes -> those uniforms, for the last few cameras
        self._cameras: dict[bytes, dict[str, bytes]] = {}
        #: LightUniforms of the pass by light switch (made again whenever the camera changes)
        self.lights: dict[int, Any] = {}
        #: the frame's own view (the same in every pass: shadow maps and mirrors draw with other views)
        self.frame_view = np.eye(4)
        self.frame_view_key = b""
        self.target_size = tuple(size)
        #: whether the bound target holds linear light (a float target), not display values
        self.linear_output = False
        #: the shader overrides of the pass being drawn as program features (``Composed.shading()``): drawers of
        #: custom kinds read them (a depth-only pass, an alpha cutoff)
        self.shading: tuple[tuple[str, Any], ...] = ()
        #: the frame's RasterApplier (None outside a frame)
        self.applier: Any = None
        #: the frame's ShadowPlan, or None
        self.shadow_plan: Any = None
        #: the ``background`` given to ``draw`` (post-processing clears with it)
        self.background: Any = None
        #: whether a frame is being drawn
        self.drawing = False
        #: the FrameRecorder of the frame being drawn (:mod:`.plan`), or None when the frame is not recorded
        self.recorder: Any = None

    def set_camera(self, view: np.ndarray, proj: np.ndarray, ortho: bool) -> None:
        """Make (``view``, ``proj``) the camera of the pass being drawn."""
        key = view.tobytes() + proj.tobytes()
        if key != getattr(self, "view_key", None):  # the same camera as the last pass's: its uniforms kept
            uniforms = self._cameras.get(key)
            if uniforms is None:  # a camera not among the last few (a shadow map's and the frame's alternate)
                uniforms = {
                    "u_view": view.T.astype(np.float32).tobytes(),
                    "u_proj": proj.T.astype(np.float32).tobytes(),
                    "u_eye_to_world": np.linalg.inv(view).T.astype(np.float32).tobytes(),
                }
                if len(self._cameras) >= _CAMERAS_KEPT:
                    self._cameras.clear()
                self._cameras[key] = uniforms
            self.uniforms = uniforms
        self.view = view
        self.proj = proj
        self.ortho = ortho
        self.view_key = key
        self.lights = {}

    def camera_state(self) -> tuple[np.ndarray, np.ndarray, bool]:
        """(view, projection, orthographic) of the pass, to give back to :meth:`set_camera` later."""
        return self.view, self.proj, self.ortho
