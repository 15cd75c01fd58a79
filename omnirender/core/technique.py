"""Techniques: strategies that evaluate a sequence of components in passes.

A technique looks up and calls handlers for shapes and attributes (the
look-up of DESIGN.md: the service, then ``"simplify"``, then the parent class
along the MRO), and controls how often the sequence is evaluated: ``start``,
then for as long as ``needs_pass`` says so ``prepare_pass``, the evaluation,
``finish_pass`` and ``next_pass``; finally ``stop``.  A technique met inside a
node takes over the rest of that node's list, so nested techniques nest passes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .component import RenderingComponent

if TYPE_CHECKING:
    from .engine import Engine

__all__ = ["Technique"]


class Technique(RenderingComponent):
    """Evaluates components for a service, once per pass (one pass by default).

    ``service`` None means "the engine's service".  Subclasses override the
    pass-control methods for multi-pass effects, or ``handle_shape`` to
    intercept shapes (a transparency pass collects them instead of drawing).
    """

    __slots__ = ("service", "passes", "_pass")

    def __init__(self, service: str | None = None, passes: int = 1) -> None:
        super().__init__()
        if isinstance(passes, bool) or not isinstance(passes, int):
            raise ValueError(f"{type(self).__name__}: passes must be an integer >= 1, got {passes!r}")
        if passes < 1:
            raise ValueError(f"{type(self).__name__}: passes must be >= 1, got {passes}")
        object.__setattr__(self, "service", service)
        object.__setattr__(self, "passes", int(passes))
        object.__setattr__(self, "_pass", 0)

    # -- pass control -----------------------------------------------------
    @property
    def current_pass(self) -> int:
        """Index of the pass being evaluated (0-based)."""
        return self._pass

    def start(self, engine: Engine) -> None:
        """Called once before the first pass."""
        object.__setattr__(self, "_pass", 0)

    def needs_pass(self, engine: Engine) -> bool:
        """Whether another pass is needed."""
        return self._pass < self.passes

    def prepare_pass(self, engine: Engine) -> None:
        """Called before each pass (set state, bind targets)."""

    def finish_pass(self, engine: Engine) -> None:
        """Called after each pass (read back, merge)."""

    def next_pass(self, engine: Engine) -> None:
        """Advance to the next pass."""
        object.__setattr__(self, "_pass", self._pass + 1)

    def stop(self, engine: Engine) -> None:
        """Called once after the last pass."""

    def run(self, program: list[tuple[int, Any]], engine: Engine) -> None:
        """Evaluate a compiled component sequence once per pass."""
        self.start(engine)
        try:
            while self.needs_pass(engine):
                self.prepare_pass(engine)
                engine.run_program(program)
                self.finish_pass(engine)
                self.next_pass(engine)
        finally:
            self.stop(engine)

    # -- handler look-up --------------------------------------------------
    def handle_shape(self, shape: Any, engine: Engine) -> None:
        """Evaluate ``shape`` with its handler (painter, simplifier, or parent class's)."""
        fn = engine._shape_fns.get(shape.__class__)
        if fn is None:
            fn = engine._resolve_shape(shape.__class__)
        fn(shape, engine)

    def handle_attribute(self, attribute: Any, engine: Engine) -> Any:
        """The handler that applies ``attribute`` (painter or simplifier), or None for passive.

        Called on push/pop/add/remove.  Override it to apply attributes
        differently in this technique (e.g. ignore materials in a depth pass).
        """
        return engine.attribute_handler(attribute.__class__)
