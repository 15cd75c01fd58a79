"""Compiled micro programs: a component sequence as a flat list of engine ops.

A node's contents compile once (per version) into ``(opcode, argument)``
pairs: push/pop, add/remove, install/deinstall, eval, and node enter/leave.
Child nodes without group tags are inlined, so evaluating a whole subtree is one
flat loop with precomputed dispatch and no per-component allocation.  A
*local* program (``inline=False``) keeps every child as one ``NODE`` op
instead: engines that cache per node (the GL compiler) evaluate those.

The opcodes are named constants; :data:`OPCODE_NAMES` gives their names in
order, so an engine's dispatch table is built by name, never by position.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from .component import Attribute, MonoAttribute, PolyAttribute, Shape
from .handler import Handler
from .technique import Technique

__all__ = [
    "PUSH",
    "POP",
    "ADD",
    "REMOVE",
    "INSTALL",
    "DEINSTALL",
    "EVAL",
    "ENTER",
    "LEAVE",
    "NODE",
    "TECHNIQUE",
    "OPCODE_NAMES",
    "compile_components",
]

PUSH, POP, ADD, REMOVE, INSTALL, DEINSTALL, EVAL, ENTER, LEAVE, NODE, TECHNIQUE = range(11)
#: Names of the opcodes, indexed by opcode (``OPCODE_NAMES[EVAL] == "eval"``).
OPCODE_NAMES = ("push", "pop", "add", "remove", "install", "deinstall", "eval", "enter", "leave", "node", "technique")

Program = list[tuple[int, Any]]


_SHAPE, _MONO, _POLY, _TECHNIQUE, _HANDLER, _NODE, _ATTRIBUTE, _OTHER = range(8)
_KINDS: dict[type, int] = {}


def _kind(cls: type) -> int:
    """What a class of item compiles to (cached per class: compiling is a dict look-up per item)."""
    kind = _KINDS.get(cls)
    if kind is None:
        if issubclass(cls, Shape):
            kind = _SHAPE
        elif issubclass(cls, MonoAttribute):
            kind = _MONO
        elif issubclass(cls, PolyAttribute):
            kind = _POLY
        elif issubclass(cls, Technique):
            kind = _TECHNIQUE
        elif issubclass(cls, Handler):
            kind = _HANDLER
        elif hasattr(cls, "_compile_node"):
            kind = _NODE
        elif issubclass(cls, Attribute):
            kind = _ATTRIBUTE
        else:
            kind = _OTHER
        _KINDS[cls] = kind
    return kind


def compile_components(items: Iterable[Any], program: Program, where: Any = "", inline: bool = True) -> Program:
    """Append the ops that evaluate ``items`` in order and then undo them.

    A technique among the items takes the rest of the sequence as its own
    program (evaluated once per pass); the items before it are undone after it.
    ``where`` (a string or an object whose ``str`` is one, computed only on
    error) says where the items come from in error messages.  ``inline=False``
    compiles child nodes to single ``NODE`` ops instead of inlining their
    programs.
    """
    items = list(items)
    undo: list[tuple[int, Any]] = []
    append = program.append
    kinds = _KINDS
    for i, item in enumerate(items):
        kind = kinds.get(item.__class__)
        if kind is None:
            kind = _kind(item.__class__)
        if kind == _NODE:
            if inline:
                item._compile_node(program)
            else:
                append((NODE, item))
        elif kind == _SHAPE:
            append((EVAL, item))
        elif kind == _MONO:
            append((PUSH, item))
            undo.append((POP, item))
        elif kind == _POLY:
            append((ADD, item))
            undo.append((REMOVE, item))
        elif kind == _TECHNIQUE:
            rest: Program = []
            compile_components(items[i + 1 :], rest, where, inline)
            append((TECHNIQUE, (item, rest)))
            break
        elif kind == _HANDLER:
            append((INSTALL, item))
            undo.append((DEINSTALL, item))
        elif kind == _ATTRIBUTE:
            raise TypeError(
                f"{type(item).__name__}{where}: an attribute must derive from MonoAttribute or PolyAttribute"
            )
        else:
            raise TypeError(
                f"cannot evaluate {type(item).__name__}{where}: expected a Shape, Attribute, Handler, Technique or Node"
            )
    undo.reverse()
    program.extend(undo)
    return program
