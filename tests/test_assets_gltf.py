"""Real assets look right in every engine (issue 14): glTF files built feature by feature, each rendered by GL,
POV-Ray and Mitsuba with a property check (colour at known pixels, cut-outs, brightness order).

The files come from ``tests/gltf_files.py`` (pygltflib), so nothing is downloaded.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from engines import require

import omnirender as om
from omnirender.formats.gltf import GLTFImportError, light_from_gltf

pytest.importorskip("pygltflib")
from gltf_files import halves, quad_file  # noqa: E402

ENGINES = ("gl", "povray", "mitsuba")
SIZE = (48, 48)
LEFT, RIGHT, MIDDLE = (15, 24), (32, 24), (24, 24)
SUN = {"type": "directional", "intensity": math.pi}  # glTF lux: E = pi shows the base colour fully lit (GL: 1)
#: a light travelling towards -x, nearly along the quad: it comes from +x (u grows to the right)
GRAZING = om.DirectionalLight(direction=(-math.sin(math.radians(75)), 0.0, -math.cos(math.radians(75))))


def _render(scene: om.Node, name: str) -> om.Image:
    require(name)
    return om.render(scene, engine=name, size=SIZE, **({"spp": 16} if name == "mitsuba" else {}))


def _lum(img: om.Image, xy: tuple[int, int], r: int = 2) -> float:
    x, y = xy
    return float(img.rgb[y - r : y + r + 1, x - r : x + r + 1].astype(np.float64).mean())


def _rgb(img: om.Image, xy: tuple[int, int], r: int = 2) -> np.ndarray:
    x, y = xy
    return img.rgb[y - r : y + r + 1, x - r : x + r + 1].reshape(-1, 3).astype(np.float64).mean(axis=0)


engines = pytest.mark.parametrize("name", [pytest.param(n, marks=getattr(pytest.mark, n)) for n in ENGINES])


@engines
def test_base_colour_texture_and_factor(tmp_path, name):
    path = tmp_path / "base.glb"
    material = {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
                                         "baseColorFactor": [1.0, 1.0, 1.0, 1.0]}}  # fmt: skip
    quad_file(path, material=material, images=[halves((255, 0, 0, 255), (0, 0, 255, 255))], light=SUN)
    img = _render(om.load_gltf(path), name)
    left, right = _rgb(img, LEFT), _rgb(img, RIGHT)
    assert left[0] > 200 > 80 > left[2] and right[2] > 200 > 80 > right[0], (left, right)


@engines
def test_metallic_roughness_texture_makes_the_metal_half_dark_under_a_diffuse_view(tmp_path, name):
    path = tmp_path / "mr.glb"
    # blue = metallic, green = roughness: left dielectric and rough, right metal and rough
    mr = halves((0, 255, 0, 255), (0, 255, 255, 255))
    material = {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 1.0,
                                         "roughnessFactor": 1.0, "metallicRoughnessTexture": {"index": 0}}}  # fmt: skip
    light = {"type": "directional", "intensity": math.pi}
    quad_file(path, material=material, images=[mr], light=light)
    img = _render(om.load_gltf(path), name)
    assert _lum(img, LEFT) > _lum(img, RIGHT) + 25, (_lum(img, LEFT), _lum(img, RIGHT))


def _bumps(n: int = 64, waves: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Heights varying along u (a sine) and their slope dh/du per column."""
    u = (np.arange(n) + 0.5) / n
    h = 0.5 + 0.5 * np.sin(2 * np.pi * waves * u)
    return np.tile(h, (n, 1)), np.cos(2 * np.pi * waves * u)


def _slope_correlation(img: om.Image, slope: np.ndarray) -> float:
    """Correlation of the quad's brightness per column with -slope (a light from +u lights descending slopes)."""
    cols = np.arange(12, 36)
    x = ((cols + 0.5) / 24 - 1) * math.tan(math.radians(22.5)) * 3  # the quad's x under each column
    u = (x + 1) / 2
    brightness = img.rgb[20:28, cols].astype(np.float64).mean(axis=(0, 2))
    assert np.ptp(brightness) > 15, f"{img.engine}: the bumps barely show ({np.ptp(brightness):.1f} levels)"
    expected = -np.interp(u, (np.arange(len(slope)) + 0.5) / len(slope), slope)
    return float(np.corrcoef(brightness, expected)[0, 1])


@engines
def test_normal_texture_turns_the_surface_towards_the_light(tmp_path, name):
    from omnirender.attributes.texturing import height_to_normal_map

    heights, slope = _bumps()
    normals = height_to_normal_map(heights, 0.06)
    path = tmp_path / "normal.glb"
    material = {"pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 1.0},
                "normalTexture": {"index": 0, "scale": 1.0}}  # fmt: skip
    quad_file(path, material=material, images=[normals])
    scene = om.load_gltf(path)
    scene.add(GRAZING)  # from +x (u grows to the right)
    img = _render(scene, name)
    assert _slope_correlation(img, slope) > 0.6


