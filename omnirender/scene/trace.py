"""Recording and counting analysis engines: ``om.trace`` and ``om.statistics``."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from typing import Any

from ..core.component import Attribute, RenderingComponent, Shape
from ..core.engine import Engine
from ..core.handler import Handler
from .node import Node, Visitor

__all__ = ["TraceEngine", "trace", "Statistics", "statistics"]


class TraceEngine(Engine):
    """An analysis engine that records its micro program as (op, object) pairs.

    Shapes are recorded, not evaluated, so any scene can be traced without
    handlers.  Techniques in the graph still run their passes.
    """

    service = "trace"

    def __init__(self, mask: str | None = None) -> None:
        super().__init__(mask=mask)
        self.program: list[tuple[str, Any]] = []

    def push(self, attribute: Attribute) -> None:
        self.program.append(("push", attribute))
        super().push(attribute)

    def pop(self, category: type) -> Attribute:
        attribute = super().pop(category)
        self.program.append(("pop", attribute))
        return attribute

    def add(self, attribute: Attribute) -> None:
        self.program.append(("add", attribute))
        super().add(attribute)

    def remove(self, attribute: Attribute) -> None:
        super().remove(attribute)
        self.program.append(("remove", attribute))

    def install(self, handler: Handler) -> None:
        self.program.append(("install", handler))
        super().install(handler)

    def deinstall(self, handler: Handler) -> None:
        super().deinstall(handler)
        self.program.append(("deinstall", handler))

    def eval(self, shape: Shape) -> None:
        self.program.append(("eval", shape))


def trace(scene: Node | Any, mask: str | None = None) -> list[tuple[str, Any]]:
    """The micro program ``scene`` emits, as a list of ``(op, object)`` tuples.

    ``op`` is one of push, pop, add, remove, install, deinstall, eval.
    """
    if not isinstance(scene, (Node, RenderingComponent, Iterable)) or isinstance(scene, (str, bytes)):
        raise TypeError(
            f"trace: scene must be an om.Node or a list of components, got {type(scene).__name__} {scene!r:.60}"
        )
    engine = TraceEngine(mask=mask)
    if isinstance(scene, Node):
        scene.evaluate(engine)
    else:
        engine.evaluate(scene)
    return engine.program


class Statistics(dict):
    """Counts of a scene: ``nodes``, ``shapes``, ``attributes``, ``handlers``,
    ``techniques`` and, under ``by_class``, counts per class name."""

    def __repr__(self) -> str:
        return f"Statistics({dict.__repr__(self)})"


class _Counter(Visitor):
    def __init__(self) -> None:
        self.nodes = 0
        self.by_class: Counter[str] = Counter()
        self.kinds: Counter[str] = Counter()

    def enter_node(self, node: Node) -> bool:
        self.nodes += 1
        return True

    def visit(self, component: RenderingComponent, node: Node) -> None:
        self.by_class[type(component).__name__] += 1
        if isinstance(component, Shape):
            self.kinds["shapes"] += 1
        elif isinstance(component, Attribute):
            self.kinds["attributes"] += 1
        elif isinstance(component, Handler):
            self.kinds["handlers"] += 1
        else:
            self.kinds["techniques"] += 1


_extensions: list[Any] = []


def register_statistic(fn: Any) -> Any:
    """Register ``fn(scene, stats)`` to add figures to :func:`statistics` (e.g. triangles)."""
    _extensions.append(fn)
    return fn


def statistics(scene: Node) -> Statistics:
    """Totals of ``scene`` (shared subgraphs counted once per occurrence)."""
    if not isinstance(scene, Node):
        raise TypeError(
            f"statistics: scene must be an om.Node, got {type(scene).__name__} {scene!r:.60}; "
            "wrap components in one: om.statistics(om.Node('scene', [...]))"
        )
    counter = _Counter()
    scene.inspect(counter)
    stats = Statistics(
        nodes=counter.nodes,
        shapes=counter.kinds["shapes"],
        attributes=counter.kinds["attributes"],
        handlers=counter.kinds["handlers"],
        techniques=counter.kinds["techniques"],
        by_class=dict(sorted(counter.by_class.items())),
    )
    for fn in _extensions:
        fn(scene, stats)
    return stats
