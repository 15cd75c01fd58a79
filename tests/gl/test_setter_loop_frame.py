"""The frame after a simulation's setter loop, written the short way (issue 22, sim3).

After a loop of ``t.offset = row`` over most translations the engine writes
the moved offsets into the plan's matrices through kept flat places, takes
each batch's translations from the compact offsets (not the matrices), writes
them into the rows as 12-byte records and scatters them into the buffer's
mirror the same way; the owners' versions are set to a bound known without
reading them when the same owners come again.  Every one of those must give
exactly what the long way gives: the GPU buffers hold the bytes a fresh pack
of the rows gives, the rows and matrices hold the transforms' values, the
picture is a fresh engine's, and every owner's version moves past what an
observer read.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.core.component import ChangeJournal

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def scene_of(
    n: int = 90, rotated: bool = False, placed: bool = False
) -> tuple[om.Node, list[om.Translation], np.ndarray]:
    """n boxes, each below its own Translation (a shared box, a colour each); with ``rotated`` every third node
    also holds a Rotation after its translation, with ``placed`` every fourth an om.Matrix (a turn and a shift)
    before it (its map's L and c are not the identity and zero)."""
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 32), (0, 0, 0), fov=50), om.DirectionalLight()])
    rng = np.random.default_rng(7)
    positions = np.zeros((n, 3))
    positions[:, 0] = np.arange(n) % 10 * 2.0 - 9.0
    positions[:, 1] = np.arange(n) // 10 * 1.7 * 90 / max(n, 90) - 7.0
    positions[:, 2] = rng.uniform(-3.0, 3.0, n)  # depths differ: the sorted batch's buffer order is not row order
    box = om.Box(size=0.8)
    moves = []
    for i in range(n):
        t = om.Translation(offset=positions[i])
        moves.append(t)
        items: list = [t]
        if placed and i % 4 == 1:
            m = om.Rotation(angle=25.0, axis=(0, 1, 1)).matrix.copy()
            m[:3, 3] = (0.3, -0.2, 0.5)
            items.insert(0, om.Matrix(m))
        if rotated and i % 3 == 0:
            items.append(om.Rotation(angle=30.0, axis=(0, 0, 1)))
        items += [om.Color(0.3 + 0.7 * i / n, 0.6, 0.3), box]
        scene.add(om.Node(f"b{i}", items))
    return scene, moves, positions


def fresh(scene: om.Node) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        return e.render(scene, background=(0, 0, 0)).array


def buffer_matches_rows(engine) -> None:  # noqa: ANN001
    """Every batch's GPU buffer holds exactly its rows packed in buffer order (the drawer's own columns)."""
    from omnirender.gl.engine.layout import ROW

    checked = 0
    for batch in engine.batches:
        if batch.buffer is None or batch.layout is None or batch.offsets is not None:
            continue
        n = len(batch.rows)
        columns = batch.layout.columns(ROW)
        order = np.arange(n) if batch.position is None else np.argsort(batch.position)
        expected = batch.rows[order][:, columns]
        stride = batch.layout.stride * 4
        held = np.frombuffer(batch.buffer.read(size=n * stride), np.float32).reshape(n, -1)
        assert np.array_equal(held, expected), "the GPU buffer differs from the rows packed again"
        if batch.packed is not None:
            assert np.array_equal(batch.packed[:n], expected), "the buffer's mirror differs from the rows"
        checked += 1
    assert checked


def rows_match_transforms(engine, moves: list[om.Translation]) -> None:  # noqa: ANN001
    """Every item's row holds its chain's matrix (float32 of the float64 product), the plan's matrices the
    transforms' own."""
    from omnirender.gl.engine.drawlist import ROW

    model = ROW.slice("model")
    plan = engine.updater.plan()
    for t, m in zip(plan.transforms, plan.matrices, strict=False):
        assert np.array_equal(m, t.matrix), f"the plan's matrix of {t!r} is not its own"
    for batch in engine.batches:
        for item, row in zip(batch.items, batch.rows, strict=True):
            m = np.eye(4)
            for t in item.chain:
                m = m @ t.matrix
            if item.local is not None:
                m = m @ item.local
            assert np.allclose(row[model].reshape(4, 4).T, m, atol=1e-5)


