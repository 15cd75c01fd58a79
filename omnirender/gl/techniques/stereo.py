"""Stereo: two eyes with off-axis projections, packed side by side, top and bottom, as an anaglyph, or one eye.

``om.gl.Stereo(mode, eye_separation, convergence)`` is a GL technique.  Given
to an engine (``GLEngine(stereo=...)``, ``om.render(scene, engine="gl",
stereo=...)``, ``om.Viewer(stereo=...)``) it runs over the whole frame; put
into a node it draws the subgraph after it that way.  Each eye is a pass with
a camera override (the issue-9 pass description): the eyes sit
``eye_separation`` apart along the camera's x axis, both look along the
camera's axis (no toe-in, so no vertical parallax), and each frustum is
sheared so that both see the same window at the ``convergence`` distance:
points there have no disparity, nearer ones cross (left image to the right),
farther ones diverge up to ``eye_separation`` on that window at infinity.

The horizontal disparity of a point at distance ``d`` on an eye image ``w``
pixels wide is ``x_left - x_right = e w / (2 tan(fov_x / 2)) (1/d - 1/c)``
pixels (:func:`disparity_pixels`).

A stereo frame whose scene is drawn by more than the forward technique -- the
deferred pipeline, or a post-processing chain at the top of the scene -- draws
each eye whole, as a frame of its own (``Pass(technique="frame")``), into an
eye-sized target, then copies it into its place: the chain's effects run on
each eye's image (a vignette is centred per eye, FXAA sees one eye's edges),
and the eye target is multisampled as the engine is (the deferred pipeline
shades the samples of edges one by one), resolved by the copy.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..engine.attributes import ColorMask
from ..engine.passes import Clear, FullScreen, Pass, Target
from ..engine.stages import FrameStage
from ..engine.technique import GLTechnique

__all__ = ["Stereo", "StereoStage", "MODES", "eye_matrices", "disparity_pixels"]

#: How the two eyes are packed into the image.
MODES = ("side-by-side", "top-bottom", "anaglyph", "left", "right")
#: Colour masks of the anaglyph's eyes: red for the left eye, green and blue (cyan) for the right.
ANAGLYPH_MASKS = (ColorMask(True, False, False, True), ColorMask(False, True, True, True))
#: A pipeline eye (deferred) copied into its place in the frame, colour over what is there and its depth.
_EYE = Target("stereo.eye")
_EYE_COPY = """uniform sampler2D u_eye;
uniform sampler2D u_eye_depth;
vec4 effect(vec2 uv) {
    // the eye target starts transparent, so what is blended "over" into it (transparent shapes, splats) holds
    // premultiplied colour: made straight again for the pass's "over" blending
    vec4 c = texture(u_eye, uv);
    if (c.a <= 0.0) discard;
    return vec4(c.rgb / c.a, c.a);
}
float effect_depth(vec2 uv) { return texture(u_eye_depth, uv).r; }
"""
#: A multisampled eye copied: its samples averaged (premultiplied: the eye target starts transparent, so an edge
#: keeps what the frame holds under its uncovered samples, and what was blended over it holds premultiplied
#: colour already), the nearest sample's depth.
_EYE_RESOLVE = """uniform sampler2DMS u_eye;
uniform sampler2DMS u_eye_depth;
uniform int u_count;
uniform vec2 u_size;
float g_depth;
vec4 effect(vec2 uv) {
    ivec2 p = ivec2(min(uv * u_size, u_size - 1.0));
    vec4 sum = vec4(0.0);
    g_depth = 1.0;
    for (int i = 0; i < u_count; ++i) {
        vec4 c = texelFetch(u_eye, p, i);
        sum += c;
        g_depth = min(g_depth, texelFetch(u_eye_depth, p, i).r);
    }
    sum /= float(u_count);
    if (sum.a <= 0.0) discard;
    return vec4(sum.rgb / sum.a, sum.a);
}
float effect_depth(vec2 uv) { return g_depth; }
"""


def eye_matrices(
    view: np.ndarray, proj: np.ndarray, aspect: float, sign: float, separation: float, convergence: float
) -> tuple[np.ndarray, np.ndarray]:
    """(view, projection) of one eye (``sign`` -1 left, +1 right) from the centre camera's matrices.

    ``proj`` is a symmetric perspective projection (its vertical field and near/far planes are kept);
    ``aspect`` is the eye image's width / height.  The eye is moved by ``sign * separation / 2`` along the
    camera's x axis and its frustum sheared so that the plane at ``convergence`` is shared by both eyes.
    """
    a, b = float(proj[2, 2]), float(proj[2, 3])
    near, far = b / (a - 1.0), b / (a + 1.0)
    top = near / float(proj[1, 1])
    right = top * aspect
    offset = sign * separation / 2.0
    shift = offset * near / convergence  # the frustum moves against the eye: the convergence window stays put
    left_edge, right_edge = -right - shift, right - shift
    p = np.zeros((4, 4))
    p[0, 0] = 2.0 * near / (right_edge - left_edge)
    p[0, 2] = (right_edge + left_edge) / (right_edge - left_edge) + proj[0, 2]  # plus an off-axis camera's shift
    p[1, 2] = proj[1, 2]
    p[1, 1] = near / top
    p[2, 2] = (far + near) / (near - far)
    p[2, 3] = 2.0 * far * near / (near - far)
    p[3, 2] = -1.0
    move = np.eye(4)
    move[0, 3] = -offset
    return move @ view, p


def disparity_pixels(distance: float, width: int, fov_x: float, separation: float, convergence: float) -> float:
    """Predicted ``x_left - x_right`` in pixels of a point ``distance`` in front of the eyes (on the axis)
    on eye images ``width`` pixels wide with horizontal field ``fov_x`` (degrees)."""
    half = math.tan(math.radians(fov_x) / 2.0)
    return separation * width / (2.0 * half) * (1.0 / distance - 1.0 / convergence)


def _positive(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"Stereo: {name} must be a finite number > 0 (world units), got {value!r}")
    return float(value)


class Stereo(GLTechnique):
    """Stereo pairs with off-axis projections (see the module docstring).

    ``mode``: ``"side-by-side"`` (left eye in the left half), ``"top-bottom"``
    (left eye on top), ``"anaglyph"`` (red left, cyan right), ``"left"`` or
    ``"right"`` (one eye over the whole image).  ``eye_separation``: the
    distance between the eyes in world units; ``convergence``: the distance of
    the zero-parallax plane from the eyes (None: the camera's distance to its
    ``center``).  Each eye keeps the camera's vertical field of view; its
    aspect is that of its half of the image.  Needs a perspective camera.

    Screen stereo (guacamole's screen and eye nodes, for head-tracked VR):
    ``screen`` is a screen node holding an ``om.Rectangle`` or its three world
    corners (lower-left, lower-right, upper-left), ``head`` a tracked node (or
    a world point; None: the frame camera's eye).  Every frame, each eye sits
    ``eye_separation / 2`` from the head along the head node's x axis (the
    screen's right axis for a point) and sees through the screen with
    ``om.Camera.from_screen``: points on the screen have no disparity, and
    moving the head node moves both frusta.  The scene camera gives only near
    and far.  ``convergence`` does not apply.
    """

    __slots__ = ("mode", "eye_separation", "convergence", "screen", "head")

    def __init__(
        self,
        mode: str = "side-by-side",
        eye_separation: float = 0.065,
        convergence: float | None = None,
        *,
        screen: Any = None,
        head: Any = None,
    ):
        if mode not in MODES:
            raise ValueError(f"Stereo: mode must be one of {MODES}, got {mode!r}")
        # per eye: the eye, then (pipelines other than forward only) its copy into the frame
        super().__init__(passes=2 if mode in ("left", "right") else 4)
        self.mode = mode
        self.eye_separation = _positive("eye_separation", eye_separation)
        self.convergence = None if convergence is None else _positive("convergence", convergence)
        if screen is None and head is not None:
            raise ValueError("Stereo: head= needs screen= (the screen node or its corners the eyes look through)")
        if screen is not None and convergence is not None:
            raise ValueError("Stereo: give either convergence= or screen= (a screen's plane has zero parallax)")
        if screen is not None:
            from ...techniques.screen import screen_corners

            screen_corners(screen)  # validated now
        self.screen = screen
        self.head = head

    def screen_eye(self, engine: Any, sign: float, aspect: float) -> tuple[np.ndarray, np.ndarray]:
        """(view, projection) of one eye looking through :attr:`screen` from the tracked head."""
        from ...core.camera import Camera, screen_frame
        from ...techniques.screen import node_frame, node_origin, screen_corners

        corners = screen_corners(self.screen)
        _, right, _, _ = screen_frame(corners)
        if self.head is None:
            head, axis = np.asarray(engine.eye_position, dtype=np.float64)[:3], right
        elif hasattr(self.head, "_compile_node"):
            frame = node_frame(self.head)
            head, axis = frame[:3, 3], frame[:3, 0] / np.linalg.norm(frame[:3, 0])
        else:
            head, axis = node_origin(self.head), right
        camera = engine.frame_camera
        near = float(getattr(camera, "near", 0.1))
        far = float(getattr(camera, "far", 1000.0))
        eye = head + sign * self.eye_separation / 2.0 * axis
        cam = Camera.from_screen(corners, eye, near=near, far=far)
        return cam.view_matrix(), cam.projection_matrix(aspect)

    def eyes(self) -> tuple[float, ...]:
        """The signs of the eyes drawn, in pass order (-1 left, +1 right)."""
        return {"left": (-1.0,), "right": (1.0,)}.get(self.mode, (-1.0, 1.0))

    def viewport(self, sign: float, size: tuple[int, int]) -> tuple[int, int, int, int] | None:
        """The pixel rectangle of an eye in a frame of ``size`` (None: the whole frame)."""
        w, h = size
        if self.mode == "side-by-side":
            half = w // 2
            return (0, 0, half, h) if sign < 0 else (half, 0, w - half, h)
        if self.mode == "top-bottom":
            half = h // 2
            return (0, h - half, w, half) if sign < 0 else (0, 0, w, h - half)
        return None

    def whole_eyes(self, engine: Any) -> bool:
        """Whether each eye is drawn whole into an eye-sized target and copied (see the module docstring): the
        frame's stereo over a scene drawn by more than the forward technique."""
        frame_stereo = len(engine.technique_frames) == 1  # GLEngine(stereo=...), not a Stereo in a node
        return frame_stereo and engine.frame_level_technique() is not engine.technique

    def eye_samples(self, engine: Any) -> int:
        """Samples of the eye target: the engine's where the pipeline draws into it (a post-processing chain
        multisamples its own scene target and writes its output once per pixel)."""
        samples = int(getattr(engine, "samples", 0) or 0)
        return samples if samples > 1 and engine.frame_level_technique() is engine.frame_technique else 0

    def convergence_for(self, engine: Any) -> float:
        """The convergence distance used with ``engine``'s frame camera."""
        if self.convergence is not None:
            return self.convergence
        camera = engine.frame_camera
        eye, center = getattr(camera, "eye", None), getattr(camera, "center", None)
        if eye is None or center is None:
            raise ValueError("Stereo: give convergence= when the frame's camera is given as matrices")
        eye_world = engine.eye_position
        # the camera's centre of interest, through the transforms above the camera (the view matrix holds them)
        d = float(np.linalg.norm(np.subtract(center, eye)))
        return d if d > 0 else float(np.linalg.norm(eye_world))

    def prepare_pass(self, engine: Any) -> bool:
        """Pass 2k draws eye k; pass 2k+1 copies it into the frame when the engine's pipeline is not forward
        (a deferred eye is drawn whole into an eye-sized target first: its passes own the viewport), else it
        is declined."""
        proj = engine.frame_projection
        if abs(proj[3, 3] - 1.0) < 1e-9:
            raise ValueError(
                "Stereo: the camera is orthographic; stereo needs a perspective camera (om.Camera.look_at)"
            )
        index, copy = divmod(engine.current_pass, 2)
        sign = self.eyes()[index]
        size = engine.target_size
        box = self.viewport(sign, size)
        w, h = (box[2], box[3]) if box is not None else size
        # the deferred pipeline, or a post-processing chain around the frame: each eye a frame of its own
        whole = self.whole_eyes(engine)
        name = "left eye" if sign < 0 else "right eye"
        mask = ANAGLYPH_MASKS[index] if self.mode == "anaglyph" else None
        samples = self.eye_samples(engine) if whole else 0
        if copy:
            if not whole:
                return False
            inputs = {"u_eye": (_EYE.name, "color"), "u_eye_depth": (_EYE.name, "depth")}
            code, uniforms = (_EYE_RESOLVE, {"u_count": samples, "u_size": (w, h)}) if samples else (_EYE_COPY, {})
            fullscreen = FullScreen(code, inputs=inputs, uniforms=uniforms,
                                    blend=True, depth=True, label="stereo eye copy",
                                    # the anaglyph's second eye starts from a cleared depth, as in forward
                                    depth_test=None if mask is not None and index == 1 else "lequal")  # fmt: skip
            engine.set_pass(Pass(f"{name} copy", fullscreen=fullscreen, viewport=box, state=(mask,) if mask else ()))
            return True
        if self.screen is not None:
            view, p = self.screen_eye(engine, sign, w / h)
        else:
            view, p = eye_matrices(
                engine.frame_view, proj, w / h, sign, self.eye_separation, self.convergence_for(engine)
            )
        if whole:  # the eye's frame into an eye-sized target (cleared transparent), copied next
            target = Target(_EYE.name, size=(w, h), samples=samples)
            engine.set_pass(Pass(name, camera=(view, p), target=target, clear=Clear(), technique="frame"))
        elif self.mode == "anaglyph":
            clear = Clear(color=None, depth=1.0) if index == 1 else None
            engine.set_pass(Pass(name, camera=(view, p), state=(mask,), clear=clear))
        else:
            engine.set_pass(Pass(name, camera=(view, p), viewport=box))
        return True


class StereoStage(FrameStage):
    """The frame stage of a stereo frame (``GLEngine(stereo=...)``): each eye's pass draws the scene through
    the engine's technique (the ``technique`` stage draws nothing then)."""

    name = "stereo"

    def replayable(self, engine: Any) -> bool:
        """A stereo frame is not recorded (the stereo technique taints the frame plan); none draws nothing."""
        return True

    def follows_rows(self, engine: Any) -> bool:
        """A recorded frame is not stereo: this stage drew nothing."""
        return True

    def draw(self, frame: Any, root: Any) -> int:
        stereo = frame.engine.stereo
        return 0 if stereo is None else frame.run(stereo, root, item_level=False)
