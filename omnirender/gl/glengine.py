"""The OpenGL engine: context, framebuffers, and the frame loop (compile, then draw).

Rendering is COMPILE then DRAW (DESIGN.md, performance model).  Compiling
runs the core interpreter over the scene once: painters append draw items to
scopes instead of issuing GL calls, and every technique met in a node opens a
nested scope (:mod:`.compiler`).  The items are cached per node and version,
so a frame whose scene did not change replays the GPU batches without any
traversal, and a frame where one subtree changed recompiles only that subtree
and rewrites only the changed instance rows.  Drawing runs the techniques'
passes at draw time, every frame (:mod:`.frame`): the default technique
``Forward`` draws opaque batches, transparent items sorted back to front and
2D overlays; nested techniques run their own passes over what they scope
(:mod:`.renderer` draws the items of one pass).  This module owns the
context, the targets, cameras and resources.
"""

from __future__ import annotations

import contextlib
import importlib
from collections.abc import Iterator
from typing import Any

import numpy as np

from ..attributes import Background, Tessellation
from ..attributes.environment import DEFAULT_BACKGROUND  # the clear colour without an om.Background (shared)
from ..core.camera import Camera
from ..core.engine import Engine
from ..core.technique import Technique
from ..image import Image
from .deferred.materials import MaterialTable
from .deferred.models import MaterialDescription
from .deferred.pipeline import Deferred
from .engine.compile_state import CompileState
from .engine.compiler import DrawListCompiler
from .engine.context import (
    GLError,
    RawGL,
    check_samples_total,
    check_size,
    create_context,
    delete_renderbuffer,
    depth_stencil_framebuffer,
    read_color_top_down,
    reads_top_down,
)
from .engine.drawer import BatchDrawer
from .engine.drawlist import Batch, DrawItem, DrawState, Scope
from .engine.dynamic import TransformUpdater
from .engine.frame import FrameRunner
from .engine.frame_state import FrameState
from .engine.geometry import Geometry, GeometryCache, unit_mesh
from .engine.imagespace import RenderTarget
from .engine.index import RenderIndex
from .engine.passes import Pass, Target, pass_camera
from .engine.renderer import BatchInstaller
from .engine.report import PassReport
from .engine.resources import gpu_call
from .engine.shaders import ProgramCache
from .engine.stages import FrameStage, PipelinesStage, StageList, TechniqueStage
from .engine.targets import FrameTargets
from .engine.technique import GLTechnique
from .techniques.forward import Forward
from .techniques.mirrors import MirrorStage, mirror_items
from .techniques.shadows import ShadowMapStage
from .techniques.stereo import StereoStage

__all__ = ["GLEngine", "GLTechnique", "DEFAULT_BACKGROUND", "PIPELINES"]

#: The frame pipelines of ``GLEngine(pipeline=...)``.
PIPELINES = ("forward", "deferred")


