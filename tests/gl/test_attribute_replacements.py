"""An attribute replaced by one of the same role is a dirty bit, not a subtree compile (issue 22, ``dirty.py``).

A transform replaced by a transform (any kinds) recomposes the rows below it; a Material / PBRMaterial
replaced by one of either, or a Color by a Color, rewrites the surface fields of the rows it decided.  Each
case is checked against a fresh engine's picture of the same scene, and the path taken is checked too: what
would choose another draw state (transparent now, a texture, another shading model, a mirroring transform)
must take the subtree compile instead.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

from .changes import SIZE, box_grid, fresh, nested_scene

pytestmark = pytest.mark.gl


def replace(node: om.Node, old: object, new: object) -> None:
    """What applications write: the old attribute out, the new one in at its place."""
    at = node.items.index(old)
    node.remove(old)
    node.insert(at, new)


def render_checked(e, scene: om.Node, path: str, before: np.ndarray | None = None, shadows: bool = False):
    image = e.render(scene)
    assert e.stats["compiled"] == path
    assert np.array_equal(image.array, fresh(scene, shadows))
    if before is not None:
        assert not np.array_equal(image.array, before)  # the change shows: a stale row would be seen
    return image


def test_a_translation_replaced_by_a_matrix_recomposes_its_rows_in_place():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        e.render(scene)
        for frame, leaf in enumerate(leaves[2:12:3]):
            m = np.eye(4)
            m[:3, 3] = np.asarray(leaf.items[0].offset) + (0.3, 0.2 * frame, 0.4)
            replace(leaf, leaf.items[0], om.Matrix(m))
            image = render_checked(e, scene, "dirty", before)
            assert e.stats["dirty"] == ("transform",) and e.stats["incremental"] == 1
            assert image.info["replayed"]  # rows uploaded, the recorded plan replayed
            before = image.array
        assert e.stats["items"] == len(leaves)


def test_a_parents_transform_replaced_moves_every_row_below_it():
    """Matrix -> Rotation and Rotation -> Matrix on a group with five leaves: each leaf's chain of three
    transforms (the group's two, its own) keeps its order with the new one at the old one's place."""
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    group = groups[1]
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        rotation = group.items[1]
        m = om.Rotation(35.0, (0, 1, 0)).matrix.copy()
        m[:3, 3] = (0.0, 0.5, 0.0)
        replace(group, rotation, om.Matrix(m))  # Rotation -> Matrix
        before = render_checked(e, scene, "dirty", before).array
        assert e.stats["incremental"] == 5
        replace(group, group.items[1], om.Rotation(-25.0, (1, 0, 0)))  # Matrix -> Rotation
        before = render_checked(e, scene, "dirty", before).array
        replace(group, group.items[0], om.Scaling(0.8))  # the first of the chain: Translation -> Scaling
        before = render_checked(e, scene, "dirty", before).array
        assert e.stats["incremental"] == 5


def test_a_transform_in_the_middle_of_a_nodes_chain_is_replaced_at_its_place():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    leaf = leaves[6]
    spin = om.Rotation(30.0, (0, 0, 1))
    leaf.insert(1, spin)
    leaf.insert(2, om.Scaling((1.0, 2.0, 1.0)))  # Translation, Rotation, Scaling: the order matters
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        replace(leaf, spin, om.Matrix(om.Rotation(-50.0, (0, 0, 1)).matrix))
        render_checked(e, scene, "dirty", before)


def test_a_mirroring_transform_takes_the_subtree_compile():
    """A transform that flips the determinant's sign changes which faces are culled: another draw state."""
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    leaf = leaves[3]
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        replace(leaf, leaf.items[0], om.Matrix(np.diag([-1.5, 1.0, 1.0, 1.0])))
        render_checked(e, scene, "subtrees", before)


def test_a_material_replaced_by_a_material_rewrites_its_row():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        e.render(scene)
        for frame, leaf in enumerate(leaves[1:16:4]):
            material = om.Material(diffuse=(1.0, 0.1 * frame, 0.1), specular=(0.5, 0.5, 0.5), shininess=40)
            replace(leaf, leaf.items[1], material)
            image = render_checked(e, scene, "dirty", before)
            assert e.stats["dirty"] == ("appearance",) and e.stats["incremental"] == 1
            before = image.array
        leaf = leaves[9]
        replace(leaf, leaf.items[1], om.PBRMaterial(base_color=(0.2, 0.9, 0.3), roughness=0.3))
        before = render_checked(e, scene, "subtrees", before).array  # another shading model: another program
        replace(leaf, leaf.items[1], om.PBRMaterial(base_color=(0.9, 0.2, 0.8), metallic=0.7))
        render_checked(e, scene, "dirty", before)  # PBR -> PBR


def test_a_material_made_transparent_or_textured_takes_the_subtree_compile():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    texture = om.Texture(np.array([[[255, 0, 0], [0, 0, 255]], [[0, 255, 0], [255, 255, 0]]], np.uint8))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        glass = leaves[7]
        replace(glass, glass.items[1], om.Material(diffuse=(0.2, 0.4, 1.0), opacity=0.4))
        before = render_checked(e, scene, "subtrees", before).array  # opaque -> transparent
        assert any(item.transparent and item.node is glass for item in e.index.items())
        replace(glass, glass.items[1], om.Material(diffuse=(1.0, 0.4, 0.2), opacity=0.6))
        before = render_checked(e, scene, "dirty", before).array  # transparent -> transparent: the row only
        replace(glass, glass.items[1], om.PBRMaterial(base_color=(0.3, 1.0, 0.2), opacity=0.5, roughness=0.2))
        before = render_checked(e, scene, "subtrees", before).array  # transparent too, another shading model
        replace(glass, glass.items[1], om.Material(diffuse=(1.0, 0.4, 0.2), opacity=0.6))
        before = render_checked(e, scene, "subtrees", before).array
        replace(glass, glass.items[1], om.Material(diffuse=(1.0, 0.4, 0.2)))
        before = render_checked(e, scene, "subtrees", before).array  # back to opaque
        box = leaves[4]  # (a box: texture coordinates)
        replace(box, box.items[1], om.PBRMaterial(base_color_texture=texture))
        before = render_checked(e, scene, "subtrees", before).array  # Material -> textured material
        replace(box, box.items[1], om.PBRMaterial(base_color=(0.3, 0.3, 0.9)))
        render_checked(e, scene, "subtrees", before)  # the texture leaves: another program


def test_a_replaced_attribute_is_drawn_the_same_in_the_next_frames():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        leaf = leaves[10]
        replace(leaf, leaf.items[1], om.Material(diffuse=(0.9, 0.9, 0.1)))
        replace(leaf, leaf.items[0], om.Matrix(np.array(om.Translation(0.5, 0.0, 1.0).matrix)))
        first = render_checked(e, scene, "dirty")
        assert e.stats["dirty"] == ("appearance", "transform")
        second = e.render(scene)
        assert e.stats["compiled"] is False and second.info["replayed"]
        assert np.array_equal(second.array, first.array)
        groups[2].items[0].offset = (1.0, 0.5, 0.0)  # a transform above the new one moves
        assert np.array_equal(e.render(scene).array, fresh(scene))
        assert e.stats["compiled"] is False
        replace(leaf, leaf.items[1], om.Material(diffuse=(0.1, 0.9, 0.9)))  # replaced again: the new entry
        render_checked(e, scene, "dirty", first.array)
        groups[2].remove(leaf)  # a splice after dirty bits
        render_checked(e, scene, "subtrees")


def test_replaced_and_moved_in_the_same_frame():
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        leaf = leaves[12]
        replace(leaf, leaf.items[1], om.Material(diffuse=(1.0, 0.0, 0.5)))
        leaf.items[0].offset = (0.0, 0.5, 1.5)  # its own transform moved
        before = render_checked(e, scene, "dirty", before).array
        replace(leaf, leaf.items[0], om.Matrix(np.array(om.Translation(0.3, -1.0, 1.0).matrix)))
        groups[2].items[1].angle = 40.0  # the parent's rotation moved
        before = render_checked(e, scene, "dirty", before).array
        new = om.Translation(0.0, 1.0, 0.0)
        replace(groups[3], groups[3].items[0], new)
        new.offset = (1.5, 1.0, 0.5)  # the new transform itself moved after it came
        before = render_checked(e, scene, "dirty", before).array
        replace(leaf, leaf.items[1], om.Material(diffuse=(0.0, 1.0, 0.5)))
        leaf.items[2].radius = 0.5  # another parameter changed in the node: the subtree compile
        render_checked(e, scene, "subtrees", before)


def test_a_colour_or_a_parents_material_rewrites_only_the_rows_it_decides():
    """A group's Material decides the leaves without one of their own; a Color after a Material tints it."""
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [om.Camera.look_at((0, 3, 10), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.4, -0.6, -1.0)))
    group = scene.add(om.Node("group", [om.Material(diffuse=(0.8, 0.8, 0.8)), om.Color(0.9, 0.3, 0.3)]))
    shapes = []
    for i in range(4):
        own = [om.Material(diffuse=(0.1, 0.9, 0.1))] if i == 2 else []
        shapes.append(group.add(om.Node(f"s{i}", [om.Translation(2.0 * i - 3.0, 0, 0), *own, om.Sphere(radius=0.6)])))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        replace(group, group.items[1], om.Color(0.2, 0.3, 0.9))
        before = render_checked(e, scene, "dirty", before).array
        assert e.stats["incremental"] == 3  # the leaf with its own material is not below the colour
        replace(group, group.items[0], om.Material(diffuse=(0.5, 0.5, 0.5), specular=(1, 1, 1), shininess=80))
        before = render_checked(e, scene, "dirty", before).array  # the colour still tints it
        assert e.stats["incremental"] == 3
        replace(shapes[2], shapes[2].items[1], om.Material(diffuse=(0.9, 0.9, 0.1)))
        render_checked(e, scene, "dirty", before)


