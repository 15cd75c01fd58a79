"""Frames in which most translations move (a simulation's setter loop): the plan's translation map (issue 22).

The move plan keeps, per installed item, where its translation column comes
from (``gl/engine/translations.py``): rows below one translation are written
from the moved offsets in one numpy operation per batch, rows below several
(nested translated nodes) are recomposed from their chains, and the map
follows splices and changes of the other transforms in the items' chains.
Every frame must render what a fresh engine renders for the same state.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def fresh(scene: om.Node) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        return e.render(scene, background=(0, 0, 0)).array


def engine():  # noqa: ANN201
    from omnirender.gl import GLEngine

    return GLEngine(size=SIZE, samples=0, shadows=False)


def flat(n: int = 80) -> tuple[om.Node, list[om.Translation], np.ndarray]:
    """n spheres, each below its own Translation (one shared sphere shape, a colour each)."""
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 30), (0, 0, 0), fov=50), om.DirectionalLight()])
    grid = np.stack(np.meshgrid(np.arange(10.0), np.arange(8.0)), -1).reshape(-1, 2)[:n]
    positions = np.zeros((n, 3))
    positions[:, :2] = grid * 2.0 - (9.0, 7.0)
    sphere = om.Sphere(radius=0.6)
    moves = []
    for i in range(n):
        t = om.Translation(offset=positions[i])
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Color(0.3 + 0.7 * i / n, 0.6, 0.3), sphere]))
    return scene, moves, positions


def nested(groups: int = 8, per: int = 10) -> tuple[om.Node, list[om.Translation], list[om.Translation], om.Rotation]:
    """Groups of boxes: even groups below a translated parent node (the children below two translations), odd
    groups below a rotated one (the children below a rotation and their own translation)."""
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 30), (0, 0, 0), fov=50), om.DirectionalLight()])
    spin = om.Rotation(axis=(0, 0, 1), angle=20.0)
    moves: list[om.Translation] = []
    parents: list[om.Translation] = []
    for g in range(groups):
        x = -8.0 + 2.2 * g
        if g % 2:
            parent = scene.add(om.Node(f"g{g}", [spin]))
        else:
            parent_move = om.Translation(x, -5.0, 0.0)
            moves.append(parent_move)
            parents.append(parent_move)
            parent = scene.add(om.Node(f"g{g}", [parent_move]))
        for k in range(per):
            t = om.Translation(x, 1.1 * k - 5.0, 0.0) if g % 2 else om.Translation(0.0, 1.1 * k, 0.0)
            moves.append(t)
            parent.add(om.Node(f"c{k}", [t, om.Color(0.2 + 0.07 * k, 0.3 + 0.06 * g, 0.5), om.Box(size=0.7)]))
    return scene, moves, parents, spin


def test_most_translations_moved_write_their_rows_and_match_a_fresh_render() -> None:
    scene, moves, positions = flat()
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(4):
            positions[:, 1] += 0.3
            positions[:, 0] -= 0.1 * frame
            for t, row in zip(moves, positions, strict=True):
                t.offset = row
            image = e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] is False and e.stats["incremental"] == len(moves)
            assert np.array_equal(image.array, fresh(scene)), frame


def test_nested_translations_and_a_moved_parent_with_its_children() -> None:
    """Items below two translations are recomposed from their chains; items below one and a rotation take L."""
    scene, moves, parents, spin = nested()
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(3):
            for i, t in enumerate(moves):  # parents and children, all in one loop
                x, y, z = t.offset
                t.offset = (x + 0.05 * (i % 3), y - 0.2, z + 0.1 * frame)
            image = e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] is False
            assert np.array_equal(image.array, fresh(scene)), frame
        # only the parents move (their children with them); then the shared rotation turns
        for t in parents:
            x, y, z = t.offset
            t.offset = (x, y + 0.7, z)
        assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))
        spin.angle = -35.0
        assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))
        for t in moves:  # all again, after the rotation changed what the rows below it are made from
            x, y, z = t.offset
            t.offset = (x - 0.1, y, z)
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] is False
        assert np.array_equal(image.array, fresh(scene))


def test_a_rotation_above_translations_changed_in_the_same_frame_as_them() -> None:
    scene, moves, _, spin = nested(6, 12)
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(3):
            for t in moves:
                x, y, z = t.offset
                t.offset = (x + 0.1, y, z)
            spin.angle = 10.0 * frame  # another class in the list: the general path, the map filled again
            assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene)), frame
            for t in moves:  # then translations alone: the map (its L made from the new angle)
                x, y, z = t.offset
                t.offset = (x, y - 0.1, z)
            assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene)), frame


def test_culled_nodes_moved_into_the_view_by_a_setter_loop_are_drawn() -> None:
    scene, moves, positions = flat()
    outside = positions.copy()
    outside[:40, 0] += 60.0  # half the nodes far to the right, out of the view
    for t, row in zip(moves, outside, strict=True):
        t.offset = row
    with engine() as e:
        first = e.render(scene, background=(0, 0, 0)).array
        assert np.array_equal(first, fresh(scene))
        for t, row in zip(moves, positions, strict=True):  # all back into the view
            t.offset = row
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] is False
        assert np.array_equal(image.array, fresh(scene))
        assert (image.array[..., :3].sum(axis=-1) > 0).mean() > (first[..., :3].sum(axis=-1) > 0).mean()


def test_setter_loops_between_splices_and_mixed_with_them() -> None:
    """Nodes added and removed between setter loops (the map follows the splices: rows moved, new items mapped,
    removed ones dropped), and in the same frame as one."""
    scene, moves, positions = flat()
    box = om.Box(size=0.8)
    rotated = om.Node("r", [om.Rotation(axis=(0, 0, 1), angle=30.0)])
    scene.add(rotated)
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(8):
            if frame % 2:  # a splice alone: one node removed, one added (below a rotation on odd splices)
                gone = scene.child(f"b{9 * frame}")
                scene.remove(gone)
                k = moves.index(gone.items[0])
                del moves[k]
                positions = np.delete(positions, k, axis=0)
                t = om.Translation(3.0 - frame, 6.0, 0.0)
                (rotated if frame % 4 == 1 else scene).add(om.Node(f"x{frame}", [t, om.Color(1, 1, 1), box]))
                moves.append(t)
                positions = np.concatenate([positions, [t.offset]])
                compiled = "subtrees"
            else:  # a setter loop over every translation
                positions[:, 1] -= 0.15
                positions[:, 0] += 0.05 * (frame - 3)
                for t, row in zip(moves, positions, strict=True):
                    t.offset = row
                compiled = False
            image = e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] == compiled, frame
            assert np.array_equal(image.array, fresh(scene)), frame


def test_moves_and_splices_in_one_frame_take_the_splice_and_the_updater() -> None:
    """A setter loop and nodes added or removed in the same frame: the splice compiles the new subtrees and the
    updater moves the rows of the rest (no full compile, once the updater has its move plan), also when a moved
    node is removed, when a node is added below a moved translation, and when a moved transform places a light
    (then the full compile)."""
    scene, moves, positions = flat()
    box = om.Box(size=0.8)
    group_move = om.Translation(0.0, -2.0, 0.0)
    group = scene.add(om.Node("group", [group_move]))
    lamp_move = om.Translation(0.0, 0.0, 5.0)
    scene.add(om.Node("lamp", [lamp_move, om.PointLight(intensity=0.5)]))
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for t, row in zip(moves, positions, strict=True):  # a frame of moves alone first (the move plan made)
            t.offset = row
        e.render(scene, background=(0, 0, 0))
        for frame in range(6):
            positions[:, 1] -= 0.1
            for t, row in zip(moves, positions, strict=True):
                t.offset = row
            group_move.offset = (0.1 * frame, -2.0, 0.0)
            if frame == 0:  # a moved node removed
                gone = scene.child("b20")
                scene.remove(gone)
            elif frame == 1:  # a node added below a moved translation
                group.add(om.Node("g1", [om.Translation(1.0, 0.0, 0.0), om.Color(1, 1, 0), box]))
            elif frame == 2:  # one added at the top, one removed
                scene.add(om.Node("top", [om.Translation(-3.0, 4.0, 0.0), om.Color(0, 1, 1), box]))
                scene.remove(scene.child("b33"))
            elif frame == 4:  # the light's transform moves too: its declarations changed, the full compile
                lamp_move.offset = (1.0, 1.0, 5.0)
                group.add(om.Node("g4", [om.Translation(-1.0, 0.0, 0.0), om.Color(1, 0, 1), box]))
            image = e.render(scene, background=(0, 0, 0))
            if frame in (0, 1, 2):
                assert e.stats["compiled"] == "subtrees", frame
            assert np.array_equal(image.array, fresh(scene)), frame


def test_a_bad_value_in_a_setter_loop_is_refused_naming_the_node_and_the_frame_stays_right() -> None:
    scene, moves, positions = flat()
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        positions[:, 0] += 0.2
        for t, row in zip(moves[:50], positions[:50], strict=True):
            t.offset = row
        bad = positions[50].copy()
        bad[1] = np.inf
        with pytest.raises(ValueError, match="/scene/b50"):
            moves[50].offset = bad
        for t, row in zip(moves[50:], positions[50:], strict=True):
            t.offset = row
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] is False
        assert moves[50].offset == tuple(positions[50].tolist())
        assert np.array_equal(image.array, fresh(scene))


def test_transforms_replaced_between_setter_loops() -> None:
    """A node's Translation replaced by a Matrix (and another node's Matrix by a Translation) between setter
    loops: the map follows the replaced transforms (the same-role replacement keeps the chains' places)."""
    scene, moves, positions = flat()
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(6):
            if frame in (1, 3):
                node = scene.child(f"b{10 + frame}")
                old = node.items[0]
                k = moves.index(old)
                m = np.eye(4)
                m[:3, 3] = positions[k] + (0.0, 0.5, 0.0)
                m[:3, :3] *= 1.3
                node.remove(old)
                node.insert(0, om.Matrix(m))
                del moves[k]
                positions = np.delete(positions, k, axis=0)
            if frame == 4:  # the Matrix of frame 1 replaced by a Translation, moved with the others from now on
                node = scene.child("b11")
                t = om.Translation(-2.0, 5.0, 1.0)
                node.remove(node.items[0])
                node.insert(0, t)
                moves.append(t)
                positions = np.concatenate([positions, [t.offset]])
            image = e.render(scene, background=(0, 0, 0))
            assert np.array_equal(image.array, fresh(scene)), frame
            positions[:, 1] += 0.2
            for t, row in zip(moves, positions, strict=True):
                t.offset = row
            image = e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] is False
            assert np.array_equal(image.array, fresh(scene)), frame


