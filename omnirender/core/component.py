"""Rendering components: the parameters a scene is made of.

A component holds parameters only, never an algorithm (algorithms are
:class:`~omnirender.core.handler.Handler` objects).  Components carry a
``version`` counter that is bumped whenever a public parameter is assigned, and
the bump is forwarded to every node that owns the component so that engines can
recompile only what changed.

Components pickle and ``copy.deepcopy`` (so scenes travel to worker processes
and clusters): the state is every slot except the owning nodes, which the
nodes re-attach when they are restored, and except the slots a class lists in
``_transient`` (caches of values derived from the parameters), which come back
empty and are recomputed on first use.
"""

from __future__ import annotations

import threading
import weakref
from collections import deque
from collections.abc import Callable
from itertools import chain
from operator import attrgetter, indexOf, is_
from typing import Any

__all__ = [
    "ChangeJournal",
    "note_change",
    "note_later",
    "flush_changes",
    "note_edit",
    "RenderingComponent",
    "Shape",
    "Attribute",
    "MonoAttribute",
    "PolyAttribute",
    "category_of",
    "version_key",
]


def version_key(component: Any) -> tuple[Any, int] | None:
    """``(component, its version)``, or None for None: a key for memos of what was made from a component.

    It changes when the component changes, and it holds the component itself
    (compared by identity), not its ``id()``: a memo keyed by ``(id, version)``
    outlives the components it was made from, and a new component made at a
    dead one's address, at the same version (every new component starts at 0),
    found the dead one's entry (a glTF export gave a colour group another
    group's material, at random).
    """
    return None if component is None else (component, component.version)


class ChangeJournal:
    """The components changed (touched) since the journal was last drained.

    An engine that updates what it compiled in place keeps one: a frame then
    knows which transforms moved without scanning the scene (the GL engine
    rewrites only the instance rows that depend on them).  Journals are
    registered weakly; while one is alive, a component change costs one dict
    store per journal.
    """

    __slots__ = ("_changed", "_edits", "_held", "__weakref__")

    def __init__(self) -> None:
        if _FORGOTTEN:
            _prune_journals()
        flush_changes()  # changes noted for later before it was made are not its to tell
        changed: dict[int, RenderingComponent] = {}
        edits: list[tuple[Any, str, Any, int] | None] = []
        #: [a batch of changes noted for later told as a whole (_Bulk, or None), the last such batch (kept), the
        #: components told before that batch (taken out of the dict)]
        held: list[Any] = [None, None, None]
        self._changed = changed
        self._edits = edits
        self._held = held
        # touch() stores into the live journals' dicts directly (no weak reference to follow per change);
        # the journal's collection takes its dict and its edit list out of the lists
        _HELD[id(changed)] = held
        _JOURNALS.append(changed)
        _EDIT_LOGS.append(edits)
        weakref.finalize(self, _forget_journal, changed, edits, held)

    def drain(self) -> list[RenderingComponent]:
        """The components changed since the last drain, in the order they were told of; empties the journal.

        Changes noted for later (:func:`note_later`) are told first.  The list
        is the caller's to read, not to modify: when a simulation's batch of
        changes (see :func:`flush_changes`) is all there is, it is the batch's
        own list, the same object while the same components move frame after
        frame (a reader may recognise it by identity).
        """
        if _FORGOTTEN:
            _prune_journals()
        flush_changes()
        held = self._held
        if held[0] is not None:  # a simulation loop's batch told as a whole (see flush_changes)
            return _drain_held(self._changed, held)
        changed = list(self._changed.values())
        self._changed.clear()
        return changed

    def drain_edits(self) -> list[tuple[Any, str, Any, int]] | None:
        """The list edits since the last drain, in order: ``(container, "insert" | "remove", item, index)``.

        None when more than :data:`EDIT_LIMIT` edits piled up (or an edit
        could not be described): the reader must assume anything changed.
        Empties the log.
        """
        if _FORGOTTEN:
            _prune_journals()
        edits = list(self._edits)
        self._edits.clear()
        return None if None in edits else edits  # type: ignore[return-value]

    def __len__(self) -> int:
        flush_changes()
        if self._held[0] is not None:
            _absorb(self._changed, self._held)
        return len(self._changed)


#: The dicts of the live change journals (a journal's dict leaves the list when the journal is collected).
_JOURNALS: list[dict[int, RenderingComponent]] = []


