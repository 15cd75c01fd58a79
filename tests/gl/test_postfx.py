"""The post-processing chain (om.gl.PostProcess): passes, stages, and measurable properties of every effect.

Images are compared in linear light where an effect's rule is stated in it (fog, vignette, tone curves);
tolerances are stated per test (8-bit sRGB output and half-float targets: about 1/255).
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.attributes.photometry import linear_rgb, srgb_to_linear

pytestmark = pytest.mark.gl

SIZE = (160, 120)


@pytest.fixture(scope="module")
def engine():
    e = om.gl.GLEngine(size=SIZE, samples=0)
    yield e
    e.release()


@pytest.fixture(scope="module")
def deferred():
    e = om.gl.GLEngine(size=SIZE, samples=0, pipeline="deferred")
    yield e
    e.release()


def linear(image) -> np.ndarray:
    """(H, W, 3) linear light of an 8-bit sRGB image."""
    return srgb_to_linear(image.array[..., :3] / 255.0)


def build(camera: om.Camera, content: list, effects=None, lights=None, background=(0.2, 0.22, 0.26)) -> om.Node:
    """A scene: camera, lights, background, then (optionally) a chain scoping the content."""
    lights = [om.DirectionalLight(direction=(-0.3, -1, -0.5), intensity=0.7), om.AmbientLight(intensity=0.3)] if (
        lights is None) else lights  # fmt: skip
    scene = om.Node("scene", [camera, *lights, om.Background(background)])
    if effects is not None:
        scene.add(om.gl.PostProcess(effects))
    for node in content:
        scene.add(node)
    return scene


def pixel_of(camera: om.Camera, point, size=SIZE) -> tuple[int, int]:
    """(x, y) pixel (top row 0) where the world ``point`` is seen."""
    clip = camera.projection_matrix(size[0] / size[1]) @ camera.view_matrix() @ np.array([*point, 1.0])
    ndc = clip[:3] / clip[3]
    return int((ndc[0] * 0.5 + 0.5) * size[0]), int((0.5 - ndc[1] * 0.5) * size[1])


def shapes() -> list:
    return [
        om.Node("floor", [om.Material(diffuse=(0.7, 0.7, 0.65)), om.Box(size=(8, 0.1, 6), center=(0, -0.05, 0))]),
        om.Node("ball", [om.Translation(0.8, 0.6, 0), om.Material(diffuse=(0.3, 0.6, 1)), om.Sphere(radius=0.6)]),
        om.Node("box", [om.Translation(-1, 0.5, -0.5), om.Material(diffuse=(1, 0.5, 0.3)), om.Box(size=(1, 1, 1))]),
    ]


#: a self-lit white surface (no light needed)
GLOW = om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), emission=(1, 1, 1))
CAMERA = om.Camera.look_at((0, 2.5, 6), (0, 0.5, 0), fov=40)


# --- the chain -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_empty_chain_looks_like_no_chain(engine, deferred, pipeline):
    e = engine if pipeline == "forward" else deferred
    plain = e.render(build(CAMERA, shapes()))
    chained = e.render(build(CAMERA, shapes(), effects=[]))
    diff = np.abs(plain.array.astype(int) - chained.array.astype(int))
    assert diff.max() <= 2, f"{pipeline}: an empty chain changes the image by up to {diff.max()} of 255"
    assert np.allclose(np.nan_to_num(plain.depth, posinf=-1), np.nan_to_num(chained.depth, posinf=-1), atol=1e-3)


@pytest.mark.gl_needs(samples=4)
@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_chain_keeps_the_engines_multisampling(pipeline):
    """With MSAA the opaque scene is drawn multisampled and resolved (in linear light, so edges differ a little
    from the frame without a chain, which averages display values); shadows off: their filtered edges are not
    the geometry edges the count of colour levels measures)."""
    e = om.gl.GLEngine(size=SIZE, samples=4, pipeline=pipeline, shadows=False)
    try:
        plain = e.render(build(CAMERA, shapes())).array.astype(int)
        chained = e.render(build(CAMERA, shapes(), effects=[]))
        names = [p["name"] for p in e.stats["passes"] if "/" not in p["name"]]
        aliased = om.gl.GLEngine(size=SIZE, samples=0, pipeline=pipeline, shadows=False)
        single = aliased.render(build(CAMERA, shapes(), effects=[])).array.astype(int)
        aliased.release()
    finally:
        e.release()
    assert names[names.index("scene") + 1] == "resolve"
    diff = np.abs(plain - chained.array.astype(int)).max(axis=2)
    assert diff.mean() < 0.5 and (diff > 8).mean() < 0.02, (diff.mean(), (diff > 8).mean())
    # the chain's image differs from the aliased one at edges only (the same shading elsewhere)
    edges = np.abs(single - chained.array.astype(int)).max(axis=2) > 8
    assert 0.002 < edges.mean() < 0.1, f"{pipeline}: {edges.mean():.2%} of pixels differ from the aliased frame"


def _coverage_levels(image: np.ndarray) -> set[int]:
    """Which of 4x MSAA's partial coverages (1/4, 2/4, 3/4 of a white sample over black, resolved in linear light
    and sRGB-encoded: 137, 188, 225) occur in ``image``, within 6/255."""
    grey = image[..., :3].astype(int)
    found = set()
    for quarters, level in ((1, 137), (2, 188), (3, 225)):
        near = (np.abs(grey - level) <= 6).all(axis=2)
        if near.sum() >= 3:
            found.add(quarters)
    return found


@pytest.mark.gl_needs(samples=4)
@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_the_chains_edges_carry_the_four_samples_coverage(pipeline):
    """A self-lit white polygon over black: without MSAA every pixel is 0 or 255 (a rasterisation rule every
    conforming driver shares); with 4 samples and a chain, edge pixels take the partial coverages 1/4, 2/4, 3/4.
    Driver-independent, unlike counting colour levels of a shaded scene (NVIDIA's shading gave 213 levels without
    MSAA and 273 with, where llvmpipe's gave 1.5x)."""
    content = [om.Node("tile", [om.Rotation(17, (0, 0, 1)), GLOW, om.Box(size=(2.2, 1.4, 0.1))])]
    camera = om.Camera.look_at((0, 0, 4), (0, 0, 0), fov=40)
    images = {}
    for samples in (0, 4):
        e = om.gl.GLEngine(size=SIZE, samples=samples, pipeline=pipeline, shadows=False)
        try:
            scene = build(camera, content, effects=[], lights=[], background=(0, 0, 0))
            images[samples] = e.render(scene).array
        finally:
            e.release()
    single, multi = images[0][..., :3].astype(int), images[4]
    extreme = ((single <= 2) | (single >= 253)).all(axis=2)
    assert extreme.all(), f"{pipeline}: without MSAA {(~extreme).sum()} pixels are neither black nor white"
    assert _coverage_levels(multi) == {1, 2, 3}, f"{pipeline}: partial coverages found {_coverage_levels(multi)}"


@pytest.mark.gl_needs(samples=4)
@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_the_chain_resolves_samples_in_a_shader_not_by_the_drivers_blit(monkeypatch, pipeline):
    """glBlitFramebuffer resolves float samples "in an implementation-dependent manner" (OpenGL 4.6, 18.3.2):
    NVIDIA's left the chain's edges aliased.  The chain averages the samples itself."""
    from omnirender.gl.engine import frame as frame_module

    multisampled_blits = []
    real = frame_module.blit

    def recording(raw, source, target, *args, **kwargs):
        if any(getattr(a, "samples", 0) > 1 for a in (*source.color_attachments, source.depth_attachment) if a):
            multisampled_blits.append(source)
        return real(raw, source, target, *args, **kwargs)

    monkeypatch.setattr(frame_module, "blit", recording)
    e = om.gl.GLEngine(size=SIZE, samples=4, pipeline=pipeline)
    try:
        e.render(build(CAMERA, shapes(), effects=[]))
    finally:
        e.release()
    assert not multisampled_blits, "the chain's samples were resolved by glBlitFramebuffer"


def test_passes_run_depth_effects_before_transparency_and_colour_effects_after(engine):
    effects = [om.gl.SSAO(), om.gl.DepthFog(start=2, end=30), om.gl.Bloom(levels=2), om.gl.ToneMap(), om.gl.FXAA()]
    engine.render(build(CAMERA, shapes(), effects=effects))
    names = [p["name"] for p in engine.stats["passes"] if "/" not in p["name"]]
    order = [n for n in names if n in ("scene", "SSAO", "DepthFog", "transparent", "Bloom", "ToneMap", "FXAA",
                                       "output", "overlay")]  # fmt: skip
    assert order == ["scene", "SSAO", "DepthFog", "transparent", "Bloom", "ToneMap", "FXAA", "output", "overlay"]


def test_depth_effect_after_a_colour_effect_is_refused_with_the_fix():
    with pytest.raises(ValueError, match=r"effect 1 \(om.gl.SSAO\).*follows the colour-only effect.*list them first"):
        om.gl.PostProcess([om.gl.ToneMap(), om.gl.SSAO()])


def test_chain_follows_the_users_order_and_repeats(engine):
    def render(effects):
        return engine.render(build(CAMERA, shapes(), effects=effects)).array.astype(int)

    a = render([om.gl.Vignette(0.5), om.gl.ToneMap("reinhard", exposure=3)])
    b = render([om.gl.ToneMap("reinhard", exposure=3), om.gl.Vignette(0.5)])
    assert np.abs(a - b).max() > 10, "vignette before and after a non-linear tone curve must differ"
    c = render([om.gl.Vignette(0.3), om.gl.Vignette(0.5, start=0.2)])
    d = render([om.gl.Vignette(0.5, start=0.2), om.gl.Vignette(0.3)])
    assert np.abs(c - d).max() <= 1, "two vignettes (products) commute"
    assert np.abs(c - render([om.gl.Vignette(0.3)])).max() > 10, "the same effect twice applies twice"


# --- SSAO ------------------------------------------------------------------------------------------------------
def corner() -> tuple[om.Camera, list]:
    wall = om.Material(diffuse=(0.8, 0.8, 0.8))
    return om.Camera.look_at((1.5, 2.0, 4.0), (0, 0.8, 0), fov=45), [
        om.Node("floor", [wall, om.Box(size=(6, 0.1, 6), center=(0, -0.05, 1))]),
        om.Node("wall", [wall, om.Box(size=(6, 4, 0.1), center=(0, 2, -1.05))]),
    ]


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_ssao_darkens_the_inside_corner_and_leaves_a_flat_wall(engine, deferred, pipeline):
    e = engine if pipeline == "forward" else deferred
    camera, content = corner()
    lights = [om.AmbientLight(intensity=1.0)]
    plain = linear(e.render(build(camera, content, lights=lights)))
    ao = linear(e.render(build(camera, content, effects=[om.gl.SSAO(radius=0.5)], lights=lights)))
    ratio = (ao.mean(axis=2) + 1e-4) / (plain.mean(axis=2) + 1e-4)
    x, y = pixel_of(camera, (0.0, 0.02, -0.98))
    at_corner = ratio[y - 2 : y + 3, x - 2 : x + 3].mean()
    x, y = pixel_of(camera, (0.3, 2.2, -1.0))
    on_wall = ratio[y - 2 : y + 3, x - 2 : x + 3].mean()
    x, y = pixel_of(camera, (0.5, 0.0, 1.5))
    on_floor = ratio[y - 2 : y + 3, x - 2 : x + 3].mean()
    assert at_corner < 0.9, f"{pipeline}: the inside corner keeps {at_corner:.2f} of its light"
    assert on_wall > 0.97 and on_floor > 0.97, f"{pipeline}: flat surfaces darkened ({on_wall:.3f}, {on_floor:.3f})"


# --- bloom -----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("emission, spreads", [(1.0, True), (0.3, False)])
def test_bloom_spreads_light_beyond_a_bright_sphere_only(engine, emission, spreads):
    camera = om.Camera.look_at((0, 0, 5), (0, 0, 0), fov=40)
    glow = om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), emission=(emission,) * 3)
    ball = om.Node("ball", [glow, om.Sphere(radius=0.6)])
    bg = (0.02, 0.02, 0.02)
    plain = linear(engine.render(build(camera, [ball], lights=[], background=bg)))
    bloom = linear(engine.render(build(camera, [ball], effects=[om.gl.Bloom(threshold=0.6)], lights=[], background=bg)))
    cx, cy = pixel_of(camera, (0, 0, 0))
    radius = cx - pixel_of(camera, (-0.6, 0, 0.6))[0]
    ring = [(cx + int(1.4 * radius), cy), (cx - int(1.4 * radius), cy), (cx, cy + int(1.4 * radius))]
    gain = np.mean([bloom[y, x].mean() - plain[y, x].mean() for x, y in ring])
    if spreads:
        assert gain > 0.01, f"bloom added only {gain:.4f} outside a bright sphere"
    else:
        assert abs(gain) < 1e-3, f"bloom spread {gain:.4f} from a sphere below the threshold"