def test_with_default_shadows_setter_loops_and_splices_match_a_fresh_render() -> None:
    from omnirender.gl import GLEngine

    scene, moves, positions = flat(72)
    scene.insert(0, om.Node("floor", [om.Translation(0.0, 0.0, -1.0), om.Box(size=(30.0, 30.0, 0.2))]))
    box = om.Box(size=0.8)
    with GLEngine(size=SIZE, samples=0) as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(4):
            positions[:, 0] += 0.2
            for t, row in zip(moves, positions, strict=True):
                t.offset = row
            if frame % 2:
                scene.add(om.Node(f"x{frame}", [om.Translation(2.0 * frame, 5.0, 0.5), om.Color(1, 1, 1), box]))
            image = e.render(scene, background=(0, 0, 0)).array
            with GLEngine(size=SIZE, samples=0) as f:
                assert np.array_equal(image, f.render(scene, background=(0, 0, 0)).array), frame


def test_a_clip_planes_ancestor_moved_once_the_move_plan_exists_compiles_again() -> None:
    """Clip planes are placed in world coordinates when compiled: a move of a transform above one compiles again,
    on the few-moves path too (after another move made the plan), and alongside a splice."""
    scene, moves, positions = flat(20)
    group_move = om.Translation(0.0, 0.0, 0.0)
    clip = om.ClipPlane(normal=(1.0, 0.0, 0.0), offset=0.0)
    group = scene.add(om.Node("group", [group_move, clip, om.Color(0.9, 0.9, 0.2)]))
    for k in range(3):
        group.add(om.Node(f"s{k}", [om.Translation(-1.0 + k, 4.0, 0.0), om.Sphere(radius=0.8)]))
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        moves[0].offset = (0.0, -6.0, 0.0)  # an unrelated move: the plan is made
        assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))
        group_move.offset = (1.5, 0.0, 0.0)  # the clip plane moves with its node
        assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))
        moves[1].offset = (0.0, -5.0, 0.0)
        e.render(scene, background=(0, 0, 0))
        group_move.offset = (-1.0, 0.0, 0.0)  # and with a node added in the same frame
        scene.add(om.Node("late", [om.Translation(3.0, -3.0, 0.0), om.Sphere(radius=0.5)]))
        assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))


