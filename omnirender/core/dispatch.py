"""The engine's handler look-up caches, patched per (service, target) on install and deinstall.

Resolving the handler of a class walks its MRO (service handler, then
simplifier, at each class); the result is cached per service and class, so a
traversal dispatches with one dict look-up.  Installing a handler does not
clear the caches: only the cached classes it can affect (subclasses of its
target, for its service, or for every service when it is a simplifier) are
re-pointed to it, and the previous entries are saved in a *patch* that
deinstalling restores.  A node that installs a handler for its subgraph
therefore costs two small patches, not a re-resolution of every class (Coin3D
fills its method tables once; here they are patched in place).  Which cached
entries a (service, target) affects is planned once and kept until an entry is
added or dropped.

Patches nest like node evaluation.  An entry first resolved while handlers
are installed that could win for its class is resolved again without each of
them, and the patches save those values, so deinstalling restores the right
entry instead of dropping it.  A deinstall that is not
the most recent install (rare: only by hand) falls back to clearing every
cache.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["HandlerCaches", "ServiceCache", "SERVICE", "SIMPLIFIER", "NOTHING"]

#: How a cached entry was resolved: by a handler of the service, by a simplifier, or not at all.
SERVICE, SIMPLIFIER, NOTHING = 0, 1, 2


class _Table:
    """Resolved values by class, with where along the MRO and how each was found."""

    __slots__ = ("values", "found")

    def __init__(self) -> None:
        self.values: dict[type, Any] = {}
        self.found: dict[type, tuple[int, int]] = {}


class ServiceCache:
    """Resolved shape functions and attribute handlers of one service.

    ``shapes[cls]`` is the function that evaluates a shape of ``cls``;
    ``attributes[cls]`` the handler applying an attribute of ``cls`` (None:
    passive).
    """

    __slots__ = ("service", "shape_table", "attribute_table", "shapes", "attributes")

    def __init__(self, service: str) -> None:
        self.service = service
        self.shape_table = _Table()
        self.attribute_table = _Table()
        self.shapes = self.shape_table.values
        self.attributes = self.attribute_table.values

    def clear(self) -> None:
        for table in (self.shape_table, self.attribute_table):
            table.values.clear()
            table.found.clear()


class HandlerCaches:
    """Per-service :class:`ServiceCache` objects and the patch stack of installed handlers."""

    __slots__ = ("services", "_patches", "_simplify", "_plans", "simplifying", "stacks", "deinstall_elsewhere")

    def __init__(
        self,
        simplify: str,
        simplifying: Callable[[Any], Any],
        stacks: dict[tuple[str, type], list[Any]],
        deinstall_elsewhere: Callable[[Any], None],
    ) -> None:
        self.services: dict[str, ServiceCache] = {}
        #: turns a simplifier into the function shapes call (the engine's)
        self.simplifying = simplifying
        #: the engine's handler stacks by (service, target)
        self.stacks = stacks
        #: the engine's general deinstall, for a handler that is not the most recently installed one
        self.deinstall_elsewhere = deinstall_elsewhere
        # the patch stack, innermost last: (handler, [(values, found, class, value, found to restore)] or None)
        self._patches: list[tuple[Any, list[tuple[dict, dict, type, Any, tuple[int, int]]] | None]] = []
        self._simplify = simplify
        # (service, target) -> [(values, found, class, MRO index of target, shape table?, found when taken over)]
        self._plans: dict[tuple[str, type], list[tuple[dict, dict, type, int, bool, tuple[int, int]]]] = {}

    def service(self, service: str) -> ServiceCache:
        cache = self.services.get(service)
        if cache is None:
            cache = self.services[service] = ServiceCache(service)
        return cache

    def clear(self) -> None:
        """Forget every resolution (registry changed, state rolled back)."""
        for cache in self.services.values():
            cache.clear()
        self._patches.clear()
        self._plans.clear()

    def store(
        self,
        cache: ServiceCache,
        shapes: bool,
        cls: type,
        resolved: tuple[Any, int, int],
        rewalk: Callable[[list[Any]], tuple[Any, int, int]],
    ) -> None:
        """Cache ``resolved`` = (value, MRO index, kind) for ``cls``; remember what it becomes on deinstalls.

        When installed handlers could win for ``cls``, the entry depends on
        them: ``rewalk(handlers)`` resolves ``cls`` again as if ``handlers``
        were not installed, and each such patch saves the value to restore, so
        the entry survives the deinstalls with the right value.
        """
        table = cache.shape_table if shapes else cache.attribute_table
        if cls not in table.values:
            self._plans.clear()
        value, index, kind = resolved
        table.values[cls] = value
        table.found[cls] = (index, kind)
        patches = self._patches
        if not patches:
            return
        simplify = self._simplify
        removed: list[Any] = []
        for level in range(len(patches) - 1, -1, -1):
            h, saved = patches[level]
            if (h.service == cache.service or h.service == simplify) and issubclass(cls, h.target):
                removed.append(h)
                base, base_index, base_kind = rewalk(removed)
                if saved is None:
                    saved = []
                    patches[level] = (h, saved)
                saved.append((table.values, table.found, cls, base, (base_index, base_kind)))

    def _plan(self, service: str, target: type) -> list[tuple[dict, dict, type, int, bool, tuple[int, int]]]:
        """The cached entries a handler for (service, target) may take over, with the found it would give them."""
        plan = []
        simplifier = service == self._simplify
        kind = SIMPLIFIER if simplifier else SERVICE
        for cache in self.services.values():
            if not simplifier and cache.service != service:
                continue
            for table, shapes in ((cache.shape_table, True), (cache.attribute_table, False)):
                for cls in table.values:
                    if issubclass(cls, target):
                        j = cls.__mro__.index(target)
                        plan.append((table.values, table.found, cls, j, shapes, (j, kind)))
        self._plans[(service, target)] = plan
        return plan

    def install(self, handler: Any) -> None:
        """Push ``handler`` on its (service, target) stack of ``stacks`` and patch the caches (the INSTALL op)."""
        key = (handler.service, handler.target)
        stack = self.stacks.get(key)
        if stack is None:
            stack = self.stacks[key] = []
        stack.append(handler)
        self.installed(handler, key)

    def deinstall(self, handler: Any) -> None:
        """The DEINSTALL op: pop ``handler`` (normally the top of its stack) and undo its patch."""
        stack = self.stacks.get((handler.service, handler.target))
        if stack and stack[-1] is handler and self._patches and self._patches[-1][0] is handler:
            stack.pop()
            saved = self._patches.pop()[1]
            if saved:
                for values, found, cls, value, old in reversed(saved):
                    values[cls] = value
                    found[cls] = old
        else:
            self.deinstall_elsewhere(handler)

    def installed(self, handler: Any, key: tuple[str, type]) -> None:
        """Re-point the cached classes ``handler`` (for ``key`` = (service, target)) now wins for.

        :meth:`deinstalled` undoes the patch.
        """
        plan = self._plans.get(key)
        if plan is None:
            plan = self._plan(*key)
        saved = None
        if plan:
            simplifier = key[0] == self._simplify
            shape_fn = None
            for values, found, cls, j, shapes, now in plan:
                old = found[cls]
                k = old[0]
                if j < k or (j == k and (not simplifier or old[1] == SIMPLIFIER)):
                    if saved is None:
                        saved = []
                    saved.append((values, found, cls, values[cls], old))
                    if shapes:
                        if shape_fn is None:
                            shape_fn = self.simplifying(handler) if simplifier else handler.exec
                        values[cls] = shape_fn
                    else:
                        values[cls] = handler
                    found[cls] = now
        self._patches.append((handler, saved))

    def deinstalled(self, handler: Any) -> bool:
        """Undo ``handler``'s patch; False when it was not the most recent one (then every cache is cleared)."""
        patches = self._patches
        if not patches or patches[-1][0] is not handler:
            self.clear()
            return False
        saved = patches.pop()[1]
        if saved:
            for values, found, cls, value, old in reversed(saved):
                values[cls] = value
                found[cls] = old
        return True
