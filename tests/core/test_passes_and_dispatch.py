"""Technique pass state in the engine, unsupported techniques, the interpreter's hooks, patched look-up caches."""

from __future__ import annotations

import numpy as np
import pytest
from test_engine import Composite, OtherPainter, RecordS, S, SimplifyComposite, SubS, recorder

import omnirender as om
from omnirender.core.program import ENTER, EVAL, LEAVE, NODE, OPCODE_NAMES, TECHNIQUE


class Passes(om.Technique):
    """Records (passes, pass index, nesting depth) in prepare_pass."""

    __slots__ = ("log",)

    def __init__(self, passes: int, log: list) -> None:
        super().__init__(passes=passes)
        object.__setattr__(self, "log", log)

    def prepare_pass(self, engine):
        self.log.append((self.passes, engine.current_pass, len(engine.technique_frames)))


def labels(engine) -> list[str]:
    return [label for label, _ in engine.seen]


def test_a_technique_shared_at_two_levels_of_a_dag_runs_its_passes_at_each():
    log: list = []
    t = Passes(3, log)
    inner = om.Node("inner", [t, S("x")])
    outer = om.Node("outer", [t, inner])
    engine = recorder()
    outer.evaluate(engine)
    assert labels(engine).count("x") == 9
    assert [entry for entry in log if entry[2] == 1] == [(3, 0, 1), (3, 1, 1), (3, 2, 1)]
    assert [entry[1] for entry in log if entry[2] == 2] == [0, 1, 2] * 3


def test_pass_state_lives_in_engine_frames_not_on_the_technique():
    t = Passes(2, [])
    assert not hasattr(t, "current_pass") and "_pass" not in t.parameters()
    engine = recorder()
    with pytest.raises(RuntimeError, match="no technique is running"):
        _ = engine.current_pass
    om.Node("n", [t, S("a")]).evaluate(engine)
    assert engine.technique_frames == ()  # every frame popped after the run


def test_frame_data_belongs_to_one_run():
    class Counting(om.Technique):
        __slots__ = ()

        def start(self, engine):
            engine.technique_frame.data["seen"] = 0

        def finish_pass(self, engine):
            engine.technique_frame.data["seen"] += 1
            assert engine.technique_frame.data["seen"] == engine.current_pass + 1

    t = Counting(passes=2)
    engine = recorder()
    om.Node("outer", [t, om.Node("inner", [t, S("x")])]).evaluate(engine)
    assert labels(engine).count("x") == 4


def test_prepare_pass_returning_false_declines_that_pass():
    """VRS: a technique told to skip 2 of 4 passes evaluates its scope twice and finishes only those."""

    class Declining(om.Technique):
        __slots__ = ("log",)

        def __init__(self, log: list) -> None:
            super().__init__(passes=4)
            object.__setattr__(self, "log", log)

        def prepare_pass(self, engine):
            self.log.append(("prepare", engine.current_pass))
            return engine.current_pass in (0, 2)

        def finish_pass(self, engine):
            self.log.append(("finish", engine.current_pass))

    log: list = []
    engine = recorder()
    om.Node("n", [Declining(log), S("x")]).evaluate(engine)
    assert labels(engine).count("x") == 2
    assert [i for kind, i in log if kind == "prepare"] == [0, 1, 2, 3]
    assert [i for kind, i in log if kind == "finish"] == [0, 2]
    assert om.core.technique.pass_accepted(None) and not om.core.technique.pass_accepted(False)


def test_an_unsupported_technique_is_ignored_and_its_scope_evaluated_once():
    log: list = []

    class Unsupported(Passes):
        __slots__ = ()

        def supported(self, engine):
            return False

    root = om.Node("root", [S("before"), Unsupported(3, log), S("during"), om.Node("child", [S("child")])])
    root.add(S("also"))
    engine = recorder()
    root.evaluate(engine)
    assert labels(engine) == ["before", "during", "child", "also"]
    assert log == []  # its pass control never ran