#: The edit lists of the live change journals (see :func:`note_edit`).
_EDIT_LOGS: list[list[tuple[Any, str, Any, int] | None]] = []
#: Edits a journal keeps before it only records that too many happened (an engine that stopped drawing).
EDIT_LIMIT = 4096


#: id(a live journal's dict) -> [a batch told to it as a whole and not drained yet, the last such batch]
_HELD: dict[int, list[Any]] = {}


#: Journals collected and not yet taken out of the registries: (dict, edit list, held) of each.
_FORGOTTEN: list[tuple[dict, list, list]] = []


def _forget_journal(changed: dict[int, RenderingComponent], edits: list, held: list) -> None:
    """A journal was collected: queue its dict and edit list for :func:`_prune_journals`.

    Finalizers run whenever the garbage collector does, which is often in the
    middle of a loop over :data:`_JOURNALS` or :data:`_EDIT_LOGS` (a store
    into each journal allocates).  Removing an entry there shifted the list
    under that loop, which then skipped the next journal: a live engine missed
    an edit or a change at random (a new node not drawn, about once in a few
    hundred frames of the splice tests).  So nothing is removed here.
    """
    _FORGOTTEN.append((changed, edits, held))


def _prune_journals() -> None:
    """Take the collected journals out of the registries; called where no loop over them runs (a journal
    made, drained, or a list edit told)."""
    while _FORGOTTEN:
        changed, edits, held = _FORGOTTEN.pop()
        if _HELD.get(id(changed)) is held:
            del _HELD[id(changed)]
        for registry, own in ((_JOURNALS, changed), (_EDIT_LOGS, edits)):
            for i, d in enumerate(registry):
                if d is own:
                    del registry[i]
                    break


def note_change(what: Any) -> None:
    """Tell the live journals that ``what`` changed: it is among the next :meth:`ChangeJournal.drain`.

    :meth:`RenderingComponent.touch` does this for a component; a bulk change
    (``om.TranslationArray.touch``) records its one array instead of each of
    its components, for an engine that applies the whole array at once.
    """
    for changed in _JOURNALS:
        changed[id(what)] = what


#: Components changed whose owners and journals are told at the next observation (see :func:`note_later`).
_PENDING: list[RenderingComponent] = []
_FLUSH_LOCK = threading.Lock()
#: Changes :data:`_PENDING` holds before the next one tells them at once (a loop that never observes).
PENDING_LIMIT = 1 << 16


def note_later(component: RenderingComponent) -> None:
    """Record that ``component`` changed; its owners (nodes) and the journals hear of it at the next observation.

    A transform's setter calls this instead of :meth:`RenderingComponent.touch`
    (after bumping its own version): a simulation loop of thousands of
    ``t.offset = row`` then pays one list append per call, and the owners'
    versions and the journals are told once, in one pass, by
    :func:`flush_changes`, which every reader of versions or journals calls
    first (``Node.version`` and every other observation of the graph,
    :meth:`ChangeJournal.drain`, list edits of nodes).
    """
    if component.__class__.__eq__ is not _IDENTITY_EQ:
        _VALUE_EQ[0] = True  # (see _VALUE_EQ)
    _PENDING.append(component)
    if len(_PENDING) > PENDING_LIMIT:
        flush_changes()


