"""Shadow maps follow changes (issue 22): a light's maps are redrawn only where a caster inside them changed.

Every change is checked against a fresh engine's render of the same scene,
pixel for pixel, and the atlas texel for texel; ``stats["shadow_maps"]`` says
which faces were kept, redrawn in full or in part (and where).
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def grid_scene(light: om.Light | None = None) -> tuple[om.Node, list[om.Node], om.Box]:
    """Boxes in a 6 x 6 grid above a floor, lit by ``light`` (a directional light by default)."""
    scene = om.Node("scene", [om.Camera.look_at((0, 9, 9), (0, 0, 0), fov=45)])
    scene.add(light or om.DirectionalLight(direction=(-0.3, -1.0, -0.5)))
    scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.8), ambient=(0, 0, 0)),
                                om.Box(size=(10, 0.1, 10), center=(0, -0.05, 0))]))  # fmt: skip
    box = om.Box(size=0.6)
    nodes = []
    for i in range(36):
        p = (i % 6 - 2.5, 0.8 + 0.3 * (i % 4), i // 6 - 2.5)
        color = (0.3 + 0.7 * (i % 3) / 2, 0.4, 0.9 - 0.6 * (i % 5) / 4)
        nodes.append(scene.add(om.Node(f"b{i}", [om.Translation(*p), om.Material(diffuse=color), box])))
    return scene, nodes, box


@pytest.fixture(autouse=True, params=[True, False], ids=["picked", "every-caster"])
def partial_picks(request, monkeypatch):
    """Every test with both ways of a partial update: the casters meeting the region picked (software
    rasterisers) and every caster drawn under the region's scissor (GPUs): the same maps, texel for texel."""
    from omnirender.gl.techniques.shadows import ShadowMapStage

    monkeypatch.setattr(ShadowMapStage, "partial_picks", request.param)
    return request.param


def engine():
    from omnirender.gl import GLEngine

    return GLEngine(size=SIZE, samples=0)


def atlas(e) -> np.ndarray:
    from omnirender.gl.techniques.shadows import ATLAS

    with e.current():  # another engine's context may be current (a fresh engine's)
        target = e.target(ATLAS)
        w, h = target.size
        return np.frombuffer(target.depth.read(), np.float32).reshape(h, w).copy()


def fresh(scene: om.Node) -> tuple[np.ndarray, np.ndarray, dict]:
    """A fresh engine's image, atlas and shadow-map report of ``scene``."""
    with engine() as e:
        image = e.render(scene).array
        return image, atlas(e), e.stats["shadow_maps"]


def map_passes(e) -> list[str]:
    return [p["name"] for p in e.stats["passes"] if p["name"].startswith("shadow-map")]


def same_as_fresh(e, image, scene) -> None:
    want_image, want_atlas, _ = fresh(scene)
    assert np.array_equal(image.array, want_image)
    assert np.array_equal(atlas(e), want_atlas)


def test_one_moved_caster_redraws_only_the_region_of_its_old_and_new_place():
    scene, nodes, _ = grid_scene()
    with engine() as e:
        e.render(scene)
        assert e.stats["shadow_maps"]["full"] == 1
        before = atlas(e)
        nodes[14].items[0].offset = (-0.5 + 0.2, 1.4, -0.5)  # 0.2 to the side: inside the fitted bounds
        image = e.render(scene)
        report = e.stats["shadow_maps"]
        assert (report["full"], report["partial"], report["kept"]) == (0, 1, 0)
        assert map_passes(e) == ["shadow-map[0] partial"]
        ((face, (x, y, w, h)),) = report["regions"]
        assert face == 0 and report["pixels"] == w * h
        after = atlas(e)
        assert w * h < 0.05 * after.size  # a small part of the map
        changed = np.argwhere(after != before)
        assert len(changed)  # the caster's depth moved in the map ...
        rows, cols = changed[:, 0], changed[:, 1]  # ... and only inside the region (rows count from the bottom)
        assert rows.min() >= y and rows.max() < y + h and cols.min() >= x and cols.max() < x + w
        same_as_fresh(e, image, scene)


def test_a_replaced_material_redraws_no_map():
    scene, nodes, _ = grid_scene()
    with engine() as e:
        e.render(scene)
        node = nodes[7]
        node.remove(node.items[1])
        node.insert(1, om.Material(diffuse=(1.0, 0.1, 0.1)))
        image = e.render(scene)
        assert e.stats["compiled"] == "dirty"  # a Material replaced by a Material: dirty bits (dirty.py)
        assert e.stats["shadow_maps"]["kept"] == 1 and map_passes(e) == []
        same_as_fresh(e, image, scene)


def test_a_caster_made_transparent_is_redrawn_out_of_the_map():
    scene, nodes, _ = grid_scene()
    with engine() as e:
        e.render(scene)
        node = nodes[7]
        node.remove(node.items[1])
        node.insert(1, om.Material(diffuse=(1.0, 0.1, 0.1), opacity=0.4))
        image = e.render(scene)
        assert e.stats["shadow_maps"]["partial"] == 1
        same_as_fresh(e, image, scene)