class GLEngine(Engine):
    """Real-time OpenGL engine (moderngl): headless EGL by default, or a given moderngl context.

    ``GLEngine(size=(w, h), samples=4)``; ``engine.render(scene) -> om.Image``
    renders frame after frame, keeping GPU resources between frames.
    ``samples=0`` turns multisampling off.  ``technique`` replaces the default
    :class:`~.techniques.Forward` technique (the passes every frame and every
    nested technique pass draws items with); ``timing=True`` measures each
    pass's GPU time with timer queries (``engine.stats["passes"]``);
    ``shadows=False`` turns shadow maps off (they are on by default, see
    :class:`~.shadows.ShadowMaps`); ``pipeline="deferred"`` (or an
    ``om.gl.Deferred(...)``) shades every frame with the deferred pipeline;
    ``stereo`` (an ``om.gl.Stereo``) draws every frame as a stereo pair.

    OpenGL version: every shader and call is OpenGL 3.3 core, also when the
    context offers 4.x.  The 4.x features that would pay off here are not
    reachable or not needed: moderngl 5 exposes neither base-instance draws
    (4.2, which would let transparent instances of one mesh share a buffer
    while drawn one by one) nor immutable buffer storage (4.4), multi-draw
    indirect (4.3) only saves calls that instancing already saves, and
    ``#version 450`` shaders would add nothing the 3.3 shaders use.  One code
    path keeps macOS (3.3/4.1) and software renderers identical to the tested one.

    Colour spaces: lighting, fog and texture filtering happen in linear light
    (textures are GL_SRGB8_ALPHA8, so the GPU decodes them before filtering and
    mipmapping); fragment shaders encode their result to sRGB for the 8-bit
    colour buffer.  Blending of transparent shapes therefore mixes sRGB-encoded
    values (as most real-time renderers with 8-bit targets do): a 50% surface
    gives the encoded average of the two colours, slightly darker than the
    linear-light mix a path tracer computes.
    """

    service = "gl.paint"
    uses_camera_mask = True
    #: Drawers for draw-item kinds that are not plain instanced geometry (text, volumes), by kind.
    _default_drawers: dict[str, Any] = {}

    def __init__(
        self,
        size: tuple[int, int] = (640, 480),
        samples: int = 4,
        context: Any = None,
        *,
        background: Any = None,
        technique: Technique | None = None,
        on_missing: str = "raise",
        mask: Any = None,
        timing: bool = False,
        programs: ProgramCache | None = None,
        shadows: bool = True,
        pipeline: Any = "forward",
        stereo: Any = None,
    ) -> None:
        importlib.import_module(f"{__package__}.painters")  # painters register on first use (plug-ins: see its doc)
        if technique is not None and not isinstance(technique, Technique):
            raise TypeError(f"GLEngine: technique must be an om.Technique (e.g. om.gl.Forward()), got {technique!r}")
        if not isinstance(pipeline, Deferred) and pipeline not in PIPELINES:
            raise ValueError(
                f"GLEngine: pipeline must be one of {PIPELINES} or an om.gl.Deferred(...), got {pipeline!r:.60}"
            )
        super().__init__(technique=technique or Forward(), on_missing=on_missing, mask=mask)
        #: "forward" or "deferred" (om.gl.Deferred runs every frame; nested techniques still draw forward)
        self._pipeline = "deferred" if isinstance(pipeline, Deferred) else pipeline
        self._pipeline_technique = (
            pipeline if isinstance(pipeline, Deferred) else (Deferred() if pipeline == "deferred" else None)
        )
        #: the engine's deferred renderer (made by the deferred pipeline on first use), or None
        self.deferred_renderer: Any = None
        self.stereo = stereo
        #: render textures (chained pipelines): the frame engine's PipelineSet, or its host's in a pipeline
        self._pipelines: Any = None
        self._pipelines_scanned = -1
        #: measure each pass's GPU time with timer queries (stats["passes"][i]["gpu_ms"])
        self.timing = bool(timing)
        if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 0:
            raise ValueError(f"GLEngine: samples must be a whole number >= 0 (0 = no multisampling), got {samples!r}")
        check_samples_total(size, int(samples))  # before a context exists: a bad size costs nothing
        #: draw shadow maps for lights that cast shadows (om.gl.ShadowMaps in a scene refines this)
        self.shadows = bool(shadows)
        self.ctx = context if context is not None else create_context()
        self._own_context = context is None
        if samples & (samples - 1):  # OpenGL drivers take 1, 2, 4, 8, 16 ... (moderngl: "invalid samples")
            raise ValueError(f"GLEngine: samples must be 0 or a power of two (1, 2, 4, 8, 16), got {samples}")
        self._samples = min(int(samples), int(self.ctx.max_samples)) if samples else 0
        self._size = check_size(size, self.ctx, self._samples)
        self.background = background
        # compiled shader programs; a cache given by the caller (for its context) outlives this engine
        self._own_programs = programs is None
        self.programs = ProgramCache(self.ctx) if programs is None else programs
        self.geometry_cache = GeometryCache()
        self.raw = RawGL()
        self._units: dict[tuple[str, int], Geometry] = {}
        self._targets: dict[str, Any] = {}
        self._target_stack: list[Any] = []
        self._preevaluated = False
        self._make_targets()
        #: the material descriptions of compiled items by id (the deferred pipeline's material table)
        self.material_table = MaterialTable()
        #: the installed draw list and its derived lists (items, mirrors, bounds), kept up to date by change kind
        self.index = RenderIndex(mirror_items)
        self.stats: dict[str, Any] = {}
        with self.current():  # (PROGRAM_POINT_SIZE is enabled by the state applier when a frame begins)
            info = self.ctx.info
            #: largest 2D texture side and 3D texture side this GPU accepts (checked before creating textures)
            self.max_texture_size = int(info.get("GL_MAX_TEXTURE_SIZE", 16384))
            self.max_texture_size_3d = int(info.get("GL_MAX_3D_TEXTURE_SIZE", 2048))
        # the frame side's collaborators, made once and handed to each other (three.js's WebGLRenderer is
        # assembled the same way): what the pass sees, its targets, its report, the drawer, the frame runner
        self.frame_state = FrameState(self._size)
        #: (camera, key, view, projection) of the last scene camera (camera_matrices); the read-back's array
        self._camera_kept: tuple[Any, Any, np.ndarray, np.ndarray] | None = None
        self._read_scratch: np.ndarray | None = None
        #: the driver reads colour rows top-down itself (Mesa's GL_MESA_pack_invert): no flipping copy per frame
        self._reads_top_down = reads_top_down(self.ctx, self.raw)
        self.frame_targets = FrameTargets(self.ctx, self.raw, self.max_texture_size)
        self.pass_report = PassReport(self.ctx)
        self.drawer = BatchDrawer(self, self.frame_state, self.frame_targets, self.pass_report, self._default_drawers)
        stages = StageList([PipelinesStage(), ShadowMapStage(), TechniqueStage(), MirrorStage(), StereoStage()])
        self.frame_runner = FrameRunner(
            self, self.frame_state, self.drawer, self.frame_targets, self.pass_report, stages
        )
        # the compile side's collaborators: the updater moves installed rows, the installer installs compiled
        # scopes as batches, the compiler owns the compile state and hands its results to both
        placements_changed = self.frame_runner.placements_changed
        self.updater = TransformUpdater(
            self.index,
            placements_changed,
            self.instance_state,
            self.frame_runner.rows_moved,
            self.frame_runner.rows_restyled,
        )
        self.installer = BatchInstaller(
            self.ctx,
            self.index,
            self.updater,
            self.drawer,
            self.geometry_cache,
            self.stats,
            placements_changed,
            self._follow_splice,
            self.frame_runner.rows_spliced,
        )
        self.compiler = DrawListCompiler(self, self.installer, self.updater, MaterialDescription)

    def check_texture_size(self, what: str, shape: tuple[int, ...], limit: int) -> None:
        """ValueError naming ``what`` and the node path when a side of ``shape`` exceeds the GPU's ``limit``.

        Without this check the driver reports a bare GL_INVALID_VALUE at draw time.
        """
        if max(shape) > limit:
            where = f" in node {self.node_path}" if self.node_path else ""
            dims = "x".join(str(int(d)) for d in shape)
            raise ValueError(
                f"{what}{where}: {dims} is larger than this GPU allows ({limit} per side); "
                f"resize or downsample it to at most {limit} per side"
            )

    def unit_geometry(self, kind: str) -> Geometry:
        """The shared unit mesh of ``kind`` at the active Tessellation level (native painters use it)."""
        tessellation = self.mono(Tessellation)
        level = tessellation.level if tessellation is not None else Tessellation.DEFAULT_LEVEL
        geom = self._units.get((kind, level))
        if geom is None:
            geom = self._units[(kind, level)] = unit_mesh(kind, level)
        return geom

    # -- targets -----------------------------------------------------------
    @contextlib.contextmanager
    def current(self) -> Iterator[Any]:
        """Make the engine's context current for GL calls (and leave it current afterwards).

        moderngl's ``with ctx:`` restores the previously current context on exit,
        which breaks when nested on the same context; an engine that owns its
        context therefore only makes it current.  A wrapped context (a window's)
        is assumed to be current already.
        """
        self._make_current()
        yield self.ctx

    def _make_current(self) -> None:
        """What :meth:`current` does on entry (nothing is undone on exit): callable without a ``with``."""
        if getattr(self, "_released", False):
            raise RuntimeError(
                "GLEngine: this engine was released (engine.release()) and its GPU resources are gone; "
                "create a new GLEngine to render again"
            )
        if self._own_context:
            self.ctx.mglo.__enter__()

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels; assigning resizes the framebuffers."""
        return self._size

    @size.setter
    def size(self, value: tuple[int, int]) -> None:
        value = check_size(value, self.ctx, self._samples)
        if value != self._size:
            self._size = value
            self._make_targets()

    @property
    def samples(self) -> int:
        """Multisample count (0: off)."""
        return self._samples

    @property
    def frame_technique(self) -> Technique:
        """The technique a frame runs over the whole scene: the deferred pipeline's, or :attr:`technique`.

        Nested techniques' passes always draw their items with :attr:`technique` (forward).
        """
        return self._pipeline_technique or self.technique

    def frame_level_technique(self) -> Technique:
        """The technique a frame runs over the installed scene: a post-processing chain holding the whole scene
        (around the pipeline), else :attr:`frame_technique`."""
        root = self.root_scope
        return self.frame_technique if root is None else self.frame_runner.frame_level(root)[0]

    def at_frame_level(self) -> bool:
        """Whether the technique running now runs over a whole frame: the frame's own, or a frame drawn into a
        target by a ``Pass(technique="frame")`` (a stereo eye); not a technique met in a node."""
        return len(self.technique_frames) == self.frame_runner.frame_base + 1

    @property
    def stereo(self) -> Any:
        """The frame's :class:`~.stereo.Stereo` technique (two eyes with off-axis projections), or None."""
        return self._stereo

    @stereo.setter
    def stereo(self, value: Any) -> None:
        from .techniques.stereo import Stereo

        if value is not None and not isinstance(value, Stereo):
            raise TypeError(f"GLEngine: stereo must be an om.gl.Stereo(...) or None, got {value!r:.60}")
        self._stereo = value

    @property
    def pipeline(self) -> Any:
        """``"forward"``, or the engine's :class:`~.deferred.DeferredRenderer` (``describe()``, ``memory()``)
        once a deferred frame was drawn or the engine was made with ``pipeline="deferred"``."""
        if self._pipeline == "deferred" or self.deferred_renderer is not None:
            from .deferred.pipeline import DeferredRenderer

            return DeferredRenderer.of(self)
        return "forward"

    def _make_targets(self) -> None:
        with self.current():
            self._create_targets()
            # releasing a detected (raw) framebuffer may leave a harmless GL error behind: drop it
            err = self.ctx.error
            if "OUT_OF_MEMORY" in err:
                raise GLError(f"GLEngine: out of memory creating {self._size[0]}x{self._size[1]} framebuffers")

    def _release_targets(self) -> None:
        seen = set()
        for obj in self._targets.values():
            if id(obj) not in seen:
                seen.add(id(obj))
                obj.release()
        self._targets.clear()
        rbo = getattr(self, "_stencil_rbo", None)
        if rbo is not None:  # made with raw GL calls: moderngl does not know it (each one leaked its pixels)
            delete_renderbuffer(self.raw, rbo)
            self._stencil_rbo = None

    def _create_targets(self) -> None:
        self._release_targets()
        ctx, size = self.ctx, self._size
        t = self._targets
        t["color"] = gpu_call(ctx.renderbuffer, size, 4, what="the colour buffer")
        t["depth"] = gpu_call(ctx.depth_renderbuffer, size, what="the depth buffer")
        t["fbo"] = ctx.framebuffer(t["color"], t["depth"])
        if self._samples:
            t["ms_color"] = gpu_call(ctx.renderbuffer, size, 4, samples=self._samples, what="the colour buffer")
            target = "ms_fbo"
            color = t["ms_color"]
        else:
            target = "draw_fbo"
            color = t["color"]
        # draw into a framebuffer with a depth-stencil attachment (StencilTest needs it); fall back to depth only
        made = depth_stencil_framebuffer(ctx, self.raw, color, size, self._samples)
        if made is not None:
            t[target] = made[0]
            self._stencil_rbo = made[1]
            self.has_stencil = True
            if not self._samples:
                t["fbo"].release()
                t["fbo"] = made[0]  # draw and read the same framebuffer: no copy per frame
        else:
            if self._samples:
                t["ms_depth"] = gpu_call(ctx.depth_renderbuffer, size, samples=self._samples, what="the depth buffer")
                t[target] = ctx.framebuffer(color, t["ms_depth"])
            else:
                t[target] = t["fbo"]
            self.has_stencil = False

    @property
    def framebuffer(self) -> Any:
        """The framebuffer drawn into (multisampled when samples > 0)."""
        if self._target_stack:
            return self._target_stack[-1].fbo
        return self._targets["ms_fbo" if self._samples else "draw_fbo"]

    # -- compile -------------------------------------------------------------
    def render(
        self,
        scene: Any = None,
        *,
        mask: Any = None,
        background: Any = None,
        read_depth: bool = True,
    ) -> Image:
        """Compile (if the scene changed) and draw ``scene``; returns an :class:`om.Image`.

        Without a scene, draws what was evaluated into the engine directly
        (``engine.push(...)``, ``engine.eval(shape)``, ...) and clears that list;
        such a frame uses the camera and lights of the last ``engine.run(root)``
        (the viewer's way), else the auto-fit camera and a headlight.
        """
        self._make_current()  # (what `with self.current():` does, without a generator per frame)
        if scene is not None:
            self.compile(scene, mask=mask)
        else:
            # immediate mode: what was evaluated directly, seen by the auto-fit camera under a headlight
            self.compiler.install_immediate()
            if not self._preevaluated:
                # no engine.run(root) since the last frame: nothing pre-evaluated a camera or lights
                self.camera = None
                self.declared = None
        self._preevaluated = False
        self.frame_runner.draw(background, True)  # draw() without a camera or framebuffer of its own
        return self._read(read_depth)

    # -- the compile (the compiler and the installer do it) -----------------------------------------
    def compile(self, scene: Any, mask: Any = None) -> Scope:
        """Compile ``scene`` (a Node or components) into the root scope; cached while nothing changed."""
        return self.compiler.compile(scene, mask)

    @property
    def compile_state(self) -> CompileState:
        """What attribute painters change during a compile (surface stack, clip planes): a ``CompileState``."""
        return self.compiler.state

    def on_enter(self, node: Any) -> None:
        self.compiler.on_enter(node)

    def on_leave(self, node: Any) -> None:
        self.compiler.on_leave(node)

    def eval_node(self, node: Any) -> Any:
        """A child node: replayed from the compiler's per-occurrence cache when unchanged, else its local program."""
        return self.compiler.eval_node(node)

    def run_technique(self, technique: Any, program: list[tuple[int, Any]]) -> None:
        """A technique's scope: compiled once into a nested Scope; its passes run when the frame is drawn."""
        self.compiler.run_technique(technique, program)

    def begin(self, root: Any) -> None:
        """The core's pre-evaluation; a following ``render(None)`` uses its camera and lights (the viewer's way)."""
        super().begin(root)
        self._preevaluated = True
        self.compiler.state.invalidate()

    def submit(
        self,
        geometry: Geometry,
        local: np.ndarray | None = None,
        kind: str | None = None,
        extra: Any = None,
        transparent: bool | None = None,
    ) -> DrawItem:
        """Append a draw item for ``geometry`` in the current state (model matrix, material, GL state).

        ``local`` is a shape-local matrix applied after the model matrix (the
        native painters scale a unit mesh with it).  Painters call this; it
        issues no GL call.
        """
        return self.compiler.submit(geometry, local, kind, extra, transparent)

    def capture(self, shape: Any) -> list[DrawItem]:
        """The draw items ``shape`` makes in the current state, without drawing them (instance sets use it)."""
        return self.compiler.capture(shape)

    def submit_instances(
        self, source: Any, template: DrawItem, matrices: np.ndarray, colors: np.ndarray | None, may_mirror: bool
    ) -> DrawItem:
        """An item drawing ``template`` once per matrix (``(N, 4, 4)``, after the current model matrix)."""
        return self.compiler.submit_instances(source, template, matrices, colors, may_mirror)

    def instance_state(self, template: DrawItem, mirrored: bool) -> DrawState:
        """The template's state, or the same without face culling when some instance mirrors."""
        return self.compiler.instance_state(template, mirrored)

    def upload(self, geometry: Geometry) -> None:
        """Make sure ``geometry`` has its GPU buffers (drawers call it)."""
        self.installer.upload(geometry)

    def filtered_batches(self, scope: Scope, composed: Any) -> dict[int, list[Batch]]:
        """Batches of the opaque items a mask/predicate keeps, per segment index (cached until the scope changes)."""
        return self.installer.filtered_batches(scope, composed)

    def _follow_splice(self, version: int, added: list[DrawItem]) -> None:
        """The pipelines scan of ``version`` still holds after a splice when no added item reads a render texture."""
        if self._pipelines is None and self._pipelines_scanned == version:
            if not any(getattr(t, "rendered", False) for it in added for _, t, _ in it.state.textures):
                self._pipelines_scanned = self.installer.version

    @property
    def scene_background(self) -> Any:
        """The first ``om.Background`` of the last pre-evaluated scene, or None."""
        declared = self.declared
        if declared is None:
            return None
        found = declared.first(Background)
        return None if found is None else found[0]

    @property
    def scene_lights(self) -> list[tuple[Any, np.ndarray]]:
        """The enabled lights of the last pre-evaluated scene with their world matrices."""
        return [] if self.declared is None else [(light, m) for light, m in self.declared.lights if light.enabled]

    @property
    def draw_items(self) -> list[DrawItem]:
        """Every compiled draw item of the installed frame, in compile order (nested scopes included)."""
        return list(self.index.items())

    @property
    def batches(self) -> list[Batch]:
        """The instanced batches of opaque items of every installed scope."""
        from .engine.drawlist import Segment

        return [b for scope in self.scopes for part in (scope.parts or []) if isinstance(part, Segment)
                for b in part.batches]  # fmt: skip

    @property
    def scopes(self) -> list[Scope]:
        """The installed root scope and every technique scope below it, depth first."""
        root = self.installer.root
        return [] if root is None else root.walk()

    def scene_bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """World-space (min, max) of the compiled draw list, or None when it is empty."""
        return self.index.bounds()

    def camera_matrices(self) -> tuple[Camera, np.ndarray, np.ndarray]:
        """(camera, view, projection) of the scene's camera (else the auto-fit one) at the engine's size.

        The scene camera's matrices are kept (read-only) while its version, its
        placement and the size stay the same: a steady frame makes none.
        """
        w, h = self._size
        aspect = w / h
        if self.camera is not None:
            camera, world = self.camera
            key = (camera.version, np.asarray(world).tobytes(), aspect)
            kept = self._camera_kept
            if kept is not None and kept[0] is camera and kept[1] == key:
                return camera, kept[2], kept[3]
            view = camera.view_matrix() @ np.linalg.inv(world)
            projection = camera.projection_matrix(aspect)
            view.setflags(write=False)
            projection.setflags(write=False)
            self._camera_kept = (camera, key, view, projection)
            return camera, view, projection
        else:
            camera = self.default_camera()
            view = camera.view_matrix()
        return camera, view, camera.projection_matrix(aspect)

    def default_camera(self) -> Camera:
        """Auto-fit: look at the compiled scene's bounds from +z (``Camera.fitted``, as every engine does)."""
        return Camera.fitted(self.scene_bounds(), self._size)

    def view_matrix(self) -> np.ndarray | None:
        if self.camera is None:
            return None
        return super().view_matrix()

    def clear_color(self, background: Any = None) -> tuple[float, float, float, float]:
        """The sRGB clear colour: ``background`` argument, scene Background, engine default."""
        bg = background if background is not None else self.background
        if bg is None and self.scene_background is not None:
            bg = self.scene_background
        if bg is None:
            return DEFAULT_BACKGROUND
        color = _background_color(getattr(bg, "color", bg))
        if len(color) == 3:
            color = (*color, 1.0)
        # a display (sRGB) colour, like every colour in a scene: cleared as it is
        return tuple(float(min(max(c, 0.0), 1.0)) for c in color[:4])  # type: ignore[return-value]

    def live_buffers(self) -> int:
        """GPU buffers this engine holds now (geometry, instance data, transient), for leak checks."""
        return self.installer.live_buffers() + self.drawer.live_buffers()

    def release(self) -> None:
        """Free every GPU resource (and the context when the engine created it); calling it again does nothing."""
        if getattr(self, "_released", False):
            return
        with self.current():
            # Mesa's llvmpipe leaks the queued work of a texture deleted before the work ran (0.7 MB for a
            # shadow atlas, every one-shot render): finish the queue before anything is freed
            if hasattr(self.ctx.mglo, "finish"):  # not when the context (a host engine's) is already gone
                self.ctx.finish()
            self._release()
        if self._own_context:
            self.ctx.release()
        self._released = True

    def _release(self) -> None:
        if self._pipelines is not None:
            if self._pipelines.host is self:
                self._pipelines.release()
            self._pipelines = None
        if self.deferred_renderer is not None:
            self.deferred_renderer.release()
            self.deferred_renderer = None
        self.material_table.release()
        self.installer.release()
        self.drawer.release()
        self.frame_targets.release()
        self.frame_runner.release()
        self.pass_report.release()
        if self._own_programs:
            self.programs.release()
        self._release_targets()
        self.compiler.forget()

    # -- the installed draw list -------------------------------------------------------------
    @property
    def root_scope(self) -> Scope | None:
        """The installed root scope (None before the first frame)."""
        return self.installer.root

    @property
    def item_count(self) -> int:
        """How many draw items the installed list holds (nested scopes included)."""
        return len(self.index.items()) if self.installer.root is not None else 0

    @property
    def draw_list_version(self) -> int:
        """Bumped whenever a compiled draw list is installed or spliced (per-frame caches of techniques key on it)."""
        return self.installer.version

    # -- framebuffers pushed by a FramebufferStack ----------------------------------------------
    @property
    def pushed_targets(self) -> int:
        """How many offscreen targets a :class:`~.engine.framebuffer.FramebufferStack` pushed (0: the engine's own)."""
        return len(self._target_stack)

    def push_target(self, target: Any) -> None:
        """Draw into ``target`` (an ``OffscreenTarget``) until :meth:`pop_target`."""
        self._target_stack.append(target)

    def pop_target(self) -> Any:
        """Stop drawing into the last pushed target and hand it back (RuntimeError when none is pushed)."""
        if not self._target_stack:
            raise RuntimeError("FramebufferStack.pop: nothing was pushed (unbalanced push/pop)")
        return self._target_stack.pop()

    # -- chained pipelines ----------------------------------------------------------------
    def pipelines(self) -> Any:
        """The frame's chained pipelines (:class:`~.engine.pipelines.PipelineSet`, made on first use)."""
        if self._pipelines is None:
            from .engine.pipelines import PipelineSet

            self._pipelines = PipelineSet(self)
        return self._pipelines

    def share_pipelines(self, pipelines: Any) -> None:
        """Use ``pipelines`` (a host engine's) as this engine's: a render texture's engine draws the others."""
        self._pipelines = pipelines

    def prepare_pipelines(self) -> None:
        """Draw the render textures the frame reads, in dependency order (only the frame engine does)."""
        if self._pipelines is None:
            if self._pipelines_scanned == self.draw_list_version:
                return
            self._pipelines_scanned = self.draw_list_version
            from .engine.pipelines import PipelineSet

            if not PipelineSet.used_by(self):
                return
        pipelines = self.pipelines()
        if pipelines.host is self:
            pipelines.prepare()

    def pipeline_image(self, texture: Any) -> Any:
        """The last image of the render texture ``texture`` as this engine drew it (an ``om.Image``)."""
        return self.pipelines().image(texture)

    # -- drawing (the frame runner and the drawer do it) ------------------------------------------
    @classmethod
    def register_drawer(cls, kind: str, drawer: Any) -> None:
        """Draw items of ``kind`` with ``drawer(engine, items, state) -> draw calls`` (text, volumes).

        A drawer sets the GL state it needs with :meth:`apply_gl_state`; one that makes GL state calls of its
        own calls :meth:`forget_gl_state` after them."""
        cls._default_drawers[kind] = drawer

    def draw(self, background: Any = None, clear: bool = True, camera: Any = None, framebuffer: Any = None) -> None:
        """Draw the installed scopes into the framebuffer: the engine technique's passes and every nested one.

        ``clear=False`` draws over what the framebuffer holds (compositing several renderers).
        ``camera`` (an ``om.Camera`` or ``(view, projection)`` 4x4 matrices) replaces the scene's camera
        for this frame; ``framebuffer`` (a moderngl framebuffer on this engine's context, e.g. another
        engine's :attr:`current_framebuffer`) is drawn into instead of the engine's own.  Together they
        let one engine draw its scene into a frame another engine is composing, seen by that frame's camera.
        """
        if framebuffer is not None and not hasattr(framebuffer, "use"):
            raise TypeError(f"GLEngine.draw: framebuffer must be a moderngl Framebuffer, got {framebuffer!r:.60}")
        override = None if camera is None else pass_camera(camera, "GLEngine.draw")
        with self.current():
            self.frame_runner.draw(background, clear, override, framebuffer)

    @property
    def stages(self) -> StageList:
        """The stages every frame runs, in order (``engine.stages.names()``: pipelines, shadow maps,
        technique, mirrors, stereo); see :mod:`~.engine.stages`."""
        return self.frame_runner.stages

    def add_stage(self, stage: FrameStage, *, before: str | None = None, after: str | None = None) -> None:
        """Run ``stage`` (an :class:`om.gl.FrameStage`) in every frame, before or after the stage named so
        (last without either): a technique of the application's joins the frame without editing it."""
        self.frame_runner.stages.add(stage, before=before, after=after)
        stage.changed()

    def remove_stage(self, stage: FrameStage | str) -> FrameStage:
        """Take ``stage`` (or the stage of that name) out of every frame; returns it."""
        return self.frame_runner.stages.remove(stage)

    def set_pass(self, description: Pass) -> None:
        """Describe the pass being prepared (call it from a technique's ``prepare_pass``)."""
        self.frame_runner.set_pass(description)

    def target(self, name: str) -> RenderTarget:
        """The offscreen target ``name`` of the current frame (its ``texture(attachment)``, ``depth``, arrays)."""
        return self.frame_targets.named(name)

    def count(self, calls: int, instances: int) -> None:
        """Add draw calls and instances to the pass being drawn (drawers of custom kinds may call it)."""
        self.pass_report.count(calls, instances)

    def forget_gl_state(self) -> None:
        """Tell the engine a drawer changed GL state itself: the next draw applies its state in full."""
        self.frame_runner.forget_gl_state()

    def apply_gl_state(self, *states: Any) -> None:
        """Set GL state from a drawer: ``engine.apply_gl_state(om.gl.DepthTest(False), om.gl.Blend())`` makes
        those states current through the engine's state applier (which then knows what GL holds: nothing
        needs resetting afterwards).  Other states stay as the pass set them."""
        self.frame_runner.apply_gl_state(*states)

    def default_gl_state(self) -> None:
        """Put every GL state kind at its default through the engine's state applier (no blending, culling,
        stencil, scissor, wireframe, offset); with :meth:`apply_gl_state` after it, a drawer or a custom pass
        sets exactly the state it needs and the engine keeps knowing what GL holds."""
        self.frame_runner.default_gl_state()

    def sample_mask(self, sample: int | None) -> None:
        """From a custom pass: the draws that follow write only sample ``sample`` of a multisampled target
        (``None``: every sample again), through the engine's state applier."""
        self.frame_runner.sample_mask(sample)

    def bind_framebuffer(self, framebuffer: Any, size: tuple[int, int]) -> None:
        """From a custom pass: draw into ``framebuffer`` (a moderngl framebuffer of ``size`` pixels) through the
        engine's state applier (moderngl's ``use()`` resets masks and scissor behind the engine's back)."""
        self.frame_runner.bind_framebuffer(framebuffer, size)

    def between_frames(self) -> contextlib.AbstractContextManager[Any]:
        """``with engine.between_frames():`` set GL state outside a frame through the engine's state applier:
        inside, :meth:`apply_gl_state`, :meth:`default_gl_state` and :meth:`bind_framebuffer` work as in a pass
        (the engine's framebuffer bound, every state at its default first); afterwards GL holds its defaults with
        the engine's framebuffer bound, as after a frame.  Inside a frame it uses the frame's state."""
        return self.frame_runner.between_frames()

    def reset_gl_state(self) -> None:
        """Put every GL state kind at its default (no blending, culling, stencil, scissor, wireframe, offset),
        for code that then sets the few states it needs with raw GL calls; the next draw applies its state in
        full.  (Engine code uses :meth:`default_gl_state` and :meth:`apply_gl_state` instead.)"""
        self.frame_runner.reset_gl_state()

    @property
    def current_framebuffer(self) -> Any:
        """The framebuffer being drawn into: the pass's offscreen target while a frame is drawn, else the engine's."""
        drawing = self.frame_runner.current_framebuffer
        return self.framebuffer if drawing is None else drawing

    def copy_framebuffer(self, description: Target) -> RenderTarget:
        """Copy colour and depth of :attr:`current_framebuffer` into the frame's offscreen target ``description``.

        The target (made at the current framebuffer's size, kept while later frames copy into it) is then
        read by :class:`FullScreen` inputs by its name, like a pass's; multisampling is resolved.  Custom
        passes and drawers use it to read what is already drawn (a filter, a merge by depth, the depth a
        volume's rays stop at).  The scissor test is switched off for the copy.
        """
        return self.frame_runner.copy_framebuffer(description)

    def light_order(self) -> list[Any]:
        """The lights of the pass being drawn in shader order (index i is light i of the light loops)."""
        return self.drawer.light_order()

    # -- what the pass being drawn sees ---------------------------------------------------
    @property
    def eye_position(self) -> np.ndarray:
        """World position of the frame's own camera (the same in every pass: shadow maps and mirrors included)."""
        return np.linalg.inv(self.frame_state.frame_view)[:3, 3]

    @property
    def frame_view(self) -> np.ndarray:
        """World-to-eye matrix of the pass being drawn (drawers use it)."""
        return self.frame_state.view

    @property
    def frame_projection(self) -> np.ndarray:
        """Projection matrix of the pass being drawn."""
        return self.frame_state.proj

    @property
    def frame_camera(self) -> Any:
        """The ``om.Camera`` of the frame (its near and far planes, projection kind)."""
        return self.frame_state.camera

    @property
    def frame_eye(self) -> np.ndarray:
        """World position of the eye of the pass being drawn."""
        return np.linalg.inv(self.frame_state.view)[:3, 3]

    @property
    def frame_orthographic(self) -> bool:
        """Whether the pass being drawn uses an orthographic projection."""
        return self.frame_state.ortho

    @property
    def target_size(self) -> tuple[int, int]:
        """Size of the framebuffer being drawn into."""
        return self.frame_state.target_size

    @property
    def pass_shading(self) -> dict[str, Any]:
        """The shader overrides of the pass being drawn as program features (``{"DEPTH_ONLY": True,
        "PASS_ALPHA_CUTOFF": 0.5}`` in the forward technique's "transparent depth" pass): drawers of custom
        kinds, which the pass's shader does not reach, read them."""
        return dict(self.frame_state.shading)

    @property
    def linear_output(self) -> bool:
        """Whether the framebuffer being drawn into holds linear light (a float target), not display values."""
        return self.frame_state.linear_output

    @property
    def frame_shadows(self) -> Any:
        """The frame's shadow maps (a :class:`~.techniques.shadows.ShadowPlan`: faces per light, uniforms), or None."""
        return self.frame_state.shadow_plan

    @property
    def frame_background(self) -> Any:
        """The ``background`` given to the frame's :meth:`draw` (None: the scene's or the engine's)."""
        return self.frame_state.background

    # -- read back -------------------------------------------------------------
    def read(self, read_depth: bool = True) -> Image:
        """Resolve multisampling and read the image (colour, and eye-space depth unless ``read_depth=False``)."""
        with self.current():
            return self._read(read_depth)

    def _read(self, read_depth: bool) -> Image:
        if self.raw.available:
            # wait for the GPU through ctypes, which releases the GIL (moderngl's resolve and read would wait
            # holding it): other Python threads (an application loop beside render threads) run meanwhile
            self.raw.glFinish()
        t = self._targets
        drawn = self.framebuffer
        if self._target_stack:
            fbo = drawn
        else:
            if drawn is not t["fbo"]:
                self.ctx.copy_framebuffer(t["fbo"], drawn)
            fbo = t["fbo"]
        w, h = self._size
        if self._reads_top_down:
            # the driver flips the rows in the read: straight into the image's own array, no copy
            array = np.empty((h, w, 4), np.uint8)
            read_color_top_down(self.raw, fbo, array)
        else:
            scratch = self._read_scratch
            if scratch is None or scratch.shape != (h, w, 4):
                scratch = self._read_scratch = np.empty((h, w, 4), np.uint8)
            fbo.read_into(scratch, components=4, alignment=1)  # into a kept array: no new buffer per frame
            array = np.ascontiguousarray(scratch[::-1])  # the image's own array, rows top-down
        depth = None
        if read_depth:
            raw = np.frombuffer(fbo.read(components=1, attachment=-1, dtype="f4", alignment=1), np.float32).reshape(
                h, w
            )[::-1]
            depth = self.linear_depth(raw)
        return Image(array, depth, engine="gl", info=dict(self.stats))

    def linear_depth(self, raw: np.ndarray) -> np.ndarray:
        """Window depth in [0, 1] -> eye-space distance along the view axis (inf for the far plane)."""
        camera = self.frame_state.camera
        if camera is None:
            camera = self.camera_matrices()[0]
        n, f = camera.near, camera.far
        d = raw.astype(np.float64)
        if camera.is_orthographic:
            z = n + d * (f - n)
        else:
            ndc = 2.0 * d - 1.0
            with np.errstate(divide="ignore", invalid="ignore"):
                z = 2.0 * f * n / ((f + n) - ndc * (f - n))
        out = z.astype(np.float32)
        out[raw >= 1.0] = np.inf
        return out

    def __enter__(self) -> GLEngine:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.release()


def _background_color(value: Any) -> tuple[float, ...]:
    """``value`` as 3 or 4 finite numbers; ValueError naming the fix otherwise."""
    fix = "give 3 or 4 numbers in [0, 1] (sRGB), e.g. background=(1, 1, 1), or an om.Background"
    try:
        color = tuple(float(c) for c in value)
    except (TypeError, ValueError):
        raise ValueError(f"GLEngine: background must be an RGB(A) colour, got {value!r:.60}; {fix}") from None
    if len(color) not in (3, 4) or not all(0.0 <= c <= 1.0 for c in color):  # NaN fails too
        raise ValueError(f"GLEngine: background must be 3 or 4 numbers in [0, 1], got {value!r:.60}; {fix}")
    return color