def flush_changes() -> None:
    """Tell the owners and the live journals of every component noted for later (:func:`note_later`).

    The journals store each once; the owners are touched (once per time
    their component was noted: a node's version moves at least once).  Cheap
    when nothing is pending (one truth test).  Safe against a thread noting
    changes meanwhile: what is noted after the batch is taken stays pending.

    A batch of at least :data:`BULK_MIN` distinct components (a simulation
    loop's setters) is told to a journal with nothing else in it as a whole,
    without a store per component; the same components again, in the same
    order, reuse the owners collected for the last such batch (a simulation
    moves the same objects every frame), patched when some of them gained
    or lost an owner since (a node's transform replaced, a node removed).
    """
    pending = _PENDING
    if not pending:
        return
    with _FLUSH_LOCK:
        n = len(pending)
        batch = pending[:n]
        del pending[:n]
    if n == 1:  # one component (an editor's drag, one simulated body): told without iterators made
        component = batch[0]
        for changed in _JOURNALS:
            changed[id(component)] = component
        one = component._owners
        if one:
            if len(one) == 1:  # one owner: its own touch (what the owners' touch does for a few), no list made
                one[0].touch()
            elif (touch_one := OWNER_TOUCH[0]) is not None:
                # (an array's kept owner list as it is: the owners' touch recognises it, no pass over it)
                touch_one(one if one.__class__ is _Owners else list(one))
            else:
                for owner in one:
                    owner.touch()
        return
    bulk = _bulk_of(batch) if n >= BULK_MIN else None
    if bulk is None or not bulk.whole:
        for changed in _JOURNALS:
            changed.update(zip(map(id, batch), batch, strict=True))
    else:
        for changed in _JOURNALS:
            held = _HELD.get(id(changed))
            if held is None:  # (a journal being made or collected meanwhile)
                changed.update(zip(map(id, batch), batch, strict=True))
                continue
            _tell_whole(changed, held, bulk)
    if bulk is None:
        # (one component, a touched TranslationArray: its own list, which the owners' touch recognises)
        owners: list[Any] = (
            (batch[0]._owners or []) if n == 1 else list(chain.from_iterable(filter(None, map(_OWNERS_OF, batch))))
        )
    else:
        owners = bulk.owners
        for held in list(_HELD.values()):
            held[1] = bulk  # kept while the journals live: the next batch of the same components finds it
    touch_many = OWNER_TOUCH[0]
    if touch_many is not None:
        touch_many(owners)
    else:
        for owner in owners:
            owner.touch()
    if bulk is not None and owners.base is not None:  # (told: the owners taken out are not kept alive by it)
        owners.base = None
        owners.gone = owners.came = []


#: Batches of at least this many components noted for later are told to journals as a whole (flush_changes).
BULK_MIN = 256


class _Owners(list):  # type: ignore[type-arg]
    """The owners of a batch of components: a list the owners' touch may recognise again (weakly referenced).

    One made from the last batch's owners when some of its components
    gained or lost an owner since (:func:`_bulk_of`) says how, until its
    owners are told: ``base`` (that list), ``gone`` (owners taken out, one
    entry per occurrence) and ``came`` (owners added); the owners' touch
    may follow what it kept for ``base`` instead of a pass over the list.
    """

    __slots__ = ("base", "gone", "came", "__weakref__")

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.base: Any = None
        self.gone: list[Any] = []
        self.came: list[Any] = []


class _Bulk:
    """A batch of components noted for later, with their owners.

    ``whole``: it is told to journals as a whole (its components are
    distinct, ``ids`` holds theirs, and it came at least twice: a batch seen
    once is told component by component, as cheap as finding out).
    """

    __slots__ = ("components", "owners", "ids", "whole", "__weakref__")

    def __init__(self, components: list[Any], owners: _Owners | None = None) -> None:
        self.components = components
        if owners is None:
            owners = _Owners(chain.from_iterable(filter(None, map(_OWNERS_OF, components))))
        self.owners = owners
        self.ids: set[int] | None = None
        self.whole = False

    def distinct(self) -> bool:
        """Whether no component is in it twice (``ids`` made on the first call)."""
        if self.ids is None:
            self.ids = set(map(id, self.components))
        return len(self.ids) == len(self.components)


#: The last batch seen (weakly: the journals told of it keep it), for :func:`_bulk_of`.
_LAST_BULK: list[Any] = [None]
#: the components that gained or lost an owner since :func:`_bulk_of` last looked, in order: ``(id(component),
#: a weak reference to the owner or None, +1 gained / -1 lost)`` (None: too many)
_RELINKED: list[list[tuple[int, Any, int]] | None] = [[]]
#: components :data:`_RELINKED` lists before it only records that too many changed
RELINKED_LIMIT = 1024
#: components told to a journal before a batch told as a whole that it keeps aside (more: the batch is stored
#: component by component)
BEFORE_LIMIT = 64


def _bulk_of(batch: list[Any]) -> _Bulk | None:
    """``batch`` as a :class:`_Bulk`: the last one when it holds the same components in the same order and
    none of them gained or lost an owner since (then ``whole`` when they are distinct), else a new one; None
    when no journal would keep it."""
    if not _JOURNALS:
        return None
    ref = _LAST_BULK[0]
    last = ref() if ref is not None else None
    relinked = _RELINKED[0]
    _RELINKED[0] = []
    if last is not None and len(last.components) == len(batch) and _same_objects(batch, last.components):
        if relinked is not None and not relinked:
            last.whole = last.distinct()
            return last
        if relinked is not None and last.distinct():
            ids = last.ids
            assert ids is not None
            mine = [event for event in relinked if event[0] in ids]
            if not mine:
                last.whole = True
                return last
            owners = _patched(last.owners, mine)
            if owners is not None:  # (the same components, some with other owners: the owners patched)
                bulk = _Bulk(last.components, owners)
                bulk.ids = ids
                bulk.whole = True
                _LAST_BULK[0] = weakref.ref(bulk)
                return bulk
    bulk = _Bulk(batch)
    _LAST_BULK[0] = weakref.ref(bulk)
    return bulk


