"""The deferred pipeline (issue 11): every reference scene, agreement with forward shading, layout, models, lights."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import omnirender as om
from omnirender.colorimetry import cielab, delta_e2000

from .scenes import SCENES, stage
from .test_references import (
    MULTISAMPLED_ONLY,
    RASTER_RULES,
    REFERENCE_SAMPLES,
    REFERENCES,
    SIZE,
    TOLERANCE,
    allowed,
    mismatches,
)
from .test_techniques import load_example

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def engines():
    from omnirender.gl import GLEngine

    forward, deferred = GLEngine(size=(128, 96)), GLEngine(size=(128, 96), pipeline="deferred")
    yield forward, deferred
    forward.release()
    deferred.release()


def delta_e(a: om.Image, b: om.Image) -> np.ndarray:
    return delta_e2000(cielab(a.array[..., :3]), cielab(b.array[..., :3]))


def assert_agree(forward: om.Image, deferred: om.Image, what: str, p99: float = 2.0, mean: float = 0.6) -> None:
    de = delta_e(forward, deferred)
    assert de.mean() <= mean and np.percentile(de, 99) <= p99, (
        f"{what}: deferred differs from forward by CIEDE2000 mean {de.mean():.2f}, 99th percentile "
        f"{np.percentile(de, 99):.2f}, max {de.max():.1f}"
    )


# -- every existing scene, unchanged ---------------------------------------------------------------------------
def test_every_reference_scene_renders_within_its_tolerance():
    """The GL reference images, drawn by the deferred pipeline: the same tolerance as the forward engine's test."""
    from PIL import Image as PILImage

    from omnirender.gl import GLEngine

    engine = GLEngine(size=SIZE, pipeline="deferred")
    failures = []
    try:
        for name in sorted(SCENES):
            if engine.samples < REFERENCE_SAMPLES and name in MULTISAMPLED_ONLY:
                continue  # as test_references skips it
            image = engine.render(SCENES[name]())
            expected = np.asarray(PILImage.open(REFERENCES / f"{name}.png").convert("RGBA"), np.int16)
            aliased = engine.samples < REFERENCE_SAMPLES  # the rules of test_references.compare
            diff = mismatches(expected, image.array.astype(np.int16), aliased or name in RASTER_RULES)
            bad = (diff > TOLERANCE).mean()
            if bad > allowed(name, aliased):
                failures.append(f"{name}: {bad:.2%} of the pixels differ by more than {TOLERANCE}")
        passes = [p["name"] for p in engine.stats["passes"]]
    finally:
        engine.release()
    assert not failures, failures
    assert "geometry" in passes and "lighting" in passes and "shading" in passes


def many_lights(count: int = 32) -> om.Node:
    """Phong and PBR shapes, a texture, every light type: ``count`` lights in all (the forward engine's limit: 32)."""
    s = stage(lights=False)
    rng = np.random.default_rng(5)
    s.add(om.AmbientLight(intensity=0.08))
    s.add(om.DirectionalLight(direction=(-0.4, -1, -0.5), intensity=0.3))
    s.add(om.SpotLight(position=(0.5, 2.5, 1.5), direction=(-0.2, -1, -0.4), cutoff=35, exponent=3, intensity=0.5))
    for _ in range(count - 3):
        x, z = rng.uniform(-2.5, 2.5, 2)
        s.add(om.PointLight(position=(x, rng.uniform(-0.6, 1.5), z), color=tuple(rng.uniform(0.3, 1, 3)),
                            intensity=0.25, quadratic=1.5, casts_shadows=False))  # fmt: skip
    s.add(om.Node("phong", [om.Material(diffuse=(0.9, 0.5, 0.3), specular=(0.7,) * 3, shininess=60),
                            om.Sphere(center=(-0.7, -0.5, 0), radius=0.5)]))  # fmt: skip
    s.add(om.Node("pbr", [om.PBRMaterial(base_color=(0.9, 0.8, 0.4), metallic=1.0, roughness=0.35),
                          om.Sphere(center=(0.5, -0.55, 0.3), radius=0.45)]))  # fmt: skip
    checker = np.kron((np.indices((8, 8)).sum(axis=0) % 2), np.ones((8, 8)))[..., None] * [200, 90, 40] + 40
    s.add(om.Node("textured", [om.Texture(checker.astype(np.uint8)), om.Box(size=0.6, center=(0.3, -0.7, -1.0))]))
    return s


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
def test_agrees_with_forward_for_32_lights_of_every_type(engines):
    forward, deferred = engines
    scene = many_lights(32)
    assert_agree(forward.render(scene), deferred.render(scene), "32 lights")
    assert deferred.pipeline.stats["lights"] == 31  # the ambient light needs no pass


