"""Errors raised by engines and the scene graph."""

from __future__ import annotations

__all__ = ["OmnirenderError", "NoHandlerError", "EvaluationError"]


class OmnirenderError(Exception):
    """Base of omnirender's own errors."""


class NoHandlerError(OmnirenderError, LookupError):
    """No handler was found for a component, not even through simplification.

    A shape class without a default simplifier on purpose may say why, and which engines
    draw it, in a class attribute ``no_handler_hint`` (appended to the message).
    """

    def __init__(self, service: str, target: type, path: str = "", engine: str = "") -> None:
        self.service = service
        self.target = target
        self.path = path
        where = f" at node {path}" if path else ""
        on = f" on {engine}" if engine else ""
        super().__init__(
            f"no handler for service {service!r} and shape class {target.__name__}{where}{on}: "
            f"install a handler for ({service!r}, {target.__name__}) or a 'simplify' handler "
            f"for {target.__name__} (or one of its base classes), or create the engine with "
            f"on_missing='warn' or 'skip'" + (f" ({hint})" if (hint := getattr(target, "no_handler_hint", "")) else "")
        )


class EvaluationError(OmnirenderError, RuntimeError):
    """Misuse of the engine's state machine, such as an unbalanced pop."""
