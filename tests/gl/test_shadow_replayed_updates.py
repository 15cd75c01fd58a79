"""Partial shadow-map updates issued again from a recorded pass (issue 22, shad3).

Where a partial update draws every caster under the region's scissor (GPUs,
``ShadowMapStage.partial_picks`` False) and runs before a recorded frame is
replayed (``follow_rows``), a face's partial pass is recorded once
(``FrameRunner.run_recorded``) and its draws issued again under each new
region's scissor (``FrameRunner.replay_draws``) while the casters' batches and
their draws hold.  Every change here is made after a steady frame (so the next
frame follows the rows and replays), and the picture and the shadow atlas are
compared with a fresh engine's, texel for texel; ``stats["shadow_maps"]
["replayed"]`` says the recorded draws were used, so the comparisons test them.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

from .test_shadow_updates import atlas, engine

pytestmark = pytest.mark.gl

SIZE = (96, 72)


@pytest.fixture(autouse=True)
def every_caster(monkeypatch):
    """Partial updates draw every caster under the region's scissor (what a GPU does)."""
    from omnirender.gl.techniques.shadows import ShadowMapStage

    monkeypatch.setattr(ShadowMapStage, "partial_picks", False)


def grid_scene(light: om.Light | None = None, count: int = 72) -> tuple[om.Node, list[om.Node], om.Box]:
    """``count`` boxes in a grid (9 to a row) above a floor, lit by ``light`` (a directional light by default):
    more than ``SORT_MIN`` rows, so the casters' batch is the sorted kind whose splices keep the frame plan."""
    scene = om.Node("scene", [om.Camera.look_at((0, 9, 9), (0, 0, 0), fov=45)])
    scene.add(light or om.DirectionalLight(direction=(-0.3, -1.0, -0.5)))
    scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.8), ambient=(0, 0, 0)),
                                om.Box(size=(10, 0.1, 10), center=(0, -0.05, 0))]))  # fmt: skip
    box = om.Box(size=0.4)
    nodes = []
    for i in range(count):
        p = ((i % 9 - 4) * 0.6, 0.8 + 0.3 * (i % 4), (i // 9 - 4) * 0.6)
        color = (0.3 + 0.7 * (i % 3) / 2, 0.4, 0.9 - 0.6 * (i % 5) / 4)
        nodes.append(scene.add(om.Node(f"b{i}", [om.Translation(*p), om.Material(diffuse=color), box])))
    return scene, nodes, box


def assert_boxes_exact(e, batch) -> tuple[np.ndarray, np.ndarray]:
    """The render index's boxes of ``batch``'s rows and its caster bounds equal ones computed afresh; returns the
    rows' boxes (lows, highs)."""
    from omnirender.gl.engine.index import row_boxes
    from omnirender.gl.techniques.shadows import caster_bounds

    lo, hi = e.index._batch_boxes(batch)
    want_lo, want_hi = row_boxes(batch.geometry, batch.rows)
    np.testing.assert_array_equal(lo, want_lo)
    np.testing.assert_array_equal(hi, want_hi)
    bounds = e.index.caster_bounds()[0]
    fresh = caster_bounds(e.root_scope)
    np.testing.assert_array_equal(bounds[0], fresh[0])
    np.testing.assert_array_equal(bounds[1], fresh[1])
    return want_lo, want_hi


def same_as_fresh(e, image, scene) -> None:
    with engine() as other:
        want = other.render(scene).array
        want_atlas = atlas(other)
    assert np.array_equal(image.array, want)
    assert np.array_equal(atlas(e), want_atlas)


def steady_then(e, scene, change) -> om.Image:
    """Steady frames until one is replayed (a frame that drew maps is not recorded, the next is), then
    ``change()`` and the frame after it."""
    for _ in range(3):
        e.render(scene)
        if e.stats["replayed"]:
            break
    assert e.stats["replayed"]
    change()
    return e.render(scene)


LIGHTS = {
    "directional": lambda: None,
    "point": lambda: om.PointLight(position=(0.2, 3.5, 0.3)),
    "spot": lambda: om.SpotLight(position=(0.5, 6.0, 1.0), direction=(-0.05, -1.0, -0.15), cutoff=40.0),
}


@pytest.mark.parametrize("light", list(LIGHTS))
def test_moves_replacements_and_splices_replay_the_recorded_partial_pass(light):
    scene, nodes, box = grid_scene(LIGHTS[light]())
    rng = np.random.default_rng(11)
    replayed = partial = 0
    with engine() as e:
        for frame in range(10):
            what = frame % 4
            moving = [n for n in nodes if isinstance(n.items[0], om.Translation)]
            node = moving[int(rng.integers(len(moving)))]

            def change(node=node, what=what, frame=frame) -> None:
                if what in (0, 1):  # one node moved (a step inside the fitted bounds)
                    x, y, z = node.items[0].offset
                    node.items[0].offset = (x + rng.uniform(-0.2, 0.2), y, z + rng.uniform(-0.2, 0.2))
                elif what == 2:  # its transform replaced by a Matrix a little higher
                    m = np.eye(4)
                    m[:3, 3] = node.items[0].matrix[:3, 3] + (0.0, 0.1, 0.0)
                    node.remove(node.items[0])
                    node.insert(0, om.Matrix(m))
                else:  # one node removed and one added
                    scene.remove(node)
                    nodes.remove(node)
                    p = (rng.uniform(-2.5, 2.5), rng.uniform(0.8, 1.7), rng.uniform(-2.5, 2.5))
                    nodes.append(scene.add(om.Node(f"n{frame}", [om.Translation(*p), om.Material(), box])))

            image = steady_then(e, scene, change)
            report = e.stats["shadow_maps"]
            partial += report["partial"]
            replayed += report["replayed"]
            assert report["replayed"] <= report["partial"]
            same_as_fresh(e, image, scene)
    assert partial >= 6 and replayed >= 4  # the recorded draws were issued again, and matched


def test_an_added_row_is_drawn_by_the_replayed_pass():
    """A node added (a row appended to the casters' batch) and then moved: the replayed pass draws the batch's
    rows as they are now (its count grew), so the new node's shadow is in the map where it moved to."""
    scene, nodes, box = grid_scene()
    with engine() as e:
        image = steady_then(e, scene, lambda: nodes[5].items[0].__setattr__("offset", (2.6, 0.8, -2.5)))
        assert e.stats["shadow_maps"]["partial"] == 1  # recorded
        added = om.Node("added", [om.Translation(0.3, 1.2, 0.4), om.Material(), box])
        image = steady_then(e, scene, lambda: scene.add(added))
        assert e.stats["compiled"] == "subtrees"
        same_as_fresh(e, image, scene)
        image = steady_then(e, scene, lambda: added.items[0].__setattr__("offset", (0.5, 1.3, 0.6)))
        assert e.stats["shadow_maps"]["replayed"] == 1
        same_as_fresh(e, image, scene)


def test_buffers_made_again_record_the_pass_again():
    """Nodes added frame after frame outgrow the casters' batch's buffer: the drawer makes it again, the
    recorded draws (its old vertex array) no longer hold and the pass is recorded again; every map and picture
    stays a fresh engine's."""
    from omnirender.gl.engine.drawlist import Batch

    scene, nodes, box = grid_scene()
    recorded_again = replayed = 0
    buffers = set()
    with engine() as e:
        steady_then(e, scene, lambda: nodes[0].items[0].__setattr__("offset", (-2.4, 0.8, -2.5)))
        for i in range(40):
            p = (-2.5 + 0.6 * (i % 9), 2.0 + 0.05 * (i // 9), -2.5 + 0.6 * (i // 9))
            node = om.Node(f"x{i}", [om.Translation(*p), om.Material(diffuse=(0.9, 0.5, 0.2)), box])
            image = steady_then(e, scene, lambda node=node: nodes.append(scene.add(node)))
            report = e.stats["shadow_maps"]
            replayed += report["replayed"]
            recorded_again += report["partial"] - report["replayed"]
            batches = [b for s in e.root_scope.walk() for part in s.parts or () if hasattr(part, "batches")
                       for b in part.batches if isinstance(b, Batch) and b.size > 60]  # fmt: skip
            buffers.add(id(batches[0].buffer))
            if i % 8 == 7:
                same_as_fresh(e, image, scene)
        image = steady_then(e, scene, lambda: nodes[-1].items[0].__setattr__("offset", (2.4, 2.3, 2.4)))
        same_as_fresh(e, image, scene)
    assert len(buffers) >= 2  # the batch's buffer was made again on the way
    assert replayed >= 20 and recorded_again >= 2


def test_the_replayed_pass_writes_no_uniform_the_frame_plan_reads():
    """The recorded partial pass draws with the depth-only program: the frame plan replayed after it keeps its
    programs' uniforms (it writes only those that differ), and its picture is a fresh engine's."""
    scene, nodes, _ = grid_scene()
    with engine() as e:
        steady_then(e, scene, lambda: nodes[3].items[0].__setattr__("offset", (0.4, 0.8, -2.4)))
        image = steady_then(e, scene, lambda: nodes[3].items[0].__setattr__("offset", (0.5, 0.8, -2.4)))
        assert e.stats["shadow_maps"]["replayed"] == 1
        assert e.programs.owner is e.frame_runner.plan
        same_as_fresh(e, image, scene)


def test_the_highlight_answer_follows_splices():
    """Whether some row of a batch is highlighted (it picks the program variant) is kept through rows appended
    and removed: a highlighted node added to the casters' batch is drawn highlighted, also after another row
    left, and when it leaves the rest are drawn without; every picture is a fresh engine's."""
    from omnirender.gl.engine.drawlist import Batch

    scene, nodes, box = grid_scene()
    with engine() as e:
        lit = om.Node("lit", [om.Translation(0.2, 2.0, 0.1), om.Highlight(color=(1.0, 1.0, 0.0)), om.Material(), box])
        image = steady_then(e, scene, lambda: scene.add(lit))
        (batch,) = [b for s in e.root_scope.walk() for part in s.parts or () if hasattr(part, "batches")
                    for b in part.batches if isinstance(b, Batch) and b.size > 60]  # fmt: skip
        assert batch.highlight_seen is None or batch.highlight_seen[1]
        same_as_fresh(e, image, scene)
        plain = om.Node("plain", [om.Translation(-0.2, 2.0, -0.1), om.Material(), box])
        image = steady_then(e, scene, lambda: scene.add(plain))
        same_as_fresh(e, image, scene)
        image = steady_then(e, scene, lambda: scene.remove(nodes.pop(10)))  # the highlighted row stays
        same_as_fresh(e, image, scene)

        def restyle(node: om.Node) -> None:  # a Material replaced: the row's surface rewritten in place
            index = next(i for i, it in enumerate(node.items) if isinstance(it, om.Material))
            node.remove(node.items[index])
            node.insert(index, om.Material(diffuse=(0.2, 0.9, 0.3)))

        for node in (lit, nodes[3]):
            image = steady_then(e, scene, lambda node=node: restyle(node))
            assert e.stats["compiled"] == "dirty"
            assert batch.highlight_seen == (batch.version, True)  # kept: no row's highlight changed
            same_as_fresh(e, image, scene)
        image = steady_then(e, scene, lambda: scene.remove(lit))
        assert batch.highlight_seen is None or not batch.highlight_seen[1]
        same_as_fresh(e, image, scene)


def test_boxes_kept_with_spare_rows_are_the_same_boxes():
    """The render index keeps every caster row's box in storage with spare rows (``row_boxes(spare=True)``) so
    a splice's appended row is written in place: the same boxes as without, and an append copies nothing."""
    from omnirender.gl.engine.index import _appended, row_boxes

    rng = np.random.default_rng(5)
    rows = rng.uniform(-2.0, 2.0, (300, 64)).astype(np.float32)

    class Geometry:  # what row_boxes reads of a GPU geometry: its local bounds
        bounds = ((-0.1, -0.55, -0.25), (0.3, 0.15, 0.85))

    lo, hi = row_boxes(Geometry, rows)
    lo2, hi2 = row_boxes(Geometry, rows, spare=True)
    assert np.array_equal(lo, lo2) and np.array_equal(hi, hi2)
    grown = _appended(lo2, lo[:1])
    assert np.shares_memory(grown, lo2) and np.array_equal(grown, np.concatenate([lo, lo[:1]]))


def test_a_few_moved_rows_keep_the_index_boxes_bounds_and_journal_exact():
    """One to four casters moved per frame (the render index follows them in Python floats): every row's kept
    box is the box computed from the rows, the casters' bounds are those computed afresh, and the journal's old
    and new boxes are where the rows were and are, frame after frame (also moves onto and off the bounds)."""

    scene, nodes, _ = grid_scene()
    rng = np.random.default_rng(3)
    with engine() as e:
        steady_then(e, scene, lambda: None)
        index = e.index
        for frame in range(12):
            picked = rng.choice(len(nodes), size=1 + frame % 4, replace=False)
            batch = next(it.slot[0] for it in index.items() if it.slot is not None and it.slot[0].size > 60)
            lo_before, hi_before = (a.copy() for a in index._batch_boxes(batch))
            for k in picked:
                x, y, z = nodes[k].items[0].offset
                far = 6.0 if frame % 3 == 0 else 0.3  # now and then beyond the bounds (the floor), else inside
                nodes[k].items[0].offset = (x + rng.uniform(-far, far), y + rng.uniform(-0.2, 0.2), z)
            e.compile(scene)
            journal = index.take_caster_changes()
            want_lo, want_hi = assert_boxes_exact(e, batch)
            assert journal is not None and len(journal) == 2
            left, took = journal
            rows = [int(r) for r in left.rows]
            assert not left.new and took.new and rows == [int(r) for r in took.rows] and len(rows) == len(picked)
            np.testing.assert_array_equal(np.array(left.lows()), lo_before[rows])
            np.testing.assert_array_equal(np.array(left.highs()), hi_before[rows])
            np.testing.assert_array_equal(np.array(took.lows()), want_lo[rows])
            np.testing.assert_array_equal(np.array(took.highs()), want_hi[rows])
            e.render(scene)


def test_a_face_redrawn_in_full_replays_the_recording_under_its_tile(monkeypatch):
    """Every caster moved a little (inside the fitted bounds) with every region redrawn in full: the face is
    redrawn, before the recorded frame is replayed, by the recorded pass under its whole tile's scissor; the
    maps and the picture are a fresh engine's."""
    from omnirender.gl.techniques import shadows

    scene, nodes, _ = grid_scene()
    with engine() as e:
        steady_then(e, scene, lambda: nodes[4].items[0].__setattr__("offset", (-0.1, 1.7, -2.4)))
        assert e.stats["shadow_maps"]["partial"] == 1  # recorded
        monkeypatch.setattr(shadows, "PARTIAL_MAX", 0.0)  # any region: the face in full

        def all_moved(step: float) -> None:
            for i, node in enumerate(nodes):
                x, y, z = node.items[0].offset
                node.items[0].offset = (x, y + step * (i % 3 - 1), z)

        for step in (0.01, -0.01, 0.02):
            image = steady_then(e, scene, lambda step=step: all_moved(step))
            report = e.stats["shadow_maps"]
            assert (report["full"], report["partial"], report["replayed"]) == (1, 0, 1)
            assert e.stats["replayed"]
            same_as_fresh(e, image, scene)


def test_splices_keep_the_index_boxes_and_bounds_exact():
    """Nodes removed and added frame after frame (the render index follows the removed and appended rows' boxes
    in Python floats): every kept box is the box computed from the rows and the casters' bounds are those
    computed afresh, also when the row that leaves was the only one on the bounds."""

    scene, nodes, box = grid_scene()
    rng = np.random.default_rng(9)
    with engine() as e:
        steady_then(e, scene, lambda: None)
        index = e.index
        far = None
        for frame in range(10):
            if far is not None:  # the one node beyond the others leaves: the bounds shrink back
                scene.remove(far)
                far = None
            else:  # one beyond every other node (the floor too) on the low side of x and y: new bounds
                place = om.Translation(-6.0 - 0.1 * frame, -0.3, 0.0)
                far = scene.add(om.Node(f"far{frame}", [place, om.Material(), box]))
            scene.remove(nodes.pop(int(rng.integers(len(nodes)))))
            p = (rng.uniform(-2.0, 2.0), rng.uniform(0.8, 1.7), rng.uniform(-2.0, 2.0))
            nodes.append(scene.add(om.Node(f"s{frame}", [om.Translation(*p), om.Material(), box])))
            e.render(scene)
            assert e.stats["compiled"] == "subtrees"
            batch = next(it.slot[0] for it in index.items() if it.slot is not None and it.slot[0].size > 60)
            assert_boxes_exact(e, batch)
            e.render(scene)


@pytest.mark.parametrize("where", ["top", "subgraph"])
def test_a_shadowmaps_technique_replays_and_follows_its_settings(where):
    """A scene with an ``om.gl.ShadowMaps`` (its settings for the receivers after it, or shadows off for a
    subgraph) replays its steady frames like one without; changing the technique's settings draws the next frame
    in full, and every picture is a fresh engine's."""
    scene, nodes, box = grid_scene()
    camera, light, floor = scene.items[:3]
    technique = om.gl.ShadowMaps(softness=2.0)
    if where == "top":
        root = om.Node("root", [camera, light, technique, floor, *nodes])
    else:  # the first 20 boxes neither receive shadows nor are they shadowed
        group = om.Node("group", [om.gl.ShadowMaps(enabled=False), *nodes[:20]])
        root = om.Node("root", [camera, light, technique, floor, group, *nodes[20:]])
    with engine() as e:
        for _ in range(3):
            e.render(root)
        assert e.stats["replayed"] and e.frame_runner.not_recorded is None
        for softness, bias in ((0.0, 2.0), (3.0, 4.0), (1.0, 0.5)):
            technique.softness, technique.bias = softness, bias
            image = e.render(root)
            assert not e.stats["replayed"]
            same_as_fresh(e, image, root)
            e.render(root)
            image = e.render(root)
            assert e.stats["replayed"]
            same_as_fresh(e, image, root)


def test_alpha_tested_casters_follow_their_texture():
    """Casters cut out by an alpha test of their texture (the depth-only draw binds the texture): moved, their
    texture's image replaced, moved again, each after a steady frame: the maps and the picture are a fresh
    engine's (a recorded draw would bind a texture made again for the new image: such draws are not kept)."""
    scene, nodes, box = grid_scene()
    checker = np.zeros((8, 8, 4), np.uint8)
    checker[..., :3] = 255
    checker[..., 3] = np.where((np.indices((8, 8)).sum(axis=0) % 2) == 0, 255, 0)
    texture = om.Texture(checker, filter="nearest", mipmap=False)
    group = scene.add(om.Node("cutouts", [texture, om.Color(1, 1, 1), om.gl.AlphaTest("greater", 0.5)]))
    cut = [group.add(om.Node(f"c{i}", [om.Translation(-1.5 + i, 2.6, 0.5), om.Box(size=0.8)])) for i in range(4)]
    with engine() as e:
        image = steady_then(e, scene, lambda: cut[1].items[0].__setattr__("offset", (-0.4, 2.6, 0.6)))
        same_as_fresh(e, image, scene)
        solid = checker.copy()
        solid[..., 3] = 255
        image = steady_then(e, scene, lambda: texture.__setattr__("image", solid))
        same_as_fresh(e, image, scene)
        image = steady_then(e, scene, lambda: cut[2].items[0].__setattr__("offset", (0.6, 2.5, 0.6)))
        same_as_fresh(e, image, scene)
        image = steady_then(e, scene, lambda: cut[2].items[0].__setattr__("offset", (0.7, 2.5, 0.6)))
        same_as_fresh(e, image, scene)


def test_many_moved_rows_keep_the_bounds_and_the_rows_on_them_exact():
    """Every caster moved (the render index makes every row's box again, counting the rows on each side of the
    bounds while it makes them), then a few at a time: the casters' bounds are those computed afresh and the
    counts of rows on each bound are the rows whose boxes lie there, frame after frame."""
    from omnirender.gl.techniques.shadows import caster_bounds

    scene, nodes, _ = grid_scene()
    rng = np.random.default_rng(4)
    with engine() as e:
        steady_then(e, scene, lambda: None)
        index = e.index
        for frame in range(8):
            picked = range(len(nodes)) if frame % 2 == 0 else rng.choice(len(nodes), size=3, replace=False)
            for k in picked:
                x, y, z = nodes[k].items[0].offset
                step = 6.0 if frame % 4 == 0 else 0.2  # now and then beyond the floor: bounds of casters alone
                nodes[k].items[0].offset = (x + rng.uniform(-step, step), y, z + rng.uniform(-step, step))
            e.render(scene)
            bounds = index.caster_bounds()[0]
            fresh = caster_bounds(e.root_scope)
            np.testing.assert_array_equal(bounds[0], fresh[0])
            np.testing.assert_array_equal(bounds[1], fresh[1])
            low, high = [0, 0, 0], [0, 0, 0]
            for batch in {it.slot[0] for it in index.items() if it.slot is not None}:
                a, b = index._batch_boxes(batch)
                for k in range(3):
                    low[k] += int(np.count_nonzero(a[:, k] == bounds[0][k]))
                    high[k] += int(np.count_nonzero(b[:, k] == bounds[1][k]))
            assert index._extremes == (low, high)
            e.render(scene)
