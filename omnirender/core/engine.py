"""The engine: the state machine every node and application talks to.

An engine owns a :class:`RenderingContext` and an active :class:`Technique`.
Its interface is the paper's micro program: ``push``/``pop`` mono attributes,
``add``/``remove`` poly attributes, ``install``/``deinstall`` handlers and
``eval`` shapes.  Handlers are resolved per class once and cached; install and
deinstall patch only the cached classes they affect (see :mod:`.dispatch`),
and new registered defaults clear the caches.

The engine is also the one interpreter of compiled micro programs
(:mod:`.program`).  Engines that mirror the graph hook into it through named,
public methods: :meth:`Engine.on_enter` / :meth:`Engine.on_leave` (a node's
contents begin / end), :meth:`Engine.eval_node` (a child node kept as one op:
group masks, per-node caches) and :meth:`Engine.run_technique` (a technique's
scope).  Technique runs keep their pass state in the engine's frame stack
(:attr:`Engine.technique_frame`).
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import numpy as np

from .camera import Camera
from .component import Attribute, MonoAttribute, PolyAttribute, Shape
from .context import RenderingContext
from .declarations import Declarations
from .dispatch import NOTHING, SERVICE, SIMPLIFIER, HandlerCaches
from .errors import EvaluationError, NoHandlerError
from .handler import SIMPLIFY, Handler, registry
from .light import Light, LightSwitch, light_on
from .program import (
    ADD,
    DEINSTALL,
    ENTER,
    EVAL,
    INSTALL,
    LEAVE,
    NODE,
    OPCODE_NAMES,
    POP,
    PUSH,
    REMOVE,
    TECHNIQUE,
    compile_components,
)
from .technique import Technique, TechniqueFrame

__all__ = ["Engine"]

_POLICIES = ("raise", "warn", "skip")
_IDENTITY = np.eye(4)
_IDENTITY.setflags(write=False)
_MISSING = object()


class Engine:
    """A generic engine; adapters subclass it and set ``service``.

    ``on_missing`` decides what happens to a shape no handler can evaluate:
    ``"raise"`` (:class:`NoHandlerError`), ``"warn"`` (once per class) or
    ``"skip"``.  ``mask`` is a group-mask expression; subgraphs whose groups do
    not match are skipped.
    """

    #: The service the default technique asks handlers for.
    service: str = "analysis"
    #: Whether a camera's own group mask applies when the engine has none.
    #: Engines that produce an image of what the camera sees set this; analysis
    #: engines (bounds, collisions, statistics) see the whole graph.
    uses_camera_mask: bool = False

    def __init__(
        self,
        *,
        technique: Technique | None = None,
        on_missing: str = "raise",
        mask: str | Callable[[frozenset[str]], bool] | None = None,
    ) -> None:
        if on_missing not in _POLICIES:
            raise ValueError(f"{type(self).__name__}: on_missing must be one of {_POLICIES}, got {on_missing!r}")
        self.context = RenderingContext()
        self._mono = self.context._mono  # the mono stacks, one attribute lookup less per push/pop
        self.on_missing = on_missing
        self._handlers = self.context._handlers  # the handler stacks
        self._caches = HandlerCaches(SIMPLIFY, _simplifying, self._handlers, self.deinstall)
        self._registry_generation = registry.generation
        self._node_stack: list[Any] = []
        self._frames: list[list[Any]] = []
        self._poly_frames: dict[int, list[Any]] = {}
        self._warned: set[type] = set()
        self._light_matrices: dict[int, np.ndarray] = {}
        self._pre_lights: dict[int, Any] = {}
        # (light, world matrix) per placement found by pre-evaluation: a light in a
        # node shared under two transforms shines from both places.
        self._placements: list[tuple[Light, np.ndarray]] = []
        self._running = 0
        self._simplify_depth = 0
        self._technique_frames: list[TechniqueFrame] = []
        #: (camera, world matrix) found by pre-evaluation, or None.
        self.camera: tuple[Camera, np.ndarray] | None = None
        #: What the last pre-evaluation found (lights, camera, first Background...), or None.
        self.declared: Declarations | None = None
        self.mask = mask
        self._saved_mask_fn = self._mask_fn
        cls = type(self)
        hooked = cls.on_enter is not Engine.on_enter or cls.on_leave is not Engine.on_leave
        ops: dict[int, Callable[[Any], Any]] = {
            PUSH: self.push,
            POP: self._pop_op if cls.pop is Engine.pop else self._pop_expected,
            ADD: self.add,
            REMOVE: self.remove,
            # the compiler checked these are Handlers: the caches push/pop the stacks and patch themselves
            INSTALL: self._caches.install if cls.install is Engine.install else self.install,
            DEINSTALL: self._caches.deinstall if cls.deinstall is Engine.deinstall else self.deinstall,
            EVAL: self.eval,
            ENTER: self._enter_hooked if hooked else self._node_stack.append,
            LEAVE: self._leave_hooked if hooked else self._node_stack.pop,
            NODE: self._node_op,
            TECHNIQUE: self._technique_op,
        }
        #: The dispatch table of compiled programs, indexed by opcode (built by name, see OPCODE_NAMES).
        self._ops: list[Callable[[Any], Any]] = [ops[code] for code in range(len(OPCODE_NAMES))]
        self._technique: Technique = technique if technique is not None else Technique()
        self._select_caches()

    # -- node hooks -------------------------------------------------------
    def on_enter(self, node: Any) -> None:
        """Called before a node's contents are evaluated (override in subclasses).

        Engines that mirror the graph's structure (exporters, the GL engine's
        per-node caches) use it; the plain engine does not pay for it.
        """

    def on_leave(self, node: Any) -> None:
        """Called after a node's contents were evaluated and undone."""

    def _enter_hooked(self, node: Any) -> None:
        self._node_stack.append(node)
        self.on_enter(node)

    def _leave_hooked(self, _arg: Any) -> None:
        self.on_leave(self._node_stack.pop())

    def eval_node(self, node: Any) -> tuple[list[tuple[int, Any]], Callable[[], None] | None] | None:
        """A child node kept as one op (a node with groups, or any child of a local program).

        Returns the program to evaluate for it and a function to call after it
        (or None), which the interpreter runs without recursion; None when the
        node is done (skipped because the group mask rejects it, or handled
        here).  Engines with per-node caches override this: a cache hit
        returns None, a miss ``node.local_program()`` with the function that
        stores what it produced.
        """
        groups = node.groups
        if groups and self._mask_fn is not None and not self._mask_fn(groups):
            return None
        return node.program(), None

    def run_technique(self, technique: Technique, program: list[tuple[int, Any]]) -> None:
        """Evaluate ``program`` (the rest of a node after ``technique``) with ``technique``.

        A technique this engine cannot run (``technique.supported(engine)`` is
        False) is ignored: the program is evaluated once with the enclosing
        technique.  Engines that run passes at another time (the GL engine
        draws them every frame) override this.
        """
        if not technique.supported(self):
            self.run_program(program)
            return
        previous = self._technique
        self.technique = technique
        try:
            technique.run(program, self)
        finally:
            self.technique = previous

    def _technique_op(self, arg: tuple[Technique, list[tuple[int, Any]]]) -> None:
        self.run_technique(arg[0], arg[1])

    # -- technique frames (pass state) --------------------------------------
    def enter_technique(self, technique: Technique) -> TechniqueFrame:
        """Push a frame for a run of ``technique`` (its pass index and data); returns it."""
        frame = TechniqueFrame(technique)
        self._technique_frames.append(frame)
        return frame

    def leave_technique(self, technique: Technique) -> TechniqueFrame:
        """Pop the frame of ``technique``'s run."""
        frames = self._technique_frames
        if not frames or frames[-1].technique is not technique:
            raise EvaluationError(
                f"{type(self).__name__}: leave_technique({type(technique).__name__}) does not match the innermost "
                f"technique run ({frames[-1] if frames else 'none'}); enter and leave techniques in nested order"
            )
        return frames.pop()

    @property
    def technique_frame(self) -> TechniqueFrame:
        """The frame of the innermost technique run (RuntimeError outside any run)."""
        if not self._technique_frames:
            raise RuntimeError(
                f"{type(self).__name__}: no technique is running; technique_frame and current_pass exist only "
                f"inside a technique's start/needs_pass/prepare_pass/finish_pass/next_pass/stop"
            )
        return self._technique_frames[-1]

    @property
    def technique_frames(self) -> tuple[TechniqueFrame, ...]:
        """Frames of the running techniques, outermost first."""
        return tuple(self._technique_frames)

    @property
    def current_pass(self) -> int:
        """The pass (0-based) of the innermost running technique."""
        return self.technique_frame.index

    @property
    def running(self) -> bool:
        """Whether a traversal (``run``) is under way."""
        return self._running > 0

    # -- technique ----------------------------------------------------------
    @property
    def technique(self) -> Technique:
        """The active technique."""
        return self._technique

    @technique.setter
    def technique(self, technique: Technique) -> None:
        if not isinstance(technique, Technique):
            raise TypeError(f"{type(self).__name__}.technique must be a Technique, got {type(technique).__name__}")
        self._technique = technique
        self._select_caches()

    @contextlib.contextmanager
    def using(self, technique: Technique) -> Iterator[Technique]:
        """Substitute ``technique`` temporarily (restored on exit)."""
        previous = self._technique
        self.technique = technique
        try:
            yield technique
        finally:
            self.technique = previous

    @property
    def active_service(self) -> str:
        """The service handlers are looked up for right now."""
        return self._technique.service or self.service

    def _select_caches(self) -> None:
        service = self._technique.service or self.service
        cache = self._service_cache = self._caches.service(service)
        tcls = type(self._technique)
        self._attr_via_technique = tcls.handle_attribute is not Technique.handle_attribute
        # When the technique decides per attribute, push/pop see an empty cache and ask it.
        self._shape_fns = cache.shapes
        self._attr_handlers = {} if self._attr_via_technique else cache.attributes
        direct = type(self).eval is Engine.eval and tcls.handle_shape is Technique.handle_shape
        self._ops[EVAL] = self._eval_direct if direct else self.eval

    def _invalidate(self) -> None:
        self._caches.clear()

    # -- handler resolution ----------------------------------------------
    def find_handler(self, service: str, target: type) -> Any:
        """The top installed handler for (service, target), else the registered default."""
        h = self.context.handler(service, target)
        if h is None:
            h = registry.lookup(type(self), service, target)
        return h

    def sync_registry(self) -> None:
        """Forget cached look-ups if default handlers were registered since (engines call it before a traversal)."""
        self._check_registry()

    def _check_registry(self) -> None:
        if self._registry_generation != registry.generation:
            self._registry_generation = registry.generation
            self._invalidate()

    def shape_handler(self, cls: type) -> Callable[[Any, Engine], Any]:
        """The function evaluating shapes of ``cls`` for the active service (painter, simplifier or policy)."""
        fn = self._shape_fns.get(cls)
        if fn is None:
            fn = self._resolve_shape(cls)
        return fn

    def _resolve_shape(self, cls: type) -> Callable[[Any, Engine], Any]:
        self._check_registry()
        resolved = self._walk(cls, True)
        if resolved[0] is None:
            resolved = (self._missing(self.active_service, cls), resolved[1], resolved[2])
        self._caches.store(self._service_cache, True, cls, resolved, lambda hs: self._rewalk(cls, True, hs))
        return resolved[0]

    def attribute_handler(self, cls: type) -> Any:
        """The painter or simplifier that applies attributes of ``cls``, or None."""
        self._check_registry()
        cache = self._service_cache
        try:
            return cache.attributes[cls]
        except KeyError:
            pass
        resolved = self._walk(cls, False)
        self._caches.store(cache, False, cls, resolved, lambda hs: self._rewalk(cls, False, hs))
        return resolved[0]

    def _walk(self, cls: type, shapes: bool) -> tuple[Any, int, int]:
        """(value, MRO index, kind): the handler look-up of DESIGN.md for ``cls``, nothing cached.

        ``value`` is the function evaluating shapes (``shapes=True``, None if
        nothing was found) or the attribute handler (None: passive).
        """
        service = self._service_cache.service
        mro = cls.__mro__
        for i, klass in enumerate(mro):
            if klass is object:
                break
            h = self.find_handler(service, klass)
            if h is not None:
                return (h.exec if shapes else h), i, SERVICE
            h = self.find_handler(SIMPLIFY, klass)
            if h is not None:
                return (_simplifying(h) if shapes else h), i, SIMPLIFIER
        return None, len(mro), NOTHING

    def _rewalk(self, cls: type, shapes: bool, handlers: list[Handler]) -> tuple[Any, int, int]:
        """:meth:`_walk` as if ``handlers`` (each on top of its stack, innermost first) were not installed."""
        stacks = [self.context.handler_stack(h.service, h.target) for h in handlers]
        for stack in stacks:
            stack.pop()
        try:
            resolved = self._walk(cls, shapes)
        finally:
            for stack, h in zip(reversed(stacks), reversed(handlers), strict=True):
                stack.append(h)
        if shapes and resolved[0] is None:
            resolved = (self._missing(self.active_service, cls), resolved[1], resolved[2])
        return resolved

    def _missing(self, service: str, cls: type) -> Callable[[Any, Engine], Any]:
        policy = self.on_missing
        if policy == "raise":

            def fail(shape: Any, engine: Engine) -> None:
                raise NoHandlerError(service, cls, engine.node_path, type(engine).__name__)

            return fail
        if policy == "warn":

            def warn(shape: Any, engine: Engine) -> None:
                if cls not in engine._warned:
                    engine._warned.add(cls)
                    warnings.warn(
                        str(NoHandlerError(service, cls, engine.node_path, type(engine).__name__)), stacklevel=2
                    )

            return warn
        return _skip

    # -- the micro program ------------------------------------------------
    def _handler_for(self, attribute: Attribute) -> Any:
        # Slow path of push/pop: the class is not in the look-up cache (first
        # sight, or the active technique decides per attribute).
        if self._attr_via_technique:
            return self._technique.handle_attribute(attribute, self)
        return self.attribute_handler(attribute.__class__)

    def push(self, attribute: Attribute) -> None:
        """Make ``attribute`` the active one of its category."""
        h = self._attr_handlers.get(attribute.__class__, _MISSING)
        if h is None:
            self._mono[attribute.category].append(attribute)
            return
        if h is _MISSING:
            if not isinstance(attribute, MonoAttribute):
                raise TypeError(
                    f"push() needs a MonoAttribute, got {type(attribute).__name__}{self._where()}; "
                    f"poly attributes are add()ed"
                )
            h = self._handler_for(attribute)
            if h is None:
                self._mono[attribute.category].append(attribute)
                return
        if h.service == SIMPLIFY:
            record = self._record(h, attribute)
            self._frames.append([attribute, h, len(self._mono[attribute.category]), record])
            return
        self._mono[attribute.category].append(attribute)
        h.exec(attribute, self)

    def pop(self, category: type) -> Attribute:
        """Remove the active attribute of ``category`` and return it."""
        if self._frames:
            frame = self._frames[-1]
            if frame[0].category is category and len(self._mono[category]) == frame[2]:
                self._frames.pop()
                attribute, h, _, record = frame
                h.unexec(attribute, self, record)
                return attribute
        stack = self._mono.get(category)
        if not stack:
            name = getattr(category, "__name__", repr(category))
            raise EvaluationError(
                f"pop({name}){self._where()}: nothing of category {name} is pushed (unbalanced push/pop)"
            )
        attribute = stack.pop()
        h = self._attr_handlers.get(attribute.__class__, _MISSING)
        if h is None:
            return attribute
        if h is _MISSING:
            h = self._handler_for(attribute)
        if h is not None and h.service != SIMPLIFY:
            h.unexec(attribute, self)
        return attribute

    def _pop_op(self, attribute: Attribute) -> None:
        # The POP op of compiled programs: pop what the node pushed and check
        # it is what comes off (a handler that pushed without popping would
        # otherwise make attributes leak to siblings).  Inlines the common case.
        if not self._frames:
            stack = self._mono.get(attribute.category)
            if stack and stack[-1] is attribute:
                stack.pop()
                h = self._attr_handlers.get(attribute.__class__, _MISSING)
                if h is None:
                    return
                if h is _MISSING:
                    h = self._handler_for(attribute)
                if h is not None and h.service != SIMPLIFY:
                    h.unexec(attribute, self)
                return
        self._pop_expected(attribute)

    def _pop_expected(self, attribute: Attribute) -> None:
        popped = self.pop(attribute.category)
        if popped is not attribute:
            raise EvaluationError(
                f"unbalanced push/pop{self._where()}: popping {type(attribute).__name__} removed "
                f"{type(popped).__name__} instead; a handler pushed {type(popped).__name__} without popping it"
            )

    def _record(self, simplifier: Any, attribute: Attribute) -> list[tuple[str, Any]]:
        """Run an attribute simplifier's exec, recording what it pushes, adds and installs."""
        record: list[tuple[str, Any]] = []
        shadowed = {name: self.__dict__.get(name) for name in ("push", "add", "install")}
        cls = type(self)

        def recorder(name: str) -> Callable[[Any], None]:
            method = getattr(cls, name).__get__(self)

            def call(obj: Any) -> None:
                record.append((name, obj))
                method(obj)

            return call

        for name in shadowed:
            setattr(self, name, recorder(name))
        try:
            simplifier.exec(attribute, self)
        finally:
            for name, previous in shadowed.items():
                if previous is None:
                    delattr(self, name)
                else:
                    setattr(self, name, previous)
        return record

    def add(self, attribute: Attribute) -> None:
        """Activate a poly attribute (lights, clip planes, pick ids)."""
        if not isinstance(attribute, PolyAttribute):
            raise TypeError(
                f"add() needs a PolyAttribute, got {type(attribute).__name__}{self._where()}; "
                f"mono attributes are push()ed"
            )
        if attribute.category is Light and (id(attribute) in self._pre_lights or not light_on(attribute)):
            return  # pre-evaluated already, or disabled: a disabled light is as if absent
        h = self._handler_for(attribute)
        if h is not None and h.service == SIMPLIFY:
            self._poly_frames[id(attribute)] = [attribute, h, 0, self._record(h, attribute)]
            return
        self.context.poly_set(attribute.category).append(attribute)
        if attribute.category is Light:
            self._light_matrices[id(attribute)] = self.context.model_matrix()
        if h is not None:
            h.exec(attribute, self)

    def remove(self, attribute: Attribute) -> None:
        """Deactivate a poly attribute added before."""
        if attribute.category is Light and (id(attribute) in self._pre_lights or not light_on(attribute)):
            return
        frame = self._poly_frames.pop(id(attribute), None)
        if frame is not None:
            frame[1].unexec(attribute, self, frame[3])
            return
        items = self.context.poly_set(attribute.category)
        for i in range(len(items) - 1, -1, -1):
            if items[i] is attribute:
                del items[i]
                break
        else:
            raise EvaluationError(f"remove({type(attribute).__name__}){self._where()}: the attribute was not added")
        if attribute.category is Light and not any(x is attribute for x in items):
            self._light_matrices.pop(id(attribute), None)
        h = self._handler_for(attribute)
        if h is not None and h.service != SIMPLIFY:
            h.unexec(attribute, self)

    def install(self, handler: Handler) -> None:
        """Put ``handler`` on top of its (service, target) stack."""
        if not isinstance(handler, Handler):
            raise TypeError(f"install() needs a Handler, got {type(handler).__name__}{self._where()}")
        if self._registry_generation != registry.generation:
            self._check_registry()
        self._caches.install(handler)

    def deinstall(self, handler: Handler) -> None:
        """Remove ``handler`` from its (service, target) stack."""
        if not isinstance(handler, Handler):
            raise TypeError(f"deinstall() needs a Handler, got {type(handler).__name__}{self._where()}")
        stack = self._handlers.get((handler.service, handler.target)) or []
        for i in range(len(stack) - 1, -1, -1):
            if stack[i] is handler:
                del stack[i]
                break
        else:
            raise EvaluationError(f"deinstall({handler!r}){self._where()}: the handler is not installed")
        self._caches.deinstalled(handler)

    def eval(self, shape: Shape) -> None:
        """Evaluate ``shape`` with the active technique."""
        self._technique.handle_shape(shape, self)

    def _eval_direct(self, shape: Shape) -> None:
        # eval() for techniques that do not override handle_shape: two calls less.
        fn = self._shape_fns.get(shape.__class__)
        if fn is None:
            fn = self._resolve_shape(shape.__class__)
        fn(shape, self)

    def simplify(self, shape: Shape) -> None:
        """Evaluate ``shape`` through its simplifier, bypassing painters.

        For painters that cannot draw a particular case natively (a clipped
        quadric, a non-uniformly scaled sphere) and fall back to triangles.
        """
        for klass in type(shape).__mro__:
            if klass is object:
                break
            h = self.find_handler(SIMPLIFY, klass)
            if h is not None:
                _simplifying(h)(shape, self)
                return
        raise EvaluationError(
            f"{type(self).__name__}: {type(shape).__name__}{self._where()} cannot be drawn natively here and "
            f"has no simplifier; register an om.ShapeSimplifier for it"
        )

    def undo(self, record: Iterable[tuple[str, Any]]) -> None:
        """Undo recorded (op, object) calls in reverse order."""
        for op, obj in reversed(list(record)):
            if op == "push":
                self.pop(obj.category)
            elif op == "add":
                self.remove(obj)
            elif op == "install":
                self.deinstall(obj)

    # -- evaluation of sequences and graphs ---------------------------------
    def evaluate(self, components: Iterable[Any]) -> None:
        """Evaluate components in order, scoped like a node's list."""
        if hasattr(components, "_compile_node"):
            self.run(components)
            return
        self.run_program(compile_components(components, []))

    def run_program(self, program: list[tuple[int, Any]]) -> None:
        """Execute a compiled micro program.

        Child nodes kept as ``NODE`` ops are entered without recursion: when
        :meth:`eval_node` returns ``(program, on_done)`` the loop continues in
        that program and calls ``on_done()`` after it, so graphs of any depth
        evaluate with a constant Python stack.
        """
        ops = self._ops
        pending: list[tuple[Any, Any]] = []
        ops_iter = iter(program)
        done = None
        while True:
            try:
                for code, arg in ops_iter:
                    ops[code](arg)
            except _Descend as descend:  # a NODE op with a program to enter (see _node_op)
                pending.append((ops_iter, done))
                ops_iter, done = iter(descend.program), descend.done
                continue
            if done is not None:
                done()
            if not pending:
                return
            ops_iter, done = pending.pop()

    def _node_op(self, node: Any) -> None:
        # The NODE op: a program to enter leaves the op loop (no Python recursion per level of the graph); the
        # loop above catches it, so flat programs pay nothing for the rare NODE op.
        nested = self.eval_node(node)
        if nested is not None:
            raise _Descend(*nested)

    def run(self, root: Any, mask: str | None = None) -> None:
        """Pre-evaluate ``root`` (lights, camera), then evaluate it.

        Nested calls (a node evaluated while another traversal runs) skip the
        pre-evaluation and evaluate in the current state.
        """
        if self._running:
            self.run_program([(NODE, root)])
            return
        if mask is not None:
            self.mask = mask
        self._running += 1
        snapshot = self._snapshot()
        try:
            self.begin(root)
            self.run_program([(NODE, root)])
        except BaseException as exc:
            path = self.node_path
            self._reset(snapshot)
            if path and type(exc) in (ValueError, TypeError) and path not in str(exc):
                raise type(exc)(f"{exc} (in node {path})") from exc
            raise
        else:
            self.end(root)
        finally:
            self._running -= 1

    def run_partial(self, root: Any, body: Callable[[], Any]) -> Any:
        """Evaluate parts of ``root`` in the state its pre-evaluation makes: ``body()`` runs them.

        Like :meth:`run`, but the caller chooses what is evaluated: ``body``
        runs programs (:meth:`run_program`, :attr:`ops`) for some of ``root``'s
        subtrees after ``begin(root)``; ``end(root)`` follows.  An exception
        from ``body`` rolls the traversal state back (the engine stays usable)
        and propagates; otherwise ``body``'s result is returned.  An engine
        that compiles only the subtrees an edit touched uses it.
        """
        self._running += 1
        snapshot = self._snapshot()
        try:
            self.begin(root)
            result = body()
        except BaseException:
            self._reset(snapshot)
            raise
        else:
            self.end(root)
        finally:
            self._running -= 1
        return result

    @property
    def ops(self) -> list[Callable[[Any], Any]]:
        """The dispatch table of compiled programs, indexed by opcode (``ops[ENTER](node)`` runs one op)."""
        return self._ops

    def _snapshot(self) -> tuple[dict, dict, dict, int]:
        ctx = self.context
        return (
            {c: len(s) for c, s in ctx._mono.items()},
            {c: len(s) for c, s in ctx._poly.items()},
            {k: len(s) for k, s in ctx._handlers.items()},
            len(self._technique_frames),
        )

    def preevaluate(self, root: Any) -> Declarations:
        """The declarative pre-evaluation of ``root`` under this engine's mask (cached by the graph).

        Nodes answer with their incremental, per-node cached
        ``declarations(mask_fn)``; other roots (a viewer frame) may offer
        ``preevaluate(mask_fn) -> (lights, camera)`` instead.
        """
        declare = getattr(root, "declarations", None)
        if declare is not None:
            return declare(self._mask_fn)
        lights, camera = root.preevaluate(self._mask_fn)
        return Declarations.of(lights, camera)

    def begin(self, root: Any) -> None:
        """Declarative pre-evaluation: activate every light and find the camera."""
        self._check_registry()
        del self.context._matrices[1:]
        declared = self.declared = self.preevaluate(root)
        lights, camera = declared.lights, declared.camera
        lights_set = self.context.poly_set(Light)
        for light, matrix in lights:
            if not light_on(light):
                continue  # disabled: no placement, no painter
            self._placements.append((light, matrix))
            if id(light) not in self._pre_lights:
                self._pre_lights[id(light)] = light
                lights_set.append(light)
                h = self.attribute_handler(light.__class__)
                if h is not None and h.service != SIMPLIFY:
                    h.exec(light, self)
        self.camera = camera
        self._saved_mask_fn = self._mask_fn
        if self.uses_camera_mask and camera is not None and camera[0].mask and self._mask_fn is None:
            from .mask import compile_mask

            self._mask_fn = compile_mask(camera[0].mask)  # what this camera sees

    def end(self, root: Any) -> None:
        """Undo the pre-evaluation after the traversal."""
        lights_set = self.context.poly_set(Light)
        for light in self._pre_lights.values():
            for i in range(len(lights_set) - 1, -1, -1):
                if lights_set[i] is light:
                    del lights_set[i]
                    break
        self._pre_lights.clear()
        self._placements.clear()
        self._mask_fn = self._saved_mask_fn

    def _reset(self, snapshot: tuple[dict, dict, dict, int] | None = None) -> None:
        """Roll the state back to ``snapshot`` (or empty) after an error so the engine stays usable."""
        ctx = self.context
        mono, poly, handlers, frames = snapshot if snapshot is not None else ({}, {}, {}, 0)
        del self._technique_frames[frames:]
        for c, stack in ctx._mono.items():
            del stack[mono.get(c, 0) :]
        for c, items in ctx._poly.items():
            del items[poly.get(c, 0) :]
        del ctx._matrices[1:]
        for k, stack in ctx._handlers.items():
            del stack[handlers.get(k, 0) :]
        self._invalidate()
        self._node_stack.clear()
        self._frames.clear()
        self._poly_frames.clear()
        self._pre_lights.clear()
        self._placements.clear()
        self._light_matrices.clear()
        self._mask_fn = self._saved_mask_fn

    # -- mask ------------------------------------------------------------
    @property
    def mask(self) -> Any:
        """The group-mask expression this engine evaluates with (None: everything)."""
        return self._mask

    @property
    def mask_function(self) -> Callable[[frozenset[str]], bool] | None:
        """The group-mask predicate in effect (the camera's own mask during its traversal), or None."""
        return self._mask_fn

    def admits(self, groups: frozenset[str]) -> bool:
        """Whether the mask in effect lets a node with ``groups`` be evaluated (an untagged node always is)."""
        return not groups or self._mask_fn is None or bool(self._mask_fn(groups))

    @mask.setter
    def mask(self, mask: Any) -> None:
        self._mask = mask
        if mask is None:
            self._mask_fn = None
        elif callable(mask):
            self._mask_fn = mask
        else:
            from .mask import compile_mask

            self._mask_fn = compile_mask(mask)

    # -- queries for handlers --------------------------------------------
    def model_matrix(self) -> np.ndarray:
        """The accumulated model-to-world matrix (4x4 float64)."""
        return self.context.model_matrix()

    def mono(self, category: type, default: Any = None) -> Any:
        """The active attribute of ``category`` (model matrix for ``Transform``)."""
        return self.context.mono(category, default)

    def poly(self, category: type) -> tuple[Any, ...]:
        """The active attributes of ``category``."""
        return self.context.poly(category)

    def lights(self) -> list[tuple[Light, np.ndarray]]:
        """Active lights with their world matrices, after the light switch; disabled lights are left out.

        Pre-evaluated lights come first, once per placement; lights added
        during the traversal follow with the model matrix they were added with.
        """
        switch = self.context.mono(LightSwitch)
        allows = light_on if switch is None else switch.allows
        out = [(light, m) for light, m in self._placements if allows(light)]
        pre = self._pre_lights
        for light in self.context.poly(Light):
            if id(light) not in pre and allows(light):
                out.append((light, self._light_matrices.get(id(light), _IDENTITY)))
        return out

    def view_matrix(self) -> np.ndarray | None:
        """World-to-eye matrix of the pre-evaluated camera, or None."""
        if self.camera is None:
            return None
        camera, world = self.camera
        return camera.view_matrix() @ np.linalg.inv(world)

    @property
    def current_node(self) -> Any:
        """The node being evaluated (innermost), or None outside any node."""
        stack = self._node_stack
        return stack[-1] if stack else None

    @property
    def node_path(self) -> str:
        """Path of the node being evaluated ("" outside any node)."""
        stack = self._node_stack
        if not stack:
            return ""
        head = stack[0].path
        rest = "/".join(n.name for n in stack[1:])
        return f"{head}/{rest}" if rest else head

    def _where(self) -> str:
        return f" in node {self.node_path}" if self._node_stack else ""


class _Descend(Exception):  # noqa: N818 - control flow of run_program, never seen by users
    """Raised by the NODE op to make the interpreter continue in a child's program."""

    __slots__ = ("program", "done")

    def __init__(self, program: list[tuple[int, Any]], done: Callable[[], None] | None) -> None:
        self.program = program
        self.done = done


def _skip(shape: Any, engine: Engine) -> None:
    return None


_MAX_SIMPLIFY_DEPTH = 64


def _simplifying(simplifier: Any) -> Callable[[Any, Engine], None]:
    def simplify(shape: Any, engine: Engine) -> None:
        result = simplifier.exec(shape, engine)
        if result is None:
            return
        depth = engine._simplify_depth
        if depth >= _MAX_SIMPLIFY_DEPTH:
            raise EvaluationError(
                f"{type(simplifier).__name__}{engine._where()}: simplification of {type(shape).__name__} nested "
                f"{depth} levels deep; a simplifier probably returns a shape it simplifies again (itself?)"
            )
        engine._simplify_depth = depth + 1
        try:
            engine.evaluate(result)
        finally:
            engine._simplify_depth = depth

    return simplify
