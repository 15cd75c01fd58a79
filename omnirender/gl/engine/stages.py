"""The frame as a list of stages.

A frame runs its stages in order (``engine.stages``; the engine facade makes
the default list): each stage's :meth:`FrameStage.prepare` first, before the
frame's target is bound (a stage that draws other targets, e.g. the chained
pipelines' render textures, does it there), then, with the target bound,
cleared and the frame's camera set, each stage's :meth:`FrameStage.draw`.

The default stages, in order:

=================  ======================================================================
``pipelines``      render textures the frame reads (chained pipelines), in dependency order
``shadow maps``    the shadow-map atlas of the lights that cast shadows (``techniques/shadows.py``)
``technique``      the frame technique over the scene (``Forward``, or the deferred pipeline),
                   inside a frame-level post-processing chain when the scene has one
``mirrors``        the planar mirrors' stencil passes (``techniques/mirrors.py``)
``stereo``         both eyes of an ``om.gl.Stereo`` frame (instead of ``technique``)
=================  ======================================================================

A user stage subclasses :class:`FrameStage` and joins with
``engine.add_stage(stage, before="mirrors")`` (or ``after=``); it draws with
``frame.run(technique, root)``, so its passes are recorded in
``engine.stats["passes"]`` like every other.
"""

from __future__ import annotations

from typing import Any

from .drawlist import Scope
from .passes import Composed

__all__ = ["FrameStage", "PipelinesStage", "TechniqueStage", "StageList"]


class FrameStage:
    """One stage of every frame.  Subclasses override :meth:`draw` (and :meth:`prepare`, :meth:`changed`)."""

    #: the stage's name in ``engine.stages`` (``add_stage(before=..., after=...)`` refers to it)
    name = "stage"

    def prepare(self, engine: Any) -> None:
        """Before the frame's target is bound: draw into other targets here (nothing by default)."""

    def draw(self, frame: Any, root: Scope) -> int:
        """Draw this stage into the frame; returns the draw calls made.

        ``frame`` is the engine's :class:`~.frame.FrameRunner` (``frame.engine`` the engine,
        ``frame.run(technique, scope)`` runs a technique's passes, ``frame.state`` what the pass
        sees); ``root`` the installed root scope (empty before anything was compiled).
        """
        return 0

    def changed(self) -> None:
        """The installed draw list changed or items moved (stages caching what depends on placement
        forget it here)."""

    def replayable(self, engine: Any) -> bool:
        """Whether a frame that changed nothing may replay what this stage drew in the frame before instead
        of calling :meth:`draw` (the frame plan, :mod:`.plan`).

        True only when what the stage draws depends on nothing but what the engine's change tracker follows
        (the draw list, placements, camera, lights, the engine's settings) and it draws only through
        ``frame.run``.  False by default: a stage of the application may draw something else every frame.
        """
        return False

    def follows_rows(self, engine: Any) -> bool:
        """Whether what this stage drew in a recorded frame is still right after rows moved in place (items'
        model matrices only; nothing added or removed) once the moved rows are uploaded: nothing it draws
        or writes depends on where items are.  Then the next frame replays the plan after uploading them
        instead of drawing in full.  False by default (the frame is drawn in full after any move)."""
        return False

    def follow_rows(self, frame: Any, root: Scope, plan: Any) -> bool:
        """Rows moved in place and the recorded frame ``plan`` is about to be replayed (every stage said it
        :meth:`follows_rows`): draw here what this stage keeps up to date with rows, into its own targets
        (e.g. the regions of the shadow maps the moved casters cover), and return whether the plan's draws
        still hold (what the stage hands the frame's passes, its uniforms and textures, is what the plan
        recorded); False draws the frame in full.  A stage that overrides nothing is not called.  The frame
        runner then binds the frame's target again with every GL state at its default."""
        return True

    def follows_plan(self, plan: Any) -> bool:
        """Whether :meth:`follow_rows` has anything to draw before ``plan`` is replayed (True by default); a
        stage saying False is not called, and when none says True the frame is replayed without binding its
        target again or writing every uniform (e.g. shadow maps the recorded frame did not draw).  Asked once
        per recorded plan: the answer must depend on the plan only."""
        return True

    def release(self) -> None:
        """The engine is released: free what the stage holds on the GPU."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r})"


class PipelinesStage(FrameStage):
    """The chained pipelines: render textures the frame reads, drawn first by their own engines."""

    name = "pipelines"

    def prepare(self, engine: Any) -> None:
        engine.prepare_pipelines()  # their engines use the context: before the frame binds its target

    def replayable(self, engine: Any) -> bool:
        return True  # it draws in prepare (called in replayed frames too); a render texture read taints

    def follows_rows(self, engine: Any) -> bool:
        return True  # render textures are drawn by their own engines


class TechniqueStage(FrameStage):
    """The frame technique over the scene (in a frame-level post-processing chain when the scene has one);
    nothing in stereo frames (the ``stereo`` stage draws both eyes)."""

    name = "technique"

    def draw(self, frame: Any, root: Scope) -> int:
        if frame.engine.stereo is not None:
            return 0
        return frame.run_frame_level(root, Composed())  # e.g. a post-processing chain around the pipeline

    def replayable(self, engine: Any) -> bool:
        return True  # the techniques it runs say whether they are

    def follows_rows(self, engine: Any) -> bool:
        return True  # recorded passes draw batches, whose rows carry the model matrices


class StageList:
    """The ordered stages of an engine's frames, with insertion by name."""

    def __init__(self, stages: list[FrameStage]) -> None:
        self._stages = list(stages)
        self._tuple: tuple[FrameStage, ...] | None = None

    def __iter__(self) -> Any:
        return iter(self.frozen())

    def frozen(self) -> tuple[FrameStage, ...]:
        """The stages in order as a tuple: the same object until a stage is added or removed."""
        if self._tuple is None:
            self._tuple = tuple(self._stages)
        return self._tuple

    def __len__(self) -> int:
        return len(self._stages)

    def __getitem__(self, index: int) -> FrameStage:
        return self._stages[index]

    def names(self) -> list[str]:
        """The stages' names in frame order."""
        return [stage.name for stage in self._stages]

    def add(self, stage: FrameStage, before: str | None = None, after: str | None = None) -> None:
        """Insert ``stage`` before or after the stage named so (at the end without either)."""
        if not isinstance(stage, FrameStage):
            raise TypeError(f"GLEngine.add_stage needs an om.gl.FrameStage, got {stage!r:.60}")
        if before is not None and after is not None:
            raise ValueError("GLEngine.add_stage: give before= or after=, not both")
        if stage in self._stages:
            raise ValueError(f"GLEngine.add_stage: {stage!r} is already a stage of this engine")
        anchor = before if before is not None else after
        self._tuple = None
        if anchor is None:
            self._stages.append(stage)
            return
        names = self.names()
        if anchor not in names:
            raise ValueError(f"GLEngine.add_stage: no stage named {anchor!r} (stages: {names})")
        index = names.index(anchor) + (0 if before is not None else 1)
        self._stages.insert(index, stage)

    def remove(self, stage: FrameStage | str) -> FrameStage:
        """Take ``stage`` (or the stage of that name) out of the frame; returns it."""
        for found in self._stages:
            if found is stage or found.name == stage:
                self._stages.remove(found)
                self._tuple = None
                return found
        raise ValueError(f"GLEngine.remove_stage: no stage {stage!r} (stages: {self.names()})")