def test_a_replaced_matrix_and_an_added_and_removed_node_match_a_fresh_engine():
    scene, nodes, box = grid_scene()
    with engine() as e:
        e.render(scene)
        node = nodes[20]
        m = np.eye(4)
        m[:3, 3] = node.items[0].matrix[:3, 3] + (0.0, 0.15, 0.1)
        node.remove(node.items[0])
        node.insert(0, om.Matrix(m))
        image = e.render(scene)
        assert e.stats["compiled"] == "dirty" and e.stats["shadow_maps"]["partial"] == 1  # (dirty.py)
        same_as_fresh(e, image, scene)
        scene.remove(nodes.pop(3))
        nodes.append(scene.add(om.Node("extra", [om.Translation(0.1, 1.1, 0.2), om.Material(), box])))
        image = e.render(scene)
        assert e.stats["compiled"] == "subtrees" and e.stats["shadow_maps"]["partial"] == 1
        same_as_fresh(e, image, scene)


def test_a_move_that_leaves_the_fitted_bounds_redraws_in_full():
    scene, nodes, _ = grid_scene()
    with engine() as e:
        e.render(scene)
        nodes[0].items[0].offset = (-6.0, 0.8, -2.5)  # far out: the map's projection changes
        image = e.render(scene)
        assert e.stats["shadow_maps"]["full"] == 1 and e.stats["shadow_maps"]["partial"] == 0
        same_as_fresh(e, image, scene)


def test_all_moved_redraw_in_full_and_a_still_frame_keeps_the_maps():
    scene, nodes, _ = grid_scene()
    with engine() as e:
        e.render(scene)
        for i, node in enumerate(nodes):
            x, y, z = node.items[0].offset
            node.items[0].offset = (x, y + 0.01 * (i % 3), z)
        image = e.render(scene)
        report = e.stats["shadow_maps"]
        assert report["full"] + report["partial"] == 1
        same_as_fresh(e, image, scene)
        e.render(scene)
        assert e.stats["shadow_maps"]["kept"] == 1 and map_passes(e) == []


def test_a_move_outside_a_spot_lights_cone_redraws_nothing():
    spot = om.SpotLight(position=(0, 6, 0), direction=(0, -1, 0), cutoff=25)
    scene, nodes, _ = grid_scene(spot)
    outside = scene.add(om.Node("outside", [om.Translation(4.6, 0.5, 4.6), om.Box(size=0.3)]))
    with engine() as e:
        e.render(scene)
        outside.items[0].offset = (4.6, 0.5, 4.5)  # still out of the cone (and inside the fitted bounds)
        image = e.render(scene)
        assert e.stats["shadow_maps"]["kept"] == 1 and map_passes(e) == []
        same_as_fresh(e, image, scene)
        nodes[14].items[0].offset = (-0.3, 1.4, -0.5)  # inside the cone: a partial update
        image = e.render(scene)
        assert e.stats["shadow_maps"]["partial"] == 1
        same_as_fresh(e, image, scene)


def test_a_point_light_redraws_only_the_faces_a_move_reaches():
    scene, nodes, _ = grid_scene(om.PointLight(position=(0.2, 3.5, 0.3)))
    with engine() as e:
        e.render(scene)
        drawn = e.stats["shadow_maps"]["full"]
        assert drawn >= 2
        nodes[0].items[0].offset = (-2.5, 0.75, -2.5)
        image = e.render(scene)
        report = e.stats["shadow_maps"]
        assert report["full"] == 0 and report["partial"] >= 1 and report["kept"] >= 1
        assert report["partial"] + report["kept"] == drawn
        same_as_fresh(e, image, scene)


def test_lights_settings_and_size_changes_redraw_in_full():
    scene, _, _ = grid_scene()
    with engine() as e:
        e.render(scene)
        scene.items[1].direction = (-0.35, -1.0, -0.5)
        e.render(scene)
        assert e.stats["shadow_maps"]["full"] == 1
        e.size = (80, 60)  # the same map resolution (512): the maps are kept
        e.render(scene)
        assert e.stats["shadow_maps"]["kept"] == 1
        e.size = (600, 400)  # the map resolution follows the image (1024): a new atlas
        image = e.render(scene)
        assert e.stats["shadow_maps"]["full"] == 1
        from omnirender.gl import GLEngine

        with GLEngine(size=(600, 400), samples=0) as other:
            assert np.array_equal(image.array, other.render(scene).array)


def test_a_clear_box_is_validated():
    with pytest.raises(ValueError, match="box"):
        om.gl.Clear(box=(0, 0, 0, 4))
    assert om.gl.Clear(box=(1.0, 2, 3, 4)).box == (1, 2, 3, 4)


