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
    loose = om.Translation()  # in no node: told at once, not noted for later
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
