"""Immutable scene snapshots for render threads (guacamole's app/render decoupling).

At the end of an application frame, :meth:`Snapshotter.take` makes a
:class:`Snapshot`: a tree of :class:`SnapNode` (one per node occurrence) that
holds frozen copies of the components, the world matrix at the end of each
node (its transforms composed with its parents') and each subtree's world
bounds.  Nothing in it changes afterwards, so render threads can read it
while the application goes on changing the scene.

Snapshots are cheap because they are incremental, on core's version
counters: a node whose version and incoming world matrix are those of the
previous snapshot is *shared* with it (the same ``SnapNode`` object, its
whole subtree included), and a component whose version did not move keeps
its frozen copy.  Changing one node of 10,000 rebuilds the nodes on its path
from the root only (``bench/snapshots.py``).

Frozen copies are the components' own state (the pickling state of
:class:`~omnirender.core.component.RenderingComponent`), with writeable numpy
arrays copied and made read-only (an ``InstanceSet`` holds the application's
arrays by reference).  Objects a component refers to (a texture of a texture
layer, a track's target) are shared, not copied: change such objects by
replacing them, not in place, while render threads run.

A render thread turns snapshots back into a scene graph of its own with a
:class:`SceneMirror`: unchanged subtrees are skipped, changed components are
updated in place (their versions move, so the GL engine's incremental
compile and its move-only fast path apply), changed lists are rebuilt.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..core.component import RenderingComponent
from ..core.transform import Transform
from .node import Node

__all__ = ["Snapshot", "SnapNode", "Snapshotter", "SceneMirror", "freeze"]

_UNKNOWN = object()
_IDENTITY = np.eye(4)
_IDENTITY.setflags(write=False)


def freeze(component: RenderingComponent) -> RenderingComponent:
    """An unattached copy of ``component`` whose numpy arrays are read-only copies (never the application's)."""
    state = component.__getstate__()
    for name, value in state.items():
        if isinstance(value, np.ndarray) and value.flags.writeable:
            value = value.copy()
            value.setflags(write=False)
            state[name] = value
    copy = object.__new__(type(component))
    copy.__setstate__(state)
    return copy


class SnapNode:
    """One node occurrence in a snapshot: frozen components and child snap nodes, in the node's order.

    ``items`` mixes frozen components and ``SnapNode`` children as the node
    did; ``sources`` are the ids of the application's items at those places;
    ``world`` is the world matrix after the node's transforms (what its last
    items see), ``parent_world`` the one it was placed with, ``bounds`` the
    world box ``(lo, hi)`` of its subtree (None: nothing with a cheap bound),
    computed when first asked for and kept (shared subtrees keep theirs).
    """

    __slots__ = ("name", "path", "groups", "items", "sources", "source", "version", "world", "parent_world", "_bounds")

    def __init__(self, **values: Any) -> None:
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"SnapNode {self.path}: snapshots are immutable (change the scene and take another)")

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """World box of the subtree: analytic and vertex shapes (computed on first use, then kept)."""
        if self._bounds is _UNKNOWN:
            world = self.parent_world
            boxes = []
            for item in self.items:
                if isinstance(item, SnapNode):
                    boxes.append(item.bounds)
                elif isinstance(item, Transform):
                    if item.static:
                        world = world @ item.matrix
                else:
                    boxes.append(_shape_bounds(item, world))
            boxes = [b for b in boxes if b is not None]
            box = None
            if boxes:
                box = (np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0))
            object.__setattr__(self, "_bounds", box)
        return self._bounds

    @property
    def children(self) -> tuple[SnapNode, ...]:
        return tuple(i for i in self.items if isinstance(i, SnapNode))

    @property
    def components(self) -> tuple[RenderingComponent, ...]:
        return tuple(i for i in self.items if not isinstance(i, SnapNode))

    def walk(self) -> Any:
        """This snap node and every one below it, depth first."""
        yield self
        for child in self.children:
            yield from child.walk()

    def __repr__(self) -> str:
        return f"SnapNode({self.path!r}, {len(self.items)} items, version {self.version})"


class Snapshot:
    """One application frame, frozen: ``root`` (a :class:`SnapNode`), ``frame`` (its number) and ``time``.

    ``built`` and ``shared`` count the snap nodes made anew and taken over from the previous snapshot.
    """

    __slots__ = ("root", "frame", "time", "built", "shared", "data")

    def __init__(self, root: SnapNode, frame: int, built: int, shared: int, data: Any = None) -> None:
        self.root, self.frame, self.time = root, frame, time.perf_counter()
        self.built, self.shared, self.data = built, shared, data

    def __repr__(self) -> str:
        return f"Snapshot(frame {self.frame}, {self.built} nodes built, {self.shared} shared)"


