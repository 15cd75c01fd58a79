"""The frame plan: a steady frame recorded once and replayed while the change tracker reports no change.

A frame that changed nothing issues the same GL calls as the frame before
it: the same programs, uniform values, GL state and draw calls.  Running the
stages, techniques, passes and drawer in Python again to find them out is
what a steady frame costs (issue 22: the fixed per-frame cost).  So the frame
runner records, while it draws a frame, what the drawer issues
(:class:`FrameRecorder`): per draw call the raster tuple and clip distances
given to the applier, the textures bound, every uniform written (through
:class:`RecordingProgram`) and the vertex array, mode and instance count.
The next frame replays that list (:class:`FramePlan`) as long as its
:class:`PlanKey` is the same:

* the change tracker's own signals: the frame runner's ``generation`` (bumped
  by every ``placements_changed``: an install, a splice, moved rows, updated
  instance sets) and the installer's draw-list version;
* the pre-evaluated declarations (lights, camera; a new object whenever the
  scene is pre-evaluated again), the view and projection of the frame, the
  clear colour, the target (framebuffer and size);
* the engine's settings a frame reads: technique, frame technique, stereo,
  shadows, the stage list.

A frame is recorded only when everything it does is a plain draw the
recorder sees.  Anything else *taints* the recording and the frame keeps no
plan: a technique or stage that does not declare itself replayable (an
application's technique may change its passes every frame), a pass with its
own target, viewport, camera, clear, front face, full-screen or custom
function, draw-item kinds with drawers of their own (text, volumes),
transparent items (sorted by the view every frame), shadow maps drawn (a
frame whose shadow stage kept every face of the atlas is recorded: the atlas
bind and the shadow uniforms are draws' textures and writes like others),
area lights' tables, render textures, pass inputs, tessellated patches, GL state set from
outside the drawer (``apply_gl_state`` and the other public state calls),
timer queries.

Uniforms: a program keeps its uniform values between frames, so a replay
writes only the values that differ from what the program holds at that point
of the frame (the values the frame itself wrote last: a program drawn once
per frame with the same camera gets no write at all).  That holds while no
other code wrote the programs since: the :class:`ProgramCache`'s ``owner``
says which plan wrote them last; every frame that is not a replay (of any
engine sharing the cache) and every ``ProgramCache.get`` clears it, and a
replay then writes every recorded value.
"""

from __future__ import annotations

from typing import Any

from .state import defaults, kinds

__all__ = ["FramePlan", "FrameRecorder", "PlanKey", "RecordingProgram", "DrawOp", "RecordedPass"]


class PlanKey:
    """What a frame's plan depends on: objects by identity, values by equality, compared as one tuple.

    The objects are held (``objects``) while the key lives, so their ids in ``values`` name them alone.
    """

    __slots__ = ("objects", "values")

    def __init__(self, objects: tuple[Any, ...], values: tuple[Any, ...]) -> None:
        self.objects = objects
        self.values = (*map(id, objects), *values)

    def matches(self, other: PlanKey) -> bool:
        return self.values == other.values


class DrawOp:
    """One recorded draw call: GL state, textures, uniform writes, then ``vao.render(mode, instances=n)``."""

    __slots__ = ("raster", "clip", "textures", "writes", "needed", "vao", "mode", "n", "changes", "batch")

    def __init__(self) -> None:
        self.raster: tuple[Any, ...] = ()
        self.clip = 0
        #: (texture, unit) bound for the draw
        self.textures: list[tuple[Any, int]] = []
        #: (uniform, value, raw): ``uniform.write(value)`` when raw, else ``uniform.value = value``
        self.writes: list[tuple[Any, Any, bool]] = []
        #: the writes whose value differs from what the program holds at this point of a replayed frame
        self.needed: list[tuple[Any, Any, bool]] = []
        self.vao: Any = None
        self.mode = 0
        self.n = 0
        #: (apply, value) of the state kinds whose value differs from the draw before (the first: from the
        #: defaults a frame begins with)
        self.changes: list[tuple[Any, Any]] = []
        #: the batch drawn (None: not said)
        self.batch: Any = None


class RecordingUniform:
    """A program's uniform that records what is written into it (and writes it)."""

    __slots__ = ("uniform", "op")

    def __init__(self, uniform: Any, op: DrawOp) -> None:
        self.uniform = uniform
        self.op = op

    def write(self, data: Any) -> None:
        data = bytes(data)
        self.uniform.write(data)
        self.op.writes.append((self.uniform, data, True))

    @property
    def value(self) -> Any:
        return self.uniform.value

    @value.setter
    def value(self, value: Any) -> None:
        self.uniform.value = value
        self.op.writes.append((self.uniform, value, False))

    def __getattr__(self, name: str) -> Any:  # array_length, dimension, ...
        return getattr(self.uniform, name)


class RecordingProgram:
    """A moderngl program seen through the recorder: its uniforms record their writes into ``op``."""

    __slots__ = ("program", "op")

    def __init__(self, program: Any, op: DrawOp) -> None:
        self.program = program
        self.op = op

    def get(self, name: str, default: Any = None) -> Any:
        u = self.program.get(name, None)
        return default if u is None else RecordingUniform(u, self.op)

    def __getitem__(self, name: str) -> RecordingUniform:
        return RecordingUniform(self.program[name], self.op)

    def __getattr__(self, name: str) -> Any:  # ctx, ...
        return getattr(self.program, name)


