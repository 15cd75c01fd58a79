"""Techniques: strategies that evaluate a sequence of components in passes.

A technique looks up and calls handlers for shapes and attributes (the
look-up of DESIGN.md: the service, then ``"simplify"``, then the parent class
along the MRO), and controls how often the sequence is evaluated: ``start``,
then for as long as ``needs_pass`` says so ``prepare_pass``, the evaluation,
``finish_pass`` and ``next_pass``; finally ``stop``.  ``prepare_pass`` may
decline its pass by returning ``False`` (the VRS protocol): that pass is
neither evaluated nor finished, and ``next_pass`` moves on
(:func:`pass_accepted` is the one rule every engine applies).  A technique met inside a
node takes over the rest of that node's list, so nested techniques nest passes.

Pass state lives in the engine, not in the technique: every run of a technique
gets a :class:`TechniqueFrame` on the engine's frame stack
(``engine.technique_frame``, ``engine.current_pass``), so one technique
instance shared by two nesting levels of a DAG runs its passes at each level
independently (3 x 3 = 9 passes, not 3).

A technique an engine cannot run (``supported(engine)`` is False) is ignored:
its scoped components are evaluated once with the enclosing technique (the
generalized scene graph's rule).  That is how POV-Ray and Mitsuba ignore GL
techniques.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .component import RenderingComponent

if TYPE_CHECKING:
    from .engine import Engine

__all__ = ["Technique", "TechniqueFrame", "pass_accepted"]


def pass_accepted(prepared: object) -> bool:
    """Whether a pass runs, given what ``prepare_pass`` returned: anything but ``False`` (None included)."""
    return prepared is not False


class TechniqueFrame:
    """One run of a technique on an engine: the technique, its pass index and scratch data.

    ``index`` is the pass being evaluated (0-based); ``data`` is a dict the
    technique may use for state that belongs to this run (a target made in
    ``start`` and released in ``stop``), never to the technique instance.
    """

    __slots__ = ("technique", "index", "data")

    def __init__(self, technique: Technique) -> None:
        self.technique = technique
        self.index = 0
        self.data: dict[str, Any] = {}

    def __repr__(self) -> str:
        return f"TechniqueFrame({type(self.technique).__name__}, pass {self.index})"


class Technique(RenderingComponent):
    """Evaluates components for a service, once per pass (one pass by default).

    ``service`` None means "the engine's service".  Subclasses override the
    pass-control methods for multi-pass effects, or ``handle_shape`` to
    intercept shapes (a transparency pass collects them instead of drawing).
    The pass being evaluated is ``engine.current_pass``.
    """

    __slots__ = ("service", "passes")

    def __init__(self, service: str | None = None, passes: int = 1) -> None:
        super().__init__()
        if isinstance(passes, bool) or not isinstance(passes, int):
            raise ValueError(f"{type(self).__name__}: passes must be an integer >= 1, got {passes!r}")
        if passes < 1:
            raise ValueError(f"{type(self).__name__}: passes must be >= 1, got {passes}")
        object.__setattr__(self, "service", service)
        object.__setattr__(self, "passes", int(passes))

    # -- validation -------------------------------------------------------
    def supported(self, engine: Engine) -> bool:
        """Whether ``engine`` can run this technique (else its scope is evaluated once without it)."""
        return True

    # -- pass control -----------------------------------------------------
    def start(self, engine: Engine) -> None:
        """Called once before the first pass (``engine.technique_frame`` is this run's frame)."""

    def needs_pass(self, engine: Engine) -> bool:
        """Whether another pass is needed."""
        return engine.current_pass < self.passes

    def prepare_pass(self, engine: Engine) -> bool | None:
        """Called before each pass (set state, bind targets); return ``False`` to skip this pass.

        A skipped pass is neither evaluated nor finished (``finish_pass`` is not
        called); ``next_pass`` still advances.  None (the default) runs it.
        """
        return None

    def finish_pass(self, engine: Engine) -> None:
        """Called after each pass (read back, merge)."""

    def next_pass(self, engine: Engine) -> None:
        """Advance to the next pass."""
        engine.technique_frame.index += 1

    def stop(self, engine: Engine) -> None:
        """Called once after the last pass."""

    def run(self, program: list[tuple[int, Any]], engine: Engine) -> None:
        """Evaluate a compiled component sequence once per pass, with this run's frame on the engine."""
        engine.enter_technique(self)
        try:
            self.start(engine)
            try:
                while self.needs_pass(engine):
                    if pass_accepted(self.prepare_pass(engine)):
                        engine.run_program(program)
                        self.finish_pass(engine)
                    self.next_pass(engine)
            finally:
                self.stop(engine)
        finally:
            engine.leave_technique(self)

    # -- handler look-up --------------------------------------------------
    def handle_shape(self, shape: Any, engine: Engine) -> None:
        """Evaluate ``shape`` with its handler (painter, simplifier, or parent class's)."""
        engine.shape_handler(shape.__class__)(shape, engine)

    def handle_attribute(self, attribute: Any, engine: Engine) -> Any:
        """The handler that applies ``attribute`` (painter or simplifier), or None for passive.

        Called on push/pop/add/remove.  Override it to apply attributes
        differently in this technique (e.g. ignore materials in a depth pass).
        """
        return engine.attribute_handler(attribute.__class__)