@pytest.mark.parametrize(
    "name", ["light_spot", "pbr", "textures", "clip_planes", "fog", "transparency", "shape_volume"]
)
def test_agrees_with_forward(engines, name):
    forward, deferred = engines
    scene = SCENES[name]()
    assert_agree(forward.render(scene), deferred.render(scene), name)


def test_depth_mask_and_picking_are_the_same(engines):
    forward, deferred = engines
    scene = SCENES["transparency"]()
    a, b = forward.render(scene), deferred.render(scene)
    assert (a.mask == b.mask).mean() > 0.995
    both = np.isfinite(a.depth) & np.isfinite(b.depth)
    assert (np.isfinite(a.depth) == np.isfinite(b.depth)).mean() > 0.995
    assert np.percentile(np.abs(a.depth[both] - b.depth[both]), 99) < 1e-3
    hits = om.pick(scene, pixel=(64, 60), size=(128, 96))
    assert hits and hits[0].path.startswith("/scene")
    masked = SCENES["shape_sphere"]()
    masked["/shape"].groups = {"hidden"}
    a, b = forward.render(masked, mask="!hidden"), deferred.render(masked, mask="!hidden")
    assert_agree(a, b, "group mask")
    forward.render(masked, mask=None)
    deferred.render(masked, mask=None)


def test_deferred_at_the_top_of_a_scene_is_the_deferred_pipeline(engines):
    forward, deferred = engines
    scene = SCENES["light_point"]()
    top = om.Node("root", [om.gl.Deferred(), scene])
    image = forward.render(top)
    drawn = {p["name"] for p in forward.stats["passes"] if p["draw_calls"]}
    assert {"opaque/geometry", "opaque/shading"} <= drawn
    assert {"opaque/lighting/lights", "opaque/lighting"} & drawn  # lights in a sub-pass with multisampling
    assert np.abs(image.array.astype(int) - deferred.render(scene).array.astype(int)).max() <= 2
    assert_agree(forward.render(scene), image, "om.gl.Deferred at the top")


def test_a_deferred_subgraph_composes_with_the_forward_rest(engines):
    forward, _ = engines
    scene = SCENES["light_spot"]()
    reference = forward.render(scene)
    scene["/objects"].insert(0, om.gl.Deferred())  # the sphere deferred, floor and box forward
    image = forward.render(scene)
    assert any(p["name"].endswith("shading") for p in forward.stats["passes"])
    assert_agree(reference, image, "a deferred subgraph")


# -- what stays forward ----------------------------------------------------------------------------------------
def test_items_the_gbuffer_cannot_hold_are_drawn_forward(engines):
    from omnirender.gl.deferred import in_gbuffer

    forward, deferred = engines
    scene = SCENES["flat_and_highlight"]()  # a highlighted sphere: forward
    scene.add(om.Node("wire", [om.DrawStyle(mode="wireframe"), om.Sphere(radius=0.3, center=(0, 0.5, 0))]))
    deferred.render(scene)
    kinds = {(it.path, in_gbuffer(it)) for it in deferred.draw_items}
    assert ("/scene/flat", True) in kinds and ("/scene/highlight", False) in kinds and ("/scene/wire", False) in kinds
    assert_agree(forward.render(scene), deferred.render(scene), "highlight and wireframe")