#: Whether something noted for later compares by value (its class defines ``__eq__``): a component class that
#: does (``RenderingComponent.__init_subclass__``), or anything else given to :func:`note_later` that does
_VALUE_EQ = [False]
_IDENTITY_EQ = object.__eq__


def _same_objects(a: list[Any], b: list[Any]) -> bool:
    """Whether the lists ``a`` and ``b`` (of one length) hold the same objects in the same order.

    A list comparison (one C loop whose item test is an identity test first) while nothing noted for later
    compares by value: two distinct objects then compare unequal.  Otherwise a pass of identity tests.
    """
    if _VALUE_EQ[0]:
        return all(map(is_, a, b))
    return a == b


def _patched(owners: _Owners, events: list[tuple[int, Any, int]]) -> _Owners | None:
    """A copy of ``owners`` with the owners that ``events`` (of components of its batch) say were gained added
    and those lost taken out (one occurrence each), saying so (:class:`_Owners`); None when an event names an
    owner that is gone or not among them."""
    out = _Owners(owners)
    out.base = owners  # (until told: flush_changes lets it go)
    for _, ref, sign in events:
        owner = ref() if ref is not None else None
        if owner is None:
            return None
        if sign > 0:
            out.append(owner)
            out.came.append(owner)
            continue
        try:
            at = indexOf(out, owner)
        except ValueError:
            return None
        if out[at] is not owner:  # (an owner that compares equal to another: found again by identity)
            at = next((i for i, o in enumerate(out) if o is owner), -1)
            if at < 0:
                return None
        del out[at]
        out.gone.append(owner)
    return out


def _tell_whole(changed: dict[int, Any], held: list[Any], bulk: _Bulk) -> None:
    """Tell a journal (its dict and its ``held`` list) of the batch ``bulk`` as a whole where it can."""
    ids = bulk.ids
    assert ids is not None
    if held[0] is bulk and not changed:
        return  # the same components told already, nothing since
    if held[0] is None and len(changed) <= BEFORE_LIMIT and ids.isdisjoint(changed):
        held[0] = bulk
        held[2] = list(changed.values()) if changed else None  # told before the batch: they come first
        changed.clear()
        return
    if held[0] is not None:
        _absorb(changed, held)
    changed.update(zip(map(id, bulk.components), bulk.components, strict=True))


def _relinked(component: Any, owner: Any, sign: int) -> None:
    """``component`` gained (``sign`` +1) or lost (-1) ``owner``: a batch holding it has its owners patched."""
    found = _RELINKED[0]
    if found is not None:
        if len(found) < RELINKED_LIMIT:
            try:
                ref = weakref.ref(owner)
            except TypeError:  # (an owner without weak references: the batch's owners are collected again)
                ref = None
            found.append((id(component), ref, sign))
        else:
            _RELINKED[0] = None


def _absorb(changed: dict[int, Any], held: list[Any]) -> None:
    """Make the batch a journal holds as a whole (``held``), and what was told before it, entries of its dict
    ``changed``, before the entries the dict holds (told after the batch), each once."""
    bulk, before = held[0], held[2]
    held[0] = held[2] = None
    later = list(changed.items())
    changed.clear()
    if before:
        changed.update(zip(map(id, before), before, strict=True))
    changed.update(zip(map(id, bulk.components), bulk.components, strict=True))
    changed.update(later)


def _drain_held(changed: dict[int, Any], held: list[Any]) -> list[Any]:
    """What a journal holding a batch as a whole drains: what came before it, the batch, what came after (each
    once); empties the journal."""
    bulk, before = held[0], held[2]
    if len(changed) > BEFORE_LIMIT:
        _absorb(changed, held)
        out = list(changed.values())
        changed.clear()
        return out
    held[0] = held[2] = None
    if not before and not changed:
        return bulk.components  # (the batch's own list: the same object while the same components move)
    out = list(before) if before else []
    out.extend(bulk.components)
    if changed:
        ids = bulk.ids
        first = set(map(id, before)) if before else ()
        out.extend(v for k, v in changed.items() if k not in ids and k not in first)
        changed.clear()
    return out


