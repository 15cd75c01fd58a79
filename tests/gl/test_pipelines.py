"""Chained pipelines: om.gl.RenderTexture (portals, self-reference, cycles), and what other engines do with one."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.gl.engine.render_texture import PipelineCycleError

HUES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def glow(color) -> om.Material:
    """A surface that shows exactly ``color`` (no diffuse or ambient light)."""
    return om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), emission=color)


def quad(x0: float, y0: float, x1: float, y1: float) -> om.TriangleSet:
    v = np.array([[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0]], float)
    uv = [[0, 0], [1, 0], [1, 1], [0, 1]]
    return om.TriangleSet(v, [[0, 1, 2], [0, 2, 3]], normals=[[0, 0, 1]] * 4, texcoords=uv)


def other_scene() -> om.Node:
    """Red left half, blue bottom-right quarter, green background (seen by an orthographic camera 2 units tall)."""
    other = om.Node("other")
    other.add(om.Background((0, 1, 0)))
    red = other.add(om.Node("red"))
    red.add(glow((1, 0, 0)))
    red.add(quad(-1, -1, 0, 1))
    blue = other.add(om.Node("blue"))
    blue.add(glow((0, 0, 1)))
    blue.add(quad(0, -1, 1, 0))
    return other


def portal_scene(size=(64, 64)) -> tuple[om.Node, om.gl.RenderTexture]:
    texture = om.gl.RenderTexture(other_scene(), om.Camera.orthographic((0, 0, 5), height=2), size, name="portal")
    main = om.Node("main")
    # a perspective camera that sees the plane z = 0 four units tall, as the orthographic pipeline camera sees 2
    main.add(om.Camera.look_at((0, 0, 5), fov=2 * np.degrees(np.arctan(2 / 5))))
    main.add(om.Background((0.2, 0.2, 0.2)))
    portal = main.add(om.Node("portal"))
    portal.add(texture)
    portal.add(quad(-1, -1, 1, 1))
    return main, texture


def hue(pixel) -> int:
    """Index of the dominant channel of an RGB pixel, -1 when none dominates."""
    rgb = np.asarray(pixel[:3], float)
    top = int(np.argmax(rgb))
    return top if rgb[top] > 60 and rgb[top] > 3 * np.sort(rgb)[-2] + 10 else -1


# the portal spans pixels [W/4, 3W/4) of the main image (the main camera is twice as tall as the portal)
PREDICTED = {(0.3, 0.3): 0, (0.3, 0.7): 0, (0.7, 0.3): 1, (0.7, 0.7): 2}


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_portal_shows_the_other_scene_at_the_predicted_pixels(pipeline):
    main, _ = portal_scene()
    img = om.render(main, engine="gl", size=(200, 200), pipeline=pipeline).array
    for (u, v), expected in PREDICTED.items():  # (u, v) across the portal, v down from its top
        x, y = int(50 + u * 100), int(50 + v * 100)
        assert hue(img[y, x]) == expected, ((u, v), img[y, x])
    assert tuple(img[10, 10, :3]) == (51, 51, 51)  # outside the portal: the main scene's background
    # the portal's image is exact where a texel is sampled in its middle: the emitted colour times the headlight
    assert img[80, 80, 0] == img[80, 80, :3].max() and img[80, 80, 1:3].max() == 0


@pytest.mark.slow
@pytest.mark.parametrize(
    "engine",
    [
        pytest.param("povray", marks=pytest.mark.povray),
        pytest.param("mitsuba", marks=pytest.mark.mitsuba),
        pytest.param("radiance", marks=pytest.mark.radiance),
    ],
)
def test_offline_engines_render_the_pipeline_themselves_and_agree(engine):
    main, texture = portal_scene()
    gl = om.render(main, engine="gl", size=(100, 100)).array
    img = om.render(main, engine=engine, size=(100, 100)).array
    assert engine in texture._offline  # the engine rendered the pipeline's scene itself
    for (u, v), expected in PREDICTED.items():
        x, y = int(25 + u * 50), int(25 + v * 50)
        assert hue(img[y, x]) == expected == hue(gl[y, x]), ((u, v), engine, img[y, x], gl[y, x])
        assert np.abs(img[y, x, :3].astype(int) - gl[y, x, :3]).max() <= 6


def test_exporters_embed_the_gl_image_of_the_pipeline():
    _, texture = portal_scene((32, 32))
    pixels = texture.image_array()
    assert pixels.shape == (32, 32, 4)
    assert hue(pixels[8, 8]) == 0 and hue(pixels[24, 24]) == 2 and hue(pixels[8, 24]) == 1
    assert texture.image_array() is pixels  # cached while the scene is unchanged
    texture.scene["/red"].items[0].emission = (1, 1, 0)
    assert texture.image_array()[8, 8, 1] > 200  # a change of the pipeline's scene makes a new image


def test_the_portal_follows_changes_of_the_other_scene_and_is_drawn_once_per_change():
    main, texture = portal_scene()
    with om.gl.GLEngine(size=(200, 200)) as engine:
        engine.render(main)
        pipeline = engine.pipelines().pipelines[id(texture)]
        assert pipeline.drawn == 1
        engine.render(main)
        assert pipeline.drawn == 1  # nothing changed: the last image is kept
        texture.scene["/red"].items[0].emission = (0, 1, 0)
        img = engine.render(main).array
        assert pipeline.drawn == 2 and hue(img[80, 80]) == 1
        assert hue(engine.pipeline_image(texture).array[16, 16]) == 1


def frame_scene() -> tuple[om.Node, om.gl.RenderTexture, om.Material]:
    """A marker showing the frame number's hue on the left; on the right a screen showing the scene itself."""
    scene = om.Node("feedback")
    camera = om.Camera.orthographic((0, 0, 5), height=2)
    scene.add(camera)
    scene.add(om.Background((0, 0, 0)))
    marker_material = glow(HUES[0])
    marker = scene.add(om.Node("marker"))
    marker.add(marker_material)
    marker.add(quad(-1, -1, 0, 1))
    texture = om.gl.RenderTexture(scene, camera, (64, 64), name="feedback", filter="nearest")
    screen = scene.add(om.Node("screen"))
    screen.add(texture)
    screen.add(quad(0, -1, 1, 1))
    return scene, texture, marker_material


