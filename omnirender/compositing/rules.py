"""Checking a renderer against the four integration rules of DESIGN.md.

:func:`check_rules` draws the renderer twice inside a GL frame, the way a tree
draws it: once over an empty framebuffer (transparent black, depth 1, stencil
0), which shows its *footprint*, and once over a framebuffer pre-filled with
known patterns -- cells of distinct colours, of depths spread over the
renderer's depth range (some cells at the far plane: background), of stencil
values.  Before each run the GL state is set to an unusual but harmless value
(blending on with factors one/zero, depth function ``lequal``, a scissor box
covering everything, a stencil test that always passes, ...), which a renderer
that sets what it needs does not notice.  Then:

1. **preservation of results**: outside the footprint, no colour or depth of
   the pattern changed (filters are exempt: changing the image is their job);
2. **colour-depth consistency**: depth changed only where colour changed, and
   colour changed only where the depth afterwards is a surface (not the far
   plane), unless the new colour is empty (alpha 0); a filter changes no depth;
3. **stencil invariability**: the stencil buffer is the same afterwards;
4. **state preservation**: the GL state afterwards equals the state before.

The :class:`RuleReport` lists each violation with the pixels (count, bounding
box, examples with values before and after) or the GL states involved.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..gl import Target
from ..gl.engine.glenum import (
    GL_ALWAYS,
    GL_FRONT,
    GL_LEQUAL,
    GL_ONE,
    GL_ZERO,
)
from ..gl.engine.technique import GLTechnique
from .canvas import Canvas
from .renderer import Filter, Renderer

__all__ = ["check_rules", "RuleReport", "RuleViolation", "RULES"]

#: The four rules by number.
RULES = {
    1: "preservation of results",
    2: "colour-depth consistency",
    3: "stencil invariability",
    4: "state preservation",
}

_CELL = 6  # pattern cell size in pixels

#: What the found state differs in (harmless for a renderer that sets the state it needs).

_RESTORE = """
uniform sampler2D u_color;
uniform sampler2D u_depth;
vec4 effect(vec2 uv) { return texelFetch(u_color, ivec2(gl_FragCoord.xy), 0); }
float effect_depth(vec2 uv) { return texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r; }
"""


@dataclass
class RuleViolation:
    """One broken rule: its number and name, a message, and the pixels (x, y from the top left) or GL states."""

    rule: int
    message: str
    pixels: np.ndarray | None = None
    states: list[tuple[str, Any, Any]] | None = None

    @property
    def name(self) -> str:
        return RULES[self.rule]

    def __str__(self) -> str:
        return f"rule {self.rule} ({self.name}) violated: {self.message}"


@dataclass
class RuleReport:
    """The outcome of :func:`check_rules`: ``ok``, the ``violations`` and which ``rules`` they break."""

    renderer: Any
    size: tuple[int, int]
    violations: list[RuleViolation] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.violations

    @property
    def rules(self) -> set[int]:
        """Numbers of the rules violated."""
        return {v.rule for v in self.violations}

    def __bool__(self) -> bool:
        return self.ok

    def __str__(self) -> str:
        name = type(self.renderer).__name__
        if self.ok:
            return f"{name} follows the four integration rules ({self.size[0]}x{self.size[1]} test framebuffers)"
        lines = [f"{name} violates {len(self.rules)} of the four integration rules:"]
        lines += [f"  - {v}" for v in self.violations]
        return "\n".join(lines)


@dataclass
class _Run:
    before: dict[str, np.ndarray]
    after: dict[str, np.ndarray]
    states: list[tuple[str, Any, Any]]


class _Harness(GLTechnique):
    """Fills the framebuffer, sets the found state, draws the renderer and reads everything back."""

    __slots__ = ("renderer", "pattern", "runs")

    def __init__(self, renderer: Renderer, pattern: dict[str, np.ndarray]) -> None:
        super().__init__(passes=1)
        object.__setattr__(self, "renderer", renderer)
        object.__setattr__(self, "pattern", pattern)
        object.__setattr__(self, "runs", [])

    def prepare_pass(self, engine: Any) -> None:
        from ..gl import Pass

        engine.set_pass(Pass("check-rules", custom=self._run))

    def _run(self, engine: Any, draw: Any) -> int:
        from ..gl.engine.glstate import capture_state

        canvas = Canvas(engine, draw)
        fbo = canvas.framebuffer
        _fill(canvas, self.pattern)
        before = _read(canvas)
        found = capture_state(fbo)
        unusual = _unusual(found, canvas.size)
        unusual.restore()
        self.renderer.draw(canvas)
        after_state = capture_state(fbo)
        states = unusual.diff(after_state)
        found.restore()
        self.runs.append(_Run(before, _read(canvas), states))
        return canvas.calls


def _unusual(state: Any, size: tuple[int, int]) -> Any:
    w, h = size
    return state.replace(
        blend=True,
        blend_src_rgb=GL_ONE,
        blend_dst_rgb=GL_ZERO,
        blend_src_alpha=GL_ONE,
        blend_dst_alpha=GL_ZERO,
        blend_color=(0.1, 0.2, 0.3, 0.4),
        depth_func=GL_LEQUAL,
        scissor_test=True,
        scissor_box=(0, 0, w, h),
        polygon_offset_fill=True,
        stencil_test=True,
        stencil_func=GL_ALWAYS,
        stencil_back_func=GL_ALWAYS,
        cull_face=False,
        cull_face_mode=GL_FRONT,
        depth_clamp=True,
    )


def _fill(canvas: Canvas, pattern: dict[str, np.ndarray]) -> None:
    """Write the pattern's colour, depth and stencil into the framebuffer."""
    from ..gl.engine.glstate import write_stencil

    name = "check-rules.pattern"
    target = canvas.copy(Target(name))
    target.texture("color").write(np.ascontiguousarray(pattern["color"][::-1]).tobytes())
    target.depth.write(np.ascontiguousarray(pattern["depth"][::-1], dtype=np.float32).tobytes())
    canvas.fullscreen("pattern", _RESTORE, {"u_color": (name, "color"), "u_depth": (name, "depth")}, depth=True)
    write_stencil(canvas.framebuffer, pattern["stencil"], _CELL)  # scissored clears, the state put back after