def test_an_arrays_translations_whose_nodes_come_later_move_with_it() -> None:
    """A TranslationArray whose translations are in the scene only in part: nodes holding the others added
    later (a splice) move with the array's next touch; a node removed and added back does too."""
    n = 80
    positions = np.zeros((n, 3))
    positions[:, :2] = np.stack(np.meshgrid(np.arange(10.0), np.arange(8.0)), -1).reshape(-1, 2) * 2.0 - (9.0, 7.0)
    array = om.TranslationArray(positions)
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 30), (0, 0, 0), fov=50), om.DirectionalLight()])
    sphere = om.Sphere(radius=0.6)
    nodes = [om.Node(f"b{i}", [array[i], om.Color(0.3 + 0.7 * i / n, 0.6, 0.3), sphere]) for i in range(n)]
    for node in nodes[:60]:
        scene.add(node)
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(5):
            positions[:, 1] += 0.2
            array.touch()
            assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene)), frame
            if frame == 1:
                for node in nodes[60:]:  # the rest come (a splice each)
                    scene.add(node)
                assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))
            if frame == 3:
                scene.remove(nodes[5])
                e.render(scene, background=(0, 0, 0))
                scene.add(nodes[5])


def test_a_simulation_loop_over_translations_that_changed_hands_between_frames() -> None:
    """A loop over the same translations (enough to be told as one batch, ``component.BULK_MIN``) frame after
    frame, with between two frames of moves: a node's Translation replaced by a Matrix (the loop still sets the
    old one, in no node now), a translation taken to another node, a node added and one removed.  The batch's
    owners are patched, the move plan's look-ups kept or made again; each frame of moves draws what a fresh
    engine draws, without a compile."""
    from omnirender.core import component

    n = component.BULK_MIN + 64
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 40), (0, 0, 0), fov=50), om.DirectionalLight()])
    positions = np.zeros((n, 3))
    positions[:, 0] = np.arange(n) % 20 * 1.2 - 11.4
    positions[:, 1] = np.arange(n) // 20 * 1.2 - 9.0
    positions[:, 2] = 0.1 + 0.02 * np.arange(n)  # (each at its own depth: boxes the loop moves over others never tie)
    box = om.Box(size=0.7)
    group_move = om.Translation(0.0, 0.0, 0.0)  # above a few nodes whose translation the frames replace
    group = scene.add(om.Node("group", [group_move]))
    nodes = [
        (group if i in (22, 56) else scene).add(
            om.Node(f"b{i}", [om.Translation(offset=positions[i]), om.Color(0.3 + 0.7 * i / n, 0.6, 0.3), box])
        )
        for i in range(n)
    ]
    # two translations in the loop from the start, in no node until frames 3 and 5 (then they move what they hold)
    loose = [om.Translation(-14.0, -12.0, 0.0), om.Translation(14.0, -12.0, 0.0)]
    moves = [node.items[0] for node in nodes] + loose
    positions = np.concatenate([positions, [t.offset for t in loose]])
    spare = scene.add(om.Node("spare", [om.Color(1, 1, 1), box]))
    extra = None
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for frame in range(6):
            j = 17 * frame + 5
            node = nodes[j]
            node.remove(node.items[0])  # (the loop below still sets the translation it held)
            m = np.eye(4)
            m[:3, 3] = positions[j] + (0.0, 0.3, 0.0)
            node.insert(0, om.Matrix(m))
            if frame == 1:  # many replaced in one frame (their places dropped from the plan's look-ups at once)
                for k in range(100, 112):
                    m = np.eye(4)
                    m[:3, 3] = positions[k] - (0.0, 0.3, 0.0)
                    nodes[k].remove(nodes[k].items[0])
                    nodes[k].insert(0, om.Matrix(m))
            if frame == 5:  # one the loop moved in no node replaces a node's translation (taking its place)
                node = nodes[60]
                node.remove(node.items[0])
                node.insert(0, loose[1])
            e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] == "dirty", frame  # (replacements alone: the move plan's places taken)
            if frame == 2:  # a translation taken to another node: that node moves with the loop from now on
                taken = nodes[40].items[0]
                nodes[40].remove(taken)
                spare.insert(0, taken)
            if frame == 3:  # a node added with one the loop moved while it was in no node
                scene.add(om.Node("came", [loose[0], om.Color(0, 1, 1), box]))
            if extra is not None:
                scene.remove(extra)
            extra = scene.add(om.Node(f"x{frame}", [om.Translation(float(frame), 10.0, 0.0), om.Color(1, 0, 1), box]))
            e.render(scene, background=(0, 0, 0))
            positions[:, 1] += 0.1
            positions[:, 0] -= 0.05
            positions[-2:, 1] += 1.0
            for t, row in zip(moves, positions, strict=True):
                t.offset = row
            image = e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] is False, frame
            assert np.array_equal(image.array, fresh(scene)), frame
            group_move.offset = (0.0, -0.5 * frame, 0.0)  # the group's rows recomposed from the plan's matrices
            image = e.render(scene, background=(0, 0, 0))
            assert np.array_equal(image.array, fresh(scene)), frame