def test_a_pipeline_that_reads_its_own_output_shows_the_previous_frame():
    scene, texture, marker = frame_scene()
    with om.gl.GLEngine(size=(64, 64), samples=0) as engine:
        for n in range(5):
            marker.emission = HUES[n % 3]
            shown = engine.render(scene).array
            own = engine.pipeline_image(texture).array
            # the pipeline's image: the marker of frame n, its screen shows frame n - 1 (black before frame 0)
            assert hue(own[32, 16]) == n % 3
            if n >= 1:
                assert hue(own[32, 40]) == (n - 1) % 3
            else:
                assert own[32, 40, :3].max() < 10
            if n >= 2:  # and inside that, frame n - 2
                assert hue(own[32, 52]) == (n - 2) % 3
            # the frame reads the pipeline after it was drawn: its screen shows frame n
            assert hue(shown[32, 16]) == n % 3 and hue(shown[32, 40]) == n % 3


def test_pipelines_are_drawn_in_dependency_order():
    inner, _ = portal_scene()  # a pipeline whose scene has a portal: two pipelines deep
    outer = om.gl.RenderTexture(inner, om.Camera.orthographic((0, 0, 5), height=4), (100, 100), name="outer")
    main = om.Node("main")
    main.add(om.Camera.orthographic((0, 0, 5), height=2))
    node = main.add(om.Node("screen"))
    node.add(outer)
    node.add(quad(-1, -1, 1, 1))
    with om.gl.GLEngine(size=(100, 100)) as engine:
        img = engine.render(main).array  # first frame: the inner portal must already be drawn
        for (u, v), expected in PREDICTED.items():
            assert hue(img[int(25 + v * 50), int(25 + u * 50)]) == expected
        report = engine.stats["pipelines"]
        assert [(p["name"], p["drawn"]) for p in report] == [("portal", True), ("outer", True)]
        assert "opaque" in report[0]["passes"]
        engine.render(main)
        assert [p["drawn"] for p in engine.stats["pipelines"]] == [False, False]  # nothing changed


def test_a_cycle_of_pipelines_is_refused_with_its_names():
    a_scene, b_scene = om.Node("a"), om.Node("b")
    a = om.gl.RenderTexture(a_scene, om.Camera.orthographic((0, 0, 5), height=2), (16, 16), name="A")
    b = om.gl.RenderTexture(b_scene, om.Camera.orthographic((0, 0, 5), height=2), (16, 16), name="B")
    for scene, texture in ((a_scene, b), (b_scene, a)):
        scene.add(texture)
        scene.add(quad(-1, -1, 1, 1))
    main = om.Node("main")
    main.add(a)
    main.add(quad(-1, -1, 1, 1))
    with pytest.raises(PipelineCycleError, match="A -> B -> A"):
        om.render(main, engine="gl", size=(32, 32))
    with pytest.raises(PipelineCycleError, match="B -> A -> B"):
        a.image_array()  # A's image drawn by a GL engine: there B is the first pipeline met


def test_render_texture_errors_name_the_parameter_and_the_fix():
    with pytest.raises(ValueError, match="scene must be an om.Node"):
        om.gl.RenderTexture("scene.yaml")
    with pytest.raises(ValueError, match="camera must be an om.Camera"):
        om.gl.RenderTexture(om.Node("s"), camera=(0, 0, 5))
    with pytest.raises(ValueError, match=r"size must be \(width, height\) in pixels"):
        om.gl.RenderTexture(om.Node("s"), size=(0, 64))
    assert isinstance(om.gl.RenderTexture(om.Node("s")), om.Texture)


