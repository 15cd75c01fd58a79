"""Renderer trees: traversal, depth groups, scene renderers, trees as images and as techniques in scene graphs."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

from .scenes import CAMERA, LIGHT, ball, cube

pytestmark = pytest.mark.gl
C = om.compositing
SIZE = (96, 72)


def combined(*nodes: om.Node) -> om.Image:
    return om.render(om.Node("scene", [CAMERA, *nodes]), size=SIZE, samples=0, background=(0, 0, 0))


def test_a_depth_group_of_scene_renderers_draws_what_one_scene_would():
    tree = C.DepthGroup([C.SceneRenderer(ball(light=False)), C.SceneRenderer(cube(light=False))])
    img = tree.render(SIZE, camera=CAMERA, samples=0, background=(0, 0, 0))
    ref = combined(ball(light=False), cube(light=False))
    assert np.abs(img.array.astype(int) - ref.array.astype(int)).max() <= 2
    both = np.isfinite(ref.depth)
    assert np.array_equal(np.isfinite(img.depth), both)
    assert np.allclose(img.depth[both], ref.depth[both], rtol=1e-5)
    # groups switch to offscreen targets only when they need to: a plain depth group draws in place
    assert not [p for p in img.info["passes"] if p["target"]]


def test_an_offscreen_depth_group_merges_its_image_by_depth():
    plain = C.DepthGroup([C.SceneRenderer(ball()), C.SceneRenderer(cube())])
    isolated = C.DepthGroup([C.SceneRenderer(ball()), C.SceneRenderer(cube())], offscreen=True)
    a = plain.render(SIZE, camera=CAMERA, samples=0)
    b = isolated.render(SIZE, camera=CAMERA, samples=0)
    assert np.abs(a.array.astype(int) - b.array.astype(int)).max() <= 2
    assert np.allclose(a.depth[np.isfinite(a.depth)], b.depth[np.isfinite(a.depth)], rtol=1e-5)
    passes = [(p["name"], p["target"]) for p in b.info["passes"]]
    assert any(name.endswith("DepthGroup/children") and target for name, target in passes)
    assert any(name.endswith("DepthGroup/merge") for name, _ in passes)


def test_om_render_draws_a_tree_with_the_first_scene_camera():
    scene = om.Node("s", [CAMERA, LIGHT, om.Color(1, 0, 0), om.Sphere()])
    tree = C.DepthGroup([C.SceneRenderer(scene)])
    via_render = om.render(tree, engine="gl", size=SIZE, samples=0)
    direct = om.render(scene, size=SIZE, samples=0)
    assert np.abs(via_render.array.astype(int) - direct.array.astype(int)).max() <= 2
    assert tree.default_camera()[0] is CAMERA
    with pytest.raises(ValueError, match="composited by the GL engine"):
        om.render(tree, engine="povray", size=SIZE)
    with pytest.raises(TypeError, match="om.Camera"):
        tree.render(SIZE, camera="top")


def test_a_tree_without_a_scene_camera_frames_its_bounds():
    tree = C.DepthGroup([C.SceneRenderer([om.Sphere(center=(5, 5, 5), radius=0.5)])])
    img = tree.render(SIZE, samples=0, background=(0, 0, 0))
    ys, xs = np.nonzero(img.mask)
    assert img.mask.mean() > 0.05 and abs(xs.mean() - SIZE[0] / 2) < 4 and abs(ys.mean() - SIZE[1] / 2) < 4


def test_a_scene_renderer_keeps_its_engine_and_compiled_scene_between_frames():
    from omnirender.gl import GLEngine

    renderer = C.SceneRenderer(ball())
    with GLEngine(size=SIZE, samples=0) as host:
        scene = renderer.as_scene("gl", SIZE, CAMERA)
        host.render(scene)
        guest = renderer.engine(host)
        assert guest.stats["compiled"] is True
        host.render(scene)
        assert renderer.engine(host) is guest and guest.stats["compiled"] is False  # replayed
        renderer.scene.add(om.Sphere(center=(1, 1, 0), radius=0.2))
        host.render(scene)
        assert guest.stats["compiled"] in (True, "subtrees")  # compiled again (the edited node alone)
    renderer.release()


def test_scene_renderer_options_mask_and_technique():
    left = om.Node("left", [om.Color(1, 0, 0), om.Sphere(center=(-1.5, 0, 0), radius=0.6)], groups="left")
    right = om.Node("right", [om.Color(0, 0, 1), om.Sphere(center=(1.5, 0, 0), radius=0.6)], groups="right")
    scene = om.Node("s", [CAMERA, left, right])
    img = C.SceneRenderer(scene, mask="left").render(SIZE, samples=0, background=(0, 0, 0))
    assert img.pixel(26, 32)[0] > 100 and img.pixel(70, 32)[2] == 0

    class FlatGreen(om.gl.GLTechnique):
        __slots__ = ()

        def prepare_pass(self, engine):
            engine.set_pass(om.gl.Pass("green", shader=om.gl.Shader(flat_color=(0, 1, 0))))

    img = C.SceneRenderer(scene, technique=FlatGreen()).render(SIZE, samples=0, background=(0, 0, 0))
    assert tuple(img.pixel(26, 32)[:3]) == (0, 255, 0) and tuple(img.pixel(70, 32)[:3]) == (0, 255, 0)


def test_a_group_decides_order_and_repetition_of_its_children():
    calls: list[str] = []

    class Logged(C.Renderer):
        __slots__ = ("name",)

        def __init__(self, name):
            super().__init__()
            self.name = name

        def draw(self, canvas):
            calls.append(self.name)

    class BackwardsTwice(C.RendererGroup):
        __slots__ = ()

        def composite(self, canvas, children):
            for child in (*reversed(children), *reversed(children)):
                child.draw(canvas)

    BackwardsTwice([Logged("a"), Logged("b")]).render((16, 16))
    assert calls == ["b", "a", "b", "a"]
    calls.clear()
    C.DepthGroup([Logged("a"), C.DepthGroup([Logged("b"), Logged("c")]), Logged("d")]).render((16, 16))
    assert calls == ["a", "b", "c", "d"]  # depth first, in registration order


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
def test_a_shadow_group_in_a_scene_graph_shadows_the_rest_of_its_node():
    floor = om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.8)), om.Box(size=(6, 0.1, 6), center=(0, -1.05, 0))])
    sphere = om.Node("sphere", [om.Material(diffuse=(0.9, 0.4, 0.2)), om.Sphere(radius=0.6)])
    light = om.PointLight(position=(0.5, 5, 0.5))
    graph = om.Node("scene", [CAMERA, light, om.Node("shadowed", [C.ShadowGroup(light), floor, sphere])])
    plain = om.Node("scene", [CAMERA, light, floor, sphere])
    shadowed = om.render(graph, size=SIZE, samples=0)
    unshadowed = om.render(plain, size=SIZE, samples=0)
    assert np.array_equal(shadowed.mask, unshadowed.mask)  # the node's content is drawn, and only that
    darker = shadowed.array[..., :3].sum(axis=2) < 0.7 * unshadowed.array[..., :3].sum(axis=2)
    assert darker[45:, 30:66].sum() > 40  # the sphere's shadow on the floor below it
    assert not darker[:25].any()  # nothing above the sphere
    # the same picture as the stand-alone tree of the same content
    content = om.Node("content", [light, floor, sphere])
    alone = C.ShadowGroup(light, [C.SceneRenderer(content)]).render(SIZE, camera=CAMERA, samples=0)
    assert (np.abs(alone.array.astype(int) - shadowed.array.astype(int)).max(axis=2) <= 3).mean() > 0.99
    # engines that cannot composite evaluate the node's content once, as if the group were not there
    shapes = lambda prog: [type(o).__name__ for op, o in prog if op == "eval"]  # noqa: E731
    assert shapes(om.trace(graph)) == shapes(om.trace(plain))


def test_a_filter_in_a_scene_graph_changes_what_was_drawn_up_to_it():
    grey = om.Node("grey", [C.LuminanceFilter(), om.Color(1, 0, 0), om.Sphere(center=(-1.2, 0, 0), radius=0.6)])
    later = om.Node("later", [om.Color(0, 0, 1), om.Sphere(center=(1.2, 0, 0), radius=0.6)])
    img = om.render(om.Node("scene", [CAMERA, grey, later]), size=SIZE, samples=0, background=(0, 0, 0))
    r, g, b, _ = img.pixel(29, 32)
    assert r == g == b and r > 30  # the red sphere turned grey
    assert img.pixel(67, 32)[2] > 100 and img.pixel(67, 32)[0] < 40  # the blue one, drawn after, did not


def test_trees_validate_their_input_with_the_fix():
    with pytest.raises(TypeError, match="SceneRenderer"):
        C.DepthGroup([om.Sphere()])
    with pytest.raises(ValueError, match="mode must be one of"):
        C.OcclusionGroup(mode="x-ray")
    with pytest.raises(ValueError, match="opacity must be"):
        C.OcclusionGroup(mode="semi-transparent", opacity=1.5)
    with pytest.raises(TypeError, match="light must be"):
        C.ShadowGroup("sun")
    with pytest.raises(ValueError, match="resolution"):
        C.ShadowGroup(LIGHT, resolution=3)
    with pytest.raises(ValueError, match="darkness"):
        C.ShadowGroup(LIGHT, darkness=2)
    with pytest.raises(TypeError, match="scene must be an om.Node"):
        C.SceneRenderer(42)
    with pytest.raises(TypeError, match="technique must be"):
        C.SceneRenderer(ball(), technique="deferred")
    with pytest.raises(TypeError, match="om.Volume"):
        C.VolumeRenderer(om.Sphere())
    with pytest.raises(NotImplementedError, match="draw"):
        C.Renderer().render((8, 8))
    group = C.DepthGroup()
    group.add(C.SceneRenderer(ball()))
    assert len(group.children) == 1
    with pytest.raises(TypeError, match="not a renderer"):
        group.add(ball())
