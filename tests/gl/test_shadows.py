"""GL shadows, mirrors and the other issue-10 techniques: switches, scoping, state hygiene, validation."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (96, 72)


def scene(*, light=None, ball=(), floor=(), top=()) -> om.Node:
    root = om.Node("scene", [*top, om.Camera.look_at((0, 4, 5), (0, 0.3, 0), fov=45),
                             light or om.PointLight(position=(0.5, 4, 0.5))])  # fmt: skip
    root.add(om.Node("floor", [*floor, om.Material(diffuse=(0.8, 0.8, 0.8), ambient=(0, 0, 0)),
                               om.Box(size=(6, 0.1, 6), center=(0, -0.05, 0))]))  # fmt: skip
    root.add(om.Node("ball", [*ball, om.Material(diffuse=(0.9, 0.3, 0.2)), om.Sphere(center=(0, 1.2, 0), radius=0.5)]))
    return root


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=SIZE, samples=0)
    yield e
    e.release()


def shadow_pixels(img) -> int:
    """Dark floor pixels under the ball (the floor has no ambient: shadowed means black)."""
    a = img.array[36:66, 30:66, :3].astype(int)
    return int((a.max(axis=2) < 20).sum())


def map_passes(engine) -> list[str]:
    return [p["name"] for p in engine.stats["passes"] if p["name"].startswith("shadow-map")]


def test_shadows_are_on_by_default_and_switch_off_in_several_ways(engine):
    assert shadow_pixels(engine.render(scene())) > 100 and map_passes(engine)
    off = [
        engine.render(scene(top=[om.gl.ShadowMaps(enabled=False)])),  # at the top of the root: the whole frame
        engine.render(scene(light=om.PointLight(position=(0.5, 4, 0.5), casts_shadows=False))),
        engine.render(scene(ball=[om.Shadowing(cast=False)])),
        engine.render(scene(floor=[om.Shadowing(receive=False)])),
        om.render(scene(), engine="gl", size=SIZE, samples=0, shadows=False),
    ]
    assert [shadow_pixels(img) for img in off] == [0] * 5
    engine.render(scene(top=[om.gl.ShadowMaps(enabled=False)]))
    assert map_passes(engine) == []  # no map is drawn at all


def test_shadow_maps_apply_to_the_subgraph_after_them(engine):
    root = scene()
    floor = root["/floor"]
    floor.insert(0, om.gl.ShadowMaps(enabled=False))  # the floor receives no shadow maps; the rest does
    assert shadow_pixels(engine.render(root)) == 0
    assert map_passes(engine), "the ball still casts into the maps other receivers read"


def test_maps_are_reused_while_casters_and_lights_stay(engine):
    root = scene()
    engine.render(root)
    engine.render(root)
    assert map_passes(engine) == []  # replayed: the maps of the last frame hold
    root["/ball"].items[-1].radius = 0.6
    engine.render(root)
    assert map_passes(engine)


def test_a_directional_light_map_is_fitted_to_the_casters():
    from omnirender.gl.techniques.shadows import ShadowMaps, ShadowPlan

    light = om.DirectionalLight(direction=(0, -1, 0))
    plan = ShadowPlan(ShadowMaps(), [(light, np.eye(4))], (np.array([-1.0, 0, -2]), np.array([1.0, 1, 2])))
    (face,) = plan.faces
    corners = np.array([[x, y, z, 1.0] for x in (-1, 1) for y in (0, 1) for z in (-2, 2)])
    ndc = corners @ (face.proj @ face.view).T
    ndc = ndc[:, :3] / ndc[:, 3:]
    assert np.all(np.abs(ndc) <= 1.0) and np.abs(ndc[:, :2]).max(axis=0).min() > 0.9  # tight around the box


def test_point_light_faces_that_see_no_caster_are_not_drawn():
    from omnirender.gl.techniques.shadows import ShadowMaps, ShadowPlan

    plan = ShadowPlan(ShadowMaps(), [(om.PointLight(position=(0, 5, 0)), np.eye(4))],
                      (np.array([-1.0, 0, -1]), np.array([1.0, 1, 1])))  # fmt: skip
    assert len(plan.faces) == 6 and [f.tile is not None for f in plan.faces] == [
        False,
        False,
        False,
        True,
        False,
        False,
    ]


def test_shadow_map_settings_are_validated():
    for kwargs, message in (({"resolution": 8}, "resolution"), ({"softness": -1}, "softness"),
                            ({"enabled": 1}, "enabled"), ({"bias": float("nan")}, "bias")):  # fmt: skip
        with pytest.raises(ValueError, match=message):
            om.gl.ShadowMaps(**kwargs)


def test_shadow_volumes_shadow_and_leave_the_stencil_clear(engine):
    img = engine.render(scene(top=[om.gl.ShadowVolumes()]))
    assert shadow_pixels(img) > 100
    assert map_passes(engine) == []  # the whole frame has exact shadows: no maps
    names = [p["name"] for p in engine.stats["passes"]]
    assert any(n.endswith("volume[0].back") for n in names) and any(n.endswith("lit[0]") for n in names)
    from omnirender.gl.engine.attributes import StencilTest

    # stencil invariability: a shape that draws only where the stencil is 0 still draws everywhere afterwards
    probe = om.Node("probe", [StencilTest(True, "equal", 0), om.Material(diffuse=(0, 0, 0), emission=(0, 1, 0)),
                              om.Box(size=(20, 20, 0.01), center=(0, 2, 3))])  # fmt: skip
    shadowed = om.Node("shadowed", [om.gl.ShadowVolumes(), scene()])
    after = engine.render(om.Node("root", [shadowed, probe])).array[..., 1]  # the probe is drawn after the volumes
    assert (after > 150).mean() > 0.95


def test_mirrors_reflect_and_restore_the_stencil(engine):
    def mirror_scene(mirror: bool) -> om.Node:
        root = om.Node("scene", [om.Camera.look_at((0, 2, 5), (0, 0.5, 0), fov=40),
                                 om.PointLight(position=(1, 4, 3), casts_shadows=False)])  # fmt: skip
        root.add(om.Node("floor", [om.Material(diffuse=(0.3, 0.3, 0.3))] + ([om.Mirror(0.8)] if mirror else [])
                         + [om.Rectangle(size=(5, 5))]))  # fmt: skip
        root.add(om.Node("ball", [om.Material(diffuse=(0.1, 0.9, 0.1)), om.Sphere(center=(0, 0.8, 0), radius=0.5)]))
        return root

    plain = engine.render(mirror_scene(False)).array
    mirrored = engine.render(mirror_scene(True)).array
    green = (mirrored[..., 1].astype(int) - mirrored[..., 0] > 60) & ~(plain[..., 1].astype(int) - plain[..., 0] > 60)
    assert green.sum() > 50  # the ball appears a second time, in the mirror
    names = [p["name"] for p in engine.stats["passes"]]
    assert {"mirror[0].mark", "mirror[0].open", "mirror[0].reflection", "mirror[0].surface"} <= set(names)
    root = mirror_scene(True)
    root.add(om.Node("probe", [om.gl.StencilTest(True, "equal", 0), om.Material(diffuse=(0, 0, 0), emission=(0, 0, 1)),
                               om.Box(size=(20, 20, 0.01), center=(0, 0.5, 2.5))]))  # fmt: skip
    assert (engine.render(root).array[..., 2] > 150).mean() > 0.95


def test_two_mirrors_each_reflect():
    root = om.Node("scene", [om.Camera.look_at((0, 2, 6), (0, 0.5, 0), fov=45), om.PointLight(position=(0, 4, 3))])
    for x in (-1.3, 1.3):
        root.add(om.Node(f"m{x}", [om.Translation(x, 0, 0), om.Material(diffuse=(0.2, 0.2, 0.2)), om.Mirror(0.9),
                                   om.Rectangle(size=(2.4, 4))]))  # fmt: skip
    root.add(om.Node("ball", [om.Material(diffuse=(0.9, 0.1, 0.1)), om.Sphere(center=(0, 0.8, 0), radius=0.4)]))
    from omnirender.gl import GLEngine

    with GLEngine(size=SIZE, samples=0) as e:
        e.render(root)
        assert sum(p["name"].endswith(".reflection") and p["draw_calls"] > 0 for p in e.stats["passes"]) == 2


def test_mirror_plane_is_validated():
    with pytest.raises(ValueError, match="normal must not be the zero vector"):
        om.Mirror(0.5, plane=((0, 0, 0), 1))
    with pytest.raises(ValueError, match="reflectance"):
        om.Mirror(1.5)


def test_surface_styles_validate_and_draw_lines(engine):
    with pytest.raises(ValueError, match="style must be one of"):
        om.gl.SurfaceStyle("sketch")
    with pytest.raises(ValueError, match="needs a line color"):
        om.gl.SurfaceStyle("silhouette", color=None)
    white = om.Background((1, 1, 1))
    hidden = engine.render(scene(top=[white, om.gl.SurfaceStyle("hidden-line", width=1)])).array
    every = engine.render(scene(top=[white, om.gl.SurfaceStyle("haloed", width=1, halo=0)])).array
    dark = lambda a: int((a[..., :3].max(axis=2) < 100).sum())  # noqa: E731
    assert 0 < dark(hidden) < 0.9 * dark(every)  # the edges behind the surfaces are gone


def test_phong_highlight_replaces_the_specular_term(engine):
    shiny = om.Node("scene", [om.Camera.look_at((0, 0, 4), (0, 0, 0)), om.PointLight(position=(0, 0, 4)),
                              om.Material(diffuse=(0.5, 0.1, 0.1), specular=(1, 1, 1), shininess=40)])  # fmt: skip
    shiny.add(om.Sphere(radius=1))
    plain = engine.render(shiny).array[..., :3].astype(int)
    black = np.zeros((16, 16, 4), np.uint8)
    black[..., 3] = 255
    shiny.insert(0, om.gl.PhongHighlight(om.Texture(black)))
    no_spec = engine.render(shiny).array[..., :3].astype(int)
    assert plain[36, 48].min() > 200 and no_spec[36, 48, 1] < 60  # the Phong highlight is gone
    with pytest.raises(ValueError, match="om.Texture"):
        om.gl.PhongHighlight("star.png")


def test_supersampling_smooths_edges():
    def square(*techniques) -> om.Node:  # a tilted white square facing the camera: jagged edges without AA
        root = om.Node("scene", [om.Camera.look_at((0, 0, 4), (0, 0, 0)), *techniques])
        root.add(om.Node("square", [om.Color(1, 1, 1), om.Rotation(12, (0, 0, 1)), om.Rotation(90, (1, 0, 0)),
                                    om.Rectangle(size=(1.6, 1.6))]))  # fmt: skip
        return root

    plain = om.render(square(), engine="gl", size=SIZE, samples=0, background=(0, 0, 0)).array[..., 0]
    smooth = om.render(square(om.gl.Supersample(8)), engine="gl", size=SIZE, samples=0, background=(0, 0, 0))
    smooth = smooth.array[..., 0]
    partial = lambda a: int(((a > 20) & (a < 235)).sum())  # noqa: E731
    assert (plain > 127).sum() > 500
    assert partial(smooth) > 3 * max(partial(plain), 1)
    assert abs(int((smooth > 127).sum()) - int((plain > 127).sum())) < 0.05 * (plain > 127).sum()
    with pytest.raises(ValueError, match="n must be"):
        om.gl.Supersample(0)


def test_pass_data_validation():
    with pytest.raises(ValueError, match="viewport"):
        om.gl.Pass("p", viewport=(0, 0, -1, 4))
    with pytest.raises(ValueError, match="source"):
        om.gl.Pass("p", source="world")
    with pytest.raises(ValueError, match="front_face"):
        om.gl.Pass("p", front_face="left")
    with pytest.raises(ValueError, match="size"):
        om.gl.Target("t", size=(0, 4))
    with pytest.raises(ValueError, match="upper-case"):
        om.gl.Shader(defines={"lower": True})
    with pytest.raises(ValueError, match="depth_test"):
        om.gl.FullScreen("vec4 effect(vec2 uv) { return vec4(1.0); }", depth_test=True)


def test_partial_shadow_updates_pick_casters_only_on_a_software_rasteriser():
    """The default way of a partial shadow-map update follows the GL renderer: llvmpipe and softpipe pay for
    every vertex a scissor rejects (the casters meeting the region are picked), a GPU does not (every caster is
    drawn under the region's scissor)."""
    from omnirender.gl.techniques.shadows import software_rasterizer

    class Ctx:
        def __init__(self, renderer: str) -> None:
            self.info = {"GL_RENDERER": renderer}

    assert software_rasterizer(Ctx("llvmpipe (LLVM 15.0.6, 256 bits)"))
    assert software_rasterizer(Ctx("softpipe"))
    assert not software_rasterizer(Ctx("NVIDIA H200/PCIe/SSE2"))
    assert not software_rasterizer(Ctx("NOOP"))
    assert not software_rasterizer(Ctx("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 17.0.6, DRM 3.57)"))