# -- buffer layout -------------------------------------------------------------------------------------------
def test_phong_only_layout_fits_32_mib_at_1080p():
    from omnirender.gl.deferred import PBR, PHONG, UNLIT, BufferLayout

    compact = BufferLayout([PHONG], light_format="r11g11b10f")
    assert compact.memory((1920, 1080)) <= 32 * 2**20 and compact.bytes_per_pixel() == 16
    phong = BufferLayout([PHONG])  # the default: half-float light layers
    assert phong.bytes_per_pixel() == 20
    assert [n for n, _ in phong.layers] == ["fixed", "light_0"]  # the diffuse colour rides in the fixed layer
    both = BufferLayout([PHONG, PBR])
    assert both.bytes_per_pixel() == BufferLayout([PBR]).bytes_per_pixel()  # shared channels: the maximum
    assert both.bytes_per_pixel() < phong.bytes_per_pixel() + BufferLayout([PBR]).bytes_per_pixel()
    assert not BufferLayout([UNLIT]).has_lbuffer
    text = both.describe()
    assert "pbr: base[" in text and "MiB at 1920x1080" in text


def test_layout_and_shaders_are_rebuilt_only_when_the_models_change():
    from omnirender.gl import GLEngine

    toon = load_example("15_toon_model.py").TOON
    engine = GLEngine(size=(64, 48), samples=0, pipeline="deferred")
    try:
        scene = SCENES["shape_sphere"]()
        engine.render(scene)
        layout = engine.pipeline.layout
        programs = len(engine.pipeline._programs) + len(engine.programs)
        scene["/shape"].items[0].diffuse = (0.2, 0.9, 0.3)  # a new colour: same models
        engine.render(scene)
        assert engine.pipeline.layout is layout
        assert len(engine.pipeline._programs) + len(engine.programs) == programs
        scene["/shape"].insert(0, toon())
        engine.render(scene)
        assert engine.pipeline.layout is not layout and toon in engine.pipeline.layout.models
        assert "toon: diffuse[" in engine.pipeline.describe()
    finally:
        engine.release()


def test_material_ids_start_again_when_the_table_is_full(monkeypatch, engines):
    import omnirender.gl.deferred.materials as materials
    from omnirender.gl import GLEngine

    forward, _ = engines
    monkeypatch.setattr(materials, "CAPACITY", 4)
    deferred = GLEngine(size=(128, 96), pipeline="deferred")

    def scene(first: int) -> om.Node:  # three Phong descriptions (shininess differs)
        s = stage()
        for i in range(3):
            s.add(om.Node(f"s{i}", [om.Material(diffuse=(0.9, 0.4, 0.2), specular=(1, 1, 1), shininess=first + 30 * i),
                                    om.Sphere(center=(-1.0 + 0.9 * i, -0.6, 0), radius=0.4)]))  # fmt: skip
        return s

    try:
        deferred.render(scene(5))
        generation = deferred.material_table.generation
        image = deferred.render(scene(7))  # three more: the table starts again during the compile
        assert deferred.material_table.generation > generation and len(deferred.material_table) <= 4
        assert_agree(forward.render(scene(7)), image, "a full material table")
    finally:
        deferred.release()


# -- shading models --------------------------------------------------------------------------------------------
def test_bad_model_code_names_model_stage_and_line():
    from omnirender.gl import GLEngine

    model = om.gl.ShadingModel(
        "broken",
        gbuffer={"color": "color"},
        lbuffer={"light": "float"},
        visibility="void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) { g.color = s.base.rgb; }",
        lighting="void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l) {\n"
        "    l.light += dot(p.N, light.L);\n    l.light += undefined_name;\n}",
        shading="vec3 shading(Pixel p, GBuffer g, LBuffer l) { return g.color * l.light; }",
    )
    engine = GLEngine(size=(32, 32), samples=0, pipeline="deferred")
    try:
        with pytest.raises(om.gl.ShadingModelError, match=r"'broken', lighting stage, line 3: .*undefined_name"):
            engine.render(om.Node("s", [model(), om.Sphere()]))
        bad_visibility = om.gl.ShadingModel(
            "vis", gbuffer={"c": "color"}, shading="vec3 shading(Pixel p, GBuffer g, LBuffer l) { return g.c; }",
            visibility="void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) {\n  g.c = s.nothing;\n}",
        )  # fmt: skip
        with pytest.raises(om.gl.ShadingModelError, match=r"'vis', visibility stage, line 2"):
            engine.render(om.Node("s", [bad_visibility(), om.Sphere()]))
    finally:
        engine.release()


