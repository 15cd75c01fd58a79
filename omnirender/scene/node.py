"""Scene-graph nodes: ordered, inhomogeneous lists of components and child nodes.

A node emits the engine micro program of its contents: attributes are applied
in order and undone in reverse at the end, so they affect only what follows
them in the node and its children, never siblings.  Nodes may be shared by
several parents (a DAG); paths then name the first parent.  Every change bumps
the node's ``version`` and its ancestors', which is how engines notice what to
recompile.

Nodes pickle and ``copy.deepcopy``: a node comes back with its items, groups
and version, and every node restored in the same stream re-attaches itself to
its children, in the original parent order (so paths are kept).  Parents that
were not part of the pickled graph are not (a pickled subgraph comes back
detached), and compiled programs and pre-evaluation caches are rebuilt on use.
"""

from __future__ import annotations

import threading
import weakref
from collections import Counter, deque
from collections.abc import Iterable, Iterator
from itertools import chain, count, repeat
from operator import attrgetter
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..core.component import OWNER_TOUCH, RenderingComponent, flush_changes, note_edit
from ..core.declarations import FIRST, Declarations
from ..core.engine import Engine
from ..core.light import Light
from ..core.program import ENTER, LEAVE, NODE, compile_components
from ..core.transform import Transform

__all__ = ["Node", "Visitor", "declarations_kept"]


class Visitor:
    """Receives a walk over a graph without any engine (see :meth:`Node.inspect`).

    Return False from ``enter_node`` to skip a node's contents.
    """

    def enter_node(self, node: Node) -> bool | None:
        return True

    def leave_node(self, node: Node) -> None:
        pass

    def visit(self, component: RenderingComponent, node: Node) -> None:
        pass