@engines
def test_bump_map_attribute_shades_like_its_height_texture(name):
    heights, slope = _bumps()
    quad = om.TriangleSet([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 1, 2], [0, 2, 3]],
                          texcoords=[[0, 0], [1, 0], [1, 1], [0, 1]])  # fmt: skip
    gray = np.repeat(np.round(heights * 255).astype(np.uint8)[:, :, None], 3, axis=2)
    scene = om.Node("s", [om.Camera.look_at(eye=(0, 0, 3), fov=45)])
    scene.add(GRAZING)
    scene.add(om.Node("bumpy", [om.Material(diffuse=(0.8, 0.8, 0.8)), om.BumpMap(om.Texture(gray), 0.06), quad]))
    img = _render(scene, name)
    assert _slope_correlation(img, slope) > 0.6


@engines
def test_emissive_texture_glows_where_it_is_bright(tmp_path, name):
    path = tmp_path / "emissive.glb"
    material = {"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0},
                "emissiveFactor": [1.0, 0.5, 0.2], "emissiveTexture": {"index": 0},
                "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1.0}}}  # fmt: skip
    quad_file(path, material=material, images=[halves((255, 255, 255, 255), (0, 0, 0, 255))])
    img = _render(om.load_gltf(path), name)
    left, right = _rgb(img, LEFT), _rgb(img, RIGHT)
    # dark on the right: no emission there (POV-Ray's PBR approximation adds a faint highlight of the headlight)
    assert left[0] > 200 and left[0] > left[1] > left[2] and right.max() < 70, (left, right)


@engines
def test_alpha_mask_cuts_out_below_the_cutoff(tmp_path, name):
    path = tmp_path / "mask.glb"
    material = {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0},
                "alphaMode": "MASK", "alphaCutoff": 0.5}  # fmt: skip
    # alpha 0.3 on the left (cut out), 0.7 on the right (kept, opaque)
    quad_file(path, material=material, images=[halves((255, 255, 255, 77), (255, 255, 255, 179))], light=SUN)
    img = _render(om.load_gltf(path), name)
    # nothing drawn on the left: the mask is the coverage by shapes in every engine
    assert not img.mask[LEFT[1], LEFT[0]] and img.mask[RIGHT[1], RIGHT[0]]
    assert _lum(img, RIGHT) > 200  # the kept part is opaque: no blending with the background


@engines
def test_alpha_opaque_ignores_alpha_and_blend_sees_through(tmp_path, name):
    image = halves((255, 255, 255, 60), (255, 255, 255, 60))
    base = {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}
    quad_file(tmp_path / "opaque.glb", material={**base, "alphaMode": "OPAQUE"}, images=[image], light=SUN)
    quad_file(tmp_path / "blend.glb", material={**base, "alphaMode": "BLEND"}, images=[image], light=SUN)
    opaque = _render(om.load_gltf(tmp_path / "opaque.glb"), name)
    blend = _render(om.load_gltf(tmp_path / "blend.glb"), name)
    assert opaque.array[MIDDLE[1], MIDDLE[0], 3] == 255 and _lum(opaque, MIDDLE) > 200
    assert blend.array[MIDDLE[1], MIDDLE[0], 3] < 140 or _lum(blend, MIDDLE) < 140


@engines
def test_vertex_colours_multiply_the_base_colour(tmp_path, name):
    colors = np.array([[1, 0, 0, 1], [1, 0, 0, 1], [0, 1, 0, 1], [0, 1, 0, 1]], np.float32)  # bottom red, top green
    factor = [0.5, 0.5, 0.5, 1.0]  # linear: half as bright
    material = {"pbrMetallicRoughness": {"baseColorFactor": factor, "metallicFactor": 0.0}}
    quad_file(tmp_path / "vc.glb", material=material, colors=colors, light=SUN)
    img = _render(om.load_gltf(tmp_path / "vc.glb"), name)
    top, bottom = _rgb(img, (24, 10)), _rgb(img, (24, 38))
    assert top[1] > 120 > top[0] and bottom[0] > 120 > bottom[1], (top, bottom)
    assert max(top[1], bottom[0]) < 225  # multiplied by the factor, not replacing it


@engines
def test_texture_transform_tiles_the_texture(tmp_path, name):
    material = {"pbrMetallicRoughness": {"metallicFactor": 0.0, "baseColorTexture": {
        "index": 0, "extensions": {"KHR_texture_transform": {"scale": [2.0, 1.0]}}}}}  # fmt: skip
    quad_file(tmp_path / "tt.glb", material=material, images=[halves((255, 0, 0, 255), (0, 0, 255, 255))], light=SUN)
    img = _render(om.load_gltf(tmp_path / "tt.glb"), name)
    row = img.rgb[24, 8:40].astype(int)
    red = row[:, 0] > row[:, 2]
    assert int(np.count_nonzero(red[1:] != red[:-1])) == 3  # red, blue, red, blue: tiled twice along u