@pytest.mark.parametrize(
    "options, message",
    [
        ({"gbuffer": {"c": "vec9"}}, "has type 'vec9'"),
        ({"gbuffer": {"material": "unorm"}}, "must be a lower-case GLSL identifier"),
        ({"lighting": "void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l) {}"}, "needs L-buffer outputs"),
        ({"shading": ""}, "needs a shading stage"),
        ({"parameters": {"k": ("color", (2, 0, 0))}}, "needs values in \\[0, 1\\]"),
    ],
)
def test_model_declarations_are_validated(options, message):
    kwargs = {"shading": "vec3 shading(Pixel p, GBuffer g, LBuffer l) { return vec3(1.0); }", **options}
    with pytest.raises(om.gl.ShadingModelError, match=message):
        om.gl.ShadingModel("checked", **kwargs)


def test_descriptions_validate_their_values():
    toon = load_example("15_toon_model.py").TOON
    with pytest.raises(ValueError, match="has no parameter"):
        toon(stripes=2)
    with pytest.raises(ValueError, match="takes its values from om.Material"):
        om.gl.MaterialDescription(om.gl.deferred.PHONG)
    description = toon(bands=4)
    assert description.packed[0] == 4.0 and len(description.packed) == 8


def test_toon_model_example(engines, tmp_path):
    module = load_example("15_toon_model.py")
    forward, deferred = engines
    scene = module.build_scene()
    toon, plain = deferred.render(scene), forward.render(scene)
    toon.save(tmp_path / "deferred_toon.png")  # kept by pytest for a look (its basetemp), in any test order

    def banded(img: om.Image) -> float:  # how much of the blue ball its six most common tones cover
        rgb = img.array[..., :3].astype(int)
        _, counts = np.unique(rgb[rgb[..., 2] > rgb[..., 0] + 40] // 4, axis=0, return_counts=True)
        return float(np.sort(counts)[::-1][:6].sum() / counts.sum())

    assert banded(toon) > 0.85 and banded(plain) < 0.5  # flat bands instead of a smooth gradient
    assert (toon.array[..., :3].sum(axis=2) < 60).sum() > 50  # the dark rim outlines


def test_the_geometry_stage_displaces_vertices(engines):
    """guacamole's geometry stage (per vertex, before the G-buffer): a model moving each vertex 0.3 along its
    normal draws a 0.5 sphere as the forward pipeline draws a 0.8 one (silhouette IoU >= 0.97), lit as one."""
    inflate = om.gl.ShadingModel(
        "inflate",
        parameters={"amount": ("float", 0.3)},
        gbuffer={"diffuse": "color"},
        geometry="""
void geometry(inout vec3 world, inout vec3 normal) {
    world += normalize(normal) * material.amount;
}""",
        visibility="""
void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) {
    g.diffuse = s.base.rgb;
}""",
        shading="""
vec3 shading(Pixel p, GBuffer g, LBuffer l) {
    return g.diffuse * max(dot(p.N, p.V), 0.0);
}""",
    )
    forward, deferred = engines

    def scene(radius: float, *model) -> om.Node:
        s = om.Node("s", [om.Camera.look_at((0, 0, 5), (0, 0, 0), fov=40), om.Background((0, 0, 0))])
        s.add(om.Node("ball", [*model, om.Material(diffuse=(1, 1, 1)), om.Tessellation(8), om.Sphere(radius=radius)]))
        return s

    displaced = deferred.render(scene(0.5, inflate(amount=0.3))).array[..., :3].sum(axis=-1) > 30
    bigger = forward.render(scene(0.8)).array[..., :3].sum(axis=-1) > 30
    smaller = forward.render(scene(0.5)).array[..., :3].sum(axis=-1) > 30
    iou = (displaced & bigger).sum() / (displaced | bigger).sum()
    assert iou >= 0.97 and displaced.sum() > 2 * smaller.sum()


def test_integer_and_boolean_gbuffer_outputs_round_trip(engines):
    """guacamole allows integer and boolean G-buffer outputs: a uint8 and a bool written in the visibility stage
    read back exactly in the shading stage (right half band 200, left half band 7; the upper half flagged)."""
    coded = om.gl.ShadingModel(
        "coded",
        gbuffer={"band": "uint8", "up": "bool", "big": "uint8"},
        visibility="""
void visibility(inout Surface s, inout GBuffer g, inout LBuffer l) {
    g.band = s.world.x > 0.0 ? 200u : 7u;
    g.up = s.world.y > 0.0;
    g.big = 1000u;  // clamped to 255
}""",
        shading="""
vec3 shading(Pixel p, GBuffer g, LBuffer l) {
    return vec3(g.band == 200u ? 1.0 : 0.0, g.band == 7u ? 1.0 : 0.0, g.up && g.big == 255u ? 1.0 : 0.0);
}""",
    )
    _, deferred = engines
    s = om.Node("s", [om.Camera.look_at((0, 0, 5), (0, 0, 0), fov=40), om.Background((0, 0, 0))])
    s.add(om.Node("box", [coded(), om.Box(size=(2, 2, 0.2))]))
    rgb = deferred.render(s).array[..., :3].astype(int)
    assert tuple(rgb[30, 80]) == (255, 0, 255) and tuple(rgb[66, 80]) == (255, 0, 0)  # right: up / down
    assert tuple(rgb[30, 48]) == (0, 255, 255) and tuple(rgb[66, 48]) == (0, 255, 0)  # left: up / down
    with pytest.raises(ValueError, match="int"):
        om.gl.ShadingModel(
            "bad", gbuffer={"x": "int"}, shading="vec3 shading(Pixel p, GBuffer g, LBuffer l) { return vec3(0.0); }"
        )


def test_see_through_model_example(engines):
    module = load_example("16_see_through.py")
    forward, deferred = engines
    scene = module.build_scene()
    opened, closed = deferred.render(scene), forward.render(scene)

    def yellow(img: om.Image) -> int:
        rgb = img.array[..., :3].astype(int)
        return int(((rgb[..., 0] > 150) & (rgb[..., 1] > 100) & (rgb[..., 2] < 80)).sum())

    assert yellow(opened) > 100 and yellow(closed) == 0  # the sphere behind the wall shows through the cone


# -- lights -----------------------------------------------------------------------------------------------
def test_light_reach_follows_the_threshold():
    light = om.PointLight(intensity=2.0, quadratic=0.5, threshold=0.01)
    d = light.reach()
    assert np.isclose(2.0 * light.attenuation(d), 0.01)
    assert om.PointLight().reach() == np.inf and om.PointLight(constant=2000.0).reach() == 0.0
    with pytest.raises(ValueError, match="threshold"):
        om.PointLight(threshold=0)


def test_proxies_enclose_the_lights_reach():
    from omnirender.gl.deferred.proxies import LightTable, proxy_meshes

    meshes = proxy_meshes()
    for name in ("sphere", "cone"):
        pos, tri = meshes[name]
        normals = np.cross(pos[tri[:, 1]] - pos[tri[:, 0]], pos[tri[:, 2]] - pos[tri[:, 0]])
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        distance = np.einsum("ij,ij->i", normals, pos[tri[:, 0]])
        assert (distance > -1e-6).all()  # outward faces (the cone's sides pass through its apex)
        if name == "sphere":
            assert distance.min() >= 1.0 - 1e-6  # every face plane outside the unit sphere
        else:  # the unit cone (radius 1 at z = 1): every side plane outside it
            rim = np.stack([np.cos(a := np.linspace(0, 2 * np.pi, 97)), np.sin(a), np.ones_like(a)], 1)
            assert (rim @ normals.T - distance <= 1e-6).all()
    lights = [(om.PointLight(quadratic=1.0), np.eye(4)), (om.PointLight(), np.eye(4)),
              (om.SpotLight(cutoff=30, quadratic=1.0), np.eye(4)), (om.SpotLight(cutoff=80, quadratic=1.0), np.eye(4)),
              (om.DirectionalLight(), np.eye(4)), (om.AmbientLight(), np.eye(4))]  # fmt: skip
    groups = {key: len(rows) for key, rows in LightTable(lights, {}).groups.items()}
    assert groups == {("point", "sphere"): 1, ("point", "fullscreen"): 1, ("spot", "cone"): 1, ("spot", "sphere"): 1,
                      ("directional", "fullscreen"): 1}  # fmt: skip


def test_small_lights_light_their_reach_only():
    """A small light on a floor: lit inside its reach like forward shading, untouched beyond (culled there)."""
    from omnirender.gl import GLEngine

    light = om.PointLight(position=(0, 0.3, 0), quadratic=30.0, threshold=1 / 64, casts_shadows=False)
    floor = om.Box(size=(8, 0.1, 8), center=(0, -0.05, 0))
    scene = om.Node("s", [om.Camera.look_at((0, 6, 0.01), (0, 0, 0), fov=60), om.AmbientLight(intensity=0.1),
                          om.Material(diffuse=(0.8, 0.8, 0.8)), floor, light])  # fmt: skip
    engines = [GLEngine(size=(96, 96), samples=0, pipeline=p) for p in ("forward", "deferred")]
    try:
        forward, deferred = (e.render(scene) for e in engines)
    finally:
        for e in engines:
            e.release()
    # pixel -> floor distance from the light (the camera looks straight down at the origin)
    yy, xx = np.mgrid[0:96, 0:96]
    half = 6.0 * np.tan(np.radians(30))
    radius = np.hypot((xx + 0.5 - 48) / 48 * half, (yy + 0.5 - 48) / 48 * half)
    dist = np.hypot(radius, 0.3)
    inside, beyond = dist < light.reach() * 0.9, dist > light.reach() * 1.1
    a, b = forward.array[..., :3].astype(int), deferred.array[..., :3].astype(int)
    assert np.abs(a - b)[inside].max() <= 6
    base = b[beyond].reshape(-1, 3)
    assert (base == base[0]).all()  # nothing beyond the reach: the ambient floor only
    assert a[inside].mean() > base.mean() + 10


def test_hundreds_of_lights_each_add_light():
    from omnirender.gl import GLEngine

    floor = om.Box(size=(12, 0.1, 12), center=(0, -0.05, 0))
    scene = om.Node("s", [om.Camera.look_at((0, 9, 0.01), (0, 0, 0), fov=60), om.AmbientLight(intensity=0.05),
                          om.Material(diffuse=(0.8, 0.8, 0.8)), floor])  # fmt: skip
    grid = [(x, z) for x in np.linspace(-4.5, 4.5, 16) for z in np.linspace(-4.5, 4.5, 16)]
    for x, z in grid:
        scene.add(om.PointLight(position=(x, 0.15, z), color=(1, 0.8, 0.5), quadratic=200.0, threshold=1 / 64,
                                casts_shadows=False))  # fmt: skip
    engine = GLEngine(size=(160, 160), samples=0, pipeline="deferred")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no "more than 32 lights" in the deferred pipeline
            image = engine.render(scene)
        assert engine.pipeline.stats["lights"] == 256
    finally:
        engine.release()
    half = 9.0 * np.tan(np.radians(30))
    lit = 0
    for x, z in grid:  # the floor under every light is brighter than between the lights
        px, py = int(80 + x / half * 80), int(80 + z / half * 80)
        lit += image.array[py, px, 0] > image.array[py, min(px + 4, 159), 0] + 10
    assert lit == 256


def test_shadows_and_receivers_as_forward(engines):
    forward, deferred = engines
    scene = SCENES["light_spot"]()
    shadowed = deferred.render(scene)
    scene["/floor"].insert(0, om.Shadowing(receive=False))
    scene["/objects"].insert(0, om.gl.ShadowMaps(enabled=False))
    a, b = forward.render(scene), deferred.render(scene)
    assert_agree(a, b, "receivers")
    assert (delta_e(b, shadowed) > 3).sum() > 100  # the floor lost the shadows it had


def test_volumes_stop_at_the_gbuffer_depth(engines):
    """An opaque sphere inside a volume: the compositing pass's rays end at the G-buffer depth, so the sphere
    shows through the volume in front of it, the volume adds less there than along a whole ray, and colour and
    depth equal the forward pipeline's."""
    forward, deferred = engines
    blue = (0.2, 0.4, 1.0, 0.03)
    volume = om.Volume(np.ones((16, 16, 16), np.float32), spacing=2.0 / 15, transfer_function=[(0, blue), (1, blue)])
    camera = om.Camera.look_at(eye=(0, 0, 6), center=(0, 0, 0), fov=40)
    ball = om.Node("ball", [om.Color(1, 0.8, 0), om.Sphere(radius=0.4)])
    alone = deferred.render(om.Node("s", [camera, volume]), background=(0, 0, 0))
    inside = om.Node("s", [camera, om.PointLight(position=(2, 3, 5)), ball, volume])
    both, only = deferred.render(inside, background=(0, 0, 0)), deferred.render(om.Node("s", [camera, ball]))
    centre = np.asarray(both.pixel(64, 48)[:3], int)
    assert 100 < centre[0] < only.pixel(64, 48)[0]  # the sphere seen through the volume in front of it
    assert both.pixel(64, 48)[2] < alone.pixel(64, 48)[2]  # the rays stopped at the sphere
    reference = forward.render(inside, background=(0, 0, 0))
    assert_agree(reference, both, "a sphere inside a volume")
    assert abs(both.depth[48, 64] - reference.depth[48, 64]) < 1e-3 and both.depth[48, 64] <= only.depth[48, 64]
    hit = om.pick(inside, pixel=(64, 48), size=(128, 96))[0]
    assert abs((6.0 - hit.point[2]) - only.depth[48, 64]) < 1e-2  # picking finds the sphere where its depth is


# -- orthographic cameras --------------------------------------------------------------------------------------
def orthographic(scene: om.Node, height: float = 3.4) -> om.Node:
    """``scene`` with its camera replaced by an orthographic one at the same place, looking the same way."""
    camera = next(c for c in scene.items if isinstance(c, om.Camera))
    index = list(scene.items).index(camera)
    scene.remove(camera)
    scene.insert(index, om.Camera.orthographic(camera.eye, camera.center, camera.up, height=height))
    return scene


def ortho_mixed() -> om.Node:
    """Every light type with shadows, a textured PBR box, a Phong sphere, a transparent pane, and fog."""
    s = orthographic(stage(lights=False))
    s.add(om.AmbientLight(intensity=0.15))
    s.add(om.DirectionalLight(direction=(-0.5, -1.0, -0.6), intensity=0.5))
    s.add(om.PointLight(position=(-2, 2, 2), color=(0.6, 0.7, 1.0), intensity=0.5, quadratic=0.2))
    s.add(om.SpotLight(position=(1.0, 2.5, 1.5), direction=(-0.3, -1, -0.5), cutoff=35, exponent=2, intensity=0.6))
    s.add(om.Fog(color=(0.16, 0.16, 0.17), start=3.0, end=9.0))
    checker = np.kron((np.indices((8, 8)).sum(axis=0) % 2), np.ones((8, 8)))[..., None] * [200, 90, 40] + 40
    s.add(om.Node("textured pbr", [om.Texture(checker.astype(np.uint8)),
                                   om.PBRMaterial(base_color=(1, 1, 1), metallic=0.3, roughness=0.5),
                                   om.Box(size=0.9, center=(-0.6, -0.55, -0.2))]))  # fmt: skip
    s.add(om.Node("phong", [om.Material(diffuse=(0.9, 0.5, 0.3), specular=(0.7,) * 3, shininess=60),
                            om.Sphere(center=(0.7, -0.5, 0.2), radius=0.5)]))  # fmt: skip
    s.add(om.Node("pane", [om.Material(diffuse=(0.2, 0.5, 1.0), opacity=0.4),
                           om.Box(size=(1.6, 1.0, 0.05), center=(0.2, -0.4, 1.0))]))  # fmt: skip
    return s


ORTHO_SCENES = ["light_directional", "light_point", "light_spot", "light_ambient", "pbr", "textures",
                "transparency", "fog", "shape_volume"]  # fmt: skip


@pytest.fixture(scope="module")
def single_sampled():
    from omnirender.gl import GLEngine

    forward, deferred = GLEngine(size=(128, 96), samples=0), GLEngine(size=(128, 96), samples=0, pipeline="deferred")
    yield forward, deferred
    forward.release()
    deferred.release()


@pytest.mark.parametrize("samples", [0, pytest.param(4, marks=pytest.mark.gl_needs(samples=4))])
@pytest.mark.parametrize("name", [*ORTHO_SCENES, "mixed"])
def test_orthographic_camera_agrees_with_forward(engines, single_sampled, samples, name):
    """Under an orthographic camera (linear depth: every surface lies in front of the full-screen passes' window
    depth 0.5) the deferred image is the forward one, with and without multisampling."""
    forward, deferred = engines if samples else single_sampled
    assert deferred.samples == samples
    scene = ortho_mixed() if name == "mixed" else orthographic(SCENES[name]())
    a, b = forward.render(scene), deferred.render(scene)
    assert (np.isfinite(a.depth).mean()) > 0.3  # the scene is seen (the floor at least)
    assert_agree(a, b, f"{name}, orthographic, samples={samples}")


def test_orthographic_depth_mask_and_picking_are_the_same(engines):
    forward, deferred = engines
    scene = ortho_mixed()
    a, b = forward.render(scene), deferred.render(scene)
    assert (a.mask == b.mask).mean() > 0.995
    both = np.isfinite(a.depth) & np.isfinite(b.depth)
    assert (np.isfinite(a.depth) == np.isfinite(b.depth)).mean() > 0.995
    assert np.percentile(np.abs(a.depth[both] - b.depth[both]), 99) < 1e-3
    camera = next(c for c in scene.items if isinstance(c, om.Camera))
    forward_axis = np.subtract(camera.center, camera.eye) / np.linalg.norm(np.subtract(camera.center, camera.eye))
    for name, point in (("phong", (0.7, -0.5, 0.2)), ("textured pbr", (-0.95, -0.4, -0.2))):
        clip = camera.projection_matrix(128 / 96) @ camera.view_matrix() @ np.array([*point, 1.0])
        x, y = int((clip[0] / clip[3] * 0.5 + 0.5) * 128), int((0.5 - clip[1] / clip[3] * 0.5) * 96)
        hit = om.pick(scene, pixel=(x, y), size=(128, 96))[0]
        assert name in hit.path
        along = float(np.dot(np.subtract(hit.point, camera.eye), forward_axis))  # depth: along the view axis
        assert abs(along - b.depth[y, x]) < 0.05, (name, along, b.depth[y, x])


def test_surfaces_near_the_near_plane_are_shaded(engines, single_sampled):
    """A box nearer than twice the near plane (window depth below 0.5) is shaded as the forward pipeline shades it."""
    for forward, deferred in (engines, single_sampled):
        camera = om.Camera.look_at((0, 0, 1.0), (0, 0, 0), fov=60, near=0.5)
        scene = om.Node("s", [camera, om.PointLight(position=(1, 2, 3)), om.Color(0.8, 0.6, 0.3),
                              om.Box(size=(0.6, 0.6, 0.4), center=(0, 0, 0))])  # fmt: skip
        a, b = forward.render(scene), deferred.render(scene)
        assert a.depth[48, 64] < 0.9 and np.isfinite(b.depth[48, 64])
        assert_agree(a, b, f"a surface near the near plane, samples={deferred.samples}")


@pytest.mark.parametrize("ortho", [False, True])
def test_post_processed_deferred_frame_agrees_with_forward(engines, ortho):
    """A post-processing chain draws the scene into a target without stencil: the deferred shading pass blends
    its edges there (multisampled); its image is the forward one, under either camera."""
    forward, deferred = engines
    scene = SCENES["light_spot"]()
    if ortho:
        scene = orthographic(scene)
    scene.insert(1, om.gl.PostProcess([om.gl.ToneMap()]))
    assert_agree(forward.render(scene), deferred.render(scene), f"post-processed, orthographic={ortho}")
