"""glTF export of the one appearance model (issue 14): every slot, alpha modes, unit normals, physical lights,
the camera's group mask; the Khronos validator (npm ``gltf-validator``) finds no error; files read back."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import omnirender as om
from omnirender.demo import demo_scene


def _rgba(value, size=8):
    img = np.zeros((size, size, 4), np.uint8)
    img[...] = value
    return img


def slots_scene() -> om.Node:
    """A camera, every kind of light, and surfaces using every material slot and alpha mode."""
    scene = om.Node("slots", [om.Camera.look_at(eye=(0, 2, 6), center=(0, 0, 0), fov=40)])
    scene.add(om.PointLight(position=(3, 4, 3), intensity=0.8))
    scene.add(
        om.SpotLight(position=(0, 5, 0), direction=(0, -1, 0), cutoff=30, exponent=4, constant=0.0, quadratic=0.1)
    )
    scene.add(om.DirectionalLight(direction=(0, -1, -1), intensity=0.5))
    checker = (np.indices((8, 8)).sum(axis=0) % 2 * 255).astype(np.uint8)
    textured = om.Texture(np.stack([checker] * 3 + [np.full_like(checker, 255)], -1), offset=(0.1, 0.2), scale=(2, 3),
                          rotation=30)  # fmt: skip
    pbr = om.PBRMaterial(
        base_color=(0.9, 0.8, 0.7), metallic=0.5, roughness=0.4, emission=(0.2, 0.1, 0.0),
        base_color_texture=textured, metallic_roughness_texture=om.Texture(_rgba((0, 128, 255, 255))),
        normal_texture=om.Texture(_rgba((128, 128, 255, 255)), uv_set=1), normal_scale=0.5,
        occlusion_texture=om.Texture(_rgba((200, 200, 200, 255))), occlusion_strength=0.7,
        emissive_texture=om.Texture(_rgba((255, 255, 255, 255))), emissive_strength=3.0,
        alpha_mode="mask", alpha_cutoff=0.4, double_sided=False,
    )  # fmt: skip
    quad = om.TriangleSet(
        [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 1, 2], [0, 2, 3]],
        normals=[[0, 0, 3], [0, 0, 2], [0, 0, 1], [0, 0.001, 0.5]],  # not unit: the exporter normalises
        texcoords=[[0, 0], [1, 0], [1, 1], [0, 1]], texcoords1=[[0, 0], [2, 0], [2, 2], [0, 2]],
    )  # fmt: skip
    scene.add(om.Node("pbr", [pbr, quad]))
    scene.add(om.Node("blend", [om.Translation(2.5, 0, 0), om.Material(diffuse=(0.2, 0.6, 0.9), opacity=0.5),
                                om.Sphere(radius=0.5)]))  # fmt: skip
    colours = om.TriangleSet([[0, 0, 0], [1, 0, 0], [0, 1, 0]], colors=[[1, 0, 0], [0, 1, 0], [0, 0, 1]])
    scene.add(om.Node("vertex", [om.Translation(-2.5, 0, 0), om.Material(diffuse=(0.3, 0.3, 0.3)), colours]))
    bumpy = om.Node("bump", [om.Translation(0, -2, 0), om.BumpMap(om.Texture(checker), 0.02)])
    bumpy.add(om.MultiTexture([om.TextureLayer(textured, "multiply", 0.5)]))
    bumpy.add(om.Rectangle(size=(1, 1)))
    scene.add(bumpy)
    return scene


def _material(doc, node_name):
    node = next(n for n in doc["nodes"] if n.get("name") == node_name)
    child = doc["nodes"][node["children"][0]] if "mesh" not in node else node
    return doc["materials"][doc["meshes"][child["mesh"]]["primitives"][0]["material"]]


def _json(glb: bytes) -> dict:
    length = int.from_bytes(glb[12:16], "little")
    return json.loads(glb[20 : 20 + length])


def test_every_slot_alpha_mode_and_light_is_written():
    from omnirender.attributes.photometry import srgb_to_linear
    from omnirender.formats.gltf import writer as gltf

    glb, _ = gltf.build(slots_scene())
    doc = _json(glb)
    m = _material(doc, "pbr")
    block = m["pbrMetallicRoughness"]
    assert {"baseColorTexture", "metallicRoughnessTexture"} <= set(block)
    assert m["normalTexture"]["scale"] == 0.5 and m["normalTexture"]["texCoord"] == 1
    assert m["occlusionTexture"]["strength"] == pytest.approx(0.7)
    assert m["alphaMode"] == "MASK" and m["alphaCutoff"] == pytest.approx(0.4) and m["doubleSided"] is False
    # the emission times its strength (linear); above 1 it would go to KHR_materials_emissive_strength
    assert m["emissiveFactor"] == pytest.approx(list(srgb_to_linear((0.2, 0.1, 0.0)) * 3.0))
    transform = block["baseColorTexture"]["extensions"]["KHR_texture_transform"]
    assert transform["scale"] == [2.0, 3.0] and transform["rotation"] == pytest.approx(math.radians(30))
    assert _material(doc, "blend")["alphaMode"] == "BLEND"
    assert "normalTexture" in _material(doc, "bump")  # the bump map's derived normal map
    # vertex colours replace a Phong colour: glTF multiplies, so the factor is white
    assert _material(doc, "vertex")["pbrMetallicRoughness"]["baseColorFactor"][:3] == [1.0, 1.0, 1.0]
    lights = {light["type"]: light for light in doc["extensions"]["KHR_lights_punctual"]["lights"]}
    assert lights["directional"]["intensity"] == pytest.approx(0.5 * math.pi)  # lux: E = pi c
    # candela for constant attenuation: matched at the camera's centre of interest (distance 5.83)
    assert lights["point"]["intensity"] == pytest.approx(0.8 * math.pi * (3**2 + 4**2 + 3**2))
    assert lights["spot"]["intensity"] == pytest.approx(math.pi / 0.1)  # purely quadratic: pi / Q everywhere


def test_exported_slots_read_back():
    from omnirender.formats.gltf import writer as gltf

    scene = slots_scene()
    glb = gltf.to_bytes(scene)
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "slots.glb"
        path.write_bytes(glb)
        again = om.load_gltf(path)
    pbr = [c for n in again.walk() for c in n.components if isinstance(c, om.PBRMaterial) and c.alpha_mode == "mask"]
    (m,) = pbr
    assert m.normal_texture.uv_set == 1 and m.normal_scale == 0.5 and m.occlusion_strength == pytest.approx(0.7)
    assert m.base_color_texture.scale == (2.0, 3.0) and m.base_color_texture.offset == pytest.approx((0.1, 0.2))
    assert m.base_color_texture.rotation == pytest.approx(30)
    assert not m.double_sided and m.alpha_cutoff == pytest.approx(0.4)
    normals = [c for n in again.walk() for c in n.components if isinstance(c, om.TriangleSet)][0].normal_array()
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)


def test_camera_group_mask_hides_shapes_from_glb_and_rib(tmp_path):
    scene = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5), mask="!debug")])
    scene.add(om.Node("visible", [om.Sphere()]))
    scene.add(om.Node("hidden", [om.Sphere(center=(2, 0, 0))], groups={"debug"}))
    om.export(scene, tmp_path / "s.glb")
    names = [n.get("name") for n in _json((tmp_path / "s.glb").read_bytes())["nodes"]]
    assert "visible" in names and "hidden" not in names
    om.export(scene, tmp_path / "s.rib")
    text = (tmp_path / "s.rib").read_text()
    assert "visible" in text and "hidden" not in text


@pytest.mark.gltf_validator
def test_the_khronos_validator_finds_no_error(tmp_path):
    from gltf_files import validator_reports

    files = []
    for name, scene in (("slots", slots_scene()), ("demo", demo_scene())):
        path = tmp_path / f"{name}.glb"
        om.export(scene, path)
        files.append(path)
    for report in validator_reports(files):
        errors = [m for m in report["issues"]["messages"] if m["severity"] == 0]
        assert report["issues"]["numErrors"] == 0, (report["file"], errors[:5])
