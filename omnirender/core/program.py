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
    for i, item in enumerate(items):
        if isinstance(item, Shape):
            append((EVAL, item))
        elif isinstance(item, MonoAttribute):
            append((PUSH, item))
            undo.append((POP, item))
        elif isinstance(item, PolyAttribute):
            append((ADD, item))
            undo.append((REMOVE, item))
        elif isinstance(item, Technique):
            rest: Program = []
            compile_components(items[i + 1 :], rest, where, inline)
            append((TECHNIQUE, (item, rest)))
            break
        elif isinstance(item, Handler):
            append((INSTALL, item))
            undo.append((DEINSTALL, item))
        elif hasattr(item, "_compile_node"):
            if inline:
                item._compile_node(program)
            else:
                append((NODE, item))
        elif isinstance(item, Attribute):
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
