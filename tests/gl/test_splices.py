"""Nodes added and removed frame after frame: the splice compiles only the new node (issue 22, splice).

A splice enters the new node's ancestors with their kept programs and takes the draw state resolved where a
child of that parent was entered before (kept while the ancestors' leading components and their versions are
the same); a new plain ``om.Material`` of the values of one seen before takes the row made for it.  Each path
is checked against a fresh engine's picture of the same scene, and that it was the splice that drew it.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (80, 64)


def fresh(scene: om.Node, shadows: bool = False) -> np.ndarray:
    """A fresh engine's picture of a copy of ``scene`` (a copy: no cache the graph keeps is shared)."""
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=shadows) as e:
        return e.render(copy.deepcopy(scene)).array


def base_scene() -> tuple[om.Node, list[om.Node], om.Box]:
    """A camera and a light, then two groups of a few plain boxes (components before children everywhere)."""
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 12), (0, 0, 0), fov=45)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.8)
    groups = []
    for g in range(2):
        group = scene.add(om.Node(f"g{g}", [om.Translation(3.0 * g - 1.5, 0.0, 0.0)]))
        for i in range(3):
            group.add(om.Node(f"b{g}_{i}", [om.Translation(0.0, 1.2 * i - 1.2, 0.0), om.Material(), box]))
        groups.append(group)
    return scene, groups, box


def leaf(name: str, at: tuple[float, float, float], box: om.Box, **material: object) -> om.Node:
    return om.Node(name, [om.Translation(*at), om.Material(**material), box])


def check(e: object, scene: om.Node, what: str, spliced: bool = True) -> np.ndarray:
    image = e.render(scene)  # type: ignore[attr-defined]
    if spliced:
        assert e.stats["compiled"] == "subtrees", what  # type: ignore[attr-defined]
    assert np.array_equal(image.array, fresh(scene)), what
    return image.array


def test_a_node_added_and_the_last_one_removed_frame_after_frame_draws_like_a_fresh_engine():
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        extra = None
        before = None
        for frame in range(5):
            if extra is not None:
                scene.remove(extra)
            extra = scene.add(leaf(f"x{frame}", (frame - 2.0, 2.5, 1.0), box, diffuse=(1.0, 0.0, 0.0)))
            image = check(e, scene, f"frame {frame}")
            assert before is None or not np.array_equal(image, before)  # the red box moved
            before = image


def test_a_node_added_under_a_moved_parent_takes_the_parent_where_it_is_now():
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        groups[0].add(leaf("first", (0.0, 2.4, 0.0), box, diffuse=(0.0, 1.0, 0.0)))
        check(e, scene, "first added")
        groups[0].items[0].offset = (-3.0, -1.0, 0.5)  # moved in place (no compile)
        e.render(scene)
        assert e.stats["compiled"] is False
        groups[0].add(leaf("second", (0.0, 3.4, 0.0), box, diffuse=(0.0, 0.0, 1.0)))
        check(e, scene, "added after the parent moved")
        groups[0].items[0].offset = (-2.0, -0.5, 0.0)  # moved in the frame a node is added under it
        groups[0].add(leaf("third", (1.0, 3.4, 0.0), box, diffuse=(1.0, 1.0, 0.0)))
        check(e, scene, "added as the parent moved", spliced=False)
        groups[0].add(leaf("fourth", (-1.0, 3.4, 0.0), box, diffuse=(1.0, 0.0, 1.0)))
        check(e, scene, "added after that")


def test_new_materials_of_equal_and_of_other_values_each_draw_their_own():
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    materials = [
        {"diffuse": (1.0, 0.0, 0.0)},
        {"diffuse": (1.0, 0.0, 0.0)},  # equal values: the row made for the first
        {"diffuse": (1.0, 0.0, 0.0), "opacity": 0.5},  # each other value draws differently
        {"diffuse": (1.0, 0.0, 0.0), "specular": (1.0, 1.0, 1.0), "shininess": 8.0},
        {"diffuse": (1.0, 0.0, 0.0), "specular": (1.0, 1.0, 1.0), "shininess": 64.0},
        {"diffuse": (1.0, 0.0, 0.0), "emission": (0.0, 0.5, 0.0)},
        {"diffuse": (1.0, 0.0, 0.0), "ambient": (0.9, 0.9, 0.0)},
        {"diffuse": (0.0, 0.0, 1.0)},
    ]
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        extra = None
        seen = []
        for k, values in enumerate(materials):
            if extra is not None:
                scene.remove(extra)
            extra = scene.add(leaf(f"m{k}", (0.0, 2.6, 2.0), box, **values))
            image = check(e, scene, str(values))
            if k != 1:
                assert not any(np.array_equal(image, other) for other in seen), values
            seen.append(image)
        assert np.array_equal(seen[0], seen[1])
        extra.items[1].diffuse = (0.0, 1.0, 0.0)  # the added node's material changed after it was added
        check(e, scene, "its material changed", spliced=False)
        scene.add(leaf("again", (2.0, 2.6, 2.0), box, diffuse=(0.0, 0.0, 1.0)))
        check(e, scene, "a material of the values of the changed one's before")