# --- tone mapping ------------------------------------------------------------------------------------------------
#: an HDR ramp: exp2 from -8 to 12 stops across the image (replacing the scene's colours)
RAMP = om.gl.CustomEffect("ramp", "vec4 effect(vec2 uv) { return vec4(vec3(exp2(uv.x * 20.0 - 8.0)), 1.0); }")


@pytest.mark.parametrize("operator", ["reinhard", "aces", "uncharted2", "hejl"])
def test_tone_mappers_are_monotonic_and_map_hdr_into_unit_range(engine, operator):
    engine.render(build(CAMERA, shapes(), effects=[RAMP, om.gl.ToneMap(operator)]))
    mapped = engine.target("postfx.b").color_array()[SIZE[1] // 2, :, 0]  # the tone mapper's output row
    assert np.all(np.diff(mapped) >= -1e-3), f"{operator} is not monotonic"
    assert np.all(np.diff(mapped[: SIZE[0] // 2]) > 0), f"{operator} is flat in the lower stops"
    assert mapped.min() >= 0.0 and mapped.max() <= 1.0 + 1e-3, (
        f"{operator} leaves [0, 1]: {mapped.min()}..{mapped.max()}"
    )
    assert mapped[-1] > 0.9, f"{operator} maps 2^12 to {mapped[-1]:.3f}"
    if operator == "reinhard":  # x / (1 + x) at the pixel centres' exposures
        x = np.exp2((np.arange(SIZE[0]) + 0.5) / SIZE[0] * 20.0 - 8.0)
        assert np.allclose(mapped, x / (1 + x), atol=2e-3)


def test_auto_exposure_maps_the_average_luminance_to_the_key(engine):
    def render(intensity):
        lights = [om.DirectionalLight(direction=(-0.3, -1, -0.5), intensity=intensity)]
        effects = [om.gl.ToneMap("reinhard", auto_exposure=True)]
        return linear(engine.render(build(CAMERA, shapes(), effects=effects, lights=lights, background=(0, 0, 0))))

    dim, bright = render(0.25), render(1.0)
    assert abs(dim.mean() - bright.mean()) < 0.1 * bright.mean(), (dim.mean(), bright.mean())


# --- FXAA --------------------------------------------------------------------------------------------------------
def aliasing(image) -> float:
    """Mean absolute Laplacian of luminance: large for staircase edges."""
    y = linear(image).mean(axis=2)
    lap = 4 * y[1:-1, 1:-1] - y[:-2, 1:-1] - y[2:, 1:-1] - y[1:-1, :-2] - y[1:-1, 2:]
    return float(np.abs(lap).mean())


def test_fxaa_lowers_edge_aliasing_on_thin_rotated_lines(engine):
    camera = om.Camera.look_at((0, 0, 6), (0, 0, 0), fov=40)
    bars = [om.Node(f"bar{k}", [om.Rotation(17, (0, 0, 1)), om.Translation(-2.4 + 0.45 * k, 0, 0), GLOW,
                                om.Box(size=(0.06, 5, 0.1))])
            for k in range(11)]  # fmt: skip
    plain = engine.render(build(camera, bars, lights=[], background=(0, 0, 0)))
    smooth = engine.render(build(camera, bars, effects=[om.gl.FXAA()], lights=[], background=(0, 0, 0)))
    assert aliasing(smooth) < 0.8 * aliasing(plain), (aliasing(smooth), aliasing(plain))
    assert abs(linear(smooth).mean() - linear(plain).mean()) < 0.02, "FXAA must not change the average light much"


# --- fog ---------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["linear", "exp2"])
def test_depth_fog_matches_om_fog_formula_at_known_depths(engine, mode):
    fog = {"color": (0.6, 0.65, 0.7), "start": 3.0, "end": 14.0, "mode": mode, "density": 0.12}
    camera = om.Camera.look_at((0, 1.5, 6), (0, 0.5, -4), fov=45)
    plain = engine.render(build(camera, shapes()))
    fogged = engine.render(build(camera, shapes(), effects=[om.gl.DepthFog(**fog)]))
    seen = np.isfinite(plain.depth)
    ys, xs = np.nonzero(seen)
    picks = np.linspace(0, len(ys) - 1, 40).astype(int)
    inv = np.linalg.inv(camera.projection_matrix(SIZE[0] / SIZE[1]))
    expected, actual = [], []
    for k in picks:
        y, x = ys[k], xs[k]
        ndc = np.array([(x + 0.5) / SIZE[0] * 2 - 1, 1 - (y + 0.5) / SIZE[1] * 2, 0.0, 1.0])
        ray = inv @ ndc
        ray = ray[:3] / ray[3]
        distance = plain.depth[y, x] * np.linalg.norm(ray / -ray[2])  # along the axis -> eye distance
        f = float(om.Fog(**fog).factor(distance))
        expected.append(f * linear(plain)[y, x] + (1 - f) * np.asarray(linear_rgb(fog["color"])))
        actual.append(linear(fogged)[y, x])
    err = np.abs(np.array(expected) - np.array(actual)).max()
    assert err < 0.01, f"{mode}: DepthFog differs from om.Fog's formula by {err:.4f} (linear)"
    assert np.abs(fogged.array[~seen].astype(int) - plain.array[~seen].astype(int)).max() <= 1  # background kept


def test_depth_fog_agrees_with_om_fog_on_opaque_scenes(engine):
    fog = {"color": (0.6, 0.65, 0.7), "start": 2.0, "end": 12.0}
    with_fog = build(CAMERA, [om.Node("fog", [om.Fog(**fog), *shapes()])])
    reference = engine.render(with_fog).array.astype(int)
    post = engine.render(build(CAMERA, shapes(), effects=[om.gl.DepthFog(**fog)])).array.astype(int)
    diff = np.abs(reference - post).max(axis=2)
    assert np.percentile(diff, 99) <= 3 and diff.mean() < 0.5, (diff.max(), diff.mean())


# --- vignette ----------------------------------------------------------------------------------------------------
def test_vignette_darkens_corners_by_the_set_amount(engine):
    empty = om.Node("nothing")
    image = linear(engine.render(build(CAMERA, [empty], effects=[om.gl.Vignette(0.4, start=0.5)], lights=[],
                                       background=(0.6, 0.6, 0.6))))  # fmt: skip
    plain = linear(engine.render(build(CAMERA, [empty], lights=[], background=(0.6, 0.6, 0.6))))
    ratio = image.mean(axis=2) / plain.mean(axis=2)
    h, w = ratio.shape
    for y, x in ((0, 0), (0, w - 1), (h - 1, 0), (h - 1, w - 1)):
        assert abs(ratio[y, x] - 0.6) < 0.02, f"corner ({x}, {y}) keeps {ratio[y, x]:.3f}, not 0.6"
    assert abs(ratio[h // 2, w // 2] - 1.0) < 0.01
    assert abs(ratio[h // 2, w // 4] - 1.0) < 0.01  # within start: untouched


# --- light shafts ------------------------------------------------------------------------------------------------
def test_light_shafts_stream_from_a_visible_light_and_not_from_an_occluded_one(engine):
    camera = om.Camera.look_at((0, 0, 6), (0, 0, 0), fov=50)
    light = om.PointLight(position=(0, 0.5, -4), color=(1, 0.9, 0.7))
    ball = om.Node("ball", [om.Translation(0, 0.3, -2), om.Material(diffuse=(0.4, 0.4, 0.4)), om.Sphere(radius=0.5)])
    wall = om.Node("wall", [om.Material(diffuse=(0.4, 0.4, 0.4)), om.Box(size=(20, 20, 0.1), center=(0, 0, -1))])
    shafts = [om.gl.LightShafts(intensity=1.0)]
    bg = (0.0, 0.0, 0.0)
    x, y = pixel_of(camera, (0, 0.5, -4))
    for content, visible in (([ball], True), ([wall], False)):
        plain = linear(engine.render(build(camera, content, lights=[light], background=bg)))
        rays = linear(engine.render(build(camera, content, effects=shafts, lights=[light], background=bg)))
        gain = (rays - plain).mean(axis=2)
        near = gain[y - 25 : y + 25, x - 25 : x + 25].mean()
        if visible:
            assert near > 0.02, f"no shafts around a visible light ({near:.4f})"
            assert gain[y - 8 : y - 4, x - 2 : x + 2].mean() > gain[2:6, 2:6].mean(), "shafts fade away from the light"
        else:
            assert np.abs(gain).max() < 2e-3, f"shafts from a light hidden behind a wall ({np.abs(gain).max():.4f})"


# --- depth of field ----------------------------------------------------------------------------------------------
def test_depth_of_field_keeps_the_focus_sharp_and_blurs_far_surfaces(engine):
    camera = om.Camera.look_at((0, 0, 6), (0, 0, 0), fov=40)
    near = om.Node("near", [om.Translation(-0.9, 0, 2), om.Material(diffuse=(1, 0.3, 0.2)), om.Sphere(radius=0.5)])
    far = om.Node("far", [om.Translation(2.5, 0, -12), om.Material(diffuse=(0.2, 0.5, 1)), om.Sphere(radius=1.2)])
    content = [near, far]
    plain = engine.render(build(camera, content))
    dof = engine.render(build(camera, content, effects=[om.gl.DepthOfField(focus=4.0, range=6.0, max_radius=6)]))
    diff = np.abs(plain.array.astype(int) - dof.array.astype(int)).max(axis=2)
    x, y = pixel_of(camera, (-0.9, 0, 2))
    assert diff[y - 6 : y + 7, x - 6 : x + 7].max() <= 1, "the surface in focus changed"
    x, y = pixel_of(camera, (2.5 - 1.2, 0, -12))  # the far sphere's left silhouette
    assert diff[y - 3 : y + 4, x - 3 : x + 4].max() > 20, "the far silhouette is not blurred"


# --- colour grading ----------------------------------------------------------------------------------------------
def test_color_grading_identity_keeps_and_a_swap_table_swaps(engine):
    plain = engine.render(build(CAMERA, shapes())).array.astype(int)
    same = engine.render(build(CAMERA, shapes(), effects=[om.gl.ColorGrading()])).array.astype(int)
    assert np.abs(plain - same).max() <= 2
    swap = om.gl.ColorGrading.identity(17)[..., ::-1]
    swapped = engine.render(build(CAMERA, shapes(), effects=[om.gl.ColorGrading(swap)])).array.astype(int)
    assert np.abs(swapped[..., :3] - plain[..., 2::-1]).max() <= 3


# --- user effects and errors ---------------------------------------------------------------------------------------
def test_custom_effect_with_uniforms(engine):
    grey = om.gl.CustomEffect("grey", """uniform float u_amount;
vec4 effect(vec2 uv) { vec4 c = texture(u_input, uv); return vec4(mix(c.rgb, vec3(luminance(c.rgb)), u_amount), c.a); }
""", uniforms={"u_amount": 1.0})  # fmt: skip
    out = engine.render(build(CAMERA, shapes(), effects=[grey])).array.astype(int)
    assert np.abs(out[..., 0] - out[..., 2]).max() <= 1 and np.abs(out[..., 0] - out[..., 1]).max() <= 1
    grey.uniforms = {"u_amount": 0.0}
    back = engine.render(build(CAMERA, shapes(), effects=[grey])).array.astype(int)
    assert np.abs(back - engine.render(build(CAMERA, shapes())).array.astype(int)).max() <= 2


def test_bad_glsl_names_the_effect_its_node_and_the_fix(engine):
    bad = om.gl.CustomEffect("broken", "vec4 effect(vec2 uv) { return undefined_thing; }")
    with pytest.raises(ValueError, match=r"CustomEffect 'broken' \(effect 0 of the post-processing chain at /scene\)"
                                         r".*fix its parameters or its GLSL.*failed to compile"):  # fmt: skip
        engine.render(build(CAMERA, shapes(), effects=[bad]))


@pytest.mark.parametrize("make, words", [
    (lambda: om.gl.SSAO(radius=-1), "SSAO: radius must be > 0"),
    (lambda: om.gl.ToneMap("filmic"), "ToneMap: operator must be one of"),
    (lambda: om.gl.Bloom(levels=20), "Bloom: levels must be <= 8"),
    (lambda: om.gl.DepthFog(start=5, end=1), "DepthFog: end must be > start"),
    (lambda: om.gl.ColorGrading(np.zeros((4, 4, 3))), "ColorGrading: table must have shape (N, N, N, 3)"),
    (lambda: om.gl.CustomEffect("x", "void main() {}"), "must be GLSL source text defining vec4 effect"),
    (lambda: om.gl.CustomEffect("x", "vec4 effect(vec2 uv) { return vec4(1); }", {"u_input": 1}), "set by the chain"),
    (lambda: om.gl.PostProcess([om.Sphere()]), "not a post-processing effect"),
])  # fmt: skip
def test_bad_parameters_are_refused_with_the_fix(make, words):
    with pytest.raises(ValueError, match=None) as info:
        make()
    assert words in str(info.value)


# --- pipelines, depth, other engines, scene files ----------------------------------------------------------------
def test_forward_and_deferred_agree_with_a_full_chain(engine, deferred):
    effects = [om.gl.SSAO(), om.gl.Bloom(threshold=0.8), om.gl.ToneMap("aces"), om.gl.FXAA()]
    a = engine.render(build(CAMERA, shapes(), effects=effects)).array.astype(int)
    b = deferred.render(build(CAMERA, shapes(), effects=effects)).array.astype(int)
    diff = np.abs(a - b).max(axis=2)
    assert diff.mean() < 1.0 and np.percentile(diff, 99) <= 8, (diff.mean(), np.percentile(diff, 99))


def test_overlay_text_is_drawn_over_the_effects(engine):
    label = om.Node("label", [om.Color(1, 1, 1), om.Text("post", position=(0, 1.5, 0), size=24)])
    dark = [om.gl.ToneMap(exposure=-12)]
    out = engine.render(build(CAMERA, [*shapes(), label], effects=dark)).array
    assert out[..., :3].max() > 200, "the 2D overlay went through the effects"


def test_offline_engines_and_exporters_ignore_the_chain_and_warn(tmp_path):
    from omnirender.povray.api import scene_sdl

    plain, _ = scene_sdl(build(CAMERA, shapes()), size=(64, 48))
    with pytest.warns(UserWarning, match=r"ignores the post-processing chain at /scene \(om.gl.SSAO"):
        chained, _ = scene_sdl(build(CAMERA, shapes(), effects=[om.gl.SSAO(), om.gl.ToneMap()]), size=(64, 48))
    assert chained == plain
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # analysis engines ignore it silently
        hits = om.pick(build(CAMERA, shapes(), effects=[om.gl.SSAO()]), pixel=(80, 60), size=SIZE)
    assert hits and hits[0].path.startswith("/scene")


@pytest.mark.parametrize("extension", [".glb", ".rib"])
def test_exporters_write_the_same_file_without_the_chain(tmp_path, extension):
    (tmp_path / "plain").mkdir()
    (tmp_path / "chain").mkdir()
    om.export(build(CAMERA, shapes()), tmp_path / "plain" / f"scene{extension}")
    with pytest.warns(UserWarning, match="ignores the post-processing chain"):
        om.export(
            build(CAMERA, shapes(), effects=[om.gl.Bloom(), om.gl.FXAA()]), tmp_path / "chain" / f"scene{extension}"
        )
    assert (tmp_path / "plain" / f"scene{extension}").read_bytes() == (
        tmp_path / "chain" / f"scene{extension}"
    ).read_bytes()


def test_scene_files_save_and_load_the_chain(tmp_path, engine):
    effects = [om.gl.SSAO(radius=0.4), om.gl.DepthFog(start=2, end=20, mode="exp", density=0.1),
               om.gl.ToneMap("hejl", exposure=0.5), om.gl.ColorGrading(om.gl.ColorGrading.identity(4) ** 1.2),
               om.gl.CustomEffect("grey", "vec4 effect(vec2 uv) { return texture(u_input, uv).ggga; }")]  # fmt: skip
    scene = build(CAMERA, shapes(), effects=effects)
    path = tmp_path / "post.json"
    om.save(scene, path)
    loaded = om.load(path)
    chain = next(c for c in loaded.components if isinstance(c, om.gl.PostProcess))
    assert [type(e) for e in chain.effects] == [type(e) for e in effects]
    assert chain.effects[1].parameters() == effects[1].parameters()
    assert np.allclose(chain.effects[3].table, effects[3].table)
    a = engine.render(scene).array
    b = engine.render(loaded).array
    assert np.abs(a.astype(int) - b.astype(int)).max() <= 1


# --- reference images -----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_reference_images(pipeline):
    """Every stage at once: SSAO and fog, a transparent pane composited after them, bloom, tone curve, FXAA."""
    from .test_references import compare

    e = om.gl.GLEngine(size=(96, 72), samples=0, pipeline=pipeline)
    glass = om.Material(diffuse=(0.2, 0.9, 0.4), opacity=0.5)
    pane = om.Node("pane", [glass, om.Box(size=(1.2, 1.2, 0.05), center=(0, 0.6, 1.5))])
    effects = [om.gl.SSAO(), om.gl.DepthFog(color=(0.2, 0.22, 0.26), start=4, end=16), om.gl.Bloom(threshold=0.7),
               om.gl.ToneMap("uncharted2", exposure=1.0), om.gl.Vignette(0.3), om.gl.FXAA()]  # fmt: skip
    try:
        compare(f"postfx_{pipeline}", e.render(build(CAMERA, [*shapes(), pane], effects=effects)))
    finally:
        e.release()


GREY = "vec4 effect(vec2 uv) { vec4 c = texture(u_input, uv); return vec4(vec3(luminance(c.rgb)), c.a); }"


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
def test_a_chain_lower_in_the_graph_post_processes_what_it_scopes(engine, deferred, pipeline):
    e = engine if pipeline == "forward" else deferred
    red = om.Material(diffuse=(1, 0.1, 0.1))
    scene = build(CAMERA, [
        om.Node("red", [om.Translation(-1, 0.5, 0), red, om.Sphere(radius=0.5)]),
        om.Node("grey", [om.gl.PostProcess([om.gl.CustomEffect("grey", GREY)]), om.Translation(1, 0.5, 0), red,
                         om.Sphere(radius=0.5)]),
    ])  # fmt: skip
    out = e.render(scene).array.astype(int)
    x, y = pixel_of(CAMERA, (-1, 0.5, 0.45))
    assert out[y, x, 0] > out[y, x, 2] + 80, "the sphere outside the chain keeps its colour"
    x, y = pixel_of(CAMERA, (1, 0.5, 0.45))
    assert abs(out[y, x, 0] - out[y, x, 2]) <= 2 and out[y, x, 0] > 40, "the sphere inside the chain is grey"


def test_at_the_top_the_deferred_pipeline_shades_the_chains_scene(deferred):
    deferred.render(build(CAMERA, shapes(), effects=[om.gl.ToneMap()]))
    drawn = {p["name"]: p["draw_calls"] for p in deferred.stats["passes"]}
    assert drawn["scene/geometry"] >= 1 and drawn["scene/shading"] == 1
    assert drawn.get("scene/opaque", 0) == 0  # nothing left for the forward passes


def test_depth_effects_read_the_depth_of_the_colours_they_change(engine):
    """A depth effect that paints near pixels red and far ones green runs before a near transparent pane is
    composited, so behind the pane it sees (and paints) the far wall; the pane (two faces) then tints that green."""
    camera = om.Camera.look_at((0, 0, 6), (0, 0, 0), fov=40)
    wall = om.Node("wall", [om.Material(diffuse=(0.5, 0.5, 0.5)), om.Box(size=(20, 20, 0.1), center=(0, 0, -6))])
    pane = om.Node("pane", [om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), emission=(0, 0, 1), opacity=0.5),
                            om.Box(size=(2, 2, 0.05), center=(0, 0, 2))])  # fmt: skip
    marker = om.gl.CustomEffect("near", """vec4 effect(vec2 uv) {
    return -view_position(uv).z < 8.0 ? vec4(1.0, 0.0, 0.0, 1.0) : vec4(0.0, 1.0, 0.0, 1.0);
}""", reads_depth=True)  # fmt: skip
    out = engine.render(build(camera, [wall, pane], effects=[marker])).array.astype(int)
    x, y = pixel_of(camera, (0, 0, 2))
    r, g, b = out[y, x, :3]
    assert g > 100 and b > 150 and r < 10, f"behind the pane the depth effect saw the pane's depth: {out[y, x]}"
    x, y = pixel_of(camera, (3, 2, -6))
    assert tuple(out[y, x, :3]) == (0, 255, 0)  # the wall alone


# --- orthographic cameras ------------------------------------------------------------------------------------------
def test_ssao_leaves_tilted_flat_surfaces_under_an_orthographic_camera(engine):
    """Normals rebuilt from depth face the eye along the view axis under a parallel projection (not along the
    position vector): two flat slabs turned 60 degrees away from the axis, far off centre, keep their light."""
    camera = om.Camera.orthographic((0, 0, 10), (0, 0, 0), height=12)
    wall = om.Material(diffuse=(0.8, 0.8, 0.8))
    slabs = [om.Node(f"slab{s}", [om.Translation(6 * s, 0, 0), om.Rotation(60 * s, (0, 1, 0)), wall,
                                  om.Box(size=(3, 3, 0.1))]) for s in (-1, 1)]  # fmt: skip
    lights = [om.AmbientLight(intensity=1.0)]
    plain = linear(engine.render(build(camera, slabs, lights=lights)))
    ao = linear(engine.render(build(camera, slabs, effects=[om.gl.SSAO(radius=0.5)], lights=lights)))
    ratio = (ao.mean(axis=2) + 1e-4) / (plain.mean(axis=2) + 1e-4)
    for s in (-1, 1):
        x, y = pixel_of(camera, (6 * s, 0, 0))
        kept = ratio[y - 2 : y + 3, x - 2 : x + 3].mean()
        assert kept > 0.85, f"SSAO darkened a flat slab seen orthographically to {kept:.2f} of its light"


def test_no_light_shafts_from_a_light_behind_an_orthographic_camera(engine):
    """A parallel projection's w is 1 behind the eye as well: the light's eye-space z decides it is not seen."""
    camera = om.Camera.orthographic((0, 0, 6), (0, 0, 0), height=6)
    ball = om.Node("ball", [om.Material(diffuse=(0.4, 0.4, 0.4)), om.Sphere(radius=0.5, center=(1.5, 0, 0))])
    shafts = [om.gl.LightShafts(intensity=1.0)]
    for z, seen in ((8.0, False), (-4.0, True)):  # behind the camera, then in front of it
        light = om.PointLight(position=(0, 0.5, z), color=(1, 0.9, 0.7))
        plain = linear(engine.render(build(camera, [ball], lights=[light], background=(0, 0, 0))))
        rays = linear(engine.render(build(camera, [ball], effects=shafts, lights=[light], background=(0, 0, 0))))
        gain = np.abs(rays - plain).max()
        assert (gain > 0.05) if seen else (gain < 5e-3), f"light at z={z}: shafts add up to {gain:.4f}"
