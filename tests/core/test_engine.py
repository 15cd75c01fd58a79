"""The generic engine: micro programs, scoping, handler look-up, techniques."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import omnirender as om

# --- a tiny vocabulary for the tests -------------------------------------------------


class A1(om.MonoAttribute):
    __slots__ = ()


class A2(om.PolyAttribute):
    __slots__ = ()


class Colour(om.MonoAttribute):
    __slots__ = ("name",)

    def __init__(self, name: str) -> None:
        super().__init__()
        self.name = name


class S(om.Shape):
    __slots__ = ("label",)

    def __init__(self, label: str = "s") -> None:
        super().__init__()
        self.label = label


class SubS(S):
    __slots__ = ()


class Composite(om.Shape):
    """A shape only a simplifier knows: two S shapes, the second one coloured."""

    __slots__ = ()


class Recorder(om.Engine):
    """An analysis engine whose painters record (label, colour name) pairs."""

    service = "record"

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.seen: list[tuple[str, str | None]] = []


class RecordS(om.ShapePainter):
    __slots__ = ()
    service = "record"
    target = S

    def exec(self, shape, engine):
        colour = engine.mono(Colour)
        engine.seen.append((shape.label, colour.name if colour else None))


class OtherPainter(om.ShapePainter):
    __slots__ = ()
    service = "record"
    target = S

    def exec(self, shape, engine):
        engine.seen.append(("other:" + shape.label, None))


class SimplifyComposite(om.ShapeSimplifier):
    __slots__ = ()
    target = Composite

    def exec(self, shape, engine):
        return [S("first"), Colour("green"), S("second")]


def recorder() -> Recorder:
    engine = Recorder()
    engine.install(RecordS())
    return engine


# --- the micro program ---------------------------------------------------------------


def test_micro_program_of_the_paper_example_is_exact():
    a1, h, a2, s = A1(), OtherPainter(), A2(), S()
    root = om.Node("root")
    root.add(a1)
    root.add(h)
    child = root.add(om.Node("child"))
    child.add(a2)
    child.add(s)
    program = om.trace(root)
    assert program == [
        ("push", a1),
        ("install", h),
        ("add", a2),
        ("eval", s),
        ("remove", a2),
        ("deinstall", h),
        ("pop", a1),
    ]
    assert all(obj is expected for (_, obj), expected in zip(program, [a1, h, a2, s, a2, h, a1], strict=True))


def test_attributes_never_leak_to_siblings():
    root = om.Node("root")
    left = root.add(om.Node("left"))
    left.add(Colour("red"))
    left.add(S("l"))
    right = root.add(om.Node("right"))
    right.add(S("r"))
    root.add(S("after"))
    engine = recorder()
    root.evaluate(engine)
    assert engine.seen == [("l", "red"), ("r", None), ("after", None)]
    assert engine.context.is_empty() is False  # the installed painter remains
    assert engine.mono(Colour) is None


def test_attribute_affects_only_what_follows_in_its_node():
    root = om.Node("root", [S("before"), Colour("blue"), S("after"), om.Node("kid", [S("kid")])])
    engine = recorder()
    root.evaluate(engine)
    assert engine.seen == [("before", None), ("after", "blue"), ("kid", "blue")]


def test_handler_scoped_to_a_subgraph():
    root = om.Node("root")
    special = root.add(om.Node("special"))
    special.add(OtherPainter())
    special.add(S("a"))
    root.add(S("b"))
    engine = recorder()
    root.evaluate(engine)
    assert engine.seen == [("other:a", None), ("b", None)]


def test_simplification_fallback_evaluates_result_scoped():
    engine = recorder()
    engine.install(SimplifyComposite())
    root = om.Node("root", [Composite(), S("tail")])
    root.evaluate(engine)
    # the simplifier's Colour applies to its own second shape only
    assert engine.seen == [("first", None), ("second", "green"), ("tail", None)]


def test_parent_class_fallback_uses_the_base_class_painter():
    engine = recorder()
    engine.eval(SubS("sub"))
    assert engine.seen == [("sub", None)]


def test_painter_for_subclass_wins_over_parent():
    class SubPainter(om.ShapePainter):
        __slots__ = ()
        service = "record"
        target = SubS

        def exec(self, shape, engine):
            engine.seen.append(("subpainter", None))

    engine = recorder()
    engine.install(SubPainter())
    engine.eval(SubS())
    engine.eval(S("plain"))
    assert engine.seen == [("subpainter", None), ("plain", None)]


def test_missing_handler_error_names_service_class_and_path():
    root = om.Node("scene")
    body = root.add(om.Node("body"))
    body.add(Composite())
    with pytest.raises(om.NoHandlerError) as info:
        root.evaluate(Recorder())
    text = str(info.value)
    assert "'record'" in text and "Composite" in text and "/scene/body" in text
    assert info.value.path == "/scene/body"


def test_missing_handler_policies_warn_and_skip():
    root = om.Node("scene", [Composite(), Composite()])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        root.evaluate(Recorder(on_missing="warn"))
    assert len(caught) == 1 and "Composite" in str(caught[0].message)
    root.evaluate(Recorder(on_missing="skip"))
    with pytest.raises(ValueError, match="on_missing"):
        Recorder(on_missing="explode")


def test_engine_stays_usable_after_an_error():
    engine = recorder()
    bad = om.Node("bad", [Colour("red"), om.Node("inner", [Composite()])])
    with pytest.raises(om.NoHandlerError):
        bad.evaluate(engine)
    assert engine.mono(Colour) is None and engine.node_path == ""
    engine.install(RecordS())
    om.Node("good", [S("ok")]).evaluate(engine)
    assert engine.seen[-1] == ("ok", None)


def test_lookup_cache_is_invalidated_by_install_and_deinstall():
    engine = recorder()
    engine.eval(S("x"))
    other = OtherPainter()
    engine.install(other)
    engine.eval(S("y"))
    engine.deinstall(other)
    engine.eval(S("z"))
    assert engine.seen == [("x", None), ("other:y", None), ("z", None)]
    with pytest.raises(om.EvaluationError, match="not installed"):
        engine.deinstall(other)


def test_default_handlers_registered_per_engine_class_after_creation():
    class Special(om.Shape):
        __slots__ = ()

    class SpecialEngine(Recorder):
        pass

    engine = SpecialEngine()
    snapshot = om.registry.snapshot()
    try:

        @om.default_for(SpecialEngine)
        class SpecialPainter(om.ShapePainter):
            __slots__ = ()
            service = "record"
            target = Special

            def exec(self, shape, engine):
                engine.seen.append(("special", None))

        engine.eval(Special())
        assert engine.seen == [("special", None)]
        with pytest.raises(om.NoHandlerError):
            Recorder().eval(Special())  # a default for a subclass engine only
        assert any(row[3] == "SpecialPainter" for row in om.registry.entries())
    finally:
        om.registry.restore(snapshot)


# --- techniques ---------------------------------------------------------------------------


class CountingTechnique(om.Technique):
    __slots__ = ("log",)

    def __init__(self, passes: int, log: list) -> None:
        super().__init__(passes=passes)
        object.__setattr__(self, "log", log)

    def prepare_pass(self, engine):
        self.log.append((self.passes, engine.current_pass))


def test_nested_techniques_nest_passes():
    log: list = []
    root = om.Node("root")
    root.add(CountingTechnique(3, log))
    inner = root.add(om.Node("inner"))
    inner.add(CountingTechnique(2, log))
    inner.add(S("x"))
    root.add(S("y"))
    engine = recorder()
    root.evaluate(engine)
    assert [label for label, _ in engine.seen].count("x") == 6
    assert [label for label, _ in engine.seen].count("y") == 3
    assert log[:3] == [(3, 0), (2, 0), (2, 1)]


def test_technique_takes_over_the_rest_of_its_node_only():
    log: list = []
    root = om.Node("root", [S("before"), Colour("c"), CountingTechnique(2, log), S("during")])
    root.add(S("also-during"))
    outer = om.Node("outer", [root, S("after")])
    engine = recorder()
    outer.evaluate(engine)
    labels = [label for label, _ in engine.seen]
    assert labels == ["before", "during", "also-during", "during", "also-during", "after"]
    assert engine.seen[1] == ("during", "c") and engine.seen[-1] == ("after", None)


def test_technique_can_intercept_shapes():
    class Collect(om.Technique):
        __slots__ = ("shapes",)

        def __init__(self):
            super().__init__()
            object.__setattr__(self, "shapes", [])

        def handle_shape(self, shape, engine):
            self.shapes.append(shape.label)

    collect = Collect()
    engine = recorder()
    with engine.using(collect):
        om.Node("n", [S("a"), S("b")]).evaluate(engine)
    assert collect.shapes == ["a", "b"] and engine.seen == []
    assert engine.technique is not collect


# --- state machine misuse -----------------------------------------------------------------


def test_unbalanced_pop_on_bare_engine_names_the_category():
    engine = om.Engine()
    with pytest.raises(om.EvaluationError, match=r"pop\(Colour\).*unbalanced"):
        engine.pop(Colour)


def test_unbalanced_pop_inside_a_node_names_the_node_path():
    class Popper(om.ShapePainter):
        __slots__ = ()
        service = "record"
        target = S

        def exec(self, shape, engine):
            engine.pop(Colour)

    engine = Recorder()
    engine.install(Popper())
    root = om.Node("scene", [om.Node("deep", [S()])])
    with pytest.raises(om.EvaluationError, match="/scene/deep"):
        root.evaluate(engine)


def test_remove_of_a_poly_attribute_never_added_raises():
    with pytest.raises(om.EvaluationError, match="not added"):
        om.Engine().remove(A2())


def test_push_pop_add_remove_by_hand():
    engine = om.Engine()
    red, blue = Colour("red"), Colour("blue")
    engine.push(red)
    engine.push(blue)
    assert engine.mono(Colour) is blue
    assert engine.pop(Colour) is blue
    assert engine.mono(Colour) is red
    a, b = A2(), A2()
    engine.add(a)
    engine.add(b)
    assert engine.poly(A2) == (a, b)
    engine.remove(a)
    assert engine.poly(A2) == (b,)


# --- attribute handlers ------------------------------------------------------------------


def test_attribute_painter_exec_and_unexec_in_order():
    log = []

    class ColourPainter(om.AttributePainter):
        __slots__ = ()
        service = "record"
        target = Colour

        def exec(self, attribute, engine):
            log.append(("exec", attribute.name))

        def unexec(self, attribute, engine):
            log.append(("unexec", attribute.name))

    engine = recorder()
    engine.install(ColourPainter())
    om.Node("n", [Colour("a"), om.Node("k", [Colour("b"), S()])]).evaluate(engine)
    assert log == [("exec", "a"), ("exec", "b"), ("unexec", "b"), ("unexec", "a")]


class Spin(om.MonoAttribute):
    """An attribute that only exists through its simplifier (like the paper's billboard)."""

    __slots__ = ("angle",)
    category = om.Transform

    def __init__(self, angle):
        super().__init__()
        self.angle = angle


class SpinSimplifier(om.AttributeSimplifier):
    __slots__ = ()
    target = Spin

    def exec(self, attribute, engine):
        engine.push(om.Rotation(attribute.angle, (0, 0, 1)))
        engine.push(Colour("spun"))


def test_attribute_simplifier_unexec_undoes_exactly_what_exec_pushed():
    engine = recorder()
    engine.install(SpinSimplifier())
    matrices = []

    class MatrixPainter(om.ShapePainter):
        __slots__ = ()
        service = "record"
        target = SubS

        def exec(self, shape, engine):
            matrices.append(engine.model_matrix().copy())

    engine.install(MatrixPainter())
    node = om.Node("n", [om.Translation(1, 0, 0), Spin(90), om.Translation(0, 2, 0), SubS(), S("x")])
    node.evaluate(engine)
    assert engine.seen == [("x", "spun")]
    point = matrices[0] @ np.array([0, 0, 0, 1.0])
    np.testing.assert_allclose(point[:3], [1 - 2, 0, 0], atol=1e-12)  # rotated by 90 about z
    assert engine.context.mono_stack(om.Transform) == []
    assert engine.mono(Colour) is None
    # the trace shows the user's push/pop of the Spin, not the derived rotation
    ops = [(op, type(obj).__name__) for op, obj in om.trace(node)]
    assert ops[1] == ("push", "Spin") and ("pop", "Spin") in ops


def test_attribute_simplifier_by_hand_pop_by_category():
    engine = Recorder()
    engine.install(SpinSimplifier())
    engine.push(om.Translation(5, 0, 0))
    engine.push(Spin(45))
    assert len(engine.context.mono_stack(om.Transform)) == 2
    assert engine.pop(om.Transform).__class__ is Spin
    assert engine.context.mono_stack(om.Transform)[0].offset == (5.0, 0.0, 0.0)
    assert engine.mono(Colour) is None


# --- transforms ---------------------------------------------------------------------------


def test_transforms_accumulate_and_pop_restores():
    engine = om.Engine()
    engine.push(om.Translation(1, 2, 3))
    engine.push(om.Scaling(2))
    m = engine.model_matrix()
    np.testing.assert_allclose(m @ [1, 1, 1, 1], [3, 4, 5, 1])
    assert engine.mono(om.Transform) is m
    engine.pop(om.Transform)
    np.testing.assert_allclose(engine.model_matrix() @ [1, 1, 1, 1], [2, 3, 4, 1])
    engine.push(om.Rotation(90, (0, 0, 1)))
    np.testing.assert_allclose(engine.model_matrix() @ [1, 0, 0, 1], [1, 3, 3, 1], atol=1e-12)
    engine.pop(om.Transform)
    engine.pop(om.Transform)
    np.testing.assert_array_equal(engine.model_matrix(), np.eye(4))


def test_transform_mutation_is_seen_in_the_next_frame():
    t = om.Translation(1, 0, 0)
    seen = []

    class M(om.ShapePainter):
        __slots__ = ()
        service = "record"
        target = S

        def exec(self, shape, engine):
            seen.append(engine.model_matrix()[0, 3])

    root = om.Node("r", [t, S()])
    engine = Recorder()
    engine.install(M())
    root.evaluate(engine)
    t.offset = (4, 0, 0)
    root.evaluate(engine)
    assert seen == [1.0, 4.0]


def test_rotation_constructors_agree():
    a = om.Rotation(120, (1, 1, 1))
    b = om.Rotation.from_quaternion(*a.quaternion)
    np.testing.assert_allclose(a.matrix, b.matrix, atol=1e-12)
    m = a.matrix[:3, :3]
    np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(m @ [1, 0, 0], [0, 1, 0], atol=1e-12)  # 120 deg about the diagonal cycles axes
    with pytest.raises(ValueError, match="axis"):
        om.Rotation(10, (0, 0, 0))
    with pytest.raises(ValueError, match="finite"):
        om.Translation(np.nan, 0, 0)
    with pytest.raises(ValueError, match="non-zero"):
        om.Scaling(0)
    with pytest.raises(ValueError, match="4x4"):
        om.Matrix(np.eye(3))


def test_categories_default_to_class_and_can_be_shared():
    assert Colour.category is Colour
    assert om.Translation.category is om.Transform and om.Rotation.category is om.Transform
    assert om.Light.category is om.Light

    class MyLight(om.Light):
        __slots__ = ()

    assert MyLight.category is om.Light


def test_transforms_rebuild_from_their_parameters():
    for t in (
        om.Translation(1, 2, 3),
        om.Scaling(1, 2, 3),
        om.Rotation(33, (1, 2, 3)),
        om.Matrix(np.diag([1, 2, 3, 1.0])),
    ):
        again = type(t)(**t.parameters())
        assert again.parameters() == t.parameters()
        np.testing.assert_array_equal(again.matrix, t.matrix)


def test_node_hooks_see_structure_and_paths():
    events = []

    class Hooked(Recorder):
        def on_enter(self, node):
            events.append(("enter", self.node_path))

        def on_leave(self, node):
            events.append(("leave", node.name))

    engine = Hooked()
    engine.install(RecordS())
    om.Node("a", [om.Node("b", [S()])]).evaluate(engine)
    assert events == [("enter", "/a"), ("enter", "/a/b"), ("leave", "b"), ("leave", "a")]


def test_bare_engine_sees_a_transform_changed_between_pushes():
    engine = om.Engine()
    t = om.Translation(1, 0, 0)
    engine.push(t)
    assert engine.model_matrix()[0, 3] == 1
    engine.pop(om.Transform)
    t.offset = (5, 0, 0)
    engine.push(t)
    assert engine.model_matrix()[0, 3] == 5
    t.offset = (7, 0, 0)  # changed while pushed
    assert engine.model_matrix()[0, 3] == 7


def test_technique_can_override_attribute_handling():
    class NoColours(om.Technique):
        __slots__ = ()

        def handle_attribute(self, attribute, engine):
            return _Swallow() if isinstance(attribute, Colour) else super().handle_attribute(attribute, engine)

    class _Swallow(om.AttributeSimplifier):
        __slots__ = ()

        def exec(self, attribute, engine):
            pass  # the colour is not applied in this technique

    engine = recorder()
    node = om.Node("n", [Colour("red"), S("a")])
    with engine.using(NoColours()):
        node.evaluate(engine)
    node.evaluate(engine)
    assert engine.seen == [("a", None), ("a", "red")]


def test_a_handler_that_pushes_without_popping_is_caught():
    class Leaky(om.ShapePainter):
        __slots__ = ()
        service = "record"
        target = S

        def exec(self, shape, engine):
            engine.push(Colour("leak"))

    engine = Recorder()
    engine.install(Leaky())
    with pytest.raises(om.EvaluationError, match=r"unbalanced push/pop in node /n: popping Colour removed Colour"):
        om.Node("n", [Colour("mine"), S()]).evaluate(engine)
    assert engine.mono(Colour) is None


def test_an_error_keeps_what_was_set_up_before_the_frame():
    engine = recorder()
    outer = Colour("outer")
    engine.push(outer)
    with pytest.raises(om.NoHandlerError):
        om.Node("bad", [Colour("inner"), Composite()]).evaluate(engine)
    assert engine.mono(Colour) is outer
    om.Node("good", [S("ok")]).evaluate(engine)  # the installed painter is still there
    assert engine.seen[-1] == ("ok", "outer")


def test_simplifier_errors_name_the_node():
    class Broken(om.ShapeSimplifier):
        __slots__ = ()
        target = Composite

        def exec(self, shape, engine):
            return [42]

    engine = recorder()
    engine.install(Broken())
    with pytest.raises(TypeError, match=r"cannot evaluate int.*in node /scene/deep"):
        om.Node("scene", [om.Node("deep", [Composite()])]).evaluate(engine)


def test_wrong_types_raise_type_errors():
    engine = om.Engine()
    with pytest.raises(TypeError, match="MonoAttribute"):
        engine.push(3)
    with pytest.raises(TypeError, match="PolyAttribute"):
        engine.add(Colour("x"))
    with pytest.raises(TypeError, match="Handler"):
        engine.deinstall(3)
    with pytest.raises(TypeError, match="Handler"):
        engine.install("painter")
    with pytest.raises(ValueError, match="passes"):
        om.Technique(passes="2")


def test_misuse_messages():
    with pytest.raises(TypeError, match="items must be a list"):
        om.Node("n", om.Translation(1, 0, 0))
    with pytest.raises(TypeError, match=r"did you mean Translation\(\)"):
        om.Node("n").add(om.Translation)
    with pytest.raises(ValueError, match=r"got \(0.0, 1.0, 1.0\)"):
        om.Scaling(0, 1, 1)

    class Forgot(om.Shape):
        __slots__ = ("size",)

        def __init__(self):
            self.size = 1

    with pytest.raises(TypeError, match=r"must call super\(\).__init__\(\)"):
        Forgot()
    with pytest.raises(TypeError, match="engine classes"):
        om.default_for(int)
    with pytest.raises(ValueError, match="set 'target'"):
        om.registry.register(OtherPainter.__new__(type("NoTarget", (om.ShapePainter,), {"service": "x"})), [Recorder])
    with pytest.raises(AttributeError, match="did you mean om.Sphere"):
        om.Spere  # noqa: B018


def test_a_simplifier_returning_its_own_shape_is_stopped():
    class Loop(om.ShapeSimplifier):
        __slots__ = ()
        target = Composite

        def exec(self, shape, engine):
            return [shape]

    engine = recorder()
    engine.install(Loop())
    with pytest.raises(om.EvaluationError, match=r"Loop in node /n: simplification of Composite nested 64"):
        om.Node("n", [Composite()]).evaluate(engine)


def test_engine_simplify_bypasses_painters():
    class Painter(om.ShapePainter):
        __slots__ = ()
        service = "record"
        target = Composite

        def exec(self, shape, engine):
            engine.seen.append(("painted", None))

    engine = recorder()
    engine.install(Painter())
    engine.install(SimplifyComposite())
    engine.simplify(Composite())
    assert engine.seen == [("first", None), ("second", "green")]
    with pytest.raises(om.EvaluationError, match="has no simplifier"):
        engine.simplify(S())