def test_a_technique_inside_an_unsupported_one_still_runs():
    log: list = []

    class Unsupported(om.Technique):
        __slots__ = ()

        def supported(self, engine):
            return False

    root = om.Node("root", [Unsupported(passes=5), Passes(2, log), S("x")])
    engine = recorder()
    root.evaluate(engine)
    assert labels(engine) == ["x", "x"] and [e[:2] for e in log] == [(2, 0), (2, 1)]


def test_opcodes_are_named_and_local_programs_keep_children_as_node_ops():
    assert OPCODE_NAMES[EVAL] == "eval" and OPCODE_NAMES[NODE] == "node" and len(set(OPCODE_NAMES)) == 11
    child = om.Node("child", [S("c")])
    t = om.Technique()
    root = om.Node("root", [S("a"), child, t, om.Node("late", [S("d")])])
    flat = [code for code, _ in root.program()]
    assert NODE not in flat and flat.count(ENTER) == 2  # the first child is inlined; the rest is in the technique
    local = root.local_program()
    assert [code for code, _ in local] == [ENTER, EVAL, NODE, TECHNIQUE, LEAVE]
    assert local[2][1] is child
    technique, rest = local[3][1]
    assert technique is t and [code for code, _ in rest] == [NODE]
    assert root.local_program() is local  # cached
    child.add(S("e"))
    assert root.local_program() is local  # a child's list is not the root's: the local program stays
    flat = root.program()
    root.add(S("f"))
    assert root.local_program() is not local and root.program() is not flat
    flat = root.program()
    child.items[-1].label = "changed"  # a parameter: programs hold components, so they stay valid
    assert root.program() is flat


def test_eval_node_and_run_technique_are_the_hooks_engines_override():
    class Mirror(om.Engine):
        service = "record"

        def __init__(self):
            super().__init__(on_missing="skip")
            self.calls: list[str] = []

        def eval_node(self, node):
            self.calls.append(f"node {node.name}")
            return super().eval_node(node)

        def run_technique(self, technique, program):
            self.calls.append(f"technique {technique.passes}")
            super().run_technique(technique, program)

    tagged = om.Node("tagged", [S("x")], groups="g")
    root = om.Node("root", [om.Technique(passes=2), tagged])
    engine = Mirror()
    root.evaluate(engine)
    assert engine.calls == ["node root", "technique 2", "node tagged", "node tagged"]


# --- handler look-up caches patched per (service, target) ---------------------------------------


def test_a_handler_installed_in_every_node_patches_only_what_it_targets():
    engine = recorder()
    other = OtherPainter()
    root = om.Node("root")
    for i in range(5):
        root.add(om.Node(f"n{i}", [other, S(f"in{i}"), SubS(f"sub{i}")]))
        root.add(om.Node(f"m{i}", [S(f"out{i}")]))
    root.evaluate(engine)
    root.evaluate(engine)  # second run: every class is cached, installs only patch
    expected = []
    for i in range(5):
        expected += [f"other:in{i}", f"other:sub{i}", f"out{i}"]
    assert labels(engine) == expected * 2


def test_entries_first_resolved_under_an_installed_handler_are_right_after_it_goes():
    engine = recorder()
    other = OtherPainter()
    # SubS is first seen while `other` is installed: after deinstall it must fall back to RecordS
    engine.evaluate([other, SubS("under")])
    engine.eval(SubS("after"))
    engine.eval(S("plain"))
    assert labels(engine) == ["other:under", "after", "plain"]


def test_nested_installs_of_the_same_and_of_different_handlers_restore_in_order():
    engine = recorder()
    a, b = OtherPainter(), OtherPainter()

    class Third(om.ShapePainter):
        __slots__ = ()
        service = "record"
        target = SubS

        def exec(self, shape, engine):
            engine.seen.append(("third:" + shape.label, None))

    third = Third()
    graph = om.Node(
        "root",
        [a, S("1"), om.Node("x", [b, third, SubS("2"), S("3")]), SubS("4"), om.Node("y", [a, SubS("5")]), S("6")],
    )
    engine.evaluate([graph])
    engine.eval(SubS("7"))
    assert labels(engine) == ["other:1", "third:2", "other:3", "other:4", "other:5", "other:6", "7"]


