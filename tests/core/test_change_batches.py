"""Large batches of setters told to change journals as a whole (issue 22, ``core.component.flush_changes``).

A simulation's setter loop notes thousands of transforms for later; the
flush tells a journal with nothing else in it of the batch as a whole and
reuses the owners it collected for the same components in the same order.
Whatever the engine reads must be what a per-component journal would say:
each changed component once, in the order told, and every owner (and its
ancestors) bumped, also after components or nodes changed their owners.
"""

from __future__ import annotations

import omnirender as om
from omnirender.core import component
from omnirender.core.component import ChangeJournal, flush_changes

N = component.BULK_MIN + 40


def scene_of(n: int = N) -> tuple[om.Node, list[om.Node], list[om.Translation]]:
    scene = om.Node("scene")
    nodes = [scene.add(om.Node(f"n{i}", [om.Translation(float(i), 0.0, 0.0), om.Sphere()])) for i in range(n)]
    return scene, nodes, [node.items[0] for node in nodes]


def move(translations: list[om.Translation], dy: float) -> None:
    for t in translations:
        x, y, z = t.offset
        t.offset = (x, y + dy, z)


def test_a_batch_is_drained_in_order_once_each_with_changes_told_before_and_after_it() -> None:
    scene, nodes, moves = scene_of()
    color = om.Color(0.5, 0.5, 0.5)
    loose = om.Translation()  # in no node: noted for later all the same (a journal lives), told first
    journal = ChangeJournal()
    for frame in range(4):
        loose.offset = (float(frame), 0.0, 0.0)  # told before the batch
        move(moves, 0.1)
        flush_changes()  # the batch is told (as a whole from the second frame on) ...
        color.r = 0.1 * frame  # ... and then a component touched directly
        moves[3].offset = (0.0, 0.0, float(frame))  # and a component of the batch again, after the flush
        loose.offset = (float(frame), 1.0, 0.0)  # and the one told before it
        if frame == 3:
            assert len(journal) == N + 2
        assert journal.drain() == [loose, *moves, color]
        assert journal.drain() == []


def test_a_component_twice_in_one_batch_is_drained_once() -> None:
    _, _, moves = scene_of()
    journal = ChangeJournal()
    for _ in range(2):
        move(moves, 0.1)
        move(moves[:5], 0.2)
        assert journal.drain() == moves


def test_two_journals_each_get_the_batch_and_a_flush_before_the_drain_adds_to_it() -> None:
    scene, _, moves = scene_of()
    a, b = ChangeJournal(), ChangeJournal()
    for _ in range(3):
        move(moves, 0.1)
        before = scene.version  # an observation: the batch is flushed now
        move(moves, 0.1)  # the same batch again before any drain
        assert scene.version != before
        assert a.drain() == moves
        move(moves[:10], 0.3)
        assert b.drain() == moves
        assert a.drain() == moves[:10]


def test_every_owner_hears_of_the_batch_also_after_components_and_nodes_moved() -> None:
    scene, nodes, moves = scene_of()
    journal = ChangeJournal()
    other = scene.add(om.Node("other"))
    holder = scene.add(om.Node("holder"))
    for frame in range(6):
        if frame == 2:  # a translation of the batch moves to another node: its owners are collected again
            nodes[7].remove(moves[7])
            other.insert(0, moves[7])
        if frame == 4:  # a node holding one moves below another parent: the parents are found again
            scene.remove(nodes[9])
            holder.add(nodes[9])
        versions = {id(n): n.version for n in (*nodes, other, holder, scene)}
        move(moves, 0.1)
        flush_changes()
        owners = {id(node) for t in moves for node in t.owners}
        for node in (*nodes, other, holder, scene):
            moved = id(node) in owners or any(id(c) in owners for c in node.children) or node is scene
            assert (node.version != versions[id(node)]) == moved, (frame, node.path)
        assert journal.drain() == moves


