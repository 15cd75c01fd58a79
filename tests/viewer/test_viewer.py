"""Render lists, rerender/repaint, external lists, lights and node renderables (recording engine)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from viewer_helpers import Dot, Item, RecordingEngine

import omnirender as om
from omnirender.viewer import HIGHLIGHT, TRANSPARENT, TWO_DIMENSIONAL, RenderList, Viewer
from omnirender.viewer.renderable import renderable_of


def test_render_list_files_by_hints_and_sorts_by_z_order():
    rl = RenderList()
    items = [
        Item("t", TRANSPARENT),
        Item("o2", 0, z_order=2),
        Item("2d", TWO_DIMENSIONAL),
        Item("o1", 0, z_order=1),
        Item("t2d", TRANSPARENT | TWO_DIMENSIONAL),
        Item("o1b", 0, z_order=1),
    ]
    hidden = Item("hidden")
    hidden.visible = False
    rl.prerender([*items, hidden])
    assert [r.dot.label for r in rl.opaque] == ["o1", "o1b", "o2"]
    assert [r.dot.label for r in rl.transparent] == ["t"]
    assert [r.dot.label for r in rl.opaque_2d] == ["2d"]
    assert [r.dot.label for r in rl.transparent_2d] == ["t2d"]
    # ArtiSynth prerenders every renderable, visible or not; only visible ones are filed
    assert hidden.prerenders == 1 and all(i.prerenders == 1 for i in items)
    assert len(rl) == 6 and rl.generation == 1


def test_prerender_may_add_sub_renderables():
    class Group(Item):
        def __init__(self):
            super().__init__("group")
            self.parts = [Item("part1", TRANSPARENT), Item("part2")]

        def prerender(self, render_list):
            super().prerender(render_list)
            for p in self.parts:
                render_list.add_if_visible(p)

    rl = RenderList()
    rl.prerender([Group()])
    assert [r.dot.label for r in rl.opaque] == ["part2", "group"]
    assert [r.dot.label for r in rl.transparent] == ["part1"]
    # a hidden parent is still prerendered, so its visible children are drawn (ArtiSynth's rule)
    hidden = Group()
    hidden.visible = False
    hidden.parts[0].visible = False
    rl.prerender([hidden])
    assert hidden.prerenders == 1 and hidden.parts[0].prerenders == 1
    assert [r.dot.label for r in rl] == ["part2"]


def test_hidden_parent_draws_visible_children_in_viewer(recorder):
    class Parent(Item):
        def __init__(self):
            super().__init__("parent")
            self.child = Item("child")

        def prerender(self, render_list):
            super().prerender(render_list)
            render_list.add_if_visible(self.child)

    v = Viewer(engine=recorder)
    parent = Parent()
    parent.visible = False
    v.add_renderable(parent)
    v.rerender()
    assert recorder.drawn() == ["child"]


def test_hidden_node_renderable_hides_its_translucent_parts():
    node = om.Node("n")
    node.add(om.Box())
    node.add(om.Material(diffuse=(1, 0, 0), opacity=0.5))
    node.add(om.Sphere())
    rl = RenderList()
    r = renderable_of(node)
    rl.prerender([r])
    assert len(rl.opaque) == 1 and len(rl.transparent) == 1
    r.visible = False
    rl.prerender([r])
    assert len(rl) == 0


def test_repaint_draws_passes_in_order_without_prerendering(recorder):
    v = Viewer(engine=recorder)
    items = [Item("t", TRANSPARENT), Item("2d", TWO_DIMENSIONAL), Item("o"), Item("t2d", TRANSPARENT | TWO_DIMENSIONAL)]
    for i in items:
        v.add_renderable(i)
    v.rerender()
    assert recorder.drawn() == ["o", "t", "2d", "t2d"]
    passes = [e[1] for e in recorder.log if e[0] == "pass"]
    assert passes == ["opaque", "transparent", "opaque_2d", "transparent_2d", "end"]
    assert [i.renders for i in items] == [[TRANSPARENT], [TWO_DIMENSIONAL], [0], [TRANSPARENT | TWO_DIMENSIONAL]]
    recorder.log.clear()
    v.repaint()
    v.repaint()
    assert all(i.prerenders == 1 for i in items)
    assert recorder.drawn() == ["o", "t", "2d", "t2d"] * 2
    # a renderable added after the last prerender is drawn only after rerender
    v.add_renderable(Item("late"))
    recorder.log.clear()
    v.repaint()
    assert "late" not in recorder.drawn()
    v.rerender()
    assert "late" in recorder.drawn()


def test_highlight_flag_and_removal(recorder):
    v = Viewer(engine=recorder)
    a, b = Item("a"), Item("b")
    v.add_renderable(a)
    v.add_renderable(b)
    v.set_highlight(b)
    v.rerender()
    assert a.renders == [0] and b.renders == [HIGHLIGHT]
    assert v.remove_renderable(a) and not v.remove_renderable(a)
    recorder.log.clear()
    v.rerender()
    assert recorder.drawn() == ["b"]
    v.clear_renderables()
    recorder.log.clear()
    v.rerender()
    assert recorder.drawn() == []


def test_camera_reaches_the_engine(recorder):
    v = Viewer(size=(200, 100), engine=recorder)
    v.add_renderable(Item("a"))
    v.set_eye_to_world((1, 2, 3), (0, 0, 0), (0, 1, 0))
    v.set_perspective(-1, 1, -0.5, 0.5, 1, 10)
    v.rerender()
    camera, world = [e[3] for e in recorder.log if e[0] == "dot"][0]
    assert np.allclose(camera.view_matrix(), v.get_view_matrix()) and np.allclose(world, np.eye(4))
    assert np.allclose(camera.projection_matrix(2.0), v.get_projection_matrix())
    assert isinstance(camera, om.Camera)


def test_nodes_are_wrapped_and_evaluated_with_their_lights(recorder):
    scene = om.Node("scene")
    scene.add(om.Translation(1, 0, 0))
    body = scene.add(om.Node("body"))
    body.add(om.Translation(0, 2, 0))
    body.add(Dot("node-dot"))
    scene.add(om.PointLight(position=(0, 5, 0)))
    v = Viewer(engine=recorder)
    wrapped = v.add_renderable(scene)
    assert isinstance(wrapped, om.viewer.NodeRenderable) and v.renderable_for(scene) is wrapped
    assert isinstance(wrapped, om.IsRenderable)
    v.rerender()
    dots = [e for e in recorder.log if e[0] == "dot"]
    assert dots[0][1] == "node-dot" and np.allclose(dots[0][2], (1, 2, 0))
    # 3 default viewer lights + the scene's point light, all active during the frame
    assert ("lights", 0) in recorder.log  # lights are gone after the frame...
    v2 = Viewer(engine=recorder)
    seen = []
    probe = Item("probe")
    probe.render = lambda renderer, flags: seen.append(len(renderer.lights()))
    v2.add_renderable(scene)
    v2.add_renderable(probe)
    v2.rerender()
    assert seen == [4]
    assert v.remove_renderable(scene)


def test_lights_api_and_changes_at_next_repaint(recorder):
    v = Viewer(engine=recorder)
    assert v.num_lights() == 3
    key = v.get_light(0)
    assert v.get_index_of_light(key) == 0
    assert v.get_light_space(0) == "camera"
    seen = []
    probe = Item("probe")
    probe.render = lambda renderer, flags: seen.append({id(lt): m.copy() for lt, m in renderer.lights()})
    v.add_renderable(probe)
    lamp = om.PointLight(position=(0, 4, 0))
    assert v.add_light(lamp) == 3 and v.num_lights() == 4
    with pytest.raises(ValueError, match="already"):
        v.add_light(lamp)
    with pytest.raises(TypeError, match="om.Light"):
        v.add_light(om.Color(1, 0, 0))
    v.set_eye_to_world((0, 0, 7), (0, 0, 0), (0, 1, 0))
    v.rerender()
    assert len(seen[-1]) == 4
    # camera-space lights are placed by the eye-to-world matrix, world-space ones by the identity
    assert np.allclose(seen[-1][id(key)], v.get_eye_to_world()) and np.allclose(seen[-1][id(lamp)], np.eye(4))
    assert v.remove_light(key) and not v.remove_light(key)
    assert v.get_index_of_light(key) == -1 and v.get_index_of_light(lamp) == 2
    v.repaint()  # no prerender needed: light changes apply at the start of the next repaint
    assert len(seen[-1]) == 3
    v.remove_light(0)
    v.clear_lights()
    v.repaint()
    assert seen[-1] == {}


def test_external_render_list_shared_by_two_viewers():
    shared = RenderList()
    items = [Item("s1"), Item("s2", TRANSPARENT)]
    shared.prerender(items)
    e1, e2 = RecordingEngine(), RecordingEngine()
    v1, v2 = Viewer(engine=e1), Viewer(engine=e2)
    v1.add_renderable(Item("own"))
    for v in (v1, v2):
        v.set_external_render_list(shared)
        assert v.get_external_render_list() is shared
        v.rerender()
    assert e1.drawn() == ["own", "s1", "s2"]
    assert e2.drawn() == ["s1", "s2"]
    assert all(i.prerenders == 1 for i in items)  # the viewers never prerender the shared list
    lo, hi = v2.bounds()
    assert np.allclose(lo, -0.5) and np.allclose(hi, 0.5)
    v1.set_external_render_list(None)
    e1.log.clear()
    v1.repaint()
    assert e1.drawn() == ["own"]
    with pytest.raises(TypeError):
        v1.set_external_render_list([])


class Body:
    """A simulated body: the physics writes (x, y) non-atomically; prerender caches a consistent copy."""

    def __init__(self) -> None:
        self.x = 0
        self.y = 0
        self.cached = (0, 0)
        self.seen: list[tuple[int, int]] = []

    def step(self, k: int) -> None:
        self.x = k
        time.sleep(0.0005)  # a viewer that read x, y directly here would see a torn state
        self.y = k

    def prerender(self, render_list) -> None:
        self.cached = (self.x, self.y)

    def render(self, renderer, flags) -> None:
        x = self.cached[0]
        time.sleep(0.0005)  # a prerender running now (without the lock) would tear the pair
        self.seen.append((x, self.cached[1]))

    def update_bounds(self, pmin, pmax) -> None:
        pass

    def render_hints(self) -> int:
        return 0


def test_simulation_thread_prerenders_while_viewers_repaint_without_tearing():
    body = Body()
    shared = RenderList()
    shared.prerender([body])
    viewers = [Viewer(engine=RecordingEngine()) for _ in range(2)]
    for v in viewers:
        v.set_external_render_list(shared)
    stop = threading.Event()

    def simulate() -> None:
        k = 0
        while not stop.is_set():
            k += 1
            body.step(k)
            shared.prerender([body])

    thread = threading.Thread(target=simulate)
    thread.start()
    try:
        # count-based: repaint until enough frames and simulation states were seen, however loaded the
        # machine is (the deadline is only a guard against a simulation thread that never runs)
        deadline = time.monotonic() + 60.0
        while (len(body.seen) < 40 or len({x for x, _ in body.seen}) < 5) and time.monotonic() < deadline:
            for v in viewers:
                v.repaint()
    finally:
        stop.set()
        thread.join()
    assert len(body.seen) >= 40
    assert all(x == y for x, y in body.seen), [p for p in body.seen if p[0] != p[1]][:5]
    assert len({x for x, _ in body.seen}) >= 5  # the viewers did see the simulation advance


def test_bad_renderables_and_sizes_are_rejected(recorder):
    v = Viewer(engine=recorder)
    with pytest.raises(TypeError, match="not renderable.*render_hints"):
        v.add_renderable(object())
    with pytest.raises(ValueError, match="size"):
        Viewer(size=(0, 10), engine=recorder)
    with pytest.raises(ValueError, match="engine"):
        Viewer(engine="povray")
    with pytest.raises(ValueError, match="background"):
        v.background = (2, 0, 0)
    v.set_background_color((1, 0, 0))
    assert v.get_background_color() == (1.0, 0.0, 0.0, 1.0)


def test_render_lists_adapt_nodes_given_directly(recorder):
    from omnirender.viewer import renderable as rmod

    scene = om.Node("scene")
    scene.add(om.Material(diffuse=(1, 0, 0), opacity=0.5))
    scene.add(om.Box(size=(2, 2, 2), center=(1, 0, 0)))
    assert rmod.node_render_hints(scene) == TRANSPARENT
    pmin, pmax = np.full(3, np.inf), np.full(3, -np.inf)
    rmod.renderable_of(scene).update_bounds(pmin, pmax)
    assert np.allclose(pmin, (0, -1, -1)) and np.allclose(pmax, (2, 1, 1))
    scene.add(om.Text("label", (0, 0, 0), 12))
    assert rmod.node_render_hints(scene) == TRANSPARENT | TWO_DIMENSIONAL
    rl = RenderList()
    rl.prerender([scene])
    assert rl.transparent_2d[0].node is scene and rmod.renderable_of(scene) in list(rl)
    probe = om.Node("probe", [Dot("d")])
    rmod.renderable_of(probe).render(recorder, 0)
    seen = recorder.drawn()
    assert seen == ["d"]
    # a node drawn by a viewer lands in the sublist its hints say
    v = Viewer(engine=recorder)
    v.add_renderable(scene)
    v.rerender()
    assert len(v.render_list.transparent_2d) == 1