@pytest.mark.parametrize("rotated, placed", [(False, False), (True, False), (False, True), (True, True)])
def test_setter_loops_leave_buffers_rows_and_pictures_as_a_fresh_engine_has_them(rotated: bool, placed: bool) -> None:
    from omnirender.gl import GLEngine

    scene, moves, positions = scene_of(rotated=rotated, placed=placed)
    rng = np.random.default_rng(3)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(6):
            positions += rng.uniform(-0.3, 0.3, positions.shape)
            for t, row in zip(moves, positions, strict=True):
                t.offset = row
            image = e.render(scene, background=(0, 0, 0)).array
            buffer_matches_rows(e)
            rows_match_transforms(e, moves)
            assert all(t.offset == tuple(row.tolist()) for t, row in zip(moves, positions, strict=True))
            if frame in (0, 3, 5):
                assert np.array_equal(image, fresh(scene)), f"frame {frame} differs from a fresh render"


def test_a_loop_over_some_then_all_then_other_translations_stays_exact() -> None:
    """Loops that move other subsets between the full ones: the kept flat places and picks follow the lists."""
    from omnirender.gl import GLEngine

    scene, moves, positions = scene_of(150)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene, background=(0, 0, 0))
        # (a loop over at least 64 and half of them takes the translation map: the rows below the others keep
        # their translations, read from the plan's matrices)
        subsets = [slice(None), slice(0, 100), slice(None), slice(40, None), slice(None, None, -1), slice(0, 120, 1)]
        for k, part in enumerate(subsets):
            positions[part, 1] += 0.25 * (k + 1)
            for t, row in zip(moves[part], positions[part], strict=True):
                t.offset = row
            image = e.render(scene, background=(0, 0, 0)).array
            buffer_matches_rows(e)
            rows_match_transforms(e, moves)
            assert np.array_equal(image, fresh(scene)), f"loop {k} differs from a fresh render"


def test_owner_versions_move_past_what_was_read_also_after_other_touches_between_loops(monkeypatch) -> None:
    """The owners of a loop coming again get a version bounded without reading theirs: it must still exceed
    every version an observer read, also of owners touched one by one (many times) or by another loop since."""
    from omnirender.scene import node as node_module

    bounded: list[int] = []
    patched: list[int] = []
    original = node_module._version_bound

    def spy(owners):  # noqa: ANN001, ANN202
        found = original(owners)
        if found is not None:
            bounded.append(found)
            if getattr(owners, "base", None) is not None:
                patched.append(found)
        return found

    monkeypatch.setattr(node_module, "_version_bound", spy)
    n = 300  # above the batch size told as a whole (a batch's kept owners come again)
    moves = [om.Translation() for _ in range(n)]
    nodes = [om.Node(f"b{i}", [t, om.Color(0.5, 0.5, 0.5)]) for i, t in enumerate(moves)]
    scene = om.Node("scene", nodes)
    others = [om.Translation() for _ in range(n)]
    for i, t in enumerate(others):  # another loop's transforms, half of them in the same nodes
        (nodes[i] if i % 2 else scene.add(om.Node(f"x{i}"))).add(t)
    journal = ChangeJournal()  # noqa: F841 - alive, as an engine's: loops are told as batches
    read: list[int] = []
    for frame in range(10):
        for i, t in enumerate(moves):
            t.offset = (float(frame), float(i), 0.0)
        versions = [t.owners[0].version for t in moves]
        if read:
            assert all(v > r for v, r in zip(versions, read, strict=True)), f"frame {frame}: a version did not move"
        read = versions
        if frame in (3, 6):  # a translation changes hands: its new node's version is far above the others'
            t = moves[11 + frame]
            t.owners[0].remove(t)
            # (a node made with many items starts at a version of that many, touched no time)
            late = scene.add(om.Node(f"new{frame}", [om.Color(0.5, 0.5, 0.5) for _ in range(900)]))
            late.add(t)
        # between loops: some owners touched many times one by one (their version far above the others'), a
        # child added below one, and now and then another loop over owners shared with this one
        for node in nodes[frame : frame + 3]:
            for _ in range(5 + 10 * frame):
                node.touch()
        nodes[7 + frame].add(om.Node("late", [om.Translation(float(frame), 0.0, 0.0)]))
        if frame % 4 == 2:
            for i, t in enumerate(others):
                t.offset = (float(frame), 0.0, float(i))
        read = [t.owners[0].version for t in moves]  # what an observer saw last: the next loop must move past it
    assert len(bounded) >= 5 and patched  # the bound was used (the same owners came again, also patched)


