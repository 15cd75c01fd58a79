"""Dirty bits for attributes replaced by attributes of the same role: no subtree compile, rows patched in place.

OpenUSD Hydra's ``HdChangeTracker`` marks what changed on a prim as dirty
bits (transform, primvars, topology...) and a sync rewrites only that.  A
node's list edits of one frame (``node.remove(t); node.insert(0, om.Matrix(m))``)
are classified here the same way: when, after all of them, the node holds the
same list as when it was compiled except that some entries were replaced by
components of the same *role*, each replacement is a dirty bit on the node's
draw items instead of a topology change:

* :data:`DIRTY_TRANSFORM`: a static transform replaced by a static transform
  (any kinds: ``Translation`` -> ``Matrix``, ``Matrix`` -> ``Rotation``).  The
  items below it (the node's and its descendants') take the new transform at
  the old one's place in their chains (:attr:`~.drawlist.DrawItem.chain`, so a
  chain of several transforms keeps its order) and their rows are recomposed
  like moved transforms' (:mod:`.dynamic`).  Declined (the subtree compile
  runs) where the compile read the matrix for more than the model matrix:
  clip planes, a technique's scope (levels of detail), instance sets, or a
  mirroring change of the face culling (the determinants' signs differ).
* :data:`DIRTY_APPEARANCE`: a ``Material`` / ``PBRMaterial`` replaced by one
  of either, or a ``Color`` by a ``Color``.  Each item whose resolved surface
  the old one decided (:attr:`~.drawlist.DrawItem.surface`: the material or
  colour of its appearance) is resolved again with the new one in the same
  context (textures, highlight, material description), and its row's surface
  fields are written in place.  Declined where the new surface would choose
  another draw state: other textures or program features, another shading
  model, one- or two-sided, or opaque <-> transparent (a Material whose
  opacity falls below 1 goes to the transparent items through the splice).

Anything else - a kind added or removed, a role changed, state attributes,
techniques, shapes, lights, clip planes, child nodes - is not classified
(:func:`classify` returns None) and keeps the subtree compile + splice path.
Nothing is modified before every replacement of the frame is known to be
handled.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from ...attributes import Color, Material, PBRMaterial
from ...core.transform import Rotation, Transform, Translation
from ...scene.node import Node
from .attributes import AlphaTest, Blend
from .drawlist import DrawItem, drawn_transparent, uniform_material
from .layout import ROW, shading_model

__all__ = [
    "DIRTY_TRANSFORM",
    "DIRTY_APPEARANCE",
    "Replacement",
    "Restyle",
    "classify",
    "role",
    "transform_swaps",
    "restyles",
    "restyle",
]

#: a static transform replaced by a static transform: the rows below it are recomposed
DIRTY_TRANSFORM = "transform"
#: a surface attribute replaced by one of the same role: the rows' surface fields are resolved again
DIRTY_APPEARANCE = "appearance"

#: the row's surface fields (all between the model matrix and the point size, which a DrawStyle decides)
_SURFACE = slice(ROW.offsets["color"], ROW.offsets["point"])
#: those a batch drawn with uniforms for its material shares (its colours are per row)
_MATERIAL = slice(ROW.offsets["color"] + 4, ROW.offsets["point"])
_HIGHLIGHT_ON = ROW.at("highlight", "on")
assert [f.name for f in ROW.fields[:2]] == ["model", "color"] and ROW.fields[-1].name == "point"
#: draw kinds whose draw state the compiler makes from the surface alone (a painter's own kinds decline)
_KINDS = frozenset(("mesh", "points", "lines"))


class Replacement(NamedTuple):
    """``old`` at a place of ``node``'s list was replaced by ``new`` of the same role (``kind``: a dirty bit);
    ``entry``: what the compile made of the node (its ``own`` items as compiled and the ``entries`` it made,
    its descendants' included, nested scopes as they are)."""

    node: Any
    old: Any
    new: Any
    kind: str
    entry: Any


class Restyle(NamedTuple):
    """An item's new surface: the compiler's resolved ``surface`` entry and ``row``, the row whose surface fields
    the item's row takes (its model matrix and point size stay)."""

    item: DrawItem
    surface: tuple
    row: np.ndarray


def role(component: Any) -> str | None:
    """The role a replacement must keep: ``"transform"`` (static transforms), ``"material"``, ``"color"``, or
    None (anything else: its replacement is a topology change)."""
    cls = component.__class__
    found = _ROLES.get(cls, _UNKNOWN)
    if found is _UNKNOWN:
        found = _ROLES[cls] = _role_of(cls)
    return found


def _role_of(cls: type) -> str | None:
    if issubclass(cls, Transform):
        return DIRTY_TRANSFORM if cls.static else None
    if issubclass(cls, (Material, PBRMaterial)):
        return "material"
    if issubclass(cls, Color):
        return "color"
    return None


#: class -> its role (:func:`role`), asked once per class
_ROLES: dict[type, str | None] = {}
_UNKNOWN = object()


def classify(edits: list[tuple[Any, str, Any, int]], compiled: Callable[[Any], Any]) -> list[Replacement] | None:
    """The frame's list ``edits`` as same-role replacements, or None when they change anything else.

    ``compiled(node)`` gives what the compile made of ``node`` (None: not
    compiled once, or its entry is gone): its ``own`` items as they were
    compiled (each a child node or a ``(component, version)`` pair) and the
    ``entries`` it made.  The node's list now must hold as many items, each
    the same object or one of the same :func:`role`.  An empty list: the
    edits left every list as it was.
    """
    if len(edits) == 2:
        single = _single(edits, compiled)
        if single is not _UNKNOWN:
            return single
    nodes: dict[int, Any] = {}
    for container, op, item, _ in edits:
        if (op != "insert" and op != "remove") or isinstance(item, Node) or not isinstance(container, Node):
            return None
        nodes[id(container)] = container
    out: list[Replacement] = []
    for node in nodes.values():
        entry = compiled(node)
        if entry is None:
            return None
        before = entry.own
        after = node.items
        if len(before) != len(after):
            return None
        for held, new in zip(before, after, strict=True):
            old = held[0] if held.__class__ is tuple else held  # (a child node is held as itself)
            if old is new:
                continue
            kind = role(old)
            if kind is None or kind != role(new):
                return None
            out.append(
                Replacement(node, old, new, DIRTY_TRANSFORM if kind == DIRTY_TRANSFORM else DIRTY_APPEARANCE, entry)
            )
    return out


def _single(edits: list[tuple[Any, str, Any, int]], compiled: Callable[[Any], Any]) -> Any:
    """:func:`classify` of what applications write to replace one item, ``node.remove(old)`` then
    ``node.insert(at, new)`` at its place: the node's list is its compiled list with ``new`` at ``at`` (the
    edits since the compile say so), so only that place is compared.  ``_UNKNOWN`` for other edits."""
    (node, op, old, at), (other, op2, new, at2) = edits
    if other is not node or op != "remove" or op2 != "insert" or at != at2 or node.__class__ is not Node:
        return _UNKNOWN
    if old is new or isinstance(old, Node) or isinstance(new, Node):
        return _UNKNOWN
    entry = compiled(node)
    if entry is None:
        return None
    own = entry.own
    held = own[at] if at < len(own) else None
    if held is None or held.__class__ is not tuple or held[0] is not old:
        return _UNKNOWN  # (the compiled list is not the one the edits started from: compared in full)
    kind = role(old)
    if kind is None or kind != role(new):
        return None
    return [Replacement(node, old, new, DIRTY_TRANSFORM if kind == DIRTY_TRANSFORM else DIRTY_APPEARANCE, entry)]


def _det_sign(t: Any) -> int:
    """The sign of the determinant of ``t``'s matrix (a translation's and a rotation's: 1, unasked)."""
    if t.__class__ is Translation or t.__class__ is Rotation:
        return 1
    (a, b, c, _), (d, e, f, _), (g, h, i, _), _ = t.matrix.tolist()
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return (det > 0.0) - (det < 0.0)


def transform_swaps(replacements: list[Replacement]) -> list[tuple[DrawItem, Any, Any]] | None:
    """``(item, old, new)`` for every draw item whose chain holds a replaced transform, or None to decline.

    The node's compiled entries are its items and its descendants'; items
    whose chain does not hold ``old`` (shapes before it in the list) are not
    below it.
    """
    out: list[tuple[DrawItem, Any, Any]] = []
    for _, old, new, kind, entry in replacements:
        if kind != DIRTY_TRANSFORM:
            continue
        if _det_sign(old) != _det_sign(new):
            return None  # mirrored now (or no more): the culled faces change
        for item in entry.entries:
            if item.__class__ is not DrawItem and not isinstance(item, DrawItem):
                return None  # a technique's scope (a level of detail keeps the chain above it)
            count = 0
            for t in item.chain:
                if t is old:
                    count += 1
            if not count:
                continue
            if count > 1 or item.instances is not None or item.state.clip or item.techniques:
                return None
            out.append((item, old, new))
    return out


def _same_texture_set(a: Any, b: Any) -> bool:
    return a is b or a.key == b.key


def restyles(
    replacements: list[Replacement], surface_entry: Callable[[list[Any], tuple], tuple]
) -> list[Restyle] | None:
    """The new surface of every draw item a replaced Material / PBRMaterial / Color decided, or None to
    decline (an item whose surface is not known, or whose draw state the new surface would change)."""
    pairs: dict[int, list[Any]] = {}  # id(item) -> [item, material, colour] after the replacements so far
    for _, old, new, kind, entry in replacements:
        if kind != DIRTY_APPEARANCE:
            continue
        for item in entry.entries:
            if not isinstance(item, DrawItem) or item.surface is None or item.instances is not None or item.techniques:
                return None  # (a technique's passes may draw what the surface decides their own way)
            pair = pairs.get(id(item))
            if pair is None:
                app = item.surface[0]
                pair = [item, app.material, app.color]
            if pair[1] is old:
                pair[1] = new
            elif pair[2] is old:
                pair[2] = new
            else:
                continue  # an inner material or colour decides this item's surface
            pairs[id(item)] = pair
    out: list[Restyle] = []
    for item, material, color in pairs.values():
        app, _, texset, context = item.surface
        stack = [x for x in (material, color) if x is not None]
        entry = surface_entry(stack, context)
        new_app, row, new_texset, _ = entry
        state = item.state
        if (
            state.kind not in _KINDS
            or state.overlay
            # (an item's row holds the shading model of the surface entry it was made from: both entries are
            # of the item's context, its material description included)
            or shading_model(new_app.model, context[4]) != shading_model(app.model, context[4])
            or new_app.double_sided != app.double_sided
            or not _same_texture_set(new_texset, texset)
            or _transparent(new_app, item) != item.transparent
        ):
            return None
        out.append(Restyle(item, entry, row))
    return out


def _transparent(app: Any, item: DrawItem) -> bool:
    """Whether the compile would draw ``item`` with ``app`` as a transparent item (its state decides the rest)."""
    state = item.state
    return drawn_transparent(app, item.geometry, state.value(Blend) is not None, state.value(AlphaTest) is not None)


def restyle(changes: list[Restyle]) -> tuple[list[Any], bool]:
    """Write the new rows: ``(batches whose rows changed, whether they draw as before)``.

    False when a batch drawn with its material as uniforms (``Batch.uniform``)
    got a row of another material, or an item outside batches changed (drawn
    in full): the frame must be drawn in full, not replayed.
    """
    batches: dict[int, Any] = {}
    same = True
    for item, surface, row in changes:
        item.surface = surface
        slot = item.slot
        if slot is None:
            item.row[_SURFACE] = row[_SURFACE]
            same = False
            continue
        batch, r = slot
        highlight = float(item.row[_HIGHLIGHT_ON]) != float(row[_HIGHLIGHT_ON])
        if batch.uniform and item.row[_MATERIAL].tobytes() != row[_MATERIAL].tobytes():
            same = False
            item.row[_SURFACE] = row[_SURFACE]
            batch.uniform = uniform_material(batch.rows)
        else:
            item.row[_SURFACE] = row[_SURFACE]
        batch.row_restyled(r, highlight)  # (whether some row is highlighted is kept unless this one's changed)
        batches[id(batch)] = batch
    return list(batches.values()), same