REFRACT = """
uniform sampler2D u_scene;
uniform vec2 u_size;
uniform float u_shift;
void pass_fragment(inout vec4 color, vec3 P, vec3 N) {
    // screen-space refraction: what lies behind, a fixed shift to the right
    color = vec4(texture(u_scene, (gl_FragCoord.xy + vec2(u_shift, 0.0)) / u_size).rgb, 1.0);
}
"""


class Refraction(om.gl.GLTechnique):
    """Shades the subgraph after it with the image of a render texture, read in screen space."""

    __slots__ = ("texture", "shift")

    def __init__(self, texture, shift: float) -> None:
        super().__init__()
        self.texture, self.shift = texture, shift

    def prepare_pass(self, engine) -> None:
        uniforms = {"u_size": engine.target_size, "u_shift": self.shift}
        shader = om.gl.Shader(fragment=REFRACT, textures={"u_scene": self.texture}, uniforms=uniforms)
        engine.set_pass(om.gl.Pass("refraction", shader=shader))


def test_a_pass_shader_reads_a_render_texture_in_screen_space():
    scene = om.Node("scene")
    camera = om.Camera.orthographic((0, 0, 5), height=2, mask="!glass")  # the pipeline sees all but the glass
    scene.add(om.Camera.orthographic((0, 0, 5), height=2))
    scene.add(om.Background((0, 0, 0)))
    for name, color, x0, x1 in (("left", (1, 0, 0), -1, 0), ("right", (0, 0, 1), 0, 1)):
        scene.add(om.Node(name, [glow(color), quad(x0, -1, x1, 1)]))
    behind = om.gl.RenderTexture(scene, camera, (64, 64), name="behind")
    glass = scene.add(om.Node("glass", groups=["glass"]))
    glass.add(Refraction(behind, shift=12.0))
    glass.add(om.Translation(0, 0, 0.5))
    glass.add(quad(-0.5, -0.5, 0.5, 0.5))
    with om.gl.GLEngine(size=(64, 64), samples=0) as engine:
        first = engine.render(scene).array
        assert first[32, 26, :3].max() < 10  # met while drawing: black on the first frame
        img = engine.render(scene).array
    # left of the centre the glass shows what lies 12 pixels to its right: red up to x = 20, then blue
    assert hue(img[32, 18]) == 0 and hue(img[32, 22]) == 2
    assert hue(img[32, 10]) == 0 and hue(img[32, 54]) == 2  # outside the glass: the scene itself


def glass_scene(technique_args: dict) -> tuple[om.Node, om.Node]:
    """Red left and blue right halves behind a square of glass refracting a pipeline that leaves it out."""
    scene = om.Node("scene")
    scene.add(om.Camera.orthographic((0, 0, 5), height=2))
    scene.add(om.Background((0, 0, 0)))
    for name, color, x0, x1 in (("left", (1, 0, 0), -1, 0), ("right", (0, 0, 1), 0, 1)):
        scene.add(om.Node(name, [glow(color), quad(x0, -1, x1, 1)]))
    behind = om.gl.RenderTexture(scene, om.Camera.orthographic((0, 0, 5), height=2, mask="!glass"), (64, 64))
    glass = scene.add(om.Node("glass", groups=["glass"]))
    glass.add(om.gl.Refraction(behind, **technique_args))
    glass.add(om.Translation(0, 0, 0.5))
    glass.add(quad(-0.5, -0.5, 0.5, 0.5))
    return scene, glass


def test_refraction_shows_what_lies_behind_tinted():
    scene, glass = glass_scene({"strength": 0.0, "surface": 0.0})
    with om.gl.GLEngine(size=(64, 64), samples=0) as engine:
        engine.render(scene)  # the glass met the pipeline while drawing: from the next frame on it is drawn first
        clear = engine.render(scene).array
        glass.items[0].tint = (0.5, 0.5, 0.5)
        tinted = engine.render(scene).array
        scene.remove(glass)
        plain = engine.render(scene).array
    inside = (slice(20, 44), slice(20, 44))
    assert np.abs(clear[inside].astype(int) - plain[inside]).max() <= 2  # a flat facing glass: no displacement
    linear = (plain[inside][..., [0, 2]].astype(float) / 255) ** 2.2 * 0.5
    assert np.abs((tinted[inside][..., [0, 2]].astype(float) / 255) ** 2.2 - linear).max() < 0.03
    with pytest.raises(ValueError, match="strength must be a number"):
        om.gl.Refraction(om.gl.RenderTexture(om.Node("s")), strength=3)
    with pytest.raises(ValueError, match="texture must be an om.gl.RenderTexture"):
        om.gl.Refraction("behind.png")
