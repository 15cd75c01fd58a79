"""The GL frame: techniques run their passes at draw time, every frame, over the compiled scopes.

Drawing a frame runs the engine's technique (``om.gl.Forward`` by default:
opaque, transparent, overlay) over the root scope.  A technique met in a node
compiled into a nested scope; whenever a pass draws items, the nested scopes
among them run *their* technique: ``start``, then for as long as
``needs_pass``: ``prepare_pass`` (which describes the pass with
``engine.set_pass(Pass(...))``), the pass, ``finish_pass``, ``next_pass``;
finally ``stop``.  Each pass of a nested technique draws its items through the
engine's technique again, so a nested technique's passes see opaque,
transparent and overlay items drawn the usual way.  Pass state is kept in the
engine's technique frames, so shared technique instances nest correctly, and
all of this happens on replayed frames too: the compiled scopes are cached,
the passes are not.

Every executed pass is recorded in ``engine.stats["passes"]``: its path of
names, technique, nesting depth, draw calls, instances and (with
``GLEngine(timing=True)``) GPU time from timer queries.  Offscreen targets
are made from their :class:`~.passes.Target` descriptions, kept while later
frames describe the same targets and released when no pass uses them any more.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..techniques.mirrors import Mirrors, mirror_items
from ..techniques.shadows import ShadowPlan, caster_bounds, frame_settings
from .context import GLError, blit, clear_depth, clear_stencil, set_masks
from .drawlist import Scope
from .imagespace import FullScreenPrograms, RenderTarget
from .passes import DEPTH_FUNCS, Composed, FullScreen, Pass, Target, _camera
from .state import GLCalls, RasterApplier

__all__ = ["FrameRunner", "PassRecord", "ProjectionInfo"]

_GL_SCISSOR_TEST = 0x0C11


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


class PassRecord(dict):
    """One executed pass of a frame: ``name`` (the path of pass names), ``technique``, ``depth``,
    ``draw_calls``, ``items`` (instances drawn), ``target`` and ``gpu_ms`` (None without timing)."""

    def __repr__(self) -> str:
        gpu = "" if self["gpu_ms"] is None else f", {self['gpu_ms']:.3f} ms"
        return f"PassRecord({self['name']!r}, {self['draw_calls']} calls, {self['items']} items{gpu})"


class FrameRunner:
    """Mixin of :class:`~omnirender.gl.engine.GLEngine`: technique passes at draw time, targets, the frame report."""

    # -- what techniques call ----------------------------------------------------------
    def set_pass(self, description: Pass) -> None:
        """Describe the pass being prepared (call it from a technique's ``prepare_pass``)."""
        if not isinstance(description, Pass):
            raise TypeError(f"GLEngine.set_pass needs an om.gl.Pass, got {type(description).__name__}")
        if not self._requests:
            raise RuntimeError(
                "GLEngine.set_pass: no pass is being prepared; call it from a technique's prepare_pass while the "
                "engine draws a frame"
            )
        self._requests[-1] = description

    def target(self, name: str) -> RenderTarget:
        """The offscreen target ``name`` of the current frame (its ``texture(attachment)``, ``depth``, arrays)."""
        found = self._frame_targets.get(name)
        if found is None:
            known = sorted(self._frame_targets)
            raise KeyError(
                f"GLEngine: no offscreen target {name!r} in this frame (targets: {known}); a pass makes one with "
                f"Pass(target=om.gl.Target({name!r}))"
            )
        return found

    @property
    def eye_position(self) -> np.ndarray:
        """World position of the frame's own camera (the same in every pass: shadow maps and mirrors included)."""
        return np.linalg.inv(self._frame_view)[:3, 3]

    @property
    def frame_view(self) -> np.ndarray:
        """World-to-eye matrix of the pass being drawn (drawers use it)."""
        return self._view

    @property
    def frame_projection(self) -> np.ndarray:
        """Projection matrix of the pass being drawn."""
        return self._proj

    @property
    def frame_camera(self) -> Any:
        """The ``om.Camera`` of the frame (its near and far planes, projection kind)."""
        return self._camera_used

    @property
    def frame_eye(self) -> np.ndarray:
        """World position of the eye of the pass being drawn."""
        return np.linalg.inv(self._view)[:3, 3]

    @property
    def frame_orthographic(self) -> bool:
        """Whether the pass being drawn uses an orthographic projection."""
        return self._ortho

    @property
    def target_size(self) -> tuple[int, int]:
        """Size of the framebuffer being drawn into."""
        return self._target_size

    @property
    def linear_output(self) -> bool:
        """Whether the framebuffer being drawn into holds linear light (a float target), not display values."""
        return self._linear_output

    @property
    def frame_shadows(self) -> Any:
        """The frame's shadow maps (a :class:`~.shadows.ShadowPlan`: faces per light, uniforms), or None."""
        return self._shadow_plan

    def forget_gl_state(self) -> None:
        """Tell the engine a drawer changed GL state itself: the next draw applies its state in full."""
        self._applier.forget()

    def reset_gl_state(self) -> None:
        """Put every GL state kind at its default (no blending, culling, stencil, scissor, wireframe, offset),
        for drawers that set the few states they need themselves; the next draw applies its state in full."""
        self._applier.forget()
        self._applier.apply(self._defaults)
        self._applier.forget()

    # -- the frame ---------------------------------------------------------------------
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
        override = None if camera is None else _camera(camera, "GLEngine.draw")
        with self.current():
            self._draw_frame(background, clear, override, framebuffer)

    def _draw_frame(self, background: Any, clear: bool, override: Any = None, framebuffer: Any = None) -> None:
        ctx = self.ctx
        self._prepare_pipelines()  # render textures first: their engines use the context
        fbo = self.framebuffer if framebuffer is None else framebuffer
        size = tuple(self._size) if framebuffer is None else tuple(framebuffer.size)
        _ = ctx.error  # errors of earlier, foreign GL calls are not this frame's
        fbo.use()
        ctx.viewport = (0, 0, *size)
        self._target_size = size
        self._linear_output = False
        self._applier = RasterApplier(GLCalls(ctx, self.raw, fbo, self._target_size))
        self._nclip = 0
        set_masks(ctx, self.raw, fbo, color=(True, True, True, True), depth=True)
        self._frame_background = background
        if clear:
            fbo.clear(*self.clear_color(background), depth=1.0)
            if self.has_stencil and not self._target_stack and framebuffer is None:
                clear_stencil(self.raw, 0)
        ctx.enable(ctx.PROGRAM_POINT_SIZE)
        camera, view, proj = self._frame_camera(override, size)
        self._camera_used = camera
        self._set_camera(view, proj, camera.is_orthographic)
        self._frame_view_key = self._view_key  # the frame's own view: the one batches are culled for
        self._frame_view = self._view
        self._records: list[PassRecord] = []
        self._record_stack: list[PassRecord] = []
        self._open_query = None
        self._queries_used = 0
        self._targets_used: set[Target] = set()
        self._frame_targets = {}
        root = self._root if self._root is not None else Scope()
        self._shadow_plan = None
        self._drawing = True
        try:
            calls = self._shadow_map_passes(root)
            if self._stereo is None:
                technique, scope = self.frame_technique, root
                whole = root.entries[0] if len(root.entries) == 1 else None
                if isinstance(whole, Scope) and getattr(whole.technique, "frame_level", False):
                    technique, scope = whole.technique, whole  # e.g. a post-processing chain around the pipeline
                calls += self._run(technique, scope, Composed(), item_level=True)
                calls += self._mirror_passes(root)
            else:  # each eye's pass draws the scene through the engine's technique
                calls += self._run(self._stereo, root, Composed(), item_level=False)
                if self._root is not None and not self._warned_mirrors and mirror_items(root.all_items()):
                    self._warned_mirrors = True
                    warnings.warn("GLEngine: mirrors are drawn as plain surfaces in stereo frames (the mirror "
                                  "stage reflects one eye)", stacklevel=3)  # fmt: skip
        finally:
            self._drawing = False
            self._close_query()
            self._restore_defaults(fbo, size)
        self._release_unused_targets()
        if self.timing:
            for record in self._records:
                queries = record.pop("_queries", [])
                record["gpu_ms"] = sum(q.elapsed for q in queries) / 1e6 if queries else 0.0
        else:
            for record in self._records:
                record.pop("_queries", None)
        self.stats["draw_calls"] = calls
        self.stats["passes"] = list(self._records)
        self.stats["batches"] = sum(len(p.batches) for s in (self._root.walk() if self._root else [])
                                    for p in (s.parts or []) if not isinstance(p, Scope))  # fmt: skip
        self.stats["items"] = self._item_count if self._root is not None else 0
        err = ctx.error
        if err != "GL_NO_ERROR":
            if "OUT_OF_MEMORY" in err:
                raise GLError("GLEngine: the GPU ran out of memory while drawing; reduce the scene or image size")
            raise GLError(f"GLEngine: OpenGL reported {err} while drawing")

    # -- chained pipelines --------------------------------------------------------------
    def pipelines(self) -> Any:
        """The frame's chained pipelines (:class:`~.pipelines.PipelineSet`, made on first use)."""
        if self._pipelines is None:
            from .pipelines import PipelineSet

            self._pipelines = PipelineSet(self)
        return self._pipelines

    def _prepare_pipelines(self) -> None:
        """Draw the render textures the frame reads, in dependency order (only the frame engine does)."""
        if self._pipelines is None:
            if self._pipelines_scanned == self.draw_list_version:
                return
            self._pipelines_scanned = self.draw_list_version
            from .pipelines import PipelineSet

            if not PipelineSet.used_by(self):
                return
        pipelines = self.pipelines()
        if pipelines.host is self:
            pipelines.prepare()

    def pipeline_image(self, texture: Any) -> Any:
        """The last image of the render texture ``texture`` as this engine drew it (an ``om.Image``)."""
        return self.pipelines().image(texture)

    def _shadow_map_passes(self, root: Scope) -> int:
        """Draw the frame's shadow maps (when lights cast shadows); returns the draw calls made."""
        settings = frame_settings(root if self._root is not None else None, self.shadows)
        if settings is None:
            return 0
        lights = [(light, m) for light, m in self.scene_lights if getattr(light, "casts_shadows", False)]
        if not lights:
            return 0
        if self._caster_bounds is None:
            self._caster_bounds = (caster_bounds(root),)
        bounds = self._caster_bounds[0]
        if bounds is None:
            return 0
        key = (id(settings), settings.version, bounds[0].tobytes(), bounds[1].tobytes(),
               tuple((id(light), light.version, m.tobytes()) for light, m in lights))  # fmt: skip
        plan = self._shadow_cache[1] if self._shadow_cache is not None and self._shadow_cache[0] == key else None
        if plan is None:
            plan = ShadowPlan(settings, lights, bounds)
            self._shadow_cache = (key, plan, plan.technique())
        technique = self._shadow_cache[2]
        if technique is None:
            return 0
        self._shadow_plan = plan
        drawn = (key, self._caster_bounds, self._size)
        last = self._shadow_drawn
        fresh = last is not None and last[0] == key and last[1] is drawn[1] and last[2] == drawn[2]
        if fresh and self._keep_target(plan.target):
            return 0  # casters and lights unchanged: the maps of the last frame still hold (the camera is free)
        calls = self._run(technique, root, Composed(), item_level=True)
        self._shadow_drawn = drawn
        return calls

    def _mirror_passes(self, root: Scope) -> int:
        """The mirror stage (:mod:`.mirrors`) after the frame's technique; returns the draw calls made."""
        if self._mirrors is None:
            self._mirrors = mirror_items(root.all_items()) if self._root is not None else []
        if not self._mirrors:
            return 0
        if not self.has_stencil or self._target_stack:
            if not self._warned_mirrors:
                self._warned_mirrors = True
                warnings.warn("GLEngine: mirrors need the engine's own stencil buffer; they are drawn as plain "
                              "surfaces here", stacklevel=4)  # fmt: skip
            return 0
        technique = Mirrors.plan(self._mirrors, self._view, self._proj, self.clear_color(self._frame_background))
        return self._run(technique, root, Composed(), item_level=False)

    def _frame_camera(self, override: Any, size: tuple[int, int]) -> tuple[Any, np.ndarray, np.ndarray]:
        """(camera, view, projection) of a frame: the scene's, or ``override`` (validated ``(view, Camera|proj)``)."""
        if override is None:
            camera, view, _ = self._camera_matrices()
            return camera, view, camera.projection_matrix(size[0] / size[1])
        view, proj = override
        if isinstance(proj, np.ndarray):
            return ProjectionInfo.of(proj), view, proj
        return proj, view, proj.projection_matrix(size[0] / size[1])

    def _set_camera(self, view: np.ndarray, proj: np.ndarray, ortho: bool) -> None:
        self._view = view
        self._proj = proj
        self._ortho = ortho
        self._view_key = view.tobytes() + proj.tobytes()
        self._frame_uniforms = {
            "u_view": view.T.astype(np.float32).tobytes(),
            "u_proj": proj.T.astype(np.float32).tobytes(),
            "u_eye_to_world": np.linalg.inv(view).T.astype(np.float32).tobytes(),
        }
        self._light_cache = {}

    def _run(self, technique: Any, scope: Scope, outer: Composed, item_level: bool) -> int:
        """Run ``technique``'s passes over ``scope``; returns the draw calls made (nested passes included)."""
        self.enter_technique(technique)
        calls = 0
        try:
            technique.start(self)
            try:
                while technique.needs_pass(self):
                    index = self.current_pass
                    self._requests.append(None)
                    try:
                        technique.prepare_pass(self)
                    finally:
                        description = self._requests.pop()
                    if description is None:
                        description = Pass(f"{type(technique).__name__}[{index}]")
                    calls += self._execute(technique, description, scope, outer, item_level)
                    technique.finish_pass(self)
                    technique.next_pass(self)
            finally:
                technique.stop(self)
        finally:
            self.leave_technique(technique)
        return calls

    def _execute(self, technique: Any, description: Pass, scope: Scope, outer: Composed, item_level: bool) -> int:
        composed = outer.then(description)
        record = PassRecord(
            name="/".join(composed.names),
            technique=type(technique).__name__,
            depth=len(self.technique_frames),
            draw_calls=0,
            items=0,
            target=description.target.name if description.target is not None else None,
            gpu_ms=None,
        )
        self._records.append(record)
        saved_target = self._bind_target(description.target) if description.target is not None else None
        saved_viewport = self._set_viewport(description.viewport) if description.viewport is not None else None
        saved_camera = None
        if description.front_face != "ccw":
            self.ctx.front_face = description.front_face
        if description.camera is not None:
            saved_camera = (self._view, self._proj, self._ortho)
            view, proj = description.camera
            if not isinstance(proj, np.ndarray):  # an om.Camera: its projection for this target's aspect
                proj = proj.projection_matrix(self._target_size[0] / self._target_size[1])
                ortho = description.camera[1].is_orthographic
            else:
                ortho = bool(abs(proj[3, 3] - 1.0) < 1e-9)
            self._set_camera(view, proj, ortho)
        self._enter_record(record)
        try:
            if description.clear is not None:
                self._clear(description.clear)
            source = self._root if description.source == "scene" and self._root is not None else scope
            if description.fullscreen is not None:
                calls = self._fullscreen(description.fullscreen, composed)
            elif description.custom is not None:
                calls = self._custom(technique, description.custom, source, composed, item_level)
            else:
                calls = self._draw_scope(source, composed, item_level, description.technique)
        finally:
            self._leave_record()
            if saved_camera is not None:
                self._set_camera(*saved_camera)
            if saved_viewport is not None:
                self._restore_viewport(saved_viewport)
            if description.front_face != "ccw":
                self.ctx.front_face = "ccw"
            if saved_target is not None:
                self._unbind_target(saved_target)
        return calls

    def _nested(self, scope: Scope, composed: Composed) -> int:
        return self._run(scope.technique, scope, composed, item_level=False)

    def _draw_scope(self, scope: Scope, composed: Composed, item_level: bool, technique: str | None = None) -> int:
        """What a pass that draws items draws: the scope's items (and nested scopes), or them through the
        engine's technique when the pass is a nested technique's; with ``scopes="items"`` every item below,
        without running the nested techniques; with ``technique`` ("engine", "pipeline") through that one."""
        if composed.scopes == "items":
            return sum(self._draw_items(s, composed, None) for s in scope.walk())
        if technique is not None:
            runner = self.frame_technique if technique == "pipeline" else self.technique
            return self._run(runner, scope, composed, item_level=True)
        if item_level:
            return self._draw_items(scope, composed, lambda child: self._nested(child, composed))
        return self._run(self.technique, scope, composed, item_level=True)

    def _custom(self, technique: Any, custom: Any, scope: Scope, composed: Composed, item_level: bool) -> int:
        """A custom pass: ``custom(engine, draw)``; ``draw()`` draws what the pass selects, ``draw(Pass)`` nests."""
        calls = 0

        def draw(nested: Pass | None = None) -> int:
            nonlocal calls
            if nested is None:
                made = self._draw_scope(scope, composed, item_level)
            elif isinstance(nested, Pass):
                made = self._execute(technique, nested, scope, composed, item_level)
            else:
                raise TypeError(f"draw() takes an om.gl.Pass or nothing, got {nested!r:.60}")
            calls += made
            return made

        gl = self._applier.gl
        fbo, size = gl.framebuffer, gl.size
        try:
            own = custom(self, draw)
        finally:
            # the code may have changed any GL state and binding: the next draw applies its state in full
            self._applier.forget()
            fbo.use()
            self.ctx.viewport = (0, 0, *size)
        if own is not None and (isinstance(own, bool) or not isinstance(own, int)):
            raise TypeError(f"a custom pass returns the draw calls it made itself (an int) or None, got {own!r:.60}")
        return calls + (own or 0)

    @property
    def current_framebuffer(self) -> Any:
        """The framebuffer being drawn into: the pass's offscreen target while a frame is drawn, else the engine's."""
        if getattr(self, "_drawing", False):
            return self._applier.gl.framebuffer
        return self.framebuffer

    def copy_framebuffer(self, description: Target) -> RenderTarget:
        """Copy colour and depth of :attr:`current_framebuffer` into the frame's offscreen target ``description``.

        The target (made at the current framebuffer's size, kept while later frames copy into it) is then
        read by :class:`FullScreen` inputs by its name, like a pass's; multisampling is resolved.  Custom
        passes and drawers use it to read what is already drawn (a filter, a merge by depth, the depth a
        volume's rays stop at).  The scissor test is switched off for the copy.
        """
        if not isinstance(description, Target):
            raise TypeError(f"GLEngine.copy_framebuffer needs an om.gl.Target, got {description!r:.60}")
        if len(description.colors) > 1:
            raise ValueError(
                f"GLEngine.copy_framebuffer: target {description.name!r} has {len(description.colors)} colour "
                "attachments; a copy fills one (give colors=('color',) or colors=() for depth only)"
            )
        if not getattr(self, "_drawing", False):
            raise RuntimeError("GLEngine.copy_framebuffer: no frame is being drawn; call it from a custom pass")
        source = self.current_framebuffer
        size = tuple(source.size)
        target = self._frame_target(description, size)
        self.ctx.disable_direct(_GL_SCISSOR_TEST)
        blit(self.raw, source, target.fbo, size, bool(description.colors), description.depth)
        self._applier.forget()
        return target

    # -- the report and timer queries ----------------------------------------------------------
    def count(self, calls: int, instances: int) -> None:
        """Add draw calls and instances to the pass being drawn (drawers of custom kinds may call it)."""
        if self._record_stack:
            record = self._record_stack[-1]
            record["draw_calls"] += calls
            record["items"] += instances

    def _enter_record(self, record: PassRecord) -> None:
        self._suspend_query()
        self._record_stack.append(record)
        self._resume_query()

    def _leave_record(self) -> None:
        self._suspend_query()
        self._record_stack.pop()
        self._resume_query()

    def _suspend_query(self) -> None:
        if self._open_query is not None:
            self._open_query.__exit__(None, None, None)
            self._open_query = None

    def _resume_query(self) -> None:
        if not self.timing or not self._record_stack or self._open_query is not None:
            return
        pool = self._query_pool
        if self._queries_used == len(pool):
            pool.append(self.ctx.query(time=True))
        query = pool[self._queries_used]
        self._queries_used += 1
        query.__enter__()
        self._open_query = query
        self._record_stack[-1].setdefault("_queries", []).append(query)

    def _close_query(self) -> None:
        self._suspend_query()

    # -- targets ------------------------------------------------------------------------
    def _target_key(self, description: Target, size: tuple[int, int] | None = None) -> tuple[Target, tuple[int, int]]:
        """(description, pixel size): the key of a target's GPU objects (``size``, else its own or its scale's)."""
        if size is None:
            size = description.size
        if size is None:
            base = self._target_size if description.relative == "enclosing" else self._size
            size = (max(1, round(base[0] * description.scale)), max(1, round(base[1] * description.scale)))
        return description, size

    def _frame_target(self, description: Target, size: tuple[int, int] | None = None) -> RenderTarget:
        """The GPU target of ``description`` (at ``size``, else its scale of the frame size), named in this frame."""
        key = self._target_key(description, size)
        size = key[1]
        target = self._target_cache.get(key)
        shared = self.target(description.depth).depth if isinstance(description.depth, str) else None
        if target is not None and target.shared_depth is not shared:  # the target it shares depth with is new
            self._target_cache.pop(key).release()
            target = None
        if target is None:
            if max(size) > self.max_texture_size:
                raise ValueError(
                    f"GLEngine: target {description.name!r} of {size[0]}x{size[1]} pixels is larger than this GPU "
                    f"allows ({self.max_texture_size} per side); lower its size or resolution"
                )
            target = RenderTarget(self.ctx, description, size, self.raw, shared)
            self._target_cache[key] = target
        self._targets_used.add(key)
        self._frame_targets[description.name] = target
        return target

    def _bind_target(self, description: Target) -> tuple:
        target = self._frame_target(description)
        saved = (self._applier.gl.framebuffer, self._target_size, self._linear_output)
        self._applier.forget()
        target.fbo.use()
        self.ctx.viewport = (0, 0, *target.size)
        self._applier.gl.framebuffer = target.fbo
        self._applier.gl.size = target.size
        self._target_size = target.size
        self._linear_output = description.dtype != "f1"
        return saved

    def _unbind_target(self, saved: tuple) -> None:
        fbo, size, linear = saved
        self._applier.forget()
        fbo.use()
        self.ctx.viewport = (0, 0, *size)
        self._applier.gl.framebuffer = fbo
        self._applier.gl.size = size
        self._target_size = size
        self._linear_output = linear

    def _set_viewport(self, box: tuple[int, int, int, int]) -> tuple:
        """Draw into the pixel rectangle ``box`` (x, y from the bottom-left) of the bound target."""
        saved = (self.ctx.viewport, self._target_size)
        self.ctx.viewport = box
        self._target_size = (box[2], box[3])
        return saved

    def _restore_viewport(self, saved: tuple) -> None:
        self.ctx.viewport, self._target_size = saved

    def _keep_target(self, description: Target) -> bool:
        """Keep the target of ``description`` from the last frame in this one (False when it is gone)."""
        key = self._target_key(description)
        target = self._target_cache.get(key)
        if target is None:
            return False
        self._targets_used.add(key)
        self._frame_targets[description.name] = target
        return True

    def _release_unused_targets(self) -> None:
        unused = [k for k in self._target_cache if k not in self._targets_used]
        if unused:
            self.ctx.finish()  # deleting a texture with queued work leaks that work in llvmpipe
        for key in unused:
            self._target_cache.pop(key).release()

    def _clear(self, clear: Any) -> None:
        ctx = self.ctx
        fbo = self._applier.gl.framebuffer
        self._applier.forget()
        set_masks(ctx, self.raw, fbo, color=(True, True, True, True), depth=True)
        ctx.scissor = None
        if clear.color is None and clear.depth is not None and self.raw.available:
            # depth alone: moderngl's clear applies the framebuffer's own colour masks (a detected framebuffer's
            # clear colour would be lost), so clear only the depth buffer with a raw call
            fbo.use()
            clear_depth(self.raw, float(clear.depth))
            set_masks(ctx, self.raw, fbo, color=(True, True, True, True), depth=True)
        elif clear.color is not None or clear.depth is not None:
            color = clear.color
            if color is not None and self._linear_output:
                from ...attributes.photometry import linear_rgb

                color = (*linear_rgb(color), color[3])
            if color is None:
                set_masks(ctx, self.raw, fbo, color=(False, False, False, False))
                color = (0.0, 0.0, 0.0, 0.0)
            if clear.depth is None:
                set_masks(ctx, self.raw, fbo, depth=False)
                fbo.depth_mask = False  # moderngl applies the framebuffer's own depth mask when it clears
            fbo.clear(*color, depth=1.0 if clear.depth is None else float(clear.depth))
            fbo.depth_mask = True
            set_masks(ctx, self.raw, fbo, color=(True, True, True, True), depth=True)
        if clear.stencil is not None:
            clear_stencil(self.raw, int(clear.stencil))
            self._applier.forget()  # the stencil write mask was reset to clear every bit

    # -- image-space passes --------------------------------------------------------------
    def _fullscreen(self, effect: FullScreen, composed: Composed) -> int:
        """Draw one full-screen triangle shaded by ``effect`` into the current target."""
        ctx = self.ctx
        programs: FullScreenPrograms = self._fullscreen_programs
        prog, vao = programs.get(effect, self._linear_output)
        unit = 0
        for uniform, name, attachment in effect.inputs:
            target = self.target(name)
            texture = target.depth if attachment == "depth" else target.texture(attachment)
            if texture is None:
                raise ValueError(
                    f"FullScreen: target {name!r} has no depth texture; make it with Target(..., depth=True)"
                )
            texture.use(unit)
            u = prog.get(uniform, None)
            if u is not None:
                u.value = unit
            unit += 1
        for uniform, image in effect.textures:
            u = prog.get(uniform, None)
            if u is not None:
                self._texture(image, srgb=False).use(unit)
                u.value = unit
                unit += 1
        for name, value in effect.uniforms:
            u = prog.get(name, None)
            if u is None:
                continue
            if isinstance(value, tuple) and u.array_length > 1:  # arrays: the values in order, zeros after
                data = np.zeros(u.array_length * u.dimension, np.float32)
                data[: len(value)] = value[: data.size]
                u.write(data.tobytes())
            else:
                u.value = value
        u = prog.get("u_resolution", None)
        if u is not None:
            u.value = tuple(float(v) for v in self._target_size)
        # the pass's GL state (a stencil test, a scissor, a colour mask), then what the triangle needs
        self._applier.forget()
        self._applier.apply(composed.raster(self._defaults, self._defaults))
        self._applier.forget()
        ctx.disable(ctx.CULL_FACE)
        ctx.wireframe = False
        ctx.polygon_offset = (0.0, 0.0)
        if effect.depth:
            ctx.enable(ctx.DEPTH_TEST)
            ctx.depth_func = DEPTH_FUNCS[effect.depth_test or "always"]
            set_masks(ctx, self.raw, self._applier.gl.framebuffer, color=(True, True, True, True), depth=True)
        else:
            ctx.disable(ctx.DEPTH_TEST)
            set_masks(ctx, self.raw, self._applier.gl.framebuffer, depth=False)
        if effect.blend:
            ctx.enable(ctx.BLEND)
            ctx.blend_func = (ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA, ctx.ONE, ctx.ONE_MINUS_SRC_ALPHA)
        else:
            ctx.disable(ctx.BLEND)
        vao.render(ctx.TRIANGLES, vertices=3)
        self._applier.forget()
        self.count(1, 0)
        return 1

    def _restore_defaults(self, fbo: Any = None, size: tuple[int, int] | None = None) -> None:
        """State preservation: leave the context as a plain moderngl user expects it, ``fbo`` bound."""
        ctx = self.ctx
        self._applier.apply(self._defaults)
        self._applier.forget()
        ctx.disable(ctx.BLEND | ctx.CULL_FACE)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.depth_func = "<"
        ctx.wireframe = False
        ctx.polygon_offset = (0.0, 0.0)
        ctx.scissor = None
        fbo = self.framebuffer if fbo is None else fbo
        set_masks(ctx, self.raw, fbo, color=(True, True, True, True), depth=True)
        for i in range(self._nclip):
            ctx.disable_direct(0x3000 + i)
        self._nclip = 0
        fbo.use()
        ctx.viewport = (0, 0, *(self._size if size is None else size))