#: How :func:`flush_changes` touches the owners it collected: ``[None]`` calls each one's ``touch()``; the scene
#: package installs a function that touches many nodes in C-level loops (and others one by one).
OWNER_TOUCH: list[Callable[[list[Any]], None] | None] = [None]


def note_edit(container: Any, op: str, item: Any, index: int) -> None:
    """Tell the live journals that ``container``'s list changed: ``op`` ("insert", "remove", or another word for
    a change they cannot follow) of ``item`` at ``index``.  Nodes call it; engines read it with
    :meth:`ChangeJournal.drain_edits` to update only what the edit touches."""
    if _FORGOTTEN:
        _prune_journals()
    for log in _EDIT_LOGS:
        if len(log) < EDIT_LIMIT:
            log.append((container, op, item, index))
        elif len(log) == EDIT_LIMIT:
            log.append(None)


class RenderingComponent:
    """Base of everything a node can hold: shapes, attributes, handlers, techniques."""

    __slots__ = ("_version", "_owners", "__weakref__")

    #: Render hints for viewers and techniques (``"transparent"``, ``"2d"``).
    hints: frozenset[str] = frozenset()
    #: Declarative pre-evaluation (see :mod:`.declarations`): ``"all"`` placements are collected
    #: (lights), only the ``"first"`` (camera, background), or None: the component is not declarative.
    declared: str | None = None

    #: Slots left out of pickles and copies, with a factory for the value they are restored to.
    #: Subclasses add their caches (merged along the MRO); owners are re-attached by the nodes.
    _transient: dict[str, Callable[[], Any]] = {"_owners": lambda: None}

    def __init__(self) -> None:
        object.__setattr__(self, "_version", 0)
        object.__setattr__(self, "_owners", None)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__eq__ is not _IDENTITY_EQ:  # batches of its changes are compared object by object (_same_objects)
            _VALUE_EQ[0] = True

    def __setattr__(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)
        if name[0] != "_":
            try:
                self.touch()
            except AttributeError:
                raise TypeError(
                    f"{type(self).__name__}.__init__ must call super().__init__() before setting {name!r}"
                ) from None

    @property
    def version(self) -> int:
        """Counter bumped on every change of a public parameter."""
        return self._version

    @property
    def owners(self) -> tuple[Any, ...]:
        """The nodes that hold this component (one per occurrence in a node's list)."""
        return tuple(self._owners or ())

    def touch(self) -> None:
        """Mark the component as changed: bump its version and its owners' versions, and tell the journals."""
        _set_version(self, self._version + 1)
        for changed in _JOURNALS:
            changed[id(self)] = self
        owners = self._owners
        if owners:
            for node in owners:
                node.touch()

    @staticmethod
    def touch_all(components: list[RenderingComponent], *, journal_entry: Any = None) -> None:
        """:meth:`touch` every one of ``components`` (distinct), in loops that take no Python step per component.

        The journals are told in one update each: of every component, or, with
        ``journal_entry``, of that one object instead (see :func:`note_change`).
        """
        deque(map(_set_version, components, map(_PLUS_ONE, map(_VERSION_OF, components))), 0)
        if journal_entry is not None:
            note_change(journal_entry)
        else:
            for changed in _JOURNALS:
                changed.update(zip(map(id, components), components, strict=True))
        for owner in chain.from_iterable(filter(None, map(_OWNERS_OF, components))):
            owner.touch()

    def attach_owner(self, owner: Any) -> None:
        """Make ``owner`` (anything with ``touch()``: a node, a shape built from this one) hear of changes."""
        self._attach(owner)

    def detach_owner(self, owner: Any) -> None:
        """Undo :meth:`attach_owner`."""
        self._detach(owner)

    def _attach(self, owner: Any) -> None:
        _relinked(self, owner, 1)
        owners = self._owners
        if owners is None:
            object.__setattr__(self, "_owners", [owner])
        else:
            owners.append(owner)

    def _detach(self, owner: Any) -> None:
        owners = self._owners
        if owners:
            for i, o in enumerate(owners):
                if o is owner:
                    del owners[i]
                    _relinked(self, owner, -1)
                    break

    # -- pickling and copying ----------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        """Every slot (and ``__dict__`` entry) except the transient ones; see the module docs."""
        transient = _transient_of(type(self))
        state: dict[str, Any] = {}
        for name in _slots_of(type(self)):
            if name not in transient:
                try:
                    state[name] = object.__getattribute__(self, name)
                except AttributeError:  # an unset slot stays unset
                    pass
        extra = getattr(self, "__dict__", None)
        if extra:
            state.update((k, v) for k, v in extra.items() if k not in transient)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        # object.__setattr__: restoring must not run validation or bump versions through __setattr__
        for name, make in _transient_of(type(self)).items():
            object.__setattr__(self, name, make())
        for name, value in state.items():
            object.__setattr__(self, name, value)

    def parameters(self) -> dict[str, Any]:
        """The public parameters as a dict (used by scene files, traces and repr)."""
        out: dict[str, Any] = {}
        for cls in type(self).__mro__:
            for name in getattr(cls, "__slots__", ()):
                if not name.startswith("_") and name not in out and hasattr(self, name):
                    out[name] = getattr(self, name)
        return out

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={_short(v)}" for k, v in self.parameters().items())
        return f"{type(self).__name__}({params})"


