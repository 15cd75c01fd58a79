"""An instance set of (N, 4, 4) matrices moved through its array: the rows' model columns are written again and
their colours kept (converted once, not on every move), as long as the colours, the count and the visibility
mask are the ones the rows were made from; anything else (a bad matrix, a mirroring that changes the GL state,
new colours, another mask) goes through the full path.  Every picture equals a fresh engine's.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def fresh(scene: om.Node, shadows: bool = False) -> np.ndarray:
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0, shadows=shadows) as e:
        return e.render(scene).array


def spinning(n: int, angle: float, seed: int = 3) -> np.ndarray:
    """(n, 4, 4) matrices: rotations about y by ``angle`` (plus a per-instance tilt), at fixed places."""
    rng = np.random.default_rng(seed)
    places = rng.uniform(-3.0, 3.0, (n, 3))
    tilt = rng.uniform(0.0, 1.0, n)
    out = np.zeros((n, 4, 4))
    c, s = np.cos(angle + tilt), np.sin(angle + tilt)
    out[:, 0, 0], out[:, 0, 2], out[:, 2, 0], out[:, 2, 2] = c, s, -s, c
    out[:, 1, 1] = out[:, 3, 3] = 1.0
    out[:, :3, 3] = places
    return out


def colours(n: int, seed: int = 4) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0.15, 1.0, (n, 3))


def lit(*items: object) -> om.Node:
    """A scene of ``items`` seen from above and in front, under a directional light."""
    view = om.Camera.look_at((0, 4, 9), (0, 0, 0), fov=50)
    return om.Node("scene", [view, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), *items])


@pytest.fixture
def paths(monkeypatch):
    """How the engine made the set's rows: 'full' (``instance_rows``) or 'moved' (``moved_instance_rows``)."""
    from omnirender.gl.engine import dynamic

    calls: list[str] = []
    full, moved = dynamic.instance_rows, dynamic.moved_instance_rows

    def counting_full(*args, **kwargs):
        calls.append("full")
        return full(*args, **kwargs)

    def counting_moved(*args, **kwargs):
        made = moved(*args, **kwargs)
        calls.append("moved" if made is not None else "refused")
        return made

    monkeypatch.setattr(dynamic, "instance_rows", counting_full)
    monkeypatch.setattr(dynamic, "moved_instance_rows", counting_moved)
    return calls


@pytest.mark.parametrize("touch", [("transforms",), ()], ids=["touch naming the transforms", "plain touch"])
@pytest.mark.parametrize("sorted_", [True, False], ids=["front to back", "row order"])
def test_rotating_instances_write_their_matrices_and_keep_their_colours(paths, monkeypatch, touch, sorted_):
    from omnirender.gl import GLEngine
    from omnirender.gl.engine import instancing

    n = 240
    matrices = spinning(n, 0.0)
    spheres = om.InstanceSet(om.Box(size=(0.5, 0.2, 0.3)), matrices, colors=colours(n))
    camera = om.Camera.look_at((0, 5, 10), (0, 0, 0), fov=50)
    scene = om.Node("scene", [camera, om.DirectionalLight(direction=(-0.4, -0.6, -1.0)), spheres])
    conversions = []
    convert = instancing.srgb_to_linear
    monkeypatch.setattr(instancing, "srgb_to_linear", lambda c: conversions.append(1) or convert(c))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.drawer.sorts_instances = sorted_
        first = e.render(scene).array
        paths.clear()
        conversions.clear()
        for step in range(1, 4):
            matrices[:] = spinning(n, 0.4 * step)
            spheres.touch(*touch)
            image = e.render(scene).array
            assert e.stats["compiled"] is False
            assert paths == ["moved"], paths
            paths.clear()
            assert np.array_equal(image, fresh(scene)), step
        assert not np.array_equal(image, first)
    assert conversions == [1, 1, 1], "no colour converted by the moves (one per fresh engine)"


def test_matrix_moves_under_a_moving_chain_with_a_shifted_shape_and_shadows(paths):
    from omnirender.gl import GLEngine

    n = 60
    matrices = spinning(n, 0.2)
    bricks = om.InstanceSet(om.Box(size=(0.6, 0.3, 0.3), center=(0.3, 0.0, 0.0)), matrices, colors=colours(n))
    lift = om.Translation(0.0, 0.5, 0.0)
    turn = om.Rotation(15.0, (0, 1, 0))
    floor = om.Node("floor", [om.Box(size=(12, 0.1, 12), center=(0, -3.5, 0))])
    scene = om.Node(
        "scene",
        [
            om.Camera.look_at((0, 6, 11), (0, 0, 0), fov=50),
            om.DirectionalLight(direction=(-0.4, -0.8, -0.5)),
            floor,
            om.Node("group", [lift, turn, bricks]),
        ],
    )
    with GLEngine(size=SIZE, samples=0, shadows=True) as e:
        e.render(scene)
        for step in range(4):
            matrices[:] = spinning(n, 0.2 + 0.3 * step)
            bricks.touch("transforms")
            if step == 2:
                lift.offset = (0.2, 0.8, -0.1)  # the chain above the set moves too
            image = e.render(scene).array
            assert np.array_equal(image, fresh(scene, shadows=True)), step
    assert "moved" in paths


