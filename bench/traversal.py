"""Traversal speed of the generic engine: components evaluated per second.

A generated scene of N nodes under one root, each node holding a material
(mono attribute), a transform and a shape, is evaluated by a counting analysis
engine whose handlers count shapes.  Nodes, attributes and shapes count as
components.  The baseline, measured in the same run, is a plain recursive
Python loop over the same objects doing bare list pushes and pops.

A second measurement installs a handler in every node of the scene (the
pattern of a painter scoped to a subgraph) and compares it with the same
handler installed once at the root: install/deinstall patch only the cached
look-ups they affect, so the ratio should stay at most 2x.

Run: .venv/bin/python bench/traversal.py [N]
"""

from __future__ import annotations

import statistics
import sys
import time

import omnirender as om


class Material(om.MonoAttribute):
    __slots__ = ("diffuse",)

    def __init__(self, diffuse):
        super().__init__()
        self.diffuse = diffuse


class Cube(om.Shape):
    __slots__ = ()


class CountingPainter(om.ShapePainter):
    __slots__ = ("count",)
    service = "count"
    target = Cube

    def __init__(self):
        super().__init__()
        object.__setattr__(self, "count", 0)

    def exec(self, shape, engine):
        object.__setattr__(self, "count", self.count + 1)


class CountingEngine(om.Engine):
    service = "count"


def build(n: int) -> om.Node:
    root = om.Node("root")
    for i in range(n):
        node = root.add(om.Node(f"n{i}"))
        node.add(Material((i % 7 / 7, 0.5, 0.5)))
        node.add(om.Translation(i, 0, 0))
        node.add(Cube())
    return root


def build_scoped(n: int, painter: om.Handler, per_node: bool) -> om.Node:
    """The scene of :func:`build` with ``painter`` installed in every node, or once at the root."""
    root = om.Node("root", [] if per_node else [painter])
    for i in range(n):
        node = root.add(om.Node(f"n{i}"))
        if per_node:
            node.add(painter)
        node.add(Material((i % 7 / 7, 0.5, 0.5)))
        node.add(om.Translation(i, 0, 0))
        node.add(Cube())
    return root


def scoped_handlers(n: int) -> tuple[float, float]:
    """Median seconds per evaluation: a handler installed in each of n nodes, and once at the root."""
    painter = CountingPainter()
    per_node, at_root = build_scoped(n, painter, True), build_scoped(n, painter, False)
    engine = CountingEngine()
    per_node.evaluate(engine)
    at_root.evaluate(engine)
    a, b = [], []
    for _ in range(9):
        t = time.perf_counter()
        per_node.evaluate(engine)
        a.append(time.perf_counter() - t)
        t = time.perf_counter()
        at_root.evaluate(engine)
        b.append(time.perf_counter() - t)
    assert painter.count == 20 * n, painter.count
    return statistics.median(a), statistics.median(b)


def baseline(root: om.Node) -> int:
    """A plain recursive loop: bare list pushes/pops and a counter."""
    stacks: dict[type, list] = {}
    count = 0

    def visit(node):
        nonlocal count
        undo = []
        for item in node._items:
            if isinstance(item, om.Node):
                visit(item)
            elif isinstance(item, om.MonoAttribute):
                stacks.setdefault(item.category, []).append(item)
                undo.append(item.category)
            else:
                count += 1
        for cat in reversed(undo):
            stacks[cat].pop()

    visit(root)
    return count


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
    root = build(n)
    components = 1 + n * 4  # root + (node, material, transform, shape) per child
    engine = CountingEngine()
    painter = CountingPainter()
    engine.install(painter)
    root.evaluate(engine)  # compile once (cached while the scene is unchanged)
    om_times, base_times = [], []
    for _ in range(9):
        t = time.perf_counter()
        root.evaluate(engine)
        om_times.append(time.perf_counter() - t)
        t = time.perf_counter()
        baseline(root)
        base_times.append(time.perf_counter() - t)
    assert painter.count == 10 * n, painter.count
    om_t, base_t = statistics.median(om_times), statistics.median(base_times)
    om_best, base_best = min(om_times), min(base_times)
    t = time.perf_counter()
    root.touch()
    root.evaluate(engine)
    first = time.perf_counter() - t
    print(f"scene: {n} nodes, {components} components (nodes + attributes + shapes)")
    print("                    median of 9 runs        best of 9 runs (least disturbed by other load)")
    print(
        f"omnirender engine : {components / om_t / 1e6:6.2f} M components/s     "
        f"{components / om_best / 1e6:6.2f} M components/s  ({om_t * 1e3:.1f} / {om_best * 1e3:.1f} ms)"
    )
    print(
        f"plain Python loop : {components / base_t / 1e6:6.2f} M components/s     "
        f"{components / base_best / 1e6:6.2f} M components/s  ({base_t * 1e3:.1f} / {base_best * 1e3:.1f} ms)"
    )
    print(f"ratio omnirender/plain speed: {base_t / om_t:.2f}x (median), {base_best / om_best:.2f}x (best)")
    print("target: >= 2.0 M components/s")
    print(f"first evaluation after a change (recompile + evaluate): {first * 1e3:.1f} ms")
    scoped_n = min(n, 20_000)
    per_node, at_root = scoped_handlers(scoped_n)
    print(
        f"handler installed in each of {scoped_n} nodes: {per_node * 1e3:.1f} ms, once at the root: "
        f"{at_root * 1e3:.1f} ms, ratio {per_node / at_root:.2f}x (target <= 2x)"
    )


if __name__ == "__main__":
    main()
