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
all of this happens on every frame drawn in full: the compiled scopes are
cached, the passes are not.  A frame in which nothing changed replays the
draws the frame before it recorded instead (the frame plan, :mod:`.plan`).

Every executed pass is recorded in ``engine.stats["passes"]``: its path of
names, technique, nesting depth, draw calls, instances and (with
``GLEngine(timing=True)``) GPU time from timer queries.  Offscreen targets
are made from their :class:`~.passes.Target` descriptions, kept while later
frames describe the same targets and released when no pass uses them any more
(:mod:`.targets`).

The :class:`FrameRunner` is one of the engine's collaborators (three.js's
``WebGLRenderer`` is assembled the same way): it is made once per engine and
handed the :class:`~.frame_state.FrameState` it writes, the
:class:`~.drawer.BatchDrawer` that draws items, the
:class:`~.targets.FrameTargets` and the :class:`~.report.PassReport`.  It
uses the engine facade only through its public API (techniques get the facade
in every call).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

import numpy as np

from ...core.technique import pass_accepted
from .attributes import Blend, ColorMask, CullFace, DepthMask, DepthTest, PolygonOffset, ScissorTest, StencilOp
from .context import GLError, blit, clear_depth, clear_frame, clear_stencil
from .drawer import SORT_MIN, BatchDrawer
from .drawlist import Scope
from .frame_state import FrameState, ProjectionInfo
from .imagespace import FullScreenPrograms, RenderTarget
from .passes import Composed, FullScreen, Pass, Target
from .plan import FramePlan, FrameRecorder, PlanKey, RecordedPass
from .report import PassRecord, PassReport
from .stages import FrameStage, StageList
from .state import FillMode, GLCalls, RasterApplier, defaults
from .targets import FrameTargets

__all__ = ["FrameRunner", "PassRecord", "ProjectionInfo"]

_OVER = ("src_alpha", "one_minus_src_alpha", "add")  # blending of a full-screen pass with blend=True


def _scissor(description: Pass) -> Any:
    """The ScissorTest box a pass description sets (None: none)."""
    index = ScissorTest.index
    for kind, value in description.state_values:
        if kind == index:
            return value
    return None