def test_a_node_removed_then_added_again_draws_again():
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    node = groups[1].children[1]
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        full = e.render(scene).array
        groups[1].remove(node)
        without = check(e, scene, "removed")
        assert not np.array_equal(without, full)
        groups[1].add(node)  # again, at the end of its list
        assert np.array_equal(check(e, scene, "added again"), full)
        groups[1].remove(node)
        groups[0].add(node)  # elsewhere, in one frame
        check(e, scene, "moved to the other group", spliced=False)
        groups[0].remove(node)
        groups[0].add(node)  # removed and added again in one frame
        check(e, scene, "removed and added again in one frame", spliced=False)
        scene.remove(groups[1])  # a whole group, then back
        check(e, scene, "a group removed")
        scene.add(groups[1])
        check(e, scene, "the group added again")


def test_nodes_added_deeper_take_the_state_of_every_ancestor_as_it_is_now():
    """Under a group with a draw style, a colour and a clip plane below a moved transform: the state where a
    child enters is kept per parent, and each change of an ancestor's leading components is followed."""
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    style = om.DrawStyle(mode="filled")
    clip = om.ClipPlane(normal=(1.0, 0.0, 0.0), offset=0.0)
    inner = groups[1].add(om.Node("inner", [om.Translation(0.0, 0.0, 1.0), style, clip, om.Color(0.2, 0.9, 0.9)]))
    ball = om.Sphere(radius=0.5)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        inner.add(om.Node("a", [om.Translation(-0.3, 2.5, 0.0), ball]))  # only the Color: the parent's surface
        check(e, scene, "a plain child, cut by the clip plane")
        inner.add(leaf("b", (0.3, -2.5, 0.0), box, diffuse=(1.0, 0.5, 0.0)))
        check(e, scene, "a child with a material")
        inner.add(om.Node("c", [om.Translation(0.0, 0.0, 0.0), om.DrawStyle(mode="wireframe"), ball]))
        check(e, scene, "a child with a draw style of its own")
        inner.add(om.Node("d", [om.Translation(0.6, 0.0, 0.0), ball]))
        check(e, scene, "the next child: the parent's style, not its sibling's")
        style.mode = "wireframe"  # the parent's style changed (compiled in full), then a child added
        e.render(scene)
        inner.add(om.Node("e", [om.Translation(0.0, 1.2, 0.0), ball]))
        check(e, scene, "added after the parent's style changed")
        points = om.DrawStyle(mode="filled", point_size=3.0)
        points.mode = "points"
        assert points.version == style.version  # only which object it is tells the two apart
        inner.remove(style)
        inner.insert(1, points)  # replaced by another of its kind
        e.render(scene)
        inner.add(om.Node("f", [om.Translation(0.0, -1.2, 0.0), ball]))
        check(e, scene, "added after the parent's style was replaced")
        groups[1].items[0].offset = (2.0, 0.5, 0.0)  # the clip plane's world place moves with the grandparent
        check(e, scene, "the grandparent moved: its clip plane with it", spliced=False)
        inner.add(om.Node("g", [om.Translation(-0.6, 0.6, 0.0), ball]))
        check(e, scene, "added after the grandparent moved")
        clip.offset = 0.4
        e.render(scene)
        inner.add(om.Node("h", [om.Translation(0.4, 0.6, 0.0), ball]))
        check(e, scene, "added after the clip plane moved")