#: The ``_version`` slot's setter: a change bumps the version without going through ``__setattr__``.
_set_version = RenderingComponent._version.__set__  # type: ignore[attr-defined]
_VERSION_OF = attrgetter("_version")
_OWNERS_OF = attrgetter("_owners")
_PLUS_ONE = (1).__add__

_SLOTS: dict[type, tuple[str, ...]] = {}
_TRANSIENT: dict[type, dict[str, Callable[[], Any]]] = {}


def _slots_of(cls: type) -> tuple[str, ...]:
    """Every slot name declared along ``cls``'s MRO (base classes first), without ``__weakref__``."""
    found = _SLOTS.get(cls)
    if found is None:
        names: list[str] = []
        for klass in reversed(cls.__mro__):
            slots = klass.__dict__.get("__slots__", ())
            for name in (slots,) if isinstance(slots, str) else slots:
                if name.startswith("__") and not name.endswith("__"):  # name-mangled private slot
                    name = f"_{klass.__name__.lstrip('_')}{name}"
                if name not in ("__weakref__", "__dict__") and name not in names:
                    names.append(name)
        found = _SLOTS[cls] = tuple(names)
    return found


def _transient_of(cls: type) -> dict[str, Callable[[], Any]]:
    """The merged ``_transient`` tables along ``cls``'s MRO (subclasses win)."""
    found = _TRANSIENT.get(cls)
    if found is None:
        merged: dict[str, Callable[[], Any]] = {}
        for klass in reversed(cls.__mro__):
            merged.update(klass.__dict__.get("_transient", {}))
        found = _TRANSIENT[cls] = merged
    return found


def _short(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return text.replace("\n", " ")


class Shape(RenderingComponent):
    """Something perceived as an entity of the target medium (sphere, mesh, text).

    Engines evaluate shapes through handlers looked up by the shape's class:
    a painter for the technique's service, else a simplifier that turns the shape
    into simpler components, else the same for the parent class.
    """

    __slots__ = ()


class Attribute(RenderingComponent):
    """A modifier of shape evaluation (colour, material, transform, light...).

    ``category`` is the key of the context stack or set the attribute lives in.
    It defaults to the attribute's own class; a class that sets
    ``shares_category = True`` in its body makes itself the category of all its
    subclasses (all lights share ``Light``, all transforms share ``Transform``);
    a class may also name another category explicitly (``category = Transform``).
    """

    __slots__ = ()
    category: type = None  # type: ignore[assignment]
    shares_category = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "category" in cls.__dict__:  # set explicitly in the class body
            return
        for base in cls.__mro__:
            if base.__dict__.get("shares_category", False):
                cls.category = base
                return
        cls.category = cls


class MonoAttribute(Attribute):
    """Attribute kept on a per-category stack; only the top one is active."""

    __slots__ = ()


class PolyAttribute(Attribute):
    """Attribute kept in a per-category set; any number are active at once."""

    __slots__ = ()


Attribute.category = Attribute
MonoAttribute.category = MonoAttribute
PolyAttribute.category = PolyAttribute


def category_of(attribute: Attribute) -> type:
    """The category key of ``attribute`` (its class unless a base shares one)."""
    return attribute.category