def _read(canvas: Canvas) -> dict[str, np.ndarray]:
    from ..gl.engine.glstate import read_stencil

    fbo = canvas.framebuffer
    w, h = canvas.size
    color = np.frombuffer(fbo.read(components=4, alignment=1), np.uint8).reshape(h, w, 4)[::-1].copy()
    depth = np.frombuffer(fbo.read(components=1, attachment=-1, dtype="f4", alignment=1), np.float32)
    return {"color": color, "depth": depth.reshape(h, w)[::-1].copy(), "stencil": read_stencil(fbo, (w, h))}


def _patterns(renderer: Renderer, camera: Camera, size: tuple[int, int]) -> tuple[dict, dict]:
    """The empty framebuffer and the pre-filled one (colour cells, depth cells over the renderer's range)."""
    w, h = size
    rows, cols = np.mgrid[0:h, 0:w] // _CELL
    cell = rows * 1009 + cols * 31
    rng = np.random.default_rng(7)
    palette = rng.integers(30, 226, size=(997, 3)).astype(np.uint8)
    color = np.empty((h, w, 4), np.uint8)
    color[..., :3] = palette[cell % 997]
    color[..., 3] = 255
    near, far = _depth_range(renderer, camera, w / h)
    fractions = ((cell * 7919) % 101) / 100.0
    distance = near + fractions * (far - near)
    depth = _window_depth(camera, distance)
    depth[(rows + 2 * cols) % 5 == 0] = 1.0  # background cells
    stencil = ((rows * 7 + cols * 3) % 251 + 1).astype(np.uint8)
    filled = {"color": color, "depth": depth.astype(np.float32), "stencil": stencil}
    empty = {
        "color": np.zeros((h, w, 4), np.uint8),
        "depth": np.ones((h, w), np.float32),
        "stencil": np.zeros((h, w), np.uint8),
    }
    return empty, filled


def _depth_range(renderer: Renderer, camera: Camera, aspect: float) -> tuple[float, float]:
    """Eye distances spanning the renderer's bounds (with margin), within the camera's near and far."""
    box = renderer.bounds()
    if box is None:
        return camera.near * 1.5, min(camera.far, camera.near * 1000.0)
    from ..geometry.bounds import corners

    view = camera.view_matrix()
    pts = corners(*box) @ view[:3, :3].T + view[:3, 3]
    z = -pts[:, 2]
    lo, hi = float(z.min()), float(z.max())
    margin = 0.25 * (hi - lo) + 1e-3
    return max(camera.near * 1.01, lo - margin), min(camera.far * 0.99, hi + margin)


def _window_depth(camera: Camera, distance: np.ndarray) -> np.ndarray:
    n, f = camera.near, camera.far
    if camera.is_orthographic:
        return (distance - n) / (f - n)
    ndc = (f + n) / (f - n) - 2.0 * f * n / ((f - n) * distance)
    return ndc * 0.5 + 0.5