def test_a_simplifier_installed_for_a_subgraph_beats_the_painter_of_a_base_class_only():
    engine = recorder()

    class SubSimplifier(om.ShapeSimplifier):
        __slots__ = ()
        target = SubS

        def exec(self, shape, engine):
            return [S("simplified-" + shape.label)]

    simp = SubSimplifier()
    engine.eval(SubS("a"))  # cached: RecordS via the base class S
    engine.evaluate([simp, SubS("b"), S("c")])
    engine.eval(SubS("d"))
    assert labels(engine) == ["a", "simplified-b", "c", "d"]


def test_a_service_painter_at_a_class_wins_over_an_installed_simplifier_at_the_same_class():
    engine = recorder()
    engine.install(SimplifyComposite())

    class CompositePainter(om.ShapePainter):
        __slots__ = ()
        service = "record"
        target = Composite

        def exec(self, shape, engine):
            engine.seen.append(("painted", None))

    engine.eval(Composite())
    engine.evaluate([CompositePainter(), Composite(), SimplifyComposite(), Composite()])
    engine.eval(Composite())
    assert labels(engine) == ["first", "second", "painted", "painted", "first", "second"]


def test_out_of_order_deinstall_by_hand_stays_correct():
    engine = recorder()
    a, b = OtherPainter(), RecordS()
    engine.install(a)
    engine.eval(S("1"))
    engine.install(b)
    engine.eval(S("2"))
    engine.deinstall(a)  # not the most recent: the caches are cleared, the stack keeps b
    engine.eval(S("3"))
    engine.deinstall(b)
    engine.eval(S("4"))
    assert labels(engine) == ["other:1", "2", "3", "4"]


def test_random_install_sequences_agree_with_uncached_resolution():
    """Property: after any nested install/deinstall sequence the cached look-up equals a fresh walk."""
    rng = np.random.default_rng(7)

    class Sub2(SubS):
        __slots__ = ()

    handlers = [OtherPainter(), RecordS()]
    for klass in (SubS, Sub2):
        handlers.append(type(f"P{klass.__name__}", (OtherPainter,), {"__slots__": (), "target": klass})())

        def simplify(self, shape, engine):
            return [S("s-" + shape.label)]

        handlers.append(type(f"Z{klass.__name__}", (om.ShapeSimplifier,), {"__slots__": (), "target": klass,
                                                                          "exec": simplify})())  # fmt: skip
    for _ in range(40):
        engine = recorder()
        installed: list = []
        for _step in range(12):
            if installed and rng.random() < 0.4:
                engine.deinstall(installed.pop())
            else:
                h = handlers[int(rng.integers(len(handlers)))]
                engine.install(h)
                installed.append(h)
            for cls in (S, SubS, Sub2):
                cached = engine.shape_handler(cls)
                fresh = engine._walk(cls, True)[0]
                shape = cls("p")
                engine.seen.clear()
                cached(shape, engine)
                got = list(engine.seen)
                engine.seen.clear()
                fresh(shape, engine)
                assert got == engine.seen, (cls.__name__, installed)


def test_declarations_are_incremental_and_include_the_first_background():
    light = om.PointLight(position=(0, 0, 0))
    lamp = om.Node("lamp", [om.Translation(1, 2, 3), light])
    root = om.Node("root", [om.Translation(10, 0, 0), lamp, om.Background((0.1, 0.2, 0.3))])
    root.add(om.Node("later", [om.Background((1, 1, 1)), om.Camera.look_at((0, 0, 5), (0, 0, 0))]))
    found = root.declarations()
    ((got, matrix),) = found.lights
    assert got is light and np.allclose(matrix[:3, 3], (11, 2, 3))
    background, _ = found.first(om.Background)
    assert background.color[:3] == pytest.approx((0.1, 0.2, 0.3))
    assert found.camera is not None and found.camera[0].eye == pytest.approx((0, 0, 5))
    assert root.declarations() is found  # cached while nothing changed
    lamp.items[0].offset = (0, 0, 0)
    moved = root.declarations()
    assert moved is not found and np.allclose(moved.lights[0][1][:3, 3], (10, 0, 0))
    assert root.preevaluate() == (moved.lights, moved.camera)