def test_a_material_replaced_in_a_batch_of_one_material_draws_the_batch_anew():
    """Boxes sharing one material are drawn with it as uniforms; a different one makes the rows differ."""
    from omnirender.gl import GLEngine

    scene, nodes = box_grid(12, 4, 0.8, eye=(0, 4, 12), fov=45)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        (batch,) = e.batches
        assert batch.uniform
        replace(nodes[5], nodes[5].items[1], om.Material(diffuse=(0.9, 0.1, 0.1)))  # another colour only
        before = render_checked(e, scene, "dirty", before).array
        assert batch.uniform
        replace(nodes[0], nodes[0].items[1], om.Material(specular=(1, 1, 1), shininess=10, emission=(0.3, 0, 0)))
        image = render_checked(e, scene, "dirty", before)
        assert not batch.uniform and not image.info["replayed"]  # packed again with the material per row
        e.render(scene)
        assert e.render(scene).info["replayed"]


@pytest.mark.parametrize("shadows", [False, True])
def test_replacements_in_a_big_scene_match_a_fresh_engine(shadows):
    """With shadows too: a Material replaced changes no shadow map, so the recorded frame is replayed (the maps
    kept); a Matrix replaced moves a caster (its maps' region is redrawn: the frame is drawn in full)."""
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [om.Camera.look_at((0, 0, 22), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.3, -0.5, -1.0)))
    box = om.Box(size=0.7)
    nodes = []
    for i in range(96):
        color = om.Material(diffuse=(0.2 + (i % 5) / 6, 0.5, 0.7))
        nodes.append(scene.add(om.Node(f"b{i}", [om.Translation(i % 12 - 5.5, i // 12 - 4.0, 0), color, box])))
    with GLEngine(size=SIZE, samples=0, shadows=shadows) as e:
        for _ in range(3):
            e.render(scene)
        for frame in range(6):
            node = nodes[(frame * 37 + 11) % len(nodes)]
            if frame % 2:
                m = np.eye(4)
                m[:3, 3] = node.items[0].matrix[:3, 3] + (0.2, 0.3, 0.5)
                replace(node, node.items[0], om.Matrix(m))
            else:
                replace(node, node.items[1], om.Material(diffuse=(1.0, 0.2 * frame, 0.1)))
            image = e.render(scene)
            assert e.stats["compiled"] == "dirty"
            assert np.array_equal(image.array, fresh(scene, shadows)), frame
            if frame % 2 == 0:
                assert image.info["replayed"], frame  # the surface rows uploaded, the plan (and maps) kept
                if shadows:
                    assert e.stats["shadow_maps"]["kept"] == 1
            e.render(scene)  # (a frame recorded again after a frame drawn in full)


def test_a_material_replaced_beside_items_casting_no_shadow():
    """Shadow casters drawn from copies of the batches (some items cast none) follow their source only in frames
    drawn in full: the frame after a replaced Material is drawn in full, and right."""
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    groups[3].insert(0, om.Shadowing(cast=False))
    with GLEngine(size=SIZE, samples=0, shadows=True) as e:
        before = e.render(scene).array
        e.render(scene)
        leaf = leaves[6]
        replace(leaf, leaf.items[1], om.Material(diffuse=(1.0, 1.0, 0.2)))
        render_checked(e, scene, "dirty", before, shadows=True)
        leaf = leaves[17]  # one of the items casting no shadow
        replace(leaf, leaf.items[1], om.Material(diffuse=(0.2, 1.0, 1.0)))
        render_checked(e, scene, "dirty", before, shadows=True)


def test_a_replaced_transform_above_a_light_moves_the_light():
    """Lights and the camera below a replaced transform are placed again (the declarations follow)."""
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    lamp = scene.add(om.Node("lamp", [om.Translation(0.0, 3.0, 4.0)]))
    bulb = lamp.add(om.Node("bulb", [om.Translation(0.0, 0.0, 0.5), om.PointLight(intensity=2.0)]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        replace(lamp, lamp.items[0], om.Matrix(np.array(om.Translation(-4.0, -2.0, 4.0).matrix)))
        before = render_checked(e, scene, "dirty", before).array  # the light two nodes below it moved
        replace(bulb, bulb.items[0], om.Translation(3.0, 3.0, 0.0))
        before = render_checked(e, scene, "dirty", before).array
        declared = e.declared
        replace(leaves[4], leaves[4].items[0], om.Translation(0.0, 2.5, 1.0))  # declares nothing: kept
        render_checked(e, scene, "dirty", before)
        assert e.declared is declared


def test_replacements_in_frames_that_move_every_other_node():
    """A replaced transform in a frame whose setter loop moves all the other nodes (the translation map of many
    moves follows the replaced chain), then loops without replacements: each frame as a fresh engine draws it."""
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [om.Camera.look_at((0, 0, 24), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.3, -0.5, -1.0)))
    box = om.Box(size=0.6)
    nodes = [
        scene.add(om.Node(f"b{i}", [om.Translation(i % 10 - 4.5, i // 10 - 4.5, 0), om.Material(), box]))
        for i in range(100)
    ]
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        for frame in range(6):
            node = nodes[(frame * 31 + 7) % len(nodes)]
            if frame in (2, 4):
                m = np.eye(4)
                m[:3, 3] = node.items[0].matrix[:3, 3] + (0.0, 0.0, 1.0)
                replace(node, node.items[0], om.Matrix(m))
            for other in nodes:
                t = other.items[0]
                if isinstance(t, om.Translation):
                    x, y, z = t.offset
                    t.offset = (x, y + 0.05, z)
            image = e.render(scene)
            assert e.stats["compiled"] == ("dirty" if frame in (2, 4) else False), frame
            assert np.array_equal(image.array, fresh(scene)), frame


def test_a_material_replaced_on_points_and_lines_keeps_their_draw_style():
    """Points sized by a DrawStyle and lines: the new surface fields only (the row's point size stays)."""
    from omnirender.gl import GLEngine

    scene = om.Node("scene", [om.Camera.look_at((0, 0, 6), (0, 0, 0), fov=40)])
    scene.add(om.DirectionalLight(direction=(-0.3, -0.5, -1.0)))
    grid = np.array([(x, y, 0.0) for x in np.linspace(-1.5, 1.5, 5) for y in np.linspace(-1, 1, 4)])
    dots = scene.add(om.Node("dots", [om.DrawStyle(point_size=7.0), om.Material(diffuse=(0.9, 0.2, 0.2))]))
    dots.add(om.PointSet(grid))
    lines = scene.add(om.Node("lines", [om.Color(0.2, 0.9, 0.2)]))
    lines.add(om.LineSet(grid[:8] + (0.0, 0.0, 0.5), [(0, 5), (1, 6), (2, 7)]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        replace(dots, dots.items[1], om.Material(diffuse=(0.2, 0.3, 1.0)))
        before = render_checked(e, scene, "dirty", before).array
        replace(lines, lines.items[0], om.Color(1.0, 0.8, 0.1))
        render_checked(e, scene, "dirty", before)


def assert_close(image: np.ndarray, reference: np.ndarray) -> None:
    """Within 1/255 on at most 1 % of the pixels: softpipe blends the highlight pass of a list compiled again
    1/255 off a fresh engine's on a few pixels (the full compile's draw order; this path is not the dirty
    bits'); a wrong surface or place differs by far more."""
    diff = np.abs(image.astype(int) - reference.astype(int)).max(axis=2)
    assert diff.max() <= 1 and (diff > 0).mean() <= 0.01


def test_replacements_below_a_technique_take_the_compile():
    """A technique's passes may draw what a surface or a transform decides their own way (a highlight pass):
    items in a technique's scope take the compile, and the picture is right."""
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    groups[1].insert(0, om.gl.PhongHighlight(om.Texture(om.gl.PhongHighlight.lobe(30.0, 32))))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        leaf = leaves[6]
        replace(leaf, leaf.items[1], om.Material(diffuse=(1.0, 1.0, 0.2), specular=(1, 1, 1), shininess=20))
        image = e.render(scene)
        assert e.stats["compiled"] in (True, "subtrees")
        assert_close(image.array, fresh(scene))
        assert not np.array_equal(image.array, before)
        before = image.array
        replace(leaf, leaf.items[0], om.Matrix(np.array(om.Translation(0.5, 0.0, 1.0).matrix)))
        image = e.render(scene)
        assert e.stats["compiled"] in (True, "subtrees")
        assert_close(image.array, fresh(scene))
        assert not np.array_equal(image.array, before)
        leaf = leaves[2]  # outside the technique: dirty bits
        replace(leaf, leaf.items[1], om.Material(diffuse=(0.1, 1.0, 0.2)))
        after = e.render(scene)
        assert e.stats["compiled"] == "dirty"
        assert_close(after.array, fresh(scene))  # (the technique's pixels as the compile before left them)
        changed = np.abs(after.array.astype(int) - image.array.astype(int)).max(axis=2) > 8
        assert changed.any()  # the restyled leaf shows


def test_appearances_sampling_no_texture_share_one_texture_set_of_the_same_key():
    """A Material replaced per frame makes no texture set: the appearances that sample no texture share one per
    model and alpha mode, equal to the set made for each (the draw state a replacement must keep)."""
    from omnirender.attributes.surface import resolve_appearance
    from omnirender.gl.engine.compiler import TextureSet, texture_set

    texture = om.Texture(np.array([[[255, 0, 0], [0, 0, 255]], [[0, 255, 0], [255, 255, 0]]], np.uint8))
    stacks = [
        [om.Material(diffuse=(1.0, 0.0, 0.0))],
        [om.Material(opacity=0.5)],
        [om.Material(), om.Color(0.1, 0.2, 0.3)],
        [om.Color(0.1, 0.2, 0.3, 0.5)],
        [om.PBRMaterial()],
        [om.PBRMaterial(opacity=0.4)],
        [om.PBRMaterial(alpha_mode="mask", alpha_cutoff=0.3)],
        [om.PBRMaterial(alpha_mode="mask", alpha_cutoff=0.7)],
        [om.PBRMaterial(base_color_texture=texture)],
        [om.PBRMaterial(normal_texture=texture)],
    ]
    apps = [resolve_appearance(stack) for stack in stacks] + [resolve_appearance([om.Material()], texture=texture)]
    for app in apps:
        assert texture_set(app).key == TextureSet(app).key
    shared = texture_set(apps[0])
    assert texture_set(resolve_appearance([om.Material(diffuse=(0.0, 1.0, 0.0))])) is shared
    assert texture_set(apps[1]) is not shared  # blended: another alpha mode
    assert texture_set(apps[6]) is not texture_set(apps[7])  # another cut-off
    assert texture_set(apps[8]) is not texture_set(apps[8])  # a textured appearance's own set


def test_an_item_put_back_at_another_place_or_two_replaced_in_one_node_are_compared_in_full():
    """``remove`` then ``insert`` at another place is no replacement at its place (a Material now before the
    transform's place): the subtree compile; two items of one node replaced in one frame: both dirty bits."""
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        leaf = leaves[6]
        transform = leaf.items[0]
        leaf.remove(transform)
        leaf.insert(1, om.Translation(0.5, 0.5, 0.5))  # [Material, Translation, shape]: another list
        before = render_checked(e, scene, "subtrees", before).array
        leaf = leaves[9]
        replace(leaf, leaf.items[0], om.Matrix(np.array(om.Translation(0.3, -1.0, 0.6).matrix)))
        replace(leaf, leaf.items[1], om.Material(diffuse=(1.0, 0.2, 0.9)))
        render_checked(e, scene, "dirty", before)
        assert e.stats["dirty"] == ("appearance", "transform")


def test_a_rotating_matrix_replaced_by_a_translation_that_then_moves():
    """Translation -> rotating Matrix -> Translation on one leaf, then the translation moved by its setter (its
    moves write only the translation column of its place: the whole matrix must be the new one's)."""
    from omnirender.gl import GLEngine

    scene, groups, leaves = nested_scene()
    leaf = leaves[7]
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        before = e.render(scene).array
        m = np.array(om.Rotation(50.0, (0, 0, 1)).matrix @ om.Scaling(1.6, 0.7, 1.2).matrix)
        m[:3, 3] = (0.4, -1.0, 0.8)
        replace(leaf, leaf.items[0], om.Matrix(m))
        before = render_checked(e, scene, "dirty", before).array
        moved = om.Translation(-0.2, 1.5, 0.3)
        replace(leaf, leaf.items[0], moved)
        before = render_checked(e, scene, "dirty", before).array
        moved.offset = (0.6, 1.1, -0.4)
        image = e.render(scene)
        assert e.stats["compiled"] is False
        assert np.array_equal(image.array, fresh(scene)) and not np.array_equal(image.array, before)


def test_a_setter_loop_that_still_moves_the_replaced_translations():
    """The bench's loop: every frame one node's Translation is replaced by a Matrix, and the setter loop goes
    on writing all the original translations (the replaced ones are in no node): the move plan's kept look-ups
    must not write a replaced translation into the place its Matrix took (dropped when next used)."""
    from omnirender.gl import GLEngine

    scene, nodes = box_grid(300, 18, 0.5, eye=(0, 0, 30), light=(-0.3, -0.5, -1.0))
    moves = [node.items[0] for node in nodes]
    positions = np.array([t.offset for t in moves])
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        for frame in range(5):
            node = nodes[(frame * 37 + 11) % len(nodes)]
            m = np.eye(4)
            m[:3, 3] = positions[nodes.index(node)] + (0.0, 0.0, 2.0)
            replace(node, node.items[0], om.Matrix(m))
            image = e.render(scene)
            assert e.stats["compiled"] == "dirty"
            assert np.array_equal(image.array, fresh(scene)), frame
            positions[:, 1] += 0.1
            for t, row in zip(moves, positions, strict=True):
                t.offset = row  # the replaced ones too: they move nothing now
            image = e.render(scene)
            assert np.array_equal(image.array, fresh(scene)), frame