def test_a_batch_of_value_equal_components_is_not_taken_for_the_last_one() -> None:
    """A transform class comparing by value: a loop over other objects equal to the last loop's must touch its
    own owners (the batches are compared object by object then)."""
    from omnirender.core import component

    class ValueTranslation(om.Translation):
        __slots__ = ()

        def __eq__(self, other: object) -> bool:
            return isinstance(other, om.Translation) and self.offset == other.offset

        __hash__ = om.Translation.__hash__

    assert component._VALUE_EQ[0]
    n = 300  # above the batch size told as a whole
    a = [ValueTranslation(0.0, 0.0, 0.0) for _ in range(n)]
    b = [ValueTranslation(0.0, 0.0, 0.0) for _ in range(n)]
    scene = om.Node("scene", [om.Node(f"a{i}", [t]) for i, t in enumerate(a)])
    other = om.Node("other", [om.Node(f"b{i}", [t]) for i, t in enumerate(b)])
    journal = ChangeJournal()
    for _ in range(2):  # twice: the batch of a is told as a whole and kept
        for t in a:
            t.offset = (1.0, 0.0, 0.0)
        scene.version  # noqa: B018
        journal.drain()
    before = [t.owners[0].version for t in b]
    for t in b:
        t.offset = (1.0, 0.0, 0.0)
    assert all(t.owners[0].version > v for t, v in zip(b, before, strict=True))
    drained = journal.drain()
    assert len(drained) == n and all(x is y for x, y in zip(drained, b, strict=True))
    assert other.version > 0


def test_owners_that_are_not_plain_nodes_are_told_their_own_way_every_loop() -> None:
    """A node subclass and an owner that is not a node (anything with ``touch()``) among a loop's owners: the
    plain nodes' versions are written at once, the others keep their own ways, loop after loop."""

    class Watcher:
        """An owner that is not a node; it has a ``_version`` a blind write would silently replace."""

        def __init__(self) -> None:
            self._version = 0
            self.touched = 0

        def touch(self) -> None:
            self.touched += 1

    class Tagged(om.Node):
        __slots__ = ("writes",)

        def __setattr__(self, name: str, value) -> None:  # noqa: ANN001
            if name == "_version":
                object.__setattr__(self, "writes", getattr(self, "writes", 0) + 1)
            super().__setattr__(name, value)

    n = 300
    moves = [om.Translation() for _ in range(n)]
    nodes = [(Tagged if i % 50 == 0 else om.Node)(f"b{i}", [t]) for i, t in enumerate(moves)]
    om.Node("scene", nodes)
    watcher = Watcher()
    moves[7].attach_owner(watcher)
    journal = ChangeJournal()  # noqa: F841 - alive, as an engine's
    for frame in range(4):
        before = [node.version for node in nodes]
        for t in moves:
            t.offset = (float(frame), 1.0, 2.0)
        assert all(node.version > v for node, v in zip(nodes, before, strict=True))
        assert watcher.touched == frame + 1 and watcher._version == 0
    moves[7].detach_owner(watcher)
    for frame in range(4, 7):  # only nodes now, some of them a subclass: still every version moves
        before = [node.version for node in nodes]
        for t in moves:
            t.offset = (float(frame), 1.0, 2.0)
        assert all(node.version > v for node, v in zip(nodes, before, strict=True))