def test_a_matrix_that_mirrors_or_bad_matrices_go_through_the_full_path(paths):
    from omnirender.gl import GLEngine

    n = 30
    matrices = spinning(n, 0.0)
    boxes = om.InstanceSet(om.Box(size=(0.6, 0.3, 0.4)), matrices, colors=colours(n))
    scene = lit(boxes)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        paths.clear()
        matrices[4, :3, 0] *= -1.0  # a mirror: faces wind the other way, so culling must change
        boxes.touch("transforms")
        image = e.render(scene).array
        assert paths[-1] == "full", paths
        assert np.array_equal(image, fresh(scene))
        matrices[4, :3, 0] *= -1.0  # back: not mirrored any more
        boxes.touch("transforms")
        assert np.array_equal(e.render(scene).array, fresh(scene))
        paths.clear()
        matrices[7, :3, :3] = 0.0  # singular: refused, and the full path names the instance
        boxes.touch("transforms")
        with pytest.raises(ValueError, match=r"instance 7 is singular"):
            e.render(scene)
        assert paths[0] == "refused"
        matrices[7] = spinning(n, 0.0)[7]
        matrices[9, 0, 3] = np.nan
        boxes.touch("transforms")
        with pytest.raises(ValueError, match=r"transforms of instance 9 are not finite"):
            e.render(scene)
        matrices[9] = spinning(n, 0.0)[9]
        matrices[2, 1, 3] = 1e39  # beyond float32
        boxes.touch("transforms")
        with pytest.raises(ValueError, match=r"instance 2 is beyond float32"):
            e.render(scene)
        matrices[2] = spinning(n, 0.0)[2]
        boxes.touch("transforms")
        assert np.array_equal(e.render(scene).array, fresh(scene))


def test_new_colours_or_another_mask_make_the_rows_again(paths):
    from omnirender.gl import GLEngine

    n = 50
    matrices = spinning(n, 0.0)
    tint = colours(n)
    visible = np.ones(n, bool)
    visible[::5] = False
    boxes = om.InstanceSet(om.Box(size=0.4), matrices, colors=tint, visible=visible)
    scene = lit(boxes)
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        paths.clear()
        matrices[:] = spinning(n, 0.5)
        boxes.touch()  # a plain touch: colours and mask compared, the same: the visible ones' matrices written
        assert np.array_equal(e.render(scene).array, fresh(scene))
        assert paths == ["moved"], paths
        paths.clear()
        tint[:10] = (1.0, 0.1, 0.1)
        matrices[:] = spinning(n, 0.9)
        boxes.touch()
        assert np.array_equal(e.render(scene).array, fresh(scene))
        assert paths == ["full"], paths
        paths.clear()
        visible[1] = False
        matrices[:] = spinning(n, 1.3)
        boxes.touch()
        assert np.array_equal(e.render(scene).array, fresh(scene))
        assert "moved" not in paths, paths


def test_a_set_under_a_mirroring_transform_stays_on_the_moved_path(paths):
    """The mirroring of a moved row is the sign of its matrix's determinant times the chain's: under a mirror
    every instance mirrors, as when its rows were made, so the GL state holds and the moved path is taken."""
    from omnirender.gl import GLEngine

    n = 40
    matrices = spinning(n, 0.0)
    boxes = om.InstanceSet(om.Box(size=(0.6, 0.3, 0.4), center=(0.2, 0.0, 0.0)), matrices, colors=colours(n))
    scene = lit(om.Node("mirrored", [om.Scaling((-1.0, 1.0, 1.0)), boxes]))
    with GLEngine(size=SIZE, samples=0, shadows=False) as e:
        e.render(scene)
        paths.clear()
        for step in range(1, 3):
            matrices[:] = spinning(n, 0.5 * step)
            boxes.touch("transforms")
            assert np.array_equal(e.render(scene).array, fresh(scene)), step
        assert paths == ["moved", "moved"], paths
