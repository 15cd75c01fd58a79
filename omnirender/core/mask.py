"""Group-mask expressions: ``"!debug & (left | shared)"``.

A mask is evaluated against a node's set of group names.  Operators: ``!``
(not), ``&`` (and), ``|`` (or), parentheses; ``!`` binds tightest, then ``&``,
then ``|``.  Names are letters, digits, ``_``, ``-`` and ``.``.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from functools import lru_cache

__all__ = ["compile_mask", "MaskError"]

_TOKEN = re.compile(r"\s*(?:([A-Za-z0-9_.\-]+)|(.))")


class MaskError(ValueError):
    """A malformed mask expression; the message gives the position."""


@lru_cache(maxsize=256)
def compile_mask(expression: str) -> Callable[[frozenset[str] | set[str]], bool]:
    """Compile ``expression`` into a predicate over a set of group names."""
    if not isinstance(expression, str):
        raise MaskError(f"mask must be a string, got {type(expression).__name__}")
    tokens: list[tuple[str, str, int]] = []
    pos = 0
    while pos < len(expression):
        m = _TOKEN.match(expression, pos)
        if m is None:  # only trailing whitespace
            break
        name, op = m.group(1), m.group(2)
        start = m.start(1) if name else m.start(2)
        if name:
            tokens.append(("name", name, start))
        elif op is not None:
            if op not in "!&|()":
                raise MaskError(f"mask {expression!r}: unexpected character {op!r} at position {start}")
            tokens.append((op, op, start))
        pos = m.end()
    end = len(expression)
    index = 0

    def peek() -> tuple[str, str, int]:
        return tokens[index] if index < len(tokens) else ("end", "", end)

    def take(kind: str) -> tuple[str, str, int]:
        nonlocal index
        tok = peek()
        if tok[0] != kind:
            what = "end of expression" if tok[0] == "end" else repr(tok[1])
            raise MaskError(f"mask {expression!r}: expected {kind!r} but found {what} at position {tok[2]}")
        index += 1
        return tok

    def parse_or():
        left = parse_and()
        while peek()[0] == "|":
            take("|")
            right = parse_and()
            left = (lambda a, b: lambda g: a(g) or b(g))(left, right)
        return left

    def parse_and():
        left = parse_not()
        while peek()[0] == "&":
            take("&")
            right = parse_not()
            left = (lambda a, b: lambda g: a(g) and b(g))(left, right)
        return left

    def parse_not():
        kind, value, where = peek()
        if kind == "!":
            take("!")
            inner = parse_not()
            return lambda g: not inner(g)
        if kind == "(":
            take("(")
            inner = parse_or()
            take(")")
            return inner
        if kind == "name":
            take("name")
            return lambda g: value in g
        what = "end of expression" if kind == "end" else repr(value)
        raise MaskError(f"mask {expression!r}: expected a group name, '!' or '(' but found {what} at position {where}")

    if not tokens:
        raise MaskError(f"mask {expression!r}: empty expression at position 0")
    predicate = parse_or()
    if index != len(tokens):
        tok = tokens[index]
        raise MaskError(f"mask {expression!r}: unexpected {tok[1]!r} at position {tok[2]}")
    return predicate