def test_a_drag_after_a_setter_loop_moves_one_transform_at_a_time_through_the_map() -> None:
    """After a setter loop made the translation map, one moved transform a frame (the few-moves path): a child
    below two translations, a parent whose children's rows are made from it, a plain translation, the rotation."""
    scene, moves, parents, spin = nested()
    with engine() as e:
        e.render(scene, background=(0, 0, 0))
        for t in moves:  # the map is made by a frame of many moves
            x, y, z = t.offset
            t.offset = (x + 0.1, y - 0.2, z)
        assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))
        odd_child = moves[12]  # group 1's second child: below the rotation and its own translation
        for frame, t in enumerate([moves[1], parents[1], odd_child, moves[2], parents[0]]):
            x, y, z = t.offset
            t.offset = (x - 0.3, y + 0.4 * (frame + 1), z)
            image = e.render(scene, background=(0, 0, 0))
            assert e.stats["compiled"] is False and e.stats["incremental"] >= 1
            assert np.array_equal(image.array, fresh(scene)), frame
        spin.angle = 45.0
        assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))
        moves[3].offset = (0.5, 0.5, 0.0)
        assert np.array_equal(e.render(scene, background=(0, 0, 0)).array, fresh(scene))
        for t in moves:  # a setter loop again: the map followed what the drag moved other than through it
            x, y, z = t.offset
            t.offset = (x, y + 0.3, z)
        image = e.render(scene, background=(0, 0, 0))
        assert e.stats["compiled"] is False
        assert np.array_equal(image.array, fresh(scene))