class Node:
    """A named scene-graph node holding components and child nodes in order.

    ``Node(name, items=(), groups=())``: ``items`` is a list of components
    (shapes, attributes, handlers, techniques) and child nodes, evaluated in
    order; ``groups`` is a set of group names that mask expressions test (a
    single string is one group).  ``add``/``insert``/``remove`` edit the list;
    ``node["/scene/body"]`` finds a node by path; ``evaluate(engine)`` emits the
    micro program.  A node may be shared by several parents.
    """

    __slots__ = (
        "_name",
        "_items",
        "_parents",
        "_version",
        "_stamp",
        "_structure",
        "_sstamp",
        "_own",
        "_groups",
        "_program",
        "_program_version",
        "_local",
        "_local_version",
        "_pre",
        "_declared",
        "__weakref__",
    )

    def __init__(self, name: str = "node", items: Iterable[Any] = (), groups: Iterable[str] = ()) -> None:
        self._name = _check_name(name)
        self._items: list[Any] = []
        self._parents: list[Node] = []
        self._version = 0
        self._stamp = -1  # the observation epoch in which the version was last bumped (see touch)
        self._sstamp = -1  # the same for the structure counter
        self._structure = 0  # bumped when this node's list or a descendant's list changes (programs)
        self._own = 0  # bumped when this node's own list or groups change (its local program)
        self._groups = _group_set(groups)
        self._program: list[tuple[int, Any]] | None = None
        self._program_version = -1
        self._local: list[tuple[int, Any]] | None = None
        self._local_version = -1
        self._pre: tuple[int, Any, Any, Any] | None = None  # (version, mask, result, local placements)
        self._declared: _Local | None = None
        if isinstance(items, (RenderingComponent, Node)) or not hasattr(items, "__iter__"):
            raise TypeError(
                f"Node {self._name!r}: items must be a list of components and nodes, got {type(items).__name__}; "
                f"write Node({self._name!r}, [item])"
            )
        if type(self).insert is not Node.insert:  # a subclass's own insert sees every item, as add() would
            for item in items:
                self.add(item)
            return
        self._fill(items)

    def _fill(self, items: Iterable[Any]) -> None:
        """The constructor's items appended to the new node: what :meth:`insert` does for each, less what a new
        node needs not (no parent to touch, no declaration to patch, no journal that saw it: a simulation adding
        a node per frame pays one pass, and engines see only the edit of the parent it is added to)."""
        flush_changes()
        own = self._items
        for item in items:
            # (a new node has no parent: the item cannot be its ancestor, and it cannot be the node itself)
            self._take(item)
            own.append(item)
        if own:
            epoch = _EPOCH[0]
            n = len(own)
            self._own = self._structure = self._version = n  # one bump per item, as insert() makes
            self._sstamp = self._stamp = epoch

    def _check_item(self, item: Any) -> None:
        """Raise the error for an item a node cannot hold (a class, anything not a component or node)."""
        if isinstance(item, type):
            raise TypeError(f"Node {self.path}: cannot add the class {item.__name__}; did you mean {item.__name__}()?")
        raise TypeError(
            f"Node {self.path}: cannot add {type(item).__name__}; expected a shape, attribute, "
            f"handler, technique or Node"
        )

    @classmethod
    def transient(cls, items: Iterable[Any], name: str = "components") -> Node:
        """A root node over ``items`` that does not own them, for evaluating a plain component list once.

        The components are not attached (they keep no reference to this node,
        so rendering a list many times leaks nothing), which also means the
        node does not see later changes of them: make a new one per use.
        """
        node = cls(name)
        for item in items:
            if not (isinstance(item, (RenderingComponent, Node))):
                raise TypeError(
                    f"cannot evaluate {type(item).__name__}: expected a shape, attribute, handler, technique or Node"
                )
            node._items.append(item)
        return node

    # -- identity ---------------------------------------------------------
    @property
    def name(self) -> str:
        return self._name

    @name.setter
    def name(self, value: str) -> None:
        self._name = _check_name(value)
        self.touch()

    @property
    def groups(self) -> frozenset[str]:
        """Group tags tested by mask expressions (an empty set always matches)."""
        return self._groups

    @groups.setter
    def groups(self, value: Iterable[str]) -> None:
        self._groups = _group_set(value)
        self._restructure()
        self.touch()
        note_edit(self, "groups", None, -1)

    @property
    def parent(self) -> Node | None:
        """The first parent (the one paths go through), or None for a root."""
        return self._parents[0] if self._parents else None

    @property
    def parents(self) -> tuple[Node, ...]:
        return tuple(self._parents)

    @property
    def path(self) -> str:
        """UNIX-style path from the root through first parents: ``/scene/body``."""
        names = []
        node: Node | None = self
        while node is not None:
            names.append(node._name)
            node = node._parents[0] if node._parents else None
        return "/" + "/".join(reversed(names))

    @property
    def version(self) -> int:
        """Counter bumped when this node or anything below it changes."""
        _observe()  # an observation: the next change must reach every ancestor again (see touch)
        return self._version

    @property
    def structure_version(self) -> int:
        """Counter bumped when this node's list, or the list of a node below it, changes (not parameters)."""
        _observe()
        return self._structure

    @property
    def versions(self) -> tuple[int, int]:
        """``(version, structure_version)``, read in one observation (what a renderer asks every frame)."""
        _observe()
        return self._version, self._structure

    @property
    def list_version(self) -> int:
        """Counter bumped when this node's own list (or its groups) changes; a descendant's list does not bump it."""
        return self._own

    def touch(self) -> None:
        """Mark the node changed: bump its version and every ancestor's.

        Propagation stops at an ancestor already bumped since versions were
        last observed (read): its version already differs from anything an
        observer saw, and so, by the same rule, do its ancestors'.  Changes
        between two observations therefore cost O(1) amortised per node, not
        O(depth): building a chain of 100,000 nested nodes is linear, and a
        simulation moving thousands of nodes per frame walks each ancestor once.
        """
        epoch = _EPOCH[0]
        self._version += 1
        self._stamp = epoch
        _TOUCHED()  # (a version moved by at most one per call: touch_nodes bounds versions by it)
        parents = self._parents
        if not parents:
            return
        if len(parents) == 1:
            node = parents[0]
            while node._stamp != epoch:
                node._version += 1
                node._stamp = epoch
                up = node._parents
                if len(up) != 1:
                    if up:
                        _bump_ancestors(up, epoch, "_version", "_stamp")
                    return
                node = up[0]
            return
        _bump_ancestors(parents, epoch, "_version", "_stamp")

    def _restructure(self) -> None:
        """This node's list changed: its programs, and the flat programs of every ancestor, recompile.

        A component changing a parameter does not restructure: programs hold
        the components themselves, so they stay valid (only ``version`` moves).
        Propagation stops like :meth:`touch`'s.
        """
        epoch = _EPOCH[0]
        self._own += 1
        self._structure += 1
        self._sstamp = epoch
        parents = self._parents
        if len(parents) == 1:  # (a chain of single parents, walked as touch walks it; else the general walk)
            node = parents[0]
            while node._sstamp != epoch:
                node._structure += 1
                node._sstamp = epoch
                up = node._parents
                if len(up) != 1:
                    if up:
                        _bump_ancestors(up, epoch, "_structure", "_sstamp")
                    return
                node = up[0]
        elif parents:
            _bump_ancestors(parents, epoch, "_structure", "_sstamp")

    # -- contents ---------------------------------------------------------
    def add(self, item: Any) -> Any:
        """Append a component or child node; returns it."""
        return self.insert(len(self._items), item)

    def _take(self, item: Any) -> None:
        """Make ``item`` one of this node's: a child node links its parent, a component its owner; anything
        else is refused with the reason (``_check_item``)."""
        if isinstance(item, Node):
            item._parents.append(self)
            _relinked(item)
        elif isinstance(item, RenderingComponent):
            item._attach(self)
        else:
            self._check_item(item)

    def insert(self, index: int, item: Any) -> Any:
        """Insert a component or child node at ``index``; returns it."""
        flush_changes()  # versions noted for later reach the nodes before the declarations' patch reads them
        if isinstance(item, Node) and (item is self or item._is_ancestor_of(self)):
            raise ValueError(f"Node {self.path}: adding {item.path} would make a cycle")
        self._take(item)
        patch = _declaration_patch(self, item)
        n = len(self._items)
        at = min(index, n) if index >= 0 else max(0, n + index)  # where list.insert puts it
        self._items.insert(at, item)
        self._restructure()
        self.touch()
        if patch:
            _patch_declarations(patch, at, 1)
        note_edit(self, "insert", item, at)
        return item

    def remove(self, item: Any) -> Any:
        """Remove the first occurrence of ``item``; returns it."""
        flush_changes()
        i = self._index_of(item)
        if i < 0:
            raise ValueError(f"Node {self.path}: {item!r} is not in this node")
        patch = _declaration_patch(self, item)
        del self._items[i]
        if isinstance(item, Node):
            for j, p in enumerate(item._parents):
                if p is self:
                    del item._parents[j]
                    break
            _relinked(item)
        else:
            item._detach(self)
        self._restructure()
        self.touch()
        if patch:
            _patch_declarations(patch, i, -1)
        note_edit(self, "remove", item, i)
        return item

    def _index_of(self, item: Any) -> int:
        """The index of the first item that is ``item``, or -1.

        ``list.index`` scans in C and tests identity before equality, so a hit
        that is ``item`` is its first occurrence; an equal item found first (a
        component comparing by value), a comparison that raises or no hit
        fall back to the scan by identity.
        """
        items = self._items
        if isinstance(item, Node) and item._parents.count(self) == 1:
            n = len(items)  # held once: a hit is its first occurrence; children added last are removed first
            for i in range(n - 1, max(n - 33, -1), -1):
                if items[i] is item:
                    return i
        try:
            at = items.index(item)
        except Exception:  # noqa: BLE001  (not there, or a component's __eq__ that does not answer a bool)
            at = -1
        if at >= 0 and items[at] is item:
            return at
        for i, existing in enumerate(items):
            if existing is item:
                return i
        return -1

    def clear(self) -> None:
        """Remove every item."""
        for item in list(self._items):
            self.remove(item)

    def __iter__(self) -> Iterator[Any]:
        """The items in order, as they were when iteration began.

        Iterating a snapshot means ``for item in node: node.remove(item)``
        removes every item (iterating the live list would skip every other one).
        """
        return iter(tuple(self._items))

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, item: Any) -> bool:
        return any(existing is item for existing in self._items)

    @property
    def items(self) -> tuple[Any, ...]:
        """Components and child nodes in order."""
        return tuple(self._items)

    def last_items(self, count: int) -> tuple[Any, ...]:
        """The last ``count`` items in order (what was appended last), without copying the whole list."""
        return tuple(self._items[len(self._items) - count :]) if count > 0 else ()

    @property
    def children(self) -> list[Node]:
        """Child nodes in order."""
        return [i for i in self._items if isinstance(i, Node)]

    @property
    def components(self) -> list[RenderingComponent]:
        """Components (everything but child nodes) in order."""
        return [i for i in self._items if not isinstance(i, Node)]

    def child(self, name: str) -> Node:
        """The first child node called ``name``."""
        for c in self._items:
            if isinstance(c, Node) and c._name == name:
                return c
        raise KeyError(f"Node {self.path} has no child {name!r}; children: {[c.name for c in self.children]}")

    def walk(self) -> Iterator[Node]:
        """This node and every node below it, depth first, each once."""
        seen: set[int] = set()
        stack = [self]
        while stack:
            node = stack.pop()
            if id(node) in seen:
                continue
            seen.add(id(node))
            yield node
            stack.extend(reversed(node.children))

    def _is_ancestor_of(self, other: Node) -> bool:
        if not any(isinstance(item, Node) for item in self._items):
            return False  # a node without child nodes is nobody's ancestor: adding a leaf is O(1), not O(depth)
        stack = list(other._parents)
        seen: set[int] = set()
        while stack:
            n = stack.pop()
            if n is self:
                return True
            if id(n) not in seen:
                seen.add(id(n))
                stack.extend(n._parents)
        return False

    # -- paths ------------------------------------------------------------
    def __getitem__(self, path: str) -> Node:
        """Look up a node by path: ``"/scene/body"`` (absolute) or ``"body/arm"`` (relative).

        An absolute path may start with this node's name or directly with one of
        its children.  A miss raises KeyError naming the closest existing prefix.
        """
        if not isinstance(path, str):
            raise TypeError(f"node paths are strings, got {type(path).__name__}")
        parts = [p for p in path.split("/") if p]
        if not parts:
            return self
        attempts: list[tuple[Node, int, list[str]]] = []
        if path.startswith("/") and parts[0] == self._name:
            found = self._follow(parts[1:])
            if isinstance(found, Node):
                return found
            attempts.append((found[0], found[1] + 1, parts[1:]))
        found = self._follow(parts)
        if isinstance(found, Node):
            return found
        attempts.append((found[0], found[1], parts))
        node, depth, rel = max(attempts, key=lambda a: a[1])
        missing = rel[depth - (len(parts) - len(rel))]
        raise KeyError(
            f"no node at {path!r}: the closest existing prefix is {node.path!r}, which has no child "
            f"{missing!r} (children: {[c.name for c in node.children]})"
        )

    def _follow(self, parts: list[str]) -> Node | tuple[Node, int]:
        node = self
        for depth, name in enumerate(parts):
            nxt = None
            for c in node._items:
                if isinstance(c, Node) and c._name == name:
                    nxt = c
                    break
            if nxt is None:
                return (node, depth)
            node = nxt
        return node

    # -- evaluation -------------------------------------------------------
    def evaluate(self, engine: Engine) -> None:
        """Emit this node's micro program to ``engine`` (pre-evaluating when top level)."""
        engine.run(self)

    def program(self) -> list[tuple[int, Any]]:
        """The compiled micro program of this node (enter, contents, undo, leave).

        Cached while no list below changed (a parameter change keeps it).
        Stale descendants are compiled first, bottom-up with an explicit stack,
        so deep graphs need no deep recursion.
        """
        _observe()
        if self._program_version == self._structure and self._program is not None:
            return self._program
        order: list[Node] = []
        seen: set[int] = set()
        stack: list[tuple[Node, bool]] = [(self, False)]
        while stack:
            node, expanded = stack.pop()
            if expanded:
                order.append(node)
                continue
            if id(node) in seen or (node._program_version == node._structure and node._program is not None):
                continue
            seen.add(id(node))
            stack.append((node, True))
            for item in node._items:
                if isinstance(item, Node):
                    stack.append((item, False))
        for node in order:  # children before parents
            node._compile()
        return self._program  # type: ignore[return-value]

    def _compile(self) -> None:
        program: list[tuple[int, Any]] = [(ENTER, self)]
        compile_components(self._items, program, _Where(self))
        program.append((LEAVE, -1))
        self._program = program
        self._program_version = self._structure

    def local_program(self) -> list[tuple[int, Any]]:
        """This node's program with every child node kept as one ``NODE`` op (not inlined).

        For engines that cache per node occurrence (the GL compiler): they
        evaluate each child through :meth:`~omnirender.core.engine.Engine.eval_node`.
        Cached while this node's own list is unchanged.
        """
        _observe()
        if self._local_version != self._own or self._local is None:
            program: list[tuple[int, Any]] = [(ENTER, self)]
            compile_components(self._items, program, _Where(self), inline=False)
            program.append((LEAVE, -1))
            self._local = program
            self._local_version = self._own
        return self._local

    def _compile_node(self, program: list[tuple[int, Any]]) -> None:
        if self._groups:
            program.append((NODE, self))  # the mask is tested when the program runs
            return
        own = self.program()
        if len(own) > _INLINE_LIMIT:
            program.append((NODE, self))  # a big subtree stays one op: deep chains cost linear memory
        else:
            program.extend(own)

    def declarations(self, mask_fn: Any = None) -> Declarations:
        """What the graph below declares: every light and the first camera and background, with world matrices.

        The declarative pre-evaluation every engine runs before its traversal
        (see :mod:`omnirender.core.declarations`).  Each node caches its
        placements in its own coordinates per version and mask, so after a
        change only the nodes on the changed path are walked again.
        """
        _observe()
        cached = self._pre
        if cached is not None and cached[0] == self._version and cached[1] is mask_fn:
            return cached[2]
        if self._groups and mask_fn is not None and not mask_fn(self._groups):
            result = Declarations([])
            local = None
        else:
            local = _local_placements(self, mask_fn)
            if cached is not None and cached[1] is mask_fn and cached[3] is local:
                # the same placements (a node added or removed that declares nothing, a quiet node moved):
                # the same result, so what keys on it (an engine's recorded frame) holds
                self._pre = (self._version, mask_fn, cached[2], local)
                return cached[2]
            result = Declarations(_world(local))
        self._pre = (self._version, mask_fn, result, local)
        return result

    def preevaluate(
        self, mask_fn: Any = None
    ) -> tuple[list[tuple[Light, np.ndarray]], tuple[Camera, np.ndarray] | None]:
        """Every light with its world matrix and the first camera, in traversal order (see :meth:`declarations`)."""
        found = self.declarations(mask_fn)
        return found.lights, found.camera

    def inspect(self, visitor: Visitor) -> None:
        """Walk components and structure in evaluation order, without an engine."""
        if visitor.enter_node(self) is False:
            return
        stack: list[tuple[Node, Iterator[Any]]] = [(self, iter(self._items))]
        while stack:
            node, items = stack[-1]
            for item in items:
                if isinstance(item, Node):
                    if visitor.enter_node(item) is not False:
                        stack.append((item, iter(item._items)))
                        break
                else:
                    visitor.visit(item, node)
            else:
                stack.pop()
                visitor.leave_node(node)

    def __repr__(self) -> str:
        return f"Node({self._name!r}, {len(self._items)} items)"

    # -- pickling and copying (see the module docs) ---------------------------
    def __getstate__(self) -> dict[str, Any]:
        flush_changes()
        return {
            "name": self._name,
            "items": list(self._items),
            "groups": self._groups,
            "version": self._version,
            # identities within this pickle: children restore their parents in this order
            "key": id(self),
            "parent_keys": [id(p) for p in self._parents],
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        Node.__init__(self, state["name"], groups=state["groups"])  # every slot fresh: caches empty
        self._items = list(state["items"])
        self._version = state["version"]
        _RELINKED[0] = None  # its children gain this parent below: every kept set of parents is made again
        if len(state["parent_keys"]) > 1:
            _PARENT_ORDER[self] = state["parent_keys"]
        key = state["key"]
        # Children are restored before their parents (pickle builds the items first).
        for item in self._items:
            if isinstance(item, Node):
                order = _PARENT_ORDER.get(item)
                if order is None or key not in order:
                    item._parents.append(self)
                    continue
                rank = order.index(key)
                at = len(item._parents)
                while at > 0 and _rank(order, item._parents[at - 1]) > rank:
                    at -= 1
                item._parents.insert(at, self)
                _KEYS[self] = key
            else:
                item._attach(self)

    # Viewers draw nodes through their own adapter (om.viewer.NodeRenderable): the graph knows no viewer.

    #: Size of the picture a node shows of itself in a notebook.
    repr_size: tuple[int, int] = (480, 360)

    def _repr_png_(self) -> bytes | None:
        """Jupyter display: the node rendered by the GL engine (None when GL is unavailable)."""
        from ..render import engines, render

        if not engines().get("gl", (False, ""))[0]:
            return None
        return render(self, engine="gl", size=self.repr_size)._repr_png_()


# Unpickling bookkeeping for shared nodes: a child's original parent order, and each restored parent's
# identity in that stream.  Weak, so nothing outlives the restored nodes.
_PARENT_ORDER: weakref.WeakKeyDictionary[Node, list[int]] = weakref.WeakKeyDictionary()
_KEYS: weakref.WeakKeyDictionary[Node, int] = weakref.WeakKeyDictionary()


def _rank(order: list[int], parent: Node) -> int:
    key = _KEYS.get(parent)
    return order.index(key) if key in order else len(order)


class _Where:
    """Lazy " in node /path" for error messages (paths cost O(depth) to build)."""

    __slots__ = ("node",)

    def __init__(self, node: Node) -> None:
        self.node = node

    def __str__(self) -> str:
        return f" in node {self.node.path}"

    def __format__(self, spec: str) -> str:
        return str(self)


#: Child programs of at most this many ops are inlined into their parent's; larger ones stay one NODE op.
#: Inlining copies references, so a wide node of small children is one flat loop, while a chain of
#: 100,000 nested nodes does not hold 100,000 ever longer copies of its tail (quadratic memory).
_INLINE_LIMIT = 64

#: Observation epoch: bumped whenever a version or structure counter is read (see Node.touch).
_EPOCH = [0]
_EPOCH_LOCK = threading.Lock()


def _observe() -> None:
    """Start a new observation epoch.  Locked: render threads read versions while the application changes
    the graph, and a lost increment would let a later change stop below an ancestor an observer already read.

    Changes noted for later (transform setters, :func:`~omnirender.core.component.note_later`) reach their
    nodes first, in the epoch that is ending."""
    flush_changes()
    with _EPOCH_LOCK:
        _EPOCH[0] += 1


def touch_nodes(owners: list[Any]) -> None:
    """``touch()`` every one of ``owners``: nodes in C-level loops, anything else one by one.

    What :func:`~omnirender.core.component.flush_changes` calls with the
    owners of the transforms a simulation loop moved: every node's version
    moves, then each distinct parent is touched once (its ancestors follow as
    :meth:`Node.touch` does).  The owners are not stamped in the current
    epoch (a pass less): a later change below one of them in the same epoch
    bumps it again on its way up, which a version allows (it only has to
    differ from what an observer read), and an owner that is also a parent of
    another is touched as a parent.
    """
    if len(owners) < 16:  # a few: their own touch() is cheaper than the passes below
        for owner in owners:
            owner.touch()
        return
    try:
        # every owner's version moves past its own: to one more than the highest among them (a version only has
        # to differ from what an observer read; a single value costs no addition per node), a bound of which is
        # known without reading them when the same owners come again (_version_bound)
        bound = _version_bound(owners)
        if bound is None:
            top, plain = max(map(_VERSION_OF, owners)), False
        else:
            top, plain = bound
        if plain:  # all of them plain nodes (known from the last time): the builtin setattr, a quarter cheaper
            deque(map(setattr, owners, repeat("_version"), repeat(top + 1)), 0)
        else:  # (the slot's own setter: refuses anything but a node, whose own touch() is then called)
            deque(map(_SET_VERSION, owners, repeat(top + 1)), 0)
    except (TypeError, AttributeError):  # not all nodes: each its own way (a node bumped twice moved all the same)
        _KEPT_TOP[0] = None
        for owner in owners:
            owner.touch()
        return
    _keep_top(owners, top + 1, plain)
    epoch = _EPOCH[0]
    for parent in _parents_of(owners):
        if parent._stamp != epoch:
            parent.touch()


#: counts calls that may raise a node's version by one: each :meth:`Node.touch` raises its node and each ancestor
#: at most once (returns the count, counting itself)
_TOUCHED = count().__next__
#: the highest version :func:`touch_nodes` gave any node
_TOP = [0]
#: what :func:`touch_nodes` gave its last owners: (a weak reference to their list, the version, ``_TOUCHED()`` then,
#: whether all are plain :class:`Node` objects)
_KEPT_TOP: list[tuple[Any, int, int, bool] | None] = [None]


def _version_bound(owners: list[Any]) -> tuple[int, bool] | None:
    """An upper bound of the versions of ``owners``, read from none of them, when they are the list the last
    :func:`touch_nodes` set (the same object: a change batch's kept owners, see ``core.component``), or that list
    patched (its ``base``, with the owners that ``came`` read): each had the version it gave them; since then
    another :func:`touch_nodes` set some to at most :data:`_TOP`, and each :meth:`Node.touch` raised each by at
    most one (nothing else writes a live node's version).  With it, whether all of them are known to be plain
    :class:`Node` objects.  None otherwise."""
    kept = _KEPT_TOP[0]
    if kept is None:
        return None
    last = kept[0]()
    if last is owners:
        return max(kept[1], _TOP[0]) + (_TOUCHED() - kept[2]), kept[3]
    if last is None or getattr(owners, "base", None) is not last:
        return None
    # that list with a few owners taken out or added (``core.component._Owners``: some of the batch's components
    # changed hands): the owners added are read
    top = max(kept[1], _TOP[0]) + (_TOUCHED() - kept[2])
    came = owners.came  # type: ignore[attr-defined]
    if not came:
        return top, kept[3]
    return max(top, max(map(_VERSION_OF, came))), kept[3] and all(node.__class__ is Node for node in came)


def _keep_top(owners: list[Any], version: int, plain: bool) -> None:
    """:func:`touch_nodes` gave every one of ``owners`` ``version`` (``plain``: all known to be plain nodes):
    kept for :func:`_version_bound` (which of them are plain nodes is asked once, here)."""
    if version > _TOP[0]:
        _TOP[0] = version
    try:
        ref = weakref.ref(owners)
    except TypeError:  # (a plain list: not kept)
        _KEPT_TOP[0] = None
        return
    if not plain:
        plain = set(map(type, owners)) == _PLAIN_NODE
    _KEPT_TOP[0] = (ref, version, _TOUCHED(), plain)


#: ids of the nodes that gained or lost a parent since :func:`_parents_of` last looked (None: too many); the
#: distinct parents it found for the last owners (their ids, weak references to the parents, the owners' list,
#: the set of their ids) hold while none of those nodes is among them
_RELINKED: list[list[int] | None] = [[]]
#: nodes :data:`_RELINKED` lists before it only records that too many changed
RELINKED_LIMIT = 1024
_LAST_PARENTS: list[Any] = [None]


class _KeptParents:
    """What :func:`_parents_of` keeps of its last call: the owners (a weak reference to their list, their ids),
    their distinct parents (id -> weak reference, in order) and, once asked, how many owners each parent has."""

    __slots__ = ("ids", "owners", "parents", "owner_ids", "counts")

    def __init__(self, ids: list[int] | None, owners: Any, parents: dict[int, Any], owner_ids: set[int]) -> None:
        self.ids = ids
        self.owners = owners
        self.parents = parents
        self.owner_ids = owner_ids
        self.counts: Counter[int] | None = None

    def alive(self) -> list[Node] | None:
        parents = [ref() for ref in self.parents.values()]
        return None if None in parents else parents  # type: ignore[return-value]


def _parents_of(owners: list[Node]) -> list[Node]:
    """The distinct parents of ``owners``: those of the last call when the same nodes come again (a simulation
    moves the same nodes every frame) and none of them gained or lost a parent since.

    The same list object as the last call's (the owners a change batch kept, ``core.component``) is known
    without a pass over it; a list made from it with a few owners taken out or added (its ``base``, ``gone``
    and ``came``: some of the batch's components changed hands) is followed from what was kept for it."""
    last: _KeptParents | None = _LAST_PARENTS[0]
    relinked = _RELINKED[0]
    _RELINKED[0] = []
    if last is not None and (relinked is None or not last.owner_ids.isdisjoint(relinked)):
        last = None  # one of the owners gained or lost a parent
    if last is not None and last.owners is not None:
        kept = last.owners()
        if kept is owners:
            parents = last.alive()
            if parents is not None:
                return parents
        elif kept is not None and getattr(owners, "base", None) is kept:
            parents = _follow(last, kept, owners)
            if parents is not None:
                return parents
    ids = list(map(id, owners))  # ids, not the nodes: the cache keeps no node alive
    if last is not None and last.ids == ids:
        parents = last.alive()
        if parents is not None:
            last.owners = _weak(owners)
            return parents
    parents = list(dict.fromkeys(chain.from_iterable(map(_PARENTS_OF, owners))))  # nodes hash by identity
    _LAST_PARENTS[0] = _KeptParents(ids, _weak(owners), {id(p): weakref.ref(p) for p in parents}, set(ids))
    return parents


def _follow(last: _KeptParents, kept: list[Node], owners: Any) -> list[Node] | None:
    """The distinct parents of ``owners``, made from ``kept`` (the list ``last`` was kept for) by taking out the
    owners in ``owners.gone`` and adding those in ``owners.came``: each parent's count of owners follows; a parent
    none is left below leaves.  ``last`` is made ``owners``'; None when a parent died."""
    counts = last.counts
    if counts is None:
        counts = last.counts = Counter(map(id, chain.from_iterable(map(_PARENTS_OF, kept))))
    parents = last.parents
    for node in owners.gone:
        for p in node._parents:
            k = id(p)
            left = counts[k] - 1
            if left > 0:
                counts[k] = left
            else:
                del counts[k]
                parents.pop(k, None)
    for node in owners.came:
        for p in node._parents:
            k = id(p)
            counts[k] += 1
            if k not in parents:
                parents[k] = weakref.ref(p)
        last.owner_ids.add(id(node))  # (the owners gone stay in it: a parent change of one asks again, no harm)
    last.ids = None
    last.owners = _weak(owners)
    return last.alive()


def _relinked(node: Node) -> None:
    """``node`` gained or lost a parent: the parents :func:`_parents_of` keeps for owners holding it are made again."""
    found = _RELINKED[0]
    if found is not None:
        if len(found) < RELINKED_LIMIT:
            found.append(id(node))
        else:
            _RELINKED[0] = None


def _weak(owners: list[Node]) -> Any:
    """A weak reference to the list ``owners`` where it takes one (a plain list does not), else None."""
    try:
        return weakref.ref(owners)
    except TypeError:
        return None


def _bump_ancestors(start: list[Node], epoch: int, counter: str, stamp: str) -> None:
    """Bump ``counter`` of every ancestor from ``start`` up, stopping at nodes already stamped in ``epoch``."""
    stack = list(start)
    while stack:
        node = stack.pop()
        if getattr(node, stamp) == epoch:
            continue
        setattr(node, counter, getattr(node, counter) + 1)
        setattr(node, stamp, epoch)
        stack.extend(node._parents)


class _Local:
    """A node's declared placements in its own coordinates, valid for one version and mask."""

    __slots__ = ("version", "structure", "mask_fn", "placements", "relevant")

    def __init__(
        self,
        version: int,
        structure: int,
        mask_fn: Any,
        placements: list[tuple[Any, np.ndarray | None]],
        relevant: list[int],
    ) -> None:
        self.version = version
        self.structure = structure
        self.mask_fn = mask_fn
        self.placements = placements  # matrix None: the node's own coordinates (identity)
        #: indices of the items that can contribute while the lists below stay the same: transforms, declared
        #: components and the children that declared something (a parameter change walks only these)
        self.relevant = relevant

    def valid(self, node: Node, mask_fn: Any) -> bool:
        """Whether this result still holds for ``node``.

        A subtree that declared nothing declares nothing after any change
        that leaves every list below it alone (a moved transform, a new
        colour): what is declared depends on the lists, where only on the
        parameters.  So a simulation moving thousands of plain objects does
        not walk them again.
        """
        if self.mask_fn is not mask_fn:
            return False
        if self.version == node._version:
            return True
        if not self.placements and self.structure == node._structure:
            self.version = node._version
            return True
        return False


def _world(local: list[tuple[Any, np.ndarray | None]]) -> list[tuple[Any, np.ndarray]]:
    """A root's declared placements (:func:`_local_placements`) with its own coordinates' identity matrices made."""
    eye = np.eye(4)
    return [(c, eye if m is None else m) for c, m in local]


def _relevant_items(node: Node, mask_fn: Any) -> tuple[list[Any], list[int] | None]:
    """The items to visit when ``node``'s declarations are made again, and their indices (None: all of them).

    While the node's lists (and every list below) are unchanged, only the
    items its last result named relevant can change what it declares.
    """
    entry = node._declared
    if entry is not None and entry.mask_fn is mask_fn and entry.structure == node._structure:
        items = node._items
        return [items[i] for i in entry.relevant], entry.relevant
    return node._items, None


def _local_placements(root: Node, mask_fn: Any) -> list[tuple[Any, np.ndarray | None]]:
    """Declared placements below ``root`` in its own coordinates (matrix None: the identity), re-using per-node
    local results: post-order with an explicit stack, so graphs of any depth need no deep recursion; a child
    whose local result is valid for its version and the mask is not walked again."""
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        node, expanded = stack.pop()
        if not expanded:
            entry = node._declared
            if entry is not None and entry.valid(node, mask_fn):
                continue
            stack.append((node, True))
            for item in _relevant_items(node, mask_fn)[0]:
                if item.__class__ is Node or isinstance(item, Node):
                    e = item._declared
                    if (e is None or not e.valid(item, mask_fn)) and not (
                        item._groups and mask_fn is not None and not mask_fn(item._groups)
                    ):
                        stack.append((item, False))
            continue
        out: list[tuple[Any, np.ndarray | None]] = []
        m: np.ndarray | None = None
        pending: list[Transform] = []  # transforms met since the last placement: multiplied only when needed
        firsts: dict[Any, int] = {}  # category -> index in out of this node's own "first" declaration
        items, indices = _relevant_items(node, mask_fn)
        relevant: list[int] = []
        for position, item in enumerate(items):
            if item.__class__ is Node or isinstance(item, Node):
                if item._groups and mask_fn is not None and not mask_fn(item._groups):
                    continue
                found = item._declared.placements  # type: ignore[union-attr]
                if not found:
                    continue
                relevant.append(position if indices is None else indices[position])
                if pending:
                    m = _fold(m, pending)
                if m is None:
                    out.extend(found)
                else:
                    out.extend((c, m if cm is None else m @ cm) for c, cm in found)
            elif isinstance(item, Transform):
                relevant.append(position if indices is None else indices[position])
                pending.append(item)
            elif item.declared is not None:
                relevant.append(position if indices is None else indices[position])
                if pending:
                    m = _fold(m, pending)
                if item.declared == FIRST:
                    # stack semantics: a later one in the same node replaces the earlier for the rest of the node
                    category = getattr(item, "category", type(item))
                    at = firsts.get(category)
                    if at is not None:
                        out[at] = (item, m)
                        continue
                    firsts[category] = len(out)
                out.append((item, m))
        before = node._declared
        if before is not None and before.mask_fn is mask_fn and _same_placements(before.placements, out):
            out = before.placements  # the same list: what was made of it (a root's Declarations) is kept
        node._declared = _Local(node._version, node._structure, mask_fn, out, relevant)
    return root._declared.placements  # type: ignore[union-attr]


def declarations_kept(components: Iterable[Any], mask_fn: Any = None) -> bool:
    """Whether new parameter values of ``components`` (no node's list changed) leave every declaration as it was.

    True when each component's every owner is a node whose subtree declared
    nothing (no light, camera, background) when last pre-evaluated under
    ``mask_fn``, with its lists unchanged since: what such a component
    changes (a transform moving the shapes after it) places no declared
    component, so :meth:`Node.declarations` of any graph holding them gives
    the same placements as before.  An engine moving one plain object skips
    the pre-evaluation with it.  False when that is not known (an owner never
    pre-evaluated, or under another mask, or not a node).
    """
    for component in components:
        owners = component.owners
        if not owners:
            return False
        for node in owners:
            if node.__class__ is not Node and not isinstance(node, Node):
                return False
            entry = node._declared
            if entry is None or entry.placements or entry.mask_fn is not mask_fn or entry.structure != node._structure:
                return False
    return True


def _same_placements(a: list[tuple[Any, Any]], b: list[tuple[Any, Any]]) -> bool:
    """Whether two local placement lists name the same components at equal matrices (None: the identity)."""
    if len(a) != len(b):
        return False
    for (x, m), (y, n) in zip(a, b, strict=True):
        if x is not y:
            return False
        if m is not n and (m is None or n is None or not bool((m == n).all())):
            return False
    return True


def _declaration_patch(node: Node, item: Any) -> list[tuple[Node, _Local, bool]] | None:
    """Before ``item`` enters or leaves ``node``'s list: the valid declaration results that the edit keeps.

    An item that declares nothing (a shape, a material, a child subtree
    without lights or cameras) changes no declaration, so the results of the
    node and of its ancestors (one parent each) stay valid once their indices
    shift: a simulation adding and removing plain nodes under a root of 10,000
    does not walk the root again.  None when the edit may change what is declared.
    """
    entry = node._declared
    if entry is None or entry.structure != node._structure:
        return None
    mask_fn = entry.mask_fn
    if isinstance(item, Node):
        if item._groups and mask_fn is not None and not mask_fn(item._groups):
            pass  # masked out: declares nothing here
        elif _local_placements(item, mask_fn):
            return None
    elif isinstance(item, Transform):
        if entry.placements:  # it may move what the node declares after it
            return None
    elif getattr(item, "declared", None) is not None:
        return None
    # a node whose parameters moved since its result (a transform moved and no renderer asked since: the GL
    # engine skips the pre-evaluation when what moved declares nothing) keeps its lists: its result stays a
    # guide to the items to walk again, as its ancestors' do below (its version is left stale)
    chain = [(node, entry, _holds(entry, node))]
    up = node._parents
    while len(up) == 1:
        above = up[0]
        e = above._declared
        # an ancestor whose parameters moved since its result (its version is stale) keeps its lists: its
        # result stays a guide to which items to walk again (``relevant``), so it follows the edit too, only
        # its version is left stale (see _patch_declarations); else a splice after a move walked every child
        if e is None or e.mask_fn is not mask_fn or e.structure != above._structure:
            break
        chain.append((above, e, _holds(e, above)))
        up = above._parents
    return chain


def _holds(entry: _Local, node: Node) -> bool:
    """Whether ``entry`` is what a walk of ``node`` would give now (as :meth:`_Local.valid`, for its own mask)."""
    if entry.structure != node._structure:
        return False
    return entry.version == node._version or not entry.placements


def _patch_declarations(chain: list[tuple[Node, _Local, bool]], index: int, shift: int) -> None:
    """After the edit: the kept results are valid for the new versions; the edited node's indices shift."""
    node, entry, _ = chain[0]
    entry.relevant = [i + shift if i >= index else i for i in entry.relevant if not (shift < 0 and i == index)]
    for n, e, held in chain:
        if held:  # valid before the edit: valid after it (a stale version stays stale)
            e.version = n._version
        e.structure = n._structure
    _observe()  # recorded versions are observed: the next change must reach these nodes again


def _fold(m: np.ndarray | None, pending: list[Transform]) -> np.ndarray | None:
    """``m`` times the matrices of ``pending`` (emptied); engine-dependent transforms (Billboard) have none."""
    for t in pending:
        matrix = getattr(t, "matrix", None)
        if matrix is not None:
            m = matrix if m is None else m @ matrix
    pending.clear()
    return m


def _check_name(name: str) -> str:
    if not isinstance(name, str) or not name or "/" in name or not name.isprintable():
        raise ValueError(
            f"Node: name must be a non-empty string without '/' or control characters (NUL, newline...), got {name!r}"
        )
    return name


def _group_set(groups: Iterable[str] | str) -> frozenset[str]:
    if isinstance(groups, str):  # one group, not its characters
        groups = [groups]
    elif not isinstance(groups, Iterable):
        raise ValueError(f"Node: groups must be a group name or a list of them, got {groups!r}")
    return frozenset(_check_group(g) for g in groups)


def _check_group(group: str) -> str:
    if not isinstance(group, str) or not group or any(ch in group for ch in " !&|()") or not group.isprintable():
        raise ValueError(
            f"Node: group names must be non-empty and free of spaces, control characters and !&|(), got {group!r}"
        )
    return group


_SET_VERSION = Node._version.__set__  # type: ignore[attr-defined]
_PLAIN_NODE = {Node}
_VERSION_OF = attrgetter("_version")
_PARENTS_OF = attrgetter("_parents")
_PLUS_ONE = (1).__add__
OWNER_TOUCH[0] = touch_nodes