@pytest.mark.parametrize("light", ["directional", "point", "spot"])
def test_a_sequence_of_edits_keeps_matching_a_fresh_engine(light):
    """Moves, replaced materials and matrices, nodes added and removed, frame after frame: the partial updates
    (and the casters' rectangles they keep between frames) give the maps and the picture a fresh engine gives."""
    lights = {"directional": None, "point": om.PointLight(position=(0.2, 3.5, 0.3)),
              "spot": om.SpotLight(position=(0.5, 6.0, 1.0), direction=(-0.05, -1.0, -0.15), cutoff=40.0)}  # fmt: skip
    scene, nodes, box = grid_scene(lights[light])
    rng = np.random.default_rng(7)
    partial = 0
    with engine() as e:
        e.render(scene)
        for frame in range(8):
            for _ in range(2):
                node = nodes[int(rng.integers(len(nodes)))]
                what = frame % 4
                if what == 0:
                    x, y, z = node.items[0].offset
                    node.items[0].offset = (x + rng.uniform(-0.2, 0.2), y, z + rng.uniform(-0.2, 0.2))
                elif what == 1:
                    node.remove(node.items[1])
                    node.insert(1, om.Material(diffuse=tuple(rng.uniform(0.2, 1.0, 3))))
                elif what == 2:
                    scene.remove(node)
                    nodes.remove(node)
                    p = (rng.uniform(-2.5, 2.5), rng.uniform(0.8, 1.7), rng.uniform(-2.5, 2.5))
                    nodes.append(scene.add(om.Node(f"n{frame}", [om.Translation(*p), om.Material(), box])))
                else:
                    x, y, z = node.items[0].offset
                    node.items[0].offset = (x, y + 0.1, z)
            image = e.render(scene)
            partial += e.stats["shadow_maps"]["partial"]
            same_as_fresh(e, image, scene)
    assert partial >= 4


@pytest.mark.parametrize("light", ["directional", "spot"])
def test_a_few_boxes_project_as_many_do(light):
    """The rectangles of a few changed boxes, projected in Python floats, are those numpy's path gives for many
    (an orthographic face and a perspective one, boxes ahead of, across and behind the light camera), and so are
    the texel regions made of them."""
    from omnirender.gl.techniques import shadows

    lo = np.array([-2.0, -1.0, -2.0])
    hi = np.array([2.0, 1.0, 2.0])
    lamp = om.DirectionalLight(direction=(-0.3, -1.0, -0.5)) if light == "directional" else om.SpotLight(
        position=(0.0, 3.0, 0.0), direction=(0.1, -1.0, 0.05), cutoff=50.0)  # fmt: skip
    (face,) = shadows._light_faces(lamp, np.eye(4), lo, hi, 256)
    rng = np.random.default_rng(3)
    centers = rng.uniform(-2.5, 2.5, (12, 3))
    centers[:3, 1] = (1.0, 2.9, 3.5)  # near the light, across its plane, behind it
    lows, highs = centers - rng.uniform(0.05, 0.4, (12, 3)), centers + rng.uniform(0.05, 0.4, (12, 3))
    many, behind, away = shadows._ndc_rects(face, lows, highs)  # more than _FEW: numpy's path
    for k in range(0, 12, 4):
        few, few_behind, few_away = shadows._ndc_rects(face, lows[k : k + 4], highs[k : k + 4])
        if behind is None:
            assert few_behind is None and few_away is None
        else:
            assert np.array_equal(few_behind, behind[k : k + 4]) and np.array_equal(few_away, away[k : k + 4])
        ahead = slice(None) if behind is None else ~behind[k : k + 4]
        for a, b in zip(few, many, strict=True):
            np.testing.assert_allclose(a[ahead], b[k : k + 4][ahead], rtol=1e-12, atol=1e-12)
    assert behind is None or behind.any()  # the spot's camera has boxes behind it
    region = shadows._face_region(face, 256, lows, highs)  # as lists of a few boxes, and as arrays of many
    assert region == shadows._face_region(face, 256, np.repeat(lows, 4, axis=0), np.repeat(highs, 4, axis=0))


def test_a_scissored_pass_keeps_the_rest_of_its_description():
    from omnirender.gl.engine.attributes import DepthMask, ScissorTest

    view = np.eye(4)
    base = om.gl.Pass("p", items="opaque", clear=om.gl.Clear(color=None, depth=1.0), camera=(view, view),
                      state=(DepthMask(True), (ScissorTest, (0, 0, 8, 8))))  # fmt: skip
    part = base.scissored((2, 3, 4, 5), "p partial")
    assert part.name == "p partial" and part.clear.box == (2, 3, 4, 5) and part.clear.depth == 1.0
    assert part.state[-1] == (ScissorTest, (2, 3, 4, 5)) and len(part.state) == 2
    assert part.key()[1:] == base.scissored((2, 3, 4, 5)).key()[1:]
    assert base.clear.box is None and base.state[-1] == (ScissorTest, (0, 0, 8, 8))  # unchanged
    assert part.camera is base.camera and part.items == base.items
    with pytest.raises(ValueError, match="box"):
        base.scissored((0, 0, 0, 4))