def test_a_node_added_another_removed_and_a_third_moved_in_one_frame():
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        for frame in range(3):
            scene.add(leaf(f"n{frame}", (frame - 1.0, 2.6, 1.0), box, diffuse=(0.9, 0.1 * frame, 0.1)))
            groups[frame % 2].remove(groups[frame % 2].children[0])
            groups[1 - frame % 2].children[-1].items[0].offset = (0.2 * frame, -2.4, 0.5)
            check(e, scene, f"frame {frame}", spliced=False)
            scene.add(leaf(f"p{frame}", (frame - 1.0, -2.6, 1.0), box, diffuse=(0.1, 0.9, 0.1 * frame)))
            check(e, scene, f"a plain splice after frame {frame}")


def test_a_new_node_holding_a_subtree_or_a_light_draws_like_a_fresh_engine():
    """Node(name, items) fills itself without telling the engines; adding it to the scene is the edit they see."""
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        dark = e.render(scene).array
        sub = om.Node("sub", [om.Translation(0.0, 2.5, 0.0), om.Material(diffuse=(0.2, 0.2, 1.0)), box])
        scene.add(om.Node("holder", [om.Translation(-1.0, 0.0, 1.0), sub, om.Node("empty")]))
        check(e, scene, "a node holding a subtree")
        shared = groups[0].children[0]
        scene.add(om.Node("again", [om.Translation(0.0, 0.0, -2.0), shared]))  # a node already in the scene
        check(e, scene, "a node holding a node drawn elsewhere too", spliced=False)
        lamp = scene.add(om.Node("lamp", [om.Translation(0.0, 0.0, 4.0), om.PointLight(intensity=3.0)]))
        lit = check(e, scene, "a node holding a light", spliced=False)
        assert not np.array_equal(lit, dark)
        scene.remove(lamp)
        check(e, scene, "the light removed", spliced=False)

    class Logged(om.Node):  # a subclass's own insert still sees the constructor's items
        seen: list = []

        def insert(self, index, item):
            Logged.seen.append(item)
            return super().insert(index, item)

    t = om.Translation(1.0, 2.0, 3.0)
    node = Logged("logged", [t, box])
    assert Logged.seen == [t, box] and node.items == (t, box) and t.owners == (node,)
    assert node.last_items(1) == (box,) and node.last_items(0) == () and node.last_items(5) == (t, box)
    plain = om.Node("plain", [t, box])
    assert plain.version == node.version and plain.structure_version == node.structure_version
    with pytest.raises(TypeError, match="did you mean Box"):
        om.Node("bad", [om.Box])