class FrameRecorder:
    """Collects a frame's draw calls while it is drawn; ``taint(why)`` when the frame does what it cannot replay."""

    __slots__ = ("ops", "tainted", "_op", "draws_only", "passes")

    def __init__(self, draws_only: bool = False) -> None:
        self.ops: list[DrawOp] = []
        #: why this frame cannot be replayed (None: it can)
        self.tainted: str | None = None
        self._op: DrawOp | None = None
        #: only the draws are recorded: the passes' own targets, viewports, cameras and clears, and whether
        #: their techniques replay, are the caller's (``FrameRunner.run_recorded``)
        self.draws_only = draws_only
        #: the pass descriptions executed while it recorded (kept only when ``draws_only``)
        self.passes: list[Any] = []

    def taint(self, why: str) -> None:
        if self.tainted is None:
            self.tainted = why

    def begin_draw(self, program: Any) -> RecordingProgram:
        """A draw starts: ``program`` as the drawer writes its uniforms."""
        op = self._op = DrawOp()
        return RecordingProgram(program, op)

    def texture(self, texture: Any, unit: int) -> None:
        """The draw being recorded binds ``texture`` to ``unit``."""
        if self._op is None:
            self.taint("a texture bound outside a draw")
            return
        self._op.textures.append((texture, unit))

    def end_draw(self, raster: tuple[Any, ...], clip: int, vao: Any, mode: int, n: int, batch: Any = None) -> None:
        """The draw call of ``batch`` was issued with ``raster`` applied and ``clip`` clip distances."""
        op = self._op
        if op is None:
            self.taint("a draw the recorder did not see start")
            return
        op.raster, op.clip, op.vao, op.mode, op.n, op.batch = raster, clip, vao, mode, n, batch
        self.ops.append(op)
        self._op = None

    def plan(self, key: PlanKey, stats: dict[str, Any]) -> FramePlan | None:
        """The recorded frame as a plan (None when it was tainted)."""
        if self.tainted is not None or self._op is not None:
            return None
        return FramePlan(key, self.ops, stats)


def _same(a: Any, b: Any) -> bool:
    """Whether two recorded uniform values are certainly equal (bytes, numbers, tuples of numbers)."""
    if a is b:
        return True
    if type(a) is not type(b) or not isinstance(a, (bytes, int, float, tuple, bool)):
        return False
    try:
        return bool(a == b)
    except (TypeError, ValueError):
        return False


class FramePlan:
    """A recorded steady frame: its draw operations in order and the stats it reported."""

    __slots__ = ("key", "ops", "stats", "back")

    def __init__(self, key: PlanKey, ops: list[DrawOp], stats: dict[str, Any]) -> None:
        self.key = key
        self.ops = ops
        #: draw_calls, passes, batches, items of the recorded frame
        self.stats = stats
        # what each uniform holds after the frame: the last value written to it
        held: dict[int, tuple[Any, bool]] = {}
        for op in ops:
            for uniform, value, raw in op.writes:
                held[id(uniform)] = (value, raw)
        # a replayed frame starts from there: a write is needed where the value differs from the one held
        # GL state: a frame begins with every kind at its default (RasterApplier.begin), then each draw's
        # raster is applied by difference (RasterApplier.apply): the differences are the same every replay
        current = defaults()
        all_kinds = kinds()
        for op in ops:
            op.changes = [(all_kinds[i].apply, value) for i, (value, held_now) in
                          enumerate(zip(op.raster, current, strict=False)) if held_now != value]  # fmt: skip
            current = op.raster[: len(current)] + current[len(op.raster) :]
        #: (apply, default) of the kinds the last draw leaves away from their defaults: a frame ends at them
        self.back = [(all_kinds[i].apply, value) for i, (value, held_now) in
                     enumerate(zip(defaults(), current, strict=False)) if held_now != value]  # fmt: skip
        for op in ops:
            needed = []
            for uniform, value, raw in op.writes:
                last = held.get(id(uniform))
                if last is None or last[1] != raw or not _same(last[0], value):
                    needed.append((uniform, value, raw))
                    held[id(uniform)] = (value, raw)
            op.needed = needed

    def replay(self, applier: Any, full: bool) -> None:
        """Issue the recorded draws (every recorded uniform write when ``full``, else only the needed ones)
        after ``applier`` began the frame (every kind at its default), then every kind at its default again
        and no clip distance (what the frame leaves GL with)."""
        gl, clip_planes = applier.gl, applier.clip_planes
        for op in self.ops:
            for apply, value in op.changes:
                apply(gl, value)
            clip_planes(op.clip)
            for texture, unit in op.textures:
                texture.use(unit)
            for uniform, value, raw in op.writes if full else op.needed:
                if raw:
                    uniform.write(value)
                else:
                    uniform.value = value
            op.vao.render(op.mode, instances=op.n)
        for apply, value in self.back:
            apply(gl, value)
        applier.current = list(defaults())
        clip_planes(0)


class RecordedPass:
    """The draws of one pass, recorded (``FrameRunner.run_recorded``) to be issued again by
    ``FrameRunner.replay_draws`` under another scissor box: the pass's description, its draw operations and,
    per operation, what its batch's draw depended on (``BatchDrawer.redraw_key``)."""

    __slots__ = ("description", "ops", "keys", "batches", "uniforms")

    def __init__(self, description: Any, ops: list[DrawOp], keys: list[tuple[Any, ...]]) -> None:
        self.description = description
        self.ops = ops
        self.keys = keys
        #: the batches drawn, in order
        self.batches = [op.batch for op in ops]
        #: ids of the uniforms the draws write (held alive by ``ops``)
        self.uniforms = {id(uniform) for op in ops for uniform, _, _ in op.writes}