def test_sparse_quantized_and_draco_geometry_load_exactly(tmp_path):
    quad_file(tmp_path / "sparse.glb", sparse_move=(2, (1.0, 2.0, 0.0)))
    lo, hi = om.bounds(om.load_gltf(tmp_path / "sparse.glb"))
    assert np.allclose(hi, (1, 2, 0)) and np.allclose(lo, (-1, -1, 0))
    quad_file(tmp_path / "quantized.glb", quantized=True, node_scale=2.0)
    lo, hi = om.bounds(om.load_gltf(tmp_path / "quantized.glb"))
    assert np.allclose(lo, (-2, -2, 0), atol=1e-3) and np.allclose(hi, (2, 2, 0), atol=1e-3)
    pytest.importorskip("DracoPy")
    quad_file(tmp_path / "draco.glb", draco=True)
    scene = om.load_gltf(tmp_path / "draco.glb")
    lo, hi = om.bounds(scene)
    assert np.allclose(lo, (-1, -1, 0), atol=1e-3) and np.allclose(hi, (1, 1, 0), atol=1e-3)
    (ts,) = [c for n in scene.walk() for c in n.components if isinstance(c, om.TriangleSet)]
    assert ts.triangle_count == 2 and ts.texcoord_array() is not None
    # MeshFile reads glTF with the same importer
    assert np.allclose(om.bounds(om.Node("m", [om.MeshFile(tmp_path / "draco.glb")]))[1], (1, 1, 0), atol=1e-3)


@pytest.mark.gl
def test_draco_quad_renders_in_gl(tmp_path):
    require("gl")
    pytest.importorskip("DracoPy")
    quad_file(tmp_path / "draco.glb", draco=True, light=SUN)
    img = _render(om.load_gltf(tmp_path / "draco.glb"), "gl")
    assert img.mask.mean() > 0.4


def test_cameras_and_lights_come_from_the_file_with_physical_brightness(tmp_path):
    point = {"type": "point", "intensity": 2.0 * math.pi, "color": [1.0, 1.0, 1.0]}
    quad_file(tmp_path / "lit.glb", light=point)
    scene = om.load_gltf(tmp_path / "lit.glb")
    assert scene["/model/quad"].path == "/model/quad"  # the file's node names make the paths
    declared = scene.declarations()
    camera, world = declared.camera
    assert np.allclose(world[:3, 3], (0, 0, 3)) and camera.fov == pytest.approx(45)
    ((light, m),) = declared.lights
    assert isinstance(light, om.PointLight) and np.allclose(m[:3, 3], (0, 0, 2))
    # 2 pi cd at 2 m: E = I / d^2 = pi / 2; a white Lambertian surface shows E / pi = 0.5 (linear): GL's
    # attenuation 1/d^2 with intensity I / pi gives the same at every distance
    assert light.quadratic == 1.0 and light.constant == 0.0
    assert light.intensity * light.attenuation(2.0) == pytest.approx(0.5)
    spot = light_from_gltf({"type": "spot", "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.5}})
    assert spot.cutoff == pytest.approx(math.degrees(0.5)) and math.cos(0.3) ** spot.exponent == pytest.approx(0.5)


def test_required_extensions_are_refused_by_name_and_optional_ones_warn(tmp_path):
    quad_file(tmp_path / "req.glb", extensions_required=("EXT_meshopt_compression",))
    with pytest.raises(GLTFImportError, match="EXT_meshopt_compression"):
        om.load_gltf(tmp_path / "req.glb")
    quad_file(tmp_path / "opt.glb", extensions_used=("KHR_materials_sheen",))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        om.load_gltf(tmp_path / "opt.glb")
    assert any("KHR_materials_sheen" in str(w.message) for w in caught)


@pytest.mark.gl
def test_second_uv_set_feeds_the_occlusion_texture(tmp_path):
    require("gl")
    uv1 = np.array([[0, 1], [0, 1], [0, 0], [0, 0]], np.float32)  # set 1 (glTF's v grows downwards): v only
    # occlusion texture: top row dark, bottom row bright; through set 1 the top of the quad is occluded
    occ = np.zeros((8, 8, 4), np.uint8)
    occ[:4] = (20, 20, 20, 255)
    occ[4:] = (255, 255, 255, 255)
    material = {"pbrMetallicRoughness": {"metallicFactor": 0.0, "baseColorFactor": [1, 1, 1, 1]},
                "occlusionTexture": {"index": 0, "texCoord": 1, "strength": 1.0}}  # fmt: skip
    quad_file(tmp_path / "occ.glb", material=material, images=[occ], uv1=uv1)
    scene = om.load_gltf(tmp_path / "occ.glb")
    scene.add(om.AmbientLight(intensity=0.5))
    img = _render(scene, "gl")
    assert _lum(img, (24, 10)) + 40 < _lum(img, (24, 38))  # only ambient light: occlusion shows


@pytest.mark.gl
def test_single_sided_materials_cull_back_faces_in_gl(tmp_path):
    require("gl")
    material = {"pbrMetallicRoughness": {"metallicFactor": 0.0}, "doubleSided": False}
    quad_file(tmp_path / "single.glb", material=material, light=SUN)
    scene = om.load_gltf(tmp_path / "single.glb")
    assert _render(scene, "gl").mask.mean() > 0.4
    scene.child("quad").insert(0, om.Rotation(180, (0, 1, 0)))  # the camera now sees the back
    assert _render(scene, "gl").mask.mean() == 0.0