def test_nodes_added_in_one_frame_under_a_textured_parent_and_a_plain_one_each_take_their_own():
    """What the surface reads besides the surface stack (a texture, a highlight) is read again whenever a
    painter changed the compile state: the second new node of a frame does not take the first one's texture."""
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    checker = np.kron(np.array([[0, 1], [1, 0]] * 2, np.uint8), np.ones((8, 16), np.uint8))[..., None] * 255
    textured = scene.add(om.Node("textured", [om.Translation(0.0, 2.6, 1.0), om.Texture(np.repeat(checker, 3, 2))]))
    lit = scene.add(om.Node("lit", [om.Translation(0.0, -2.6, 1.0), om.Highlight(color=(1.0, 1.0, 0.0))]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        for frame in range(2):
            textured.add(leaf(f"t{frame}", (frame - 0.5, 0.0, 0.0), box, diffuse=(0.9, 0.9, 0.9)))
            groups[frame].add(leaf(f"p{frame}", (0.0, 2.4, 0.0), box, diffuse=(0.9, 0.9, 0.9)))
            lit.add(leaf(f"h{frame}", (frame - 0.5, 0.0, 0.0), box, diffuse=(0.9, 0.9, 0.9)))
            scene.add(leaf(f"s{frame}", (2.5 * frame - 3.0, 0.0, 2.0), box, diffuse=(0.9, 0.9, 0.9)))
            check(e, scene, f"frame {frame}")


def test_a_material_of_equal_values_replaced_after_a_splice_restyles_its_own_node():
    """Nodes added with materials of equal values share what was made for the values, but each item's
    resolved surface names its own material: replacing one of them restyles its node, not the others."""
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        nodes = [scene.add(leaf(f"e{k}", (2.0 * k - 2.0, 2.6, 1.0), box, diffuse=(0.9, 0.3, 0.1))) for k in range(3)]
        check(e, scene, "three equal materials added")
        for frame, node in enumerate([nodes[1], nodes[2], nodes[0]]):
            node.remove(node.items[1])
            node.insert(1, om.Material(diffuse=(0.1, 0.3 + 0.3 * frame, 0.9)))
            check(e, scene, f"replaced in {node.name}", spliced=False)


def test_nodes_added_and_removed_between_setter_loops_before_the_translation_map_is_used_again():
    """The map of many moved translations takes the nodes splices brought when it is next used: a node added
    and removed again before that, and one added twice over, leave no row written for a removed item."""
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [om.Camera.look_at((0, 0, 16), (0, 0, 0), fov=50)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    box = om.Box(size=0.5)
    moves = []
    for i in range(100):
        t = om.Translation(i % 10 - 4.5, i // 10 - 4.5, 0.0)
        moves.append(t)
        scene.add(om.Node(f"b{i}", [t, om.Material(diffuse=(0.3 + 0.007 * i, 0.5, 0.4)), box]))
    spun = scene.add(om.Node("spun", [om.Rotation(30.0, (0, 0, 1))]))  # new nodes below a rotation too
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        extra: list[om.Node] = []
        for frame in range(4):
            for k, t in enumerate(moves):  # all of them: the translation map writes the rows
                t.offset = (k % 10 - 4.5 + 0.1 * frame, k // 10 - 4.5, 0.2 * frame)
            check(e, scene, f"loop {frame}", spliced=False)
            for step in range(3):  # splices with no loop between: the map is not used in between
                parent = spun if step == 1 else scene
                node = parent.add(leaf(f"x{frame}_{step}", (step - 1.0, 4.5 - frame, 1.0), box, diffuse=(1, 0, 0)))
                moves.append(node.items[0])
                extra.append(node)
                if step == 2:
                    gone = extra.pop(-2)  # the one added just before, still waiting for the map
                    moves.remove(gone.items[0])
                    gone.parent.remove(gone)
                check(e, scene, f"splice {frame}.{step}")


def test_a_moved_light_and_nodes_added_after_it_draw_with_the_light_where_it_is_now():
    """A root's declarations are kept while its placements are the same components at equal matrices: a
    moved lamp makes them again (compared with a fresh engine's picture of a copy: nothing the graph caches
    is shared with it)."""
    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    lamp = om.Translation(-3.0, 2.0, 3.0)
    scene.add(om.Node("lamp", [lamp, om.PointLight(intensity=4.0)]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        scene.add(leaf("a", (0.0, 2.6, 1.0), box, diffuse=(0.9, 0.9, 0.9)))
        check(e, scene, "added with the lamp where it was")
        lamp.offset = (3.0, -2.0, 3.0)
        moved = check(e, scene, "the lamp moved", spliced=False)
        assert not np.array_equal(moved, before)
        scene.add(leaf("b", (0.0, -2.6, 1.0), box, diffuse=(0.9, 0.9, 0.9)))
        check(e, scene, "added after the lamp moved")
        lamp.offset = (3.0, -2.0, 3.0)  # the same place again: the same declarations
        check(e, scene, "moved to where it is", spliced=False)
        scene.remove(scene.child("a"))
        lamp.offset = (0.0, 0.0, 4.0)
        check(e, scene, "removed as the lamp moved", spliced=False)


def test_a_node_at_the_address_of_a_node_that_died_is_still_spliced():
    """The compiler maps id(node) -> its occurrence; a node that died leaves its entry behind, and a new node
    may take its address.  That entry must not make the new node count as met twice when a full compile meets
    it (which turned later splices below it into full compiles at random: whenever an address was reused)."""
    import gc
    import weakref

    from omnirender.gl import GLEngine

    scene, groups, box = base_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        gone = om.Node("gone")
        dead = weakref.ref(gone)
        del gone
        gc.collect()
        assert dead() is None
        holder = om.Node("holder", [om.Translation(0.0, 2.4, 0.0)])
        # what a node that died at the new node's address left behind (another key, a dead reference)
        e.compiler._occurrence_of[id(holder)] = (10_000, dead)
        groups[0].add(holder)
        groups[1].add(om.DrawStyle(mode="wireframe"))  # in the same frame: a full compile (no splice follows it)
        check(e, scene, "a node added in a full compile", spliced=False)
        assert e.stats["compiled"] is True
        holder.add(leaf("new", (0.0, 0.0, 0.0), box, diffuse=(0.2, 0.8, 0.3)))
        check(e, scene, "a node added below it")