class Snapshotter:
    """Takes snapshots of ``scene`` (an ``om.Node``), each sharing what did not change with the previous one."""

    def __init__(self, scene: Node) -> None:
        if not isinstance(scene, Node):
            raise TypeError(f"Snapshotter: scene must be an om.Node, got {type(scene).__name__}")
        self.scene = scene
        self.last: Snapshot | None = None
        self.frame = 0

    def take(self, data: Any = None) -> Snapshot:
        """A snapshot of the scene as it is now (call it at the end of an application frame).

        ``data`` rides along unchanged (e.g. the application time), for the render clients.
        """
        self.frame += 1
        counts = [0, 0]
        prev = self.last.root if self.last is not None else None
        if prev is not None and _shared(prev, self.scene, _IDENTITY):
            root = prev
            counts[1] += 1
        else:
            root = _snap(self.scene, "/" + self.scene.name, _IDENTITY, prev, counts)
        self.last = Snapshot(root, self.frame, counts[0], counts[1], data)
        return self.last


def _shared(old: Any, item: Node, world: np.ndarray) -> bool:
    """Whether the snap node ``old`` still holds for the node ``item`` placed with ``world``."""
    return (
        type(old) is SnapNode
        and old.source == id(item)
        and old.version == item.version
        and (old.parent_world is world or np.array_equal(old.parent_world, world))
    )


def _snap(node: Node, path: str, parent_world: np.ndarray, prev: SnapNode | None, counts: list[int]) -> SnapNode:
    """The snap node of ``node`` (built anew: the caller found ``prev`` outdated or missing)."""
    counts[0] += 1
    version = node.version
    same = prev is not None and prev.source == id(node)
    old_sources = prev.sources if same else ()
    old_items = prev.items if same else ()
    by_id: dict[int, Any] | None = None
    world = parent_world
    refrozen = False  # a transform of this node changed: its world matrix is new
    items: list[Any] = []
    sources: list[int] = []
    for i, item in enumerate(node._items):
        key = id(item)
        if i < len(old_sources) and old_sources[i] == key:
            old = old_items[i]
        elif same:
            if by_id is None:
                by_id = dict(zip(old_sources, old_items, strict=True))
            old = by_id.get(key)
        else:
            old = None
        if isinstance(item, Node):
            if old is not None and _shared(old, item, world):
                counts[1] += 1  # the whole subtree is unchanged: share it
                items.append(old)
            else:
                items.append(_snap(item, f"{path}/{item.name}", world, old if type(old) is SnapNode else None, counts))
        else:
            if old is not None and type(old) is not SnapNode and old.version == item.version:
                frozen = old
            else:
                frozen = freeze(item)
            items.append(frozen)
            if isinstance(item, Transform) and item.static:  # a billboard's matrix depends on the camera
                refrozen = refrozen or frozen is not old
                world = world @ frozen.matrix
        sources.append(key)
    sources_t = tuple(sources)
    if world is not parent_world:
        if same and not refrozen and prev.parent_world is parent_world and sources_t == old_sources:
            world = prev.world  # the same transforms on the same world: children compare it by identity next time
        else:
            world.setflags(write=False)
    return SnapNode(
        name=node.name, path=path, groups=node.groups, items=tuple(items), sources=sources_t, source=id(node),
        version=version, world=world, parent_world=parent_world, _bounds=_UNKNOWN,
    )  # fmt: skip


def _shape_bounds(component: Any, world: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The world box of an analytic or vertex shape, None for anything else (no traversal of simplifications)."""
    from ..geometry.bounds import points_bounds
    from ..techniques.bounds import analytic_bounds

    box = analytic_bounds(component, world)
    if box is None and hasattr(component, "vertex_array"):
        box = points_bounds(component.vertex_array(), world)
    return box


class SceneMirror:
    """A render thread's own scene graph, kept equal to the snapshots given to :meth:`apply`."""

    def __init__(self) -> None:
        self.root: Node | None = None
        self._applied: SnapNode | None = None
        #: nodes rebuilt and components updated by the last apply
        self.rebuilt = 0
        self.updated = 0

    def apply(self, snapshot: Snapshot) -> Node:
        """Bring the mirror to ``snapshot``; returns its root node (the same node from call to call)."""
        self.rebuilt = self.updated = 0
        if self.root is None or self._applied is None or self._applied.source != snapshot.root.source:
            self.root = Node(snapshot.root.name)
            self._applied = None
        self._sync(snapshot.root, self._applied, self.root)
        self._applied = snapshot.root
        return self.root

    def _sync(self, snap: SnapNode, prev: SnapNode | None, node: Node) -> None:
        if snap is prev:
            return
        if prev is None or snap.sources != prev.sources or node.groups != snap.groups:
            self.rebuilt += 1
            node.clear()
            node.groups = snap.groups
            for item in snap.items:
                if isinstance(item, SnapNode):
                    child = node.add(Node(item.name))
                    self._sync(item, None, child)
                else:
                    node.add(freeze(item))
            return
        for item, before, mine in zip(snap.items, prev.items, node._items, strict=True):
            if item is before:
                continue
            if isinstance(item, SnapNode):
                self._sync(item, before, mine)
            else:
                owners, version = mine._owners, mine._version
                mine.__setstate__(item.__getstate__())  # read-only arrays are shared, never written
                object.__setattr__(mine, "_owners", owners)
                object.__setattr__(mine, "_version", version)
                mine.touch()  # the version moves and the owners hear of it: engines update what they compiled
                self.updated += 1