def ancestors(node: om.Node) -> set[int]:
    """ids of ``node``'s ancestors (every path up)."""
    out: set[int] = set()
    stack = list(node.parents)
    while stack:
        n = stack.pop()
        if id(n) not in out:
            out.add(id(n))
            stack.extend(n.parents)
    return out


def test_a_loop_over_components_that_changed_hands_bumps_exactly_their_owners_and_ancestors() -> None:
    """The same components set frame after frame while some leave their node (and are still set: the user's
    list keeps them), go to another node, come back, or their node moves: the batch's owners are patched, not
    collected again, and still every owner and every ancestor of one is bumped, and no other node (a group whose
    one moved node lost its translation is not); the journal drains the same list object while nothing else
    changes."""
    scene = om.Node("scene")
    groups = [scene.add(om.Node(f"g{g}")) for g in range(3)]
    nodes = [groups[i % 2].add(om.Node(f"n{i}", [om.Translation(float(i), 0.0, 0.0), om.Sphere()])) for i in range(N)]
    solo = groups[2].add(om.Node("solo", [om.Translation(0.0, 5.0, 0.0), om.Sphere()]))
    spare = scene.add(om.Node("spare", [om.Sphere()]))
    moves = [node.items[0] for node in (*nodes, solo)]
    everything = [scene, *groups, *nodes, solo, spare]
    matrix = om.Matrix(om.Translation(1.0, 2.0, 3.0).matrix)
    journal = ChangeJournal()
    drained = None
    for frame in range(9):
        if frame == 2:  # the solo node's translation leaves it (the loop goes on setting it): solo and g2 rest
            solo.remove(moves[-1])
        if frame == 3:  # it comes to the spare node, below the scene
            spare.insert(0, moves[-1])
        if frame == 4:  # two translations change places between nodes of two groups
            a, b = nodes[4], nodes[7]
            ta, tb = moves[4], moves[7]
            a.remove(ta)
            b.remove(tb)
            a.insert(0, tb)
            b.insert(0, ta)
        if frame == 5:  # a node holding one goes below another group (its parents change: found again)
            groups[0].remove(nodes[10])
            groups[2].add(nodes[10])
        if frame == 6:  # a node's translation replaced by a Matrix (the old one still set by the loop)
            nodes[12].remove(moves[12])
            nodes[12].insert(0, matrix)
        if frame == 7:  # a whole group leaves the scene: its nodes still own theirs (bumped, the scene not by it)
            scene.remove(groups[1])
        versions = {id(n): n.version for n in everything}
        move(moves, 0.1)
        flush_changes()
        moved: set[int] = set()
        for t in moves:
            for owner in t.owners:
                moved.add(id(owner))
                moved |= ancestors(owner)
        for node in everything:
            assert (node.version != versions[id(node)]) == (id(node) in moved), (frame, node.path)
        out = journal.drain()
        assert out == moves, frame
        if frame >= 2:
            assert out is drained, frame  # the batch's own list, patched owners and all
        drained = out
        assert journal.drain() == []


def test_a_collected_journal_leaves_the_registries_between_loops_not_inside_one():
    """A journal's finalizer runs whenever the garbage collector does, often inside a loop over the journals
    (a store into each allocates).  It used to delete the journal's entries there, shifting the list under
    the loop, which then skipped the next journal: a live engine missed a list edit at random (a new node not
    drawn, about once in a few hundred frames).  Now the finalizer only queues; the next drain removes."""
    import gc

    dead = om.ChangeJournal()
    live = om.ChangeJournal()
    changed, log = dead._changed, dead._edits

    def registered() -> tuple[bool, bool]:
        return any(d is changed for d in component._JOURNALS), any(e is log for e in component._EDIT_LOGS)

    del dead
    gc.collect()
    assert registered() == (True, True)  # nothing shifted inside the collector
    node = om.Node("n")
    node.add(om.Node("child"))  # (told to every registered log, the collected one's too)
    edits = live.drain_edits()
    assert [(op, item.name) for _, op, item, _ in edits] == [("insert", "child")]
    assert registered() == (False, False)  # out at the drain