class FrameRunner:
    """Runs a frame: its stages (:mod:`.stages`) in order, each running techniques' passes over the compiled
    scopes (nested techniques included); binds targets, clears, draws full-screen passes."""

    def __init__(
        self,
        engine: Any,
        state: FrameState,
        drawer: BatchDrawer,
        targets: FrameTargets,
        report: PassReport,
        stages: StageList,
    ) -> None:
        #: the engine facade: techniques get it in every call; only its public API is used here
        self.engine = engine
        self.ctx = engine.ctx
        self.raw = engine.raw
        self.state = state
        self.drawer = drawer
        self.targets = targets
        self.report = report
        self.fullscreen_programs = FullScreenPrograms(self.ctx)
        #: the frame's stages, in order
        self.stages = stages
        self._requests: list[Any] = []
        #: how many technique frames enclose the technique running over a whole frame (0: the frame's own;
        #: a stereo eye drawn whole runs it inside the stereo technique)
        self.frame_base = 0
        #: bumped by every :meth:`placements_changed` (the change tracker's word that the draw list or a
        #: placement changed): a recorded frame plan is replayed only while it holds
        self.generation = 0
        #: the last frame, recorded (:mod:`.plan`): replayed while its key holds, or None
        self.plan: FramePlan | None = None
        #: record steady frames and replay them (False: every frame is drawn in full, e.g. to compare)
        self.replay = True
        #: why the last frame drawn in full was not kept as a plan (None: it was, or it was not recorded)
        self.not_recorded: str | None = None
        #: id(batch) -> batch whose rows moved in place since the plan was recorded or last replayed: the next
        #: replay uploads their changed rows first (:meth:`rows_moved`)
        self._moved: dict[int, Any] = {}
        #: (plan, root scope, draw-list version, stages) for which :meth:`rows_moved` found that the plan may be
        #: kept after rows moved in place, or None
        self._follows: tuple[Any, ...] | None = None
        #: the same for :meth:`rows_restyled` (which keeps plans with shadow maps)
        self._restyles: tuple[Any, ...] | None = None
        #: (stages, those of them that override FrameStage.follow_rows): what runs before a replay after moves
        self._followers: tuple[tuple[Any, ...], list[Any]] | None = None
        #: (stages, those of them that override FrameStage.changed): what :meth:`rows_moved` tells
        self._forgetters: tuple[tuple[Any, ...], list[Any]] | None = None
        #: (plan, stages, the followers that follow that plan): what runs before the plan's replays after moves
        self._active: tuple[Any, tuple[Any, ...], list[Any]] | None = None
        #: id(batch) -> batch whose row count a splice changed since: the replay's draws of it take the new count
        self._resized: dict[int, Any] = {}
        #: (plan, ids of the uniforms its draws write): what :meth:`replay_draws` asks of the plan being kept
        self._plan_uniforms: tuple[Any, set[int]] | None = None

    def placements_changed(self) -> None:
        """Items moved or the draw list changed: every stage forgets what it derived from placements
        (shadow casters' bounds, mirror planes); the recorded frame plan is stale."""
        self.generation += 1
        self.plan = None
        self._moved.clear()
        self._resized.clear()
        for stage in self.stages:
            stage.changed()

    def rows_spliced(self, batches: list[Any]) -> None:
        """A splice only removed and appended rows of ``batches`` (existing batches drawn the same way: see
        ``renderer._rows_only``): as :meth:`rows_moved`, and the plan's key takes the new draw-list version and
        its draws of those batches their new instance counts when it is replayed."""
        self.rows_moved(batches)
        plan = self.plan
        if plan is None:
            return
        engine = self.engine
        plan.key = self._plan_key_with_list_version(plan.key, engine.draw_list_version)
        plan.stats["items"] = engine.item_count
        for batch in batches:
            self._resized[id(batch)] = batch

    def _plan_key_with_list_version(self, key: PlanKey, version: int) -> PlanKey:
        """``key`` (made by :meth:`_plan_key`) with the draw-list version ``version``."""
        values = list(key.values[len(key.objects) :])
        values[1] = version  # (generation, draw-list version, ...): see _plan_key
        return PlanKey(key.objects, tuple(values))

    def _resize_ops(self, plan: FramePlan) -> bool:
        """The plan's draws of batches whose row count a splice changed take their new counts; False when one
        cannot (not sorted and all in view: its draw would cull or sort again)."""
        for batch in self._resized.values():
            n = batch.size
            if n < SORT_MIN or batch.position is None or len(batch.position) != n or batch.drawn != n:
                return False
            vaos = {id(vao) for vao in batch.vaos.values()}
            for op in plan.ops:
                if id(op.vao) in vaos:
                    op.n = n
        self._resized.clear()
        return True

    def rows_moved(self, batches: list[Any]) -> None:
        """Only the rows of ``batches`` moved in place (model matrices; nothing added, removed or re-made):
        every stage forgets what it derived from placements, and a recorded plan is kept when every stage
        follows rows (:meth:`~.stages.FrameStage.follows_rows`) and no scope filters batches for its passes;
        the next frame then uploads those rows, lets the stages that keep something up to date with rows draw
        it (:meth:`~.stages.FrameStage.follow_rows`: the shadow maps) and replays it (the drawer declines a
        batch whose draw would sort, cull or pack again, a stage one whose draws changed: that frame is drawn
        in full)."""
        plan = self.plan
        engine = self.engine
        root = engine.root_scope
        stages = self.stages.frozen()
        # (the answer holds for one plan, root scope, draw-list version and stage list: an editor's drag asks it
        # once; scopes gain filtered batches only in frames drawn in full, which record a new plan)
        follows = (plan, root, engine.draw_list_version, stages)
        if self._follows != follows:  # (identities, and the version's value)
            if (
                plan is None
                or root is None
                or any(scope.filtered for scope in root.walk())
                or not all(stage.follows_rows(engine) for stage in stages)
            ):
                self._follows = None
                self.placements_changed()
                return
            self._follows = follows
        forgetters = self._forgetters
        if forgetters is None or forgetters[0] is not stages:
            base = FrameStage.changed
            forgetters = self._forgetters = (stages, [s for s in stages if type(s).changed is not base])
        for stage in forgetters[1]:  # (the stages that forget something: a drag calls no empty method per frame)
            stage.changed()
        moved = self._moved
        for batch in batches:
            moved[id(batch)] = batch

    def rows_restyled(self, batches: list[Any]) -> None:
        """Only the surface fields of rows of ``batches`` changed in place (a Material replaced by one drawn
        with the same state: ``engine/dirty.py``); nothing moved, so no stage forgets what it derived from
        placements (the shadow maps, which read no surface, stay).  A recorded plan is kept when every stage
        follows rows and no scope filters batches for its passes (their copies follow a source only in frames
        drawn in full); the next frame uploads those rows and replays it."""
        plan = self.plan
        if plan is None:
            return  # the next frame is drawn in full: it uploads the changed rows
        engine = self.engine
        root = engine.root_scope
        stages = self.stages.frozen()
        # (asked once per plan, root scope, draw-list version and stage list, as rows_moved asks; what it found
        # holds here too: its conditions include these)
        follows = (plan, root, engine.draw_list_version, stages)
        if self._follows != follows and self._restyles != follows:
            if (
                root is None
                or any(scope.filtered for scope in root.walk())
                or not all(stage.follows_rows(engine) for stage in stages)
            ):
                self._restyles = None
                self.placements_changed()
                return
            self._restyles = follows
        for batch in batches:
            self._moved[id(batch)] = batch

    def _taint(self, why: str) -> None:
        """The frame being drawn does something a replay would not repeat: it keeps no plan."""
        recorder = self.state.recorder
        if recorder is not None:
            recorder.taint(why)

    # -- what techniques call (through the engine) -----------------------------------
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

    def forget_gl_state(self) -> None:
        """A drawer changed GL state itself: the next draw applies its state in full."""
        self._taint("GL state changed outside the applier (forget_gl_state)")
        self.state.applier.forget()

    def apply_gl_state(self, *states: Any) -> None:
        """Make the GL state attributes ``states`` (``om.gl.DepthTest(False)``, ``om.gl.Blend()``, ...) current,
        through the applier (the other states stay as they are)."""
        self._taint("GL state set by apply_gl_state")
        values = {}
        for state in states:
            if not hasattr(state, "capture") or getattr(type(state), "index", -1) < 0:
                raise TypeError(
                    f"GLEngine.apply_gl_state takes GL state attributes (om.gl.Blend(), ...), got {state!r:.60}"
                )
            values[type(state).index] = state.capture()
        self.state.applier.override(values)

    def default_gl_state(self) -> None:
        """Every GL state kind at its default, through the applier."""
        self._taint("GL state set by default_gl_state")
        self.state.applier.apply(defaults())

    def sample_mask(self, sample: int | None) -> None:
        """Draws write only sample ``sample`` of a multisampled target (None: every sample)."""
        self._taint("a sample mask")
        self.state.applier.sample_mask(sample)

    def bind_framebuffer(self, framebuffer: Any, size: tuple[int, int]) -> None:
        """Draw into ``framebuffer`` (of ``size``) until the pass binds another, through the applier."""
        self._taint("a framebuffer bound by bind_framebuffer")
        self.state.applier.bind(framebuffer, size)

    def reset_gl_state(self) -> None:
        """Every GL state kind at its default; the next draw applies its state in full."""
        self._taint("GL state reset by reset_gl_state")
        applier = self.state.applier
        applier.forget()
        applier.apply(defaults())
        applier.forget()

    @contextlib.contextmanager
    def between_frames(self) -> Iterator[RasterApplier]:
        """GL state for drawing outside a frame (a depth sprite drawn back, a target pushed): an applier with the
        engine's framebuffer bound and every kind at its default, so :meth:`apply_gl_state` and the others work
        as in a pass; afterwards GL is at its defaults with the engine's framebuffer bound, as after a frame.
        Inside a frame (a custom pass) it is the frame's own applier."""
        state = self.state
        if state.drawing:
            self._taint("GL state changed in between_frames")
            yield state.applier
            return
        engine = self.engine
        fbo, size = engine.framebuffer, tuple(engine.size)
        outer = state.applier
        state.applier = applier = RasterApplier(GLCalls(self.ctx, self.raw, fbo, size))
        applier.begin(fbo, size)
        try:
            yield applier
        finally:
            applier.restore_defaults()
            applier.bind(fbo, size)
            state.applier = outer

    @property
    def current_framebuffer(self) -> Any:
        """The framebuffer being drawn into while a frame is drawn (None outside a frame)."""
        return self.state.applier.gl.framebuffer if self.state.drawing else None

    # -- the frame ---------------------------------------------------------------------
    def draw(self, background: Any, clear: bool, override: Any = None, framebuffer: Any = None) -> None:
        """Draw the installed scopes into ``framebuffer`` (else the engine's): every stage and technique pass.

        A frame that changed nothing since the last one (:class:`~.plan.PlanKey`) replays its recorded
        draws (:mod:`.plan`) instead of running the stages again.
        """
        engine, ctx, state = self.engine, self.ctx, self.state
        stages = self.stages.frozen()  # the same tuple while no stage is added or removed (a plan's key holds it)
        for stage in stages:
            stage.prepare(engine)  # e.g. render textures first: their engines use the context
        fbo = engine.framebuffer if framebuffer is None else framebuffer
        size = tuple(engine.size) if framebuffer is None else tuple(framebuffer.size)
        _ = ctx.error  # errors of earlier, foreign GL calls are not this frame's
        state.target_size = size
        state.linear_output = False
        state.applier = applier = RasterApplier(GLCalls(ctx, self.raw, fbo, size))
        applier.begin(fbo, size)
        state.background = background
        color = engine.clear_color(background) if clear else None
        if clear:
            stencil = engine.has_stencil and not engine.pushed_targets and framebuffer is None
            if self.raw.available:
                # one glClear: the frame began with every kind at its default (every channel, depth and
                # stencil bit written, no scissor), what a clear of the whole target needs
                clear_frame(self.raw, color, stencil)
            else:
                fbo.clear(*color, depth=1.0)
                applier.reassert()  # moderngl's clear set the framebuffer's own masks
                if stencil:
                    clear_stencil(self.raw, 0)  # the default stencil write mask (every bit) is set
        camera, view, proj = self._frame_camera(override, size)
        state.camera = camera
        state.set_camera(view, proj, camera.is_orthographic)
        state.frame_view_key = state.view_key  # the frame's own view: the one batches are culled for
        state.frame_view = state.view
        installed = engine.root_scope
        key = self._plan_key(stages, fbo, size, color, override, framebuffer, clear, installed)
        plan = self.plan
        if key is not None and plan is not None and plan.key.matches(key):
            moved = self._moved
            if (not self._resized or self._resize_ops(plan)) and (
                not moved or (self._upload_moved(moved) and self._follow_rows(stages, plan, installed, fbo, size))
            ):
                moved.clear()
                self._replay(plan, fbo, size)
                return
        self.plan = None
        self._moved.clear()  # the frame drawn in full uploads what changed
        self._resized.clear()
        self.not_recorded = None
        engine.programs.owner = None  # this frame writes the programs' uniforms in its own order
        self.report.begin_frame(engine.timing)
        self.targets.begin_frame(tuple(engine.size))
        root = installed if installed is not None else Scope()
        state.shadow_plan = None
        state.drawing = True
        state.recorder = recorder = FrameRecorder() if key is not None else None
        calls = 0
        try:
            for stage in stages:
                if recorder is not None and not stage.replayable(engine):
                    recorder.taint(f"stage {stage.name!r} is not replayable")
                calls += stage.draw(self, root)
        finally:
            state.drawing = False
            state.recorder = None
            self.report.close()
            self._restore_defaults(fbo, size)
        self.targets.release_unused()
        stats = engine.stats
        stats["draw_calls"] = calls
        stats["passes"] = self.report.finish()
        stats["batches"] = sum(len(p.batches) for s in (installed.walk() if installed else [])
                               for p in (s.parts or []) if not isinstance(p, Scope))  # fmt: skip
        stats["items"] = engine.item_count if installed is not None else 0
        stats["replayed"] = False
        self._check_errors()
        if recorder is not None and key is not None:
            kept = {name: stats[name] for name in ("draw_calls", "batches", "items")}
            kept["passes"] = [PassRecord(record) for record in stats["passes"]]
            kept["shadow_plan"] = state.shadow_plan
            self.plan = recorder.plan(key, kept)
            self.not_recorded = recorder.tainted
            if self.plan is not None:
                engine.programs.owner = self.plan

    def _upload_moved(self, moved: dict[int, Any]) -> bool:
        """Upload the rows moved in place since the plan was recorded (:meth:`rows_moved`); False when a batch's
        draw would do more than that (the frame is drawn in full)."""
        upload = self.drawer.upload_moved
        for batch in moved.values():
            if not upload(batch):
                return False
        return True

    def _follow_rows(
        self, stages: tuple[Any, ...], plan: FramePlan, root: Any, fbo: Any, size: tuple[int, int]
    ) -> bool:
        """Before a plan is replayed after rows moved in place: the stages that keep something up to date with
        rows (:meth:`~.stages.FrameStage.follow_rows`: the shadow maps' regions the moved casters cover) draw it
        now; False when one says the plan's draws no longer hold (the frame is drawn in full)."""
        found = self._active
        if found is None or found[0] is not plan or found[1] is not stages:
            followers = self._followers
            if followers is None or followers[0] is not stages:
                base = FrameStage.follow_rows
                followers = self._followers = (stages, [s for s in stages if type(s).follow_rows is not base])
            # (asked once per recorded plan: FrameStage.follows_plan)
            found = self._active = (plan, stages, [stage for stage in followers[1] if stage.follows_plan(plan)])
        active = found[2]
        if not active:
            return True  # nothing to draw: the frame's target and state stay as they are for the replay
        engine, state, report = self.engine, self.state, self.report
        state.shadow_plan = None
        state.drawing = True
        report.begin_frame(False)
        try:
            held = all(stage.follow_rows(self, root, plan) for stage in active)
        finally:
            state.drawing = False
            report.close()
            if report.records:  # passes ran (stages draw with frame.run); else GL is as the frame began
                self._restore_defaults(fbo, size)  # a replay starts from the defaults with the target bound
                engine.programs.owner = None  # programs the stages drew with may be the plan's: all writes again
        return held

    def _plan_key(
        self,
        stages: tuple[Any, ...],
        fbo: Any,
        size: tuple[int, int],
        color: tuple[float, ...] | None,
        override: Any,
        framebuffer: Any,
        clear: bool,
        installed: Scope | None,
    ) -> PlanKey | None:
        """What a recorded plan of this frame depends on (:mod:`.plan`); None when the frame is not recorded
        (another camera or framebuffer given, no clear, timer queries, nested in another frame, nothing
        installed)."""
        engine, state = self.engine, self.state
        if (
            not self.replay
            or override is not None
            or framebuffer is not None
            or not clear
            or installed is None
            or engine.timing
            or self.technique_depth()
            or state.drawing
            or engine.pushed_targets
        ):
            return None
        objects = (fbo, engine.declared, engine.technique, engine.frame_technique, engine.stereo, installed, stages)
        values = (
            self.generation,
            engine.draw_list_version,
            size,
            tuple(engine.size),
            color,
            state.view_key,
            state.ortho,
            engine.shadows,
            engine.has_stencil,
        )
        return PlanKey(objects, values)

    def technique_depth(self) -> int:
        """How many techniques are running now (0 between frames)."""
        return len(self.engine.technique_frames)

    def _replay(self, plan: FramePlan, fbo: Any, size: tuple[int, int]) -> None:
        """Issue ``plan``'s recorded draws into the bound target (cleared, camera set) and report its stats."""
        engine, state = self.engine, self.state
        programs = engine.programs
        state.shadow_plan = plan.stats["shadow_plan"]  # what the recorded frame's shadow stage planned
        state.drawing = True
        applier = state.applier
        try:
            # the target stays bound and the front face, sample mask and viewport at their defaults: nothing
            # in a recorded frame changes them (passes that do are not recorded)
            plan.replay(applier, full=programs.owner is not plan)
        except BaseException:
            self._restore_defaults(fbo, size)
            raise
        finally:
            state.drawing = False
        programs.owner = plan
        stats = engine.stats
        kept = plan.stats
        stats["draw_calls"] = kept["draw_calls"]
        stats["passes"] = [PassRecord(record) for record in kept["passes"]]
        stats["batches"] = kept["batches"]
        stats["items"] = kept["items"]
        stats["replayed"] = True
        self._check_errors()

    def _check_errors(self) -> None:
        err = self.ctx.error
        if err != "GL_NO_ERROR":
            if "OUT_OF_MEMORY" in err:
                raise GLError("GLEngine: the GPU ran out of memory while drawing; reduce the scene or image size")
            raise GLError(f"GLEngine: OpenGL reported {err} while drawing")

    def _frame_camera(self, override: Any, size: tuple[int, int]) -> tuple[Any, np.ndarray, np.ndarray]:
        """(camera, view, projection) of a frame: the scene's, or ``override`` (validated ``(view, Camera|proj)``)."""
        if override is None:
            camera, view, projection = self.engine.camera_matrices()
            if size != tuple(self.engine.size):  # another framebuffer's aspect
                projection = camera.projection_matrix(size[0] / size[1])
            return camera, view, projection
        view, proj = override
        if isinstance(proj, np.ndarray):
            return ProjectionInfo.of(proj), view, proj
        return proj, view, proj.projection_matrix(size[0] / size[1])

    # -- techniques and passes ---------------------------------------------------------------
    def run(self, technique: Any, scope: Scope, outer: Composed | None = None, item_level: bool = True) -> int:
        """Run ``technique``'s passes over ``scope``; returns the draw calls made (nested passes included).

        ``outer`` is the pass the technique runs in (its state, masks and shader features apply to every
        pass of the technique; none for a stage's own techniques); ``item_level=False`` runs the technique's
        item passes through the engine's technique (what a nested technique's passes do).
        """
        if outer is None:
            outer = Composed()
        engine = self.engine
        recorder = self.state.recorder
        if recorder is not None and not recorder.draws_only and not type(technique).__dict__.get("replayable", False):
            # a technique's pass control is the application's code: it may draw other passes next frame
            recorder.taint(f"technique {type(technique).__name__} is not replayable")
        engine.enter_technique(technique)
        calls = 0
        try:
            technique.start(engine)
            try:
                while technique.needs_pass(engine):
                    index = engine.current_pass
                    self._requests.append(None)
                    try:
                        accepted = pass_accepted(technique.prepare_pass(engine))
                    finally:
                        description = self._requests.pop()
                    if accepted:  # a technique may decline a pass (VRS): not drawn, not finished
                        if description is None:
                            description = Pass(f"{type(technique).__name__}[{index}]")
                        calls += self._execute(technique, description, scope, outer, item_level)
                        technique.finish_pass(engine)
                    technique.next_pass(engine)
            finally:
                technique.stop(engine)
        finally:
            engine.leave_technique(technique)
        return calls

    def run_recorded(self, technique: Any, scope: Scope) -> tuple[int, RecordedPass | None]:
        """Run ``technique`` over ``scope`` as :meth:`run` does while recording its draws; returns the draw calls
        and, when it ran one pass that draws the opaque batches of its scope (``scopes="items"``, no select,
        mask, full-screen or own draw) and every draw can be issued again as recorded, a
        :class:`~.plan.RecordedPass` for :meth:`replay_draws` (else None; draws that bind textures are not kept).

        For a stage that redraws a part of its target frame after frame (the shadow maps' partial updates):
        only while a frame is drawn and not recorded itself (a stage's ``follow_rows``)."""
        state = self.state
        if state.recorder is not None or not state.drawing:
            return self.run(technique, scope), None
        recorder = state.recorder = FrameRecorder(draws_only=True)
        try:
            calls = self.run(technique, scope)
        finally:
            state.recorder = None
        if recorder.tainted is not None or len(recorder.passes) != 1:
            return calls, None
        (description,) = recorder.passes
        if (
            description.scopes != "items"
            or description.items != {"opaque"}
            or description.select is not None
            or description.mask is not None
            or description.fullscreen is not None
            or description.custom is not None
            or description.technique is not None
        ):
            return calls, None
        box = _scissor(description)
        redraw_key = self.drawer.redraw_key
        keys = []
        for op in recorder.ops:
            key = redraw_key(op.batch) if op.batch is not None else None
            if key is None or op.n != op.batch.size or op.raster[ScissorTest.index] != box or op.textures:
                return calls, None  # (textures: an alpha-tested caster's, made again when its image changes)
            keys.append(key)
        return calls, RecordedPass(description, recorder.ops, keys)

    def replay_draws(self, recorded: RecordedPass, scope: Scope, box: tuple[int, int, int, int]) -> int | None:
        """Issue the draws of ``recorded`` (:meth:`run_recorded`) again as its pass limited to the pixel rectangle
        ``box`` (x, y, width, height from the target's top-left corner, as :meth:`Pass.scissored` takes it): its
        target bound with its viewport, its clear (if any) of ``box``, each draw under ``box``'s scissor with the
        uniforms, textures and vertex arrays recorded and its batch's current row count; afterwards GL is at
        its defaults with the frame's target bound.  Returns the draw calls, or None with nothing drawn when the
        recording no longer holds: ``scope`` has other batches to draw, or a batch's draw would do more than it
        did (``BatchDrawer.redraw_key``)."""
        description = recorded.description
        root = self.engine.root_scope
        source = root if description.source == "scene" and root is not None else scope
        batches = recorded.batches
        k = 0
        for part_scope in source.walk():
            for part in part_scope.parts or ():
                if isinstance(part, Scope):
                    continue
                for batch in part.batches:
                    if not batch.size:
                        continue  # (not drawn)
                    if k >= len(batches) or batch is not batches[k]:
                        return None
                    k += 1
        if k != len(batches):
            return None
        redraw_key = self.drawer.redraw_key
        for batch, key in zip(batches, recorded.keys, strict=True):
            if redraw_key(batch) != key:
                return None
        applier = self.state.applier
        fbo, size = applier.gl.framebuffer, applier.gl.size
        try:
            if description.target is not None:
                target = self.targets.get(description.target, self.state.target_size)
                applier.bind(target.fbo, target.size, description.viewport)
            elif description.viewport is not None:
                applier.viewport(description.viewport)
            box = tuple(box)
            if description.clear is not None:
                self._clear(description.clear, box)
            index = ScissorTest.index
            for op in recorded.ops:
                raster = op.raster
                applier.apply((*raster[:index], box, *raster[index + 1 :]))
                applier.clip_planes(op.clip)
                for texture, unit in op.textures:
                    texture.use(unit)
                for uniform, value, raw in op.writes:
                    if raw:
                        uniform.write(value)
                    else:
                        uniform.value = value
                op.vao.render(op.mode, instances=op.batch.size)
        finally:
            self._restore_defaults(fbo, size)
        plan = self.plan
        programs = self.engine.programs
        if plan is not None and programs.owner is plan:
            # the plan's uniforms hold the values it left unless these draws wrote some of them
            found = self._plan_uniforms
            if found is None or found[0] is not plan:
                found = self._plan_uniforms = (plan, {id(u) for op in plan.ops for u, _, _ in op.writes})
            if not found[1].isdisjoint(recorded.uniforms):
                programs.owner = None
        return len(recorded.ops)

    def _execute(self, technique: Any, description: Pass, scope: Scope, outer: Composed, item_level: bool) -> int:
        composed = outer.then(description)
        state = self.state
        if (
            state.recorder is not None
            and not state.recorder.draws_only
            and (
                description.target is not None
                or description.viewport is not None
                or description.front_face != "ccw"
                or description.camera is not None
                or description.clear is not None
                or description.fullscreen is not None
                or description.custom is not None
            )
        ):
            state.recorder.taint(f"pass {description.name!r} sets a target, viewport, camera, clear or its own draw")
        if state.recorder is not None and state.recorder.draws_only:
            state.recorder.passes.append(description)
        record = PassRecord(
            name="/".join(composed.names),
            technique=type(technique).__name__,
            depth=len(self.engine.technique_frames),
            draw_calls=0,
            items=0,
            target=description.target.name if description.target is not None else None,
            gpu_ms=None,
        )
        self.report.add(record)
        saved_target = self._bind_target(description.target) if description.target is not None else None
        saved_viewport = self._set_viewport(description.viewport) if description.viewport is not None else None
        saved_camera = None
        if description.front_face != "ccw":
            state.applier.front_face(description.front_face)
        if description.camera is not None:
            saved_camera = state.camera_state()
            view, proj = description.camera
            if not isinstance(proj, np.ndarray):  # an om.Camera: its projection for this target's aspect
                proj = proj.projection_matrix(state.target_size[0] / state.target_size[1])
                ortho = description.camera[1].is_orthographic
            else:
                ortho = bool(abs(proj[3, 3] - 1.0) < 1e-9)
            state.set_camera(view, proj, ortho)
        self.report.enter(record)
        saved_shading = state.shading
        state.shading = composed.shading()
        try:
            if description.clear is not None:
                self._clear(description.clear)
            root = self.engine.root_scope
            source = root if description.source == "scene" and root is not None else scope
            if description.fullscreen is not None:
                calls = self._fullscreen(description.fullscreen, composed)
            elif description.custom is not None:
                calls = self._custom(technique, description.custom, source, composed, item_level)
            else:
                calls = self._draw_scope(source, composed, item_level, description.technique)
        finally:
            self.report.leave()
            state.shading = saved_shading
            if saved_camera is not None:
                state.set_camera(*saved_camera)
            if saved_viewport is not None:
                self._restore_viewport(saved_viewport)
            if description.front_face != "ccw":
                state.applier.front_face("ccw")
            if saved_target is not None:
                self._unbind_target(saved_target)
        return calls

    def frame_level(self, root: Scope) -> tuple[Any, Scope]:
        """(technique, scope) a frame runs over ``root``: the frame's pipeline over it, or the frame-level
        technique (a post-processing chain) of a root that is one scope of it, around the pipeline."""
        whole = root.entries[0] if len(root.entries) == 1 else None
        if isinstance(whole, Scope) and getattr(whole.technique, "frame_level", False):
            return whole.technique, whole
        return self.engine.frame_technique, root

    def run_frame_level(self, root: Scope, composed: Composed) -> int:
        """Run what a frame runs over ``root`` (:meth:`frame_level`) as a frame of the target bound now: its
        techniques see themselves at the frame's level and targets relative to the frame take its size."""
        technique, scope = self.frame_level(root)
        base, size = self.frame_base, self.targets.frame_size(self.state.target_size)
        self.frame_base = len(self.engine.technique_frames)
        try:
            return self.run(technique, scope, composed, item_level=True)
        finally:
            self.frame_base = base
            self.targets.frame_size(size)

    def _nested(self, scope: Scope, composed: Composed) -> int:
        return self.run(scope.technique, scope, composed, item_level=False)

    def _draw_scope(self, scope: Scope, composed: Composed, item_level: bool, technique: str | None = None) -> int:
        """What a pass that draws items draws: the scope's items (and nested scopes), or them through the
        engine's technique when the pass is a nested technique's; with ``scopes="items"`` every item below,
        without running the nested techniques; with ``technique`` ("engine", "pipeline") through that one."""
        if composed.scopes == "items":
            return sum(self.drawer.draw_items(s, composed, None) for s in scope.walk())
        engine = self.engine
        if technique == "frame":
            return self.run_frame_level(scope, composed)
        if technique is not None:
            runner = engine.frame_technique if technique == "pipeline" else engine.technique
            return self.run(runner, scope, composed, item_level=True)
        if item_level:
            return self.drawer.draw_items(scope, composed, lambda child: self._nested(child, composed))
        return self.run(engine.technique, scope, composed, item_level=True)

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

        applier = self.state.applier
        fbo, size = applier.gl.framebuffer, applier.gl.size
        try:
            own = custom(self.engine, draw)
        finally:
            # the application's code may have changed any GL state and binding: the next draw applies its
            # state in full (the one place the frame cannot know what GL holds)
            applier.forget()
            applier.bind(fbo, size)
        if own is not None and (isinstance(own, bool) or not isinstance(own, int)):
            raise TypeError(f"a custom pass returns the draw calls it made itself (an int) or None, got {own!r:.60}")
        return calls + (own or 0)

    def copy_framebuffer(self, description: Target) -> RenderTarget:
        """Copy colour and depth of the framebuffer being drawn into the frame's offscreen target ``description``
        (see ``GLEngine.copy_framebuffer``)."""
        if not isinstance(description, Target):
            raise TypeError(f"GLEngine.copy_framebuffer needs an om.gl.Target, got {description!r:.60}")
        if len(description.colors) > 1:
            raise ValueError(
                f"GLEngine.copy_framebuffer: target {description.name!r} has {len(description.colors)} colour "
                "attachments; a copy fills one (give colors=('color',) or colors=() for depth only)"
            )
        if not self.state.drawing:
            raise RuntimeError("GLEngine.copy_framebuffer: no frame is being drawn; call it from a custom pass")
        self._taint("copy_framebuffer")
        source = self.current_framebuffer
        size = tuple(source.size)
        target = self.targets.get(description, self.state.target_size, size)
        self.state.applier.override({ScissorTest.index: None})  # a blit obeys the scissor test
        blit(self.raw, source, target.fbo, size, bool(description.colors), description.depth)
        return target

    # -- targets ------------------------------------------------------------------------
    def keep_target(self, description: Target) -> bool:
        """Keep the offscreen target of ``description`` from the last frame in this one, unchanged (False when
        it is gone: draw it again).  (A replayed frame releases no target: those a recorded frame kept stay.)"""
        return self.targets.keep(description, self.state.target_size)

    def _bind_target(self, description: Target) -> tuple:
        state = self.state
        target = self.targets.get(description, state.target_size)
        applier = state.applier
        saved = (applier.gl.framebuffer, state.target_size, state.linear_output)
        applier.bind(target.fbo, target.size)
        state.target_size = target.size
        state.linear_output = description.dtype != "f1"
        return saved

    def _unbind_target(self, saved: tuple) -> None:
        fbo, size, linear = saved
        state = self.state
        state.applier.bind(fbo, size)
        state.target_size = size
        state.linear_output = linear

    def _set_viewport(self, box: tuple[int, int, int, int]) -> tuple:
        """Draw into the pixel rectangle ``box`` (x, y from the bottom-left) of the bound target."""
        saved = (self.ctx.viewport, self.state.target_size)
        self.state.applier.viewport(box)
        self.state.target_size = (box[2], box[3])
        return saved

    def _restore_viewport(self, saved: tuple) -> None:
        self.state.applier.viewport(saved[0])
        self.state.target_size = saved[1]

    def _clear(self, clear: Any, box: tuple[int, int, int, int] | None = None) -> None:
        """A pass's ``Clear``: colour, depth and stencil of the bound target (every channel and bit; no scissor,
        or the clear's ``box``, or ``box`` when given)."""
        applier = self.state.applier
        fbo = applier.gl.framebuffer
        if box is None:
            box = clear.box  # None: the whole target
        if clear.color is None and clear.depth is not None and self.raw.available:
            # depth alone: moderngl's clear applies the framebuffer's own colour masks (a detected framebuffer's
            # clear colour would be lost), so clear only the depth buffer with a raw call
            applier.override({ScissorTest.index: box, DepthMask.index: True})
            clear_depth(self.raw, float(clear.depth), scissored=box is not None)
        elif clear.color is not None or clear.depth is not None:
            color = clear.color
            if color is not None and self.state.linear_output:
                from ...attributes.photometry import linear_rgb

                color = (*linear_rgb(color), color[3])
            writes = color is not None
            applier.override({ColorMask.index: (writes,) * 4, DepthMask.index: clear.depth is not None,
                              ScissorTest.index: None})  # fmt: skip
            depth = 1.0 if clear.depth is None else float(clear.depth)
            # moderngl clears a viewport rectangle (GL's bottom-left origin) under a scissor of its own
            area = None if box is None else (box[0], applier.gl.size[1] - box[1] - box[3], box[2], box[3])
            applier.clear(fbo, color or (0.0, 0.0, 0.0, 0.0), depth, clear.depth is not None, area)
        if clear.stencil is not None:
            ops = applier.value(StencilOp)
            applier.override({StencilOp.index: (*ops[:3], 0xFF), ScissorTest.index: box})  # glClear obeys both
            clear_stencil(self.raw, int(clear.stencil))

    # -- image-space passes --------------------------------------------------------------
    def _fullscreen(self, effect: FullScreen, composed: Composed) -> int:
        """Draw one full-screen triangle shaded by ``effect`` into the current target."""
        ctx = self.ctx
        programs: FullScreenPrograms = self.fullscreen_programs
        prog, vao = programs.get(effect, self.state.linear_output)
        unit = 0
        for uniform, name, attachment in effect.inputs:
            target = self.targets.named(name)
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
                self.drawer.texture(image, srgb=False).use(unit)
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
            u.value = tuple(float(v) for v in self.state.target_size)
        # the pass's GL state (a stencil test, a scissor, a colour mask), then what the triangle needs
        raster = list(composed.raster(defaults(), defaults()))
        raster[CullFace.index] = "none"
        raster[FillMode.index] = False
        raster[PolygonOffset.index] = None
        if effect.depth:
            raster[DepthTest.index] = effect.depth_test or "always"
            if not any(raster[ColorMask.index]):  # inside a depth-only pass a depth sprite still draws colour;
                raster[ColorMask.index] = (True, True, True, True)  # a pass's partial mask (an anaglyph eye) holds
            raster[DepthMask.index] = True
        else:
            raster[DepthTest.index] = None
            raster[DepthMask.index] = False
        raster[Blend.index] = _OVER if effect.blend else None
        applier = self.state.applier
        applier.apply(tuple(raster))
        applier.clip_planes(0)  # the triangle's vertex shader writes no clip distance
        vao.render(ctx.TRIANGLES, vertices=3)
        self.report.count(1, 0)
        return 1

    def _restore_defaults(self, fbo: Any = None, size: tuple[int, int] | None = None) -> None:
        """State preservation: leave the context as a plain moderngl user expects it, ``fbo`` bound."""
        applier = self.state.applier
        applier.restore_defaults()
        applier.bind(self.engine.framebuffer if fbo is None else fbo, self.engine.size if size is None else size)

    def release(self) -> None:
        if self.plan is not None and self.engine.programs.owner is self.plan:
            self.engine.programs.owner = None  # (a cache given by the caller outlives the engine)
        self.plan = None
        self.fullscreen_programs.release()
        for stage in self.stages:
            stage.release()
