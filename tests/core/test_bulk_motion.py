"""Setting transforms from what a simulation holds, and moving thousands through one bound array (issue 22).

Every input a simulation loop writes (Python floats, ints, numpy rows, numpy
scalars) takes the setters' fast path and means exactly what the validating
path means; bad values are refused by the validating path with its message.
``om.TranslationArray`` binds many translations to one array: a ``touch()``
changes each of them as an assignment would (versions, owners, journals).
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.core.component import ChangeJournal
from omnirender.core.transform import plain_triple

INPUTS = [
    (1.0, 2.0, 3.0),
    (1, 2.0, 3),
    [1.0, 2, 3.0],
    np.array([1.0, 2.0, 3.0]),
    np.array([1, 2, 3]),
    np.array([1.0, 2.0, 3.0], np.float32),
    (np.float64(1.0), np.float64(2.0), np.float64(3.0)),
    (np.float32(1.0), np.int64(2), 3.0),
    np.arange(6.0).reshape(2, 3)[0] + 1.0,  # a row of the application's array
]


@pytest.mark.parametrize("value", INPUTS, ids=range(len(INPUTS)))
def test_every_plain_input_takes_the_fast_path_and_gives_python_floats(value):
    fast = plain_triple(value)
    assert fast == (1.0, 2.0, 3.0)
    assert all(type(c) is float for c in fast)
    t = om.Translation()
    node = om.Node("n", [t])
    before, node_before = t.version, node.version
    t.offset = value
    assert t.offset == (1.0, 2.0, 3.0) and all(type(c) is float for c in t.offset)
    assert t.version == before + 1 and node.version > node_before
    assert np.array_equal(t.matrix[:3, 3], [1.0, 2.0, 3.0])
    s = om.Scaling()
    s.factors = value
    assert s.factors == (1.0, 2.0, 3.0)


@pytest.mark.parametrize(
    "value",
    [
        (1.0, float("nan"), 0.0),
        (float("inf"), 0.0, 0.0),
        (1e16, 0.0, 0.0),
        (10**400, 0, 0),
        np.array([0.0, np.nan, 0.0]),
        np.array([1.0, 2.0]),
        (1.0, 2.0),
        "abc",
        (None, 0.0, 0.0),
    ],
)
def test_bad_values_leave_the_fast_path_and_are_refused_with_the_validating_message(value):
    assert plain_triple(value) is None
    t = om.Translation(0.5, 0.5, 0.5)
    with pytest.raises(ValueError, match="Translation: offset"):
        t.offset = value
    assert t.offset == (0.5, 0.5, 0.5)


def test_zero_scaling_factors_still_refused_and_rotation_angle_takes_numpy_numbers():
    s = om.Scaling()
    with pytest.raises(ValueError, match="non-zero"):
        s.factors = np.array([1.0, 0.0, 1.0])
    r = om.Rotation(10, (0, 1, 0))
    r.angle = np.float32(30.0)
    assert r.angle == 30.0 and type(r.angle) is float
    r.angle = 45
    assert r.angle == 45.0 and type(r.angle) is float
    with pytest.raises(ValueError):
        r.angle = float("nan")


def test_a_change_reaches_every_live_journal_and_a_collected_journal_leaves_none_behind():
    from omnirender.core import component

    t = om.Translation()
    a, b = ChangeJournal(), ChangeJournal()
    t.offset = np.array([1.0, 0.0, 0.0])
    assert a.drain() == [t] and b.drain() == [t]
    own = b._changed
    assert any(d is own for d in component._JOURNALS)
    del b
    import gc

    gc.collect()  # (taken out of the registries at the next drain, not inside the collector: see _forget_journal)
    t.offset = (2.0, 0.0, 0.0)
    assert a.drain() == [t] and not own
    assert not any(d is own for d in component._JOURNALS)


def translation_array_scene(n: int = 5) -> tuple[om.Node, om.TranslationArray, np.ndarray]:
    positions = np.zeros((n, 3))
    positions[:, 0] = np.arange(n)
    moves = om.TranslationArray(positions)
    scene = om.Node("scene")
    for i in range(n):
        scene.add(om.Node(f"b{i}", [moves[i], om.Sphere(radius=0.2)]))
    return scene, moves, positions


def test_a_translation_array_holds_the_array_and_touch_changes_every_translation_like_an_assignment():
    scene, moves, positions = translation_array_scene()
    assert moves.array is positions and len(moves) == 5
    assert [t.offset for t in moves] == [(float(i), 0.0, 0.0) for i in range(5)]
    journal = ChangeJournal()
    versions = [t.version for t in moves]
    node_versions = [scene.child(f"b{i}").version for i in range(5)]
    root = scene.version
    positions[:, 1] = 2.0  # written in place: nothing changes until touch()
    assert moves[3].offset == (3.0, 0.0, 0.0)
    moves.touch()
    assert [t.offset for t in moves] == [(float(i), 2.0, 0.0) for i in range(5)]
    assert all(type(c) is float for t in moves for c in t.offset)
    assert [t.version for t in moves] == [v + 1 for v in versions]
    assert all(scene.child(f"b{i}").version > node_versions[i] for i in range(5))
    assert scene.version > root
    assert journal.drain() == [moves]  # the array once: an engine that knows it applies its rows at once
    assert np.array_equal(moves.offsets, positions) and moves.offsets is not positions
    assert not moves.offsets.flags.writeable
    assert set(moves.owners) == {scene.child(f"b{i}") for i in range(5)}
    assert np.array_equal(moves[2].matrix[:3, 3], [2.0, 2.0, 0.0])
    assert moves.version == 1


def test_a_translation_array_refuses_bad_rows_naming_the_translation_and_its_node():
    scene, moves, positions = translation_array_scene()
    positions[3, 2] = np.inf
    with pytest.raises(ValueError, match=r"translation 3 .* \(in node /scene/b3\).*finite"):
        moves.touch()
    assert moves[3].offset == (3.0, 0.0, 0.0)  # nothing applied
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        om.TranslationArray(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="finite"):
        om.TranslationArray([[0.0, np.nan, 0.0]])


def test_a_translation_array_from_a_list_or_another_dtype_converts_once():
    moves = om.TranslationArray([[1, 2, 3], [4, 5, 6]])
    assert moves[1].offset == (4.0, 5.0, 6.0)
    f32 = np.zeros((2, 3), np.float32)
    moves = om.TranslationArray(f32)
    f32[1] = (1.5, 0, 0)
    moves.touch()
    assert moves.array is f32 and moves[1].offset == (1.5, 0.0, 0.0)


def test_translations_of_an_array_mean_the_same_to_bounds_and_picking():
    scene, moves, positions = translation_array_scene()
    plain = om.Node(
        "scene", [om.Node(f"b{i}", [om.Translation(i, 1.0, -1.0), om.Sphere(radius=0.2)]) for i in range(5)]
    )
    positions[:, 1:] = (1.0, -1.0)
    moves.touch()
    assert np.allclose(om.bounds(scene), om.bounds(plain))
    cam = om.Camera.look_at((2, 1, 6), (2, 1, -1), fov=50)
    a = om.pick(om.Node("a", [cam, scene]), pixel=(80, 60), size=(160, 120))
    b = om.pick(om.Node("b", [cam, plain]), pixel=(80, 60), size=(160, 120))
    assert [h.path for h in a] and [h.path.replace("/a/", "/") for h in a] == [h.path.replace("/b/", "/") for h in b]
    assert [h.distance for h in a] == pytest.approx([h.distance for h in b])


def test_setters_tell_nodes_and_journals_at_the_next_observation():
    from omnirender.core import component

    t = om.Translation()
    node = om.Node("b", [t, om.Sphere(radius=0.2)])
    scene = om.Node("scene", [node])
    journal = ChangeJournal()
    root, own = scene.version, node.version
    for x in range(5):
        t.offset = np.array([float(x), 0.0, 0.0])
    assert t.version >= 5 and t.offset == (4.0, 0.0, 0.0)  # the component itself changes at once
    assert node.version > own and scene.version > root  # an observation: the nodes hear of it first
    assert journal.drain() == [t]  # once, however often it was set
    assert not component._PENDING
    assert np.allclose(om.bounds(scene), [[3.8, -0.2, -0.2], [4.2, 0.2, 0.2]])


def test_a_list_edit_sees_the_setters_before_it():
    # a light after a moved translation, then a child added to the same node: the declarations' patch of the
    # edit must not keep the light where it was (the setter's node version reaches the node before the edit)
    t = om.Translation(0.0, 0.0, 0.0)
    holder = om.Node("holder", [t, om.PointLight(position=(0, 0, 0))])
    scene = om.Node("scene", [holder])
    ((light, world),) = scene.declarations().lights
    assert np.allclose(world[:3, 3], 0.0)
    t.offset = (1.0, 2.0, 3.0)
    holder.add(om.Node("child", [om.Sphere(radius=0.1)]))
    ((light, world),) = scene.declarations().lights
    assert np.allclose(world[:3, 3], (1.0, 2.0, 3.0))


def test_changes_left_unobserved_stay_bounded():
    from omnirender.core import component

    t = om.Translation()
    node = om.Node("b", [t])
    before = node.version
    for i in range(component.PENDING_LIMIT + 10):
        t.offset = (float(i), 0.0, 0.0)
    assert len(component._PENDING) <= component.PENDING_LIMIT
    assert node.version > before and not component._PENDING


def test_a_bad_value_after_many_fast_ones_is_refused_naming_the_node():
    scene, moves, positions = translation_array_scene()
    plain = [om.Translation() for _ in range(3)]
    for i, t in enumerate(plain):
        scene.add(om.Node(f"p{i}", [t]))
    for t, row in zip(plain, np.arange(9.0).reshape(3, 3), strict=True):
        t.offset = row
    with pytest.raises(ValueError, match=r"Translation \(in node /scene/p1\): offset must be finite"):
        plain[1].offset = np.array([0.0, np.inf, 0.0])
    assert plain[1].offset == (3.0, 4.0, 5.0)
    with pytest.raises(ValueError, match=r"Scaling \(in node /scene/s\): factors must be non-zero"):
        scene.add(om.Node("s", [om.Scaling(2.0)])).items[0].factors = (1.0, 0.0, 1.0)


def test_an_array_translation_reads_its_row_lazily_and_an_assignment_holds_until_the_next_touch():
    import copy
    import pickle

    scene, moves, positions = translation_array_scene()
    positions[:, 2] = 5.0
    moves.touch()
    positions[:, 2] = 7.0  # written after the touch: not seen until the next one
    assert moves[1].offset == (1.0, 0.0, 5.0) and np.array_equal(moves[1].matrix[:3, 3], [1.0, 0.0, 5.0])
    moves[1].offset = (9.0, 9.0, 9.0)  # its own value, until the array is touched again
    assert moves[1].offset == (9.0, 9.0, 9.0) and np.array_equal(moves[1].matrix[:3, 3], [9.0, 9.0, 9.0])
    assert np.allclose(om.Translation.stack_offsets(list(moves))[:, 2], [5.0, 9.0, 5.0, 5.0, 5.0])
    node = scene.child("b1")
    before = node.version
    moves.touch()
    assert node.version > before
    assert [t.offset for t in moves] == [(float(i), 0.0, 7.0) for i in range(5)]
    assert np.allclose(om.Translation.stack_matrices(list(moves))[:, 2, 3], 7.0)
    # copies and pickles are ordinary translations with the current offsets; a pickled array binds its own
    copied = copy.deepcopy(node)
    assert copied.items[0].offset == (1.0, 0.0, 7.0)
    positions[:, 2] = 8.0
    moves.touch()
    assert copied.items[0].offset == (1.0, 0.0, 7.0) and moves[1].offset == (1.0, 0.0, 8.0)
    again = pickle.loads(pickle.dumps(scene))
    assert again.child("b3").items[0].offset == (3.0, 0.0, 8.0)
    moves2 = pickle.loads(pickle.dumps(moves))
    moves2.array[:, 0] = -1.0
    moves2.touch()
    assert [t.offset for t in moves2] == [(-1.0, 0.0, 8.0)] * 5 and moves[0].offset == (0.0, 0.0, 8.0)


def test_an_array_touch_writes_no_translation_and_its_nodes_hear_of_it_once():
    scene, moves, positions = translation_array_scene(200)
    journal = ChangeJournal()
    positions[:, 1] = 1.0
    moves.touch()
    assert all(t._offset[1] == 0.0 for t in moves)  # nothing written yet: each reads its row when asked
    assert moves.owners == tuple(scene.children)
    versions = [n.version for n in scene.children]  # an observation: the nodes heard of it
    assert journal.drain() == [moves]
    extra = om.Node("extra", [moves[0]])  # a translation held by another node: the owners follow
    assert len(moves.owners) == 201 and extra in moves.owners
    moves.touch()
    assert [n.version for n in scene.children] == [v + 1 for v in versions]
    assert moves[199].offset == (199.0, 1.0, 0.0)


def test_many_owners_told_at_once_reach_ancestors_after_the_graph_changed_between_observations():
    # the distinct parents of the moved nodes are kept while no node gains or loses a parent: moving nodes to
    # another group between two frames must bump the new group, not the old one
    t = [om.Translation() for _ in range(40)]
    a, b = om.Node("a"), om.Node("b")
    scene = om.Node("scene", [a, b])
    nodes = [a.add(om.Node(f"n{i}", [t[i]])) for i in range(40)]
    for frame in range(3):
        versions = (a.version, b.version, scene.version)
        for x in t:
            x.offset = (float(frame), 0.0, 0.0)
        assert (a.version > versions[0], b.version == versions[1], scene.version > versions[2]) == (True,) * 3
    for node in nodes:
        a.remove(node)
        b.add(node)
    versions = (a.version, b.version, scene.version)
    for x in t:
        x.offset = (9.0, 0.0, 0.0)
    assert a.version == versions[0] and b.version > versions[1] and scene.version > versions[2]

    class Watcher:  # an owner that is no node (attach_owner takes anything with touch())
        touched = 0

        def touch(self) -> None:
            self.touched += 1

    watcher = Watcher()
    t[5].attach_owner(watcher)
    before = [n.version for n in nodes]
    for x in t:
        x.offset = (1.0, 1.0, 1.0)
    assert all(n.version > v for n, v in zip(nodes, before, strict=True)) and watcher.touched == 1