def check_rules(
    renderer: Renderer, size: tuple[int, int] = (96, 72), camera: Camera | None = None, tolerance: int = 1
) -> RuleReport:
    """Run ``renderer`` over known framebuffers and report the integration rules it violates.

    ``camera`` defaults to the renderer's own (its first scene camera, else one
    framing its bounds); ``tolerance`` is the colour difference (0-255) below
    which a pixel counts as unchanged.
    """
    from ..gl.glengine import GLEngine
    from ..scene.node import Node

    if not isinstance(renderer, Renderer):
        raise TypeError(f"check_rules: renderer must be an om.compositing.Renderer, got {renderer!r:.60}")
    w, h = size
    if camera is None:
        camera, world = renderer.default_camera(w / h)
        if not np.allclose(world, np.eye(4)):
            from ..core.transform import Matrix

            placed = Node("camera", [Matrix(world), camera])
            camera = _world_camera(camera, world)
        else:
            placed = Node("camera", [camera])
    else:
        placed = Node("camera", [camera])
    empty, filled = _patterns(renderer, camera, (w, h))
    report = RuleReport(renderer, (w, h))
    with GLEngine(size=(w, h), samples=0) as engine:
        runs = []
        for pattern in (empty, filled):
            harness = _Harness(renderer, pattern)
            engine.render(Node.transient([placed, harness]), background=(0, 0, 0, 0), read_depth=False)
            runs.append(harness.runs[-1])
    _judge(report, renderer, runs[0], runs[1], tolerance)
    return report


def _world_camera(camera: Camera, world: np.ndarray) -> Camera:
    """``camera`` placed by ``world`` as a camera in world coordinates (to measure depths)."""
    m = np.asarray(world, dtype=np.float64)
    eye = (m @ np.array([*camera.eye, 1.0]))[:3]
    center = (m @ np.array([*camera.center, 1.0]))[:3]
    up = m[:3, :3] @ np.asarray(camera.up)
    return Camera(
        eye, center, up, fov=camera.fov, height=camera.height, near=camera.near, far=camera.far, shift=camera.shift
    )


def _judge(report: RuleReport, renderer: Renderer, empty: _Run, filled: _Run, tolerance: int) -> None:
    is_filter = isinstance(renderer, Filter)

    def colour_changed(run: _Run) -> np.ndarray:
        diff = np.abs(run.after["color"].astype(int) - run.before["color"].astype(int)).max(axis=2)
        return diff > tolerance

    def depth_changed(run: _Run) -> np.ndarray:
        return np.abs(run.after["depth"] - run.before["depth"]) > 1e-6

    footprint = colour_changed(empty) | depth_changed(empty)
    c_filled, d_filled = colour_changed(filled), depth_changed(filled)
    if not is_filter:
        destroyed = (c_filled | d_filled) & ~footprint
        _pixels(report, 1, destroyed, filled, "earlier results outside the renderer's footprint changed")
    if is_filter:
        _pixels(report, 2, d_filled | depth_changed(empty), filled, "a filter changed the depth buffer")
    else:
        drew = colour_changed(empty) | c_filled
        for run, changed in ((empty, depth_changed(empty)), (filled, d_filled)):
            _pixels(report, 2, changed & ~drew, run, "depth changed where no colour was drawn")
        for run, changed in ((empty, colour_changed(empty)), (filled, c_filled)):
            flat = changed & (run.after["depth"] >= 1.0) & (run.after["color"][..., 3] > tolerance)
            _pixels(report, 2, flat, run, "colour was drawn where the depth is the far plane (no surface)")
    for run in (empty, filled):
        _pixels(report, 3, run.after["stencil"] != run.before["stencil"], run, "the stencil buffer changed")
    for run in (empty, filled):
        if run.states:
            names = ", ".join(f"{n} {b!r} -> {a!r}" for n, b, a in run.states[:6])
            more = f" (+{len(run.states) - 6} more)" if len(run.states) > 6 else ""
            report.violations.append(RuleViolation(4, f"GL state not restored: {names}{more}", states=run.states))
            break


def _pixels(report: RuleReport, rule: int, mask: np.ndarray, run: _Run, what: str) -> None:
    if not mask.any() or any(v.rule == rule and v.message.startswith(what) for v in report.violations):
        return
    ys, xs = np.nonzero(mask)
    examples = []
    for y, x in list(zip(ys, xs, strict=True))[:3]:
        b, a = run.before, run.after
        examples.append(
            f"({x}, {y}): colour {tuple(int(v) for v in b['color'][y, x])} -> {tuple(int(v) for v in a['color'][y, x])}"
            f", depth {b['depth'][y, x]:.5f} -> {a['depth'][y, x]:.5f}, stencil {b['stencil'][y, x]} -> "
            f"{a['stencil'][y, x]}"
        )
    message = f"{what}: {len(xs)} pixels in x {xs.min()}..{xs.max()}, y {ys.min()}..{ys.max()}; e.g. " + "; ".join(
        examples
    )
    report.violations.append(RuleViolation(rule, message, pixels=np.stack([xs, ys], axis=1)))
