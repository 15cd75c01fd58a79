"""glTF 2.0 binary export: structure of the GLB, and trimesh reading back what was written."""

from __future__ import annotations

import json
import math
import struct

import numpy as np
import pytest

import omnirender as om
from omnirender.formats.gltf import writer as gltf

trimesh = pytest.importorskip("trimesh")

_SIZES = {5126: 4, 5125: 4, 5123: 2, 5121: 1}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def _scene() -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(4, 3, 6), center=(0, 0, 0), fov=35))
    scene.add(om.PointLight(position=(5, 5, 5), intensity=2.0))
    scene.add(om.DirectionalLight(direction=(0, -1, -1)))
    scene.add(om.SpotLight(position=(0, 4, 0), direction=(0, -1, 0), cutoff=25))
    scene.add(om.AmbientLight(intensity=0.3))
    floor = scene.add(om.Node("floor"))
    floor.add(om.Material(diffuse=(0.8, 0.8, 0.8)))
    floor.add(om.Box(size=(10, 0.1, 10)))
    body = scene.add(om.Node("body"))
    body.add(om.Translation(0, 1, 0))
    body.add(om.PBRMaterial(base_color=(1, 0.4, 0.6), metallic=0.3, roughness=0.4, opacity=0.5))
    body.add(om.Rotation(90, (1, 0, 0)))
    body.add(om.Torus(major_radius=1, minor_radius=0.3))
    arm = body.add(om.Node("arm"))
    arm.add(om.Translation(3, 0, 0))
    image = np.zeros((8, 8, 3), np.uint8)
    image[:4] = (255, 0, 0)
    arm.add(om.Texture(image))
    arm.add(
        om.TriangleSet(
            vertices=[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)],
            indices=[(0, 1, 2), (0, 2, 3)],
            texcoords=[(0, 0), (1, 0), (1, 1), (0, 1)],
            colors=[(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)],
        )
    )
    return scene


def _parse(data: bytes) -> tuple[dict, bytes]:
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67 and version == 2 and length == len(data)
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert jtype == 0x4E4F534A and jlen % 4 == 0
    doc = json.loads(data[20 : 20 + jlen])
    rest = data[20 + jlen :]
    if not rest:
        return doc, b""
    blen, btype = struct.unpack_from("<II", rest, 0)
    assert btype == 0x004E4942 and blen % 4 == 0 and len(rest) == 8 + blen
    return doc, rest[8:]


def _check_structure(doc: dict, binary: bytes) -> None:
    """The structural rules of the glTF 2.0 specification that a writer can get wrong."""
    assert doc["asset"]["version"] == "2.0"
    if "buffers" in doc:
        assert doc["buffers"][0]["byteLength"] == len(binary)
    for view in doc.get("bufferViews", []):
        assert view["byteOffset"] % 4 == 0
        assert view["byteOffset"] + view["byteLength"] <= len(binary)
    for acc in doc.get("accessors", []):
        view = doc["bufferViews"][acc["bufferView"]]
        need = acc["count"] * _SIZES[acc["componentType"]] * _WIDTH[acc["type"]]
        assert need <= view["byteLength"] - acc.get("byteOffset", 0)
    nodes = doc.get("nodes", [])
    children = [c for n in nodes for c in n.get("children", [])]
    assert len(children) == len(set(children)), "a node has two parents"
    roots = doc["scenes"][doc["scene"]]["nodes"]
    assert not set(roots) & set(children)
    assert set(roots) | set(children) == set(range(len(nodes))), "every node is reachable exactly once"
    for n in nodes:
        if "matrix" in n:
            assert len(n["matrix"]) == 16 and n["matrix"][3] == 0 and n["matrix"][15] == 1
        if "mesh" in n:
            assert 0 <= n["mesh"] < len(doc["meshes"])
    for mesh in doc.get("meshes", []):
        for prim in mesh["primitives"]:
            count = doc["accessors"][prim["attributes"]["POSITION"]]["count"]
            for acc in prim["attributes"].values():
                assert doc["accessors"][acc]["count"] == count
            if "indices" in prim:
                acc = doc["accessors"][prim["indices"]]
                view = doc["bufferViews"][acc["bufferView"]]
                idx = np.frombuffer(binary, np.uint32, acc["count"], view["byteOffset"])
                assert idx.max() < count
                if prim.get("mode", 4) == 4:
                    assert acc["count"] % 3 == 0
            assert 0 <= prim["material"] < len(doc["materials"])
    for tex in doc.get("textures", []):
        assert 0 <= tex["source"] < len(doc["images"]) and 0 <= tex["sampler"] < len(doc["samplers"])


def _triangles_and_bounds(scene: om.Node) -> tuple[int, np.ndarray]:
    """Independent reference: world-space triangles from the GL-free simplification of the graph."""
    engine = gltf.GLTFEngine()
    found: list[np.ndarray] = []

    class Collect(om.ShapePainter):
        __slots__ = ()
        service = gltf.GLTFEngine.service
        target = om.TriangleSet

        def exec(self, shape, engine):
            v = shape.vertex_array().astype(np.float64)
            m = engine.model_matrix()
            found.append((v @ m[:3, :3].T + m[:3, 3])[shape.index_array().reshape(-1)])

    engine.install(Collect())
    engine.run(scene)
    points = np.concatenate(found)
    return len(points) // 3, np.array([points.min(axis=0), points.max(axis=0)])


def test_glb_structure_and_trimesh_round_trip(tmp_path):
    scene = _scene()
    path = om.export(scene, tmp_path / "scene.glb")
    data = path.read_bytes()
    doc, binary = _parse(data)
    _check_structure(doc, binary)

    count, bounds = _triangles_and_bounds(scene)
    loaded = trimesh.load(path, force="scene")
    assert sum(len(g.faces) for g in loaded.dump()) == count
    np.testing.assert_allclose(loaded.bounds, bounds, atol=1e-5)

    names = [n["name"] for n in doc["nodes"]]
    for name in ("scene", "floor", "body", "arm", "camera"):
        assert name in names
    arm = doc["nodes"][names.index("arm")]
    # arm's transform relative to body: body's rotation about x, then nothing else (arm's own
    # translation applies to its contents, i.e. its mesh node)
    m = np.array(arm["matrix"]).reshape(4, 4).T
    np.testing.assert_allclose(m[:3, 3], (0, 1, 0), atol=1e-12)
    np.testing.assert_allclose(m[:3, :3], om.Rotation(90, (1, 0, 0)).matrix[:3, :3], atol=1e-12)


def test_materials_textures_camera_and_lights(tmp_path):
    doc, _ = _parse(gltf.to_bytes(_scene(), size=(400, 200)))
    mats = {m["name"]: m for m in doc["materials"] if "baseColorTexture" not in m["pbrMetallicRoughness"]}
    pbr = mats["PBRMaterial"]["pbrMetallicRoughness"]
    assert pbr["metallicFactor"] == pytest.approx(0.3) and pbr["roughnessFactor"] == pytest.approx(0.4)
    assert pbr["baseColorFactor"][0] == pytest.approx(1.0) and pbr["baseColorFactor"][3] == pytest.approx(0.5)
    assert pbr["baseColorFactor"][1] == pytest.approx(((0.4 + 0.055) / 1.055) ** 2.4)  # linear
    assert mats["PBRMaterial"]["alphaMode"] == "BLEND"
    textured = [m for m in doc["materials"] if "baseColorTexture" in m["pbrMetallicRoughness"]]
    assert len(textured) == 1 and doc["images"][0]["mimeType"] == "image/png"

    cam = doc["cameras"][0]["perspective"]
    assert cam["yfov"] == pytest.approx(np.radians(35)) and cam["aspectRatio"] == pytest.approx(2.0)
    cam_node = next(n for n in doc["nodes"] if n.get("camera") == 0)
    m = np.array(cam_node["matrix"]).reshape(4, 4).T
    np.testing.assert_allclose(m[:3, 3], (4, 3, 6))
    forward = -m[:3, 2]
    np.testing.assert_allclose(forward, -np.array([4, 3, 6]) / np.linalg.norm([4, 3, 6]), atol=1e-12)

    assert "KHR_lights_punctual" in doc["extensionsUsed"]
    lights = doc["extensions"]["KHR_lights_punctual"]["lights"]
    assert sorted(li["type"] for li in lights) == ["directional", "point", "spot"]
    spot = next(li for li in lights if li["type"] == "spot")
    assert spot["spot"]["outerConeAngle"] == pytest.approx(np.radians(25))
    sun_index = next(i for i, li in enumerate(lights) if li["type"] == "directional")
    sun = next(
        n for n in doc["nodes"] if n.get("extensions", {}).get("KHR_lights_punctual", {}).get("light") == sun_index
    )
    d = -np.array(sun["matrix"]).reshape(4, 4).T[:3, 2]
    np.testing.assert_allclose(d, np.array([0, -1, -1]) / np.sqrt(2), atol=1e-12)
    assert doc["extras"]["ambient_light"] == pytest.approx([0.3, 0.3, 0.3])


def test_texcoords_are_flipped_to_gltf_convention_and_colours_linear():
    scene = om.Node(
        "s",
        [
            om.TriangleSet(
                vertices=[(0, 0, 0), (1, 0, 0), (0, 1, 0)],
                texcoords=[(0, 0), (1, 0), (0, 0.25)],
                colors=[(0.5, 0.5, 0.5)] * 3,
            )
        ],
    )
    doc, binary = _parse(gltf.to_bytes(scene))
    prim = doc["meshes"][0]["primitives"][0]

    def read(name):
        acc = doc["accessors"][prim["attributes"][name]]
        view = doc["bufferViews"][acc["bufferView"]]
        return np.frombuffer(binary, np.float32, acc["count"] * _WIDTH[acc["type"]], view["byteOffset"]).reshape(
            acc["count"], -1
        )

    np.testing.assert_allclose(read("TEXCOORD_0")[:, 1], [1.0, 1.0, 0.75])
    np.testing.assert_allclose(read("COLOR_0")[:, 0], 0.21404, atol=1e-4)


def test_empty_scene_and_lines_points(tmp_path):
    doc, binary = _parse(gltf.to_bytes(om.Node("empty")))
    _check_structure(doc, binary)
    scene = om.Node(
        "s",
        [
            om.LineSet(vertices=[(0, 0, 0), (1, 0, 0), (1, 1, 0)], indices=[(0, 1), (1, 2)]),
            om.PointSet(vertices=[(0, 0, 0), (2, 2, 2)]),
        ],
    )
    doc, binary = _parse(gltf.to_bytes(scene))
    _check_structure(doc, binary)
    assert sorted(p["mode"] for m in doc["meshes"] for p in m["primitives"]) == [0, 1]


def test_failed_export_leaves_no_file(tmp_path):
    target = tmp_path / "x.glb"
    with pytest.raises(ValueError):
        om.export(om.Node("s", [om.Sphere()]), target, size=(0, 10))
    assert not target.exists() and not list(tmp_path.iterdir())


def test_mesh_nodes_are_named_after_the_scene_shapes_and_color_follows_gl_rules():
    scene = om.Node("s")
    scene.add(om.Material(diffuse=(1, 0, 0)))
    scene.add(om.Color(0, 0, 1, 0.5))
    scene.add(om.Torus())
    scene.add(om.Node("n", [om.Color(0, 1, 0), om.Material(diffuse=(1, 1, 0)), om.Box()]))
    doc, _ = _parse(gltf.to_bytes(scene))
    assert [m["name"] for m in doc["meshes"]] == ["Torus", "Box"]
    torus, box = (doc["materials"][m["primitives"][0]["material"]] for m in doc["meshes"])
    assert torus["pbrMetallicRoughness"]["baseColorFactor"] == pytest.approx([0, 0, 1, 0.5])
    assert box["pbrMetallicRoughness"]["baseColorFactor"] == pytest.approx([1, 1, 0, 1])  # Color before: ignored


class _Blob(om.Shape):
    """A shape no engine knows (no painter, no simplifier)."""

    __slots__ = ()


def test_unknown_shapes_raise_by_default_and_warn_on_request():
    scene = om.Node("s", [om.Node("odd", [_Blob()])])
    with pytest.raises(om.NoHandlerError):
        gltf.to_bytes(scene)
    with pytest.warns(UserWarning):
        gltf.to_bytes(scene, on_missing="warn")


def test_light_colours_are_linear():
    scene = om.Node("s", [om.PointLight(position=(1, 2, 3), color=(0.5, 0.25, 1.0)), om.Sphere()])
    doc, _ = _parse(gltf.to_bytes(scene))
    (light,) = doc["extensions"]["KHR_lights_punctual"]["lights"]
    assert light["color"] == pytest.approx([0.21404114, 0.05087609, 1.0], rel=1e-6)


def test_missing_texture_files_name_the_node_and_the_fix(tmp_path):
    scene = om.Node("s", [om.Node("crate", [om.Texture(str(tmp_path / "gone.png")), om.Box()])])
    with pytest.raises(FileNotFoundError, match=r"Texture in node /s/crate.*check the path or pass an array"):
        om.export(scene, tmp_path / "x.glb")
    assert list(tmp_path.iterdir()) == []


def test_a_write_failing_midway_leaves_the_existing_file_unchanged(tmp_path, monkeypatch):
    import contextlib

    target = tmp_path / "scene.glb"
    target.write_bytes(b"old file")
    real = gltf.atomic_write

    @contextlib.contextmanager
    def half_then_full_disk(path, mode="w", **kw):
        with real(path, mode, **kw) as fh:

            class Half:
                def write(self, data):
                    fh.write(data[: len(data) // 2])
                    fh.flush()
                    raise OSError(28, "No space left on device")

            yield Half()

    monkeypatch.setattr(gltf, "atomic_write", half_then_full_disk)
    with pytest.raises(OSError, match="No space"):
        om.export(_scene(), target)
    assert target.read_bytes() == b"old file"
    assert [p.name for p in tmp_path.iterdir()] == ["scene.glb"]


def test_node_matrices_gltf_cannot_hold_are_applied_to_the_meshes_below(tmp_path):
    """glTF node matrices must be translation x rotation x scale: a sheared one goes into the vertices below it
    (a mirroring one stays: a negative scale is allowed)."""
    shear = np.eye(4)
    shear[0, 1] = 0.5
    inner = om.Node("inner", [om.Translation(2, 0, 0), om.Sphere(), om.Polyline([(0, 0, 0), (1, 1, 1)])])
    scene = om.Node("s", [om.Node("sheared", [om.Matrix(shear), om.Box(), inner])])
    scene.add(om.Node("mirrored", [om.Scaling(-1, 1, 1), om.Translation(3, 0, 0), om.Torus()]))
    path = om.export(scene, tmp_path / "shear.glb")
    doc, binary = _parse(path.read_bytes())
    _check_structure(doc, binary)
    nodes = doc["nodes"]
    by_name = {n["name"]: n for n in nodes}
    assert not any("matrix" in nodes[c] for c in by_name["sheared"]["children"])  # the box's and "inner"'s
    (torus,) = (nodes[c] for c in by_name["mirrored"]["children"])
    assert np.linalg.det(np.array(torus["matrix"]).reshape(4, 4)) < 0
    from omnirender.geometry.trs import decomposable

    assert all(decomposable(np.array(n["matrix"]).reshape(4, 4).T) for n in doc["nodes"] if "matrix" in n)
    np.testing.assert_allclose(np.array(om.bounds(om.load_gltf(path))), np.array(om.bounds(scene)), atol=1e-6)


def test_area_lights_are_spots_with_an_extras_record_that_load_gltf_reads(tmp_path):
    """KHR_lights_punctual has no area lights: a far-field spot (I = L A) plus extras.omnirender.area_light."""
    root = om.Node("scene", [om.Camera.look_at((0, 3, 6), (0, 0, 0))])
    lamp = root.add(om.Node("lamp", [om.Translation((0, 2, 0)), om.Scaling(2.0)]))
    lamp.add(om.RectLight(direction=(0, -1, 0), width=1.0, height=0.5, intensity=3.0, two_sided=True))
    root.add(
        om.Node("disc", [om.DiscLight(position=(1, 2, 0), direction=(0, -1, 0), radius=0.25, casts_shadows=False)])
    )
    root.add(om.Node("box", [om.Box()]))
    path = om.export(root, tmp_path / "area.glb")
    doc, _ = _parse(path.read_bytes())
    lights = doc["extensions"]["KHR_lights_punctual"]["lights"]
    rect = next(light for light in lights if light["name"] == "RectLight")
    assert rect["type"] == "spot" and rect["spot"]["outerConeAngle"] == pytest.approx(math.pi / 2)
    assert rect["intensity"] == pytest.approx(3.0 * 2.0 * 1.0)  # L A, the world area 2 x 1
    record = rect["extras"]["omnirender"]["area_light"]
    assert record == {"shape": "rect", "two_sided": True, "casts_shadows": True, "radiance": 3.0,
                      "width": pytest.approx(2.0), "height": pytest.approx(1.0)}  # fmt: skip
    back = om.load_gltf(path)
    found = {type(c).__name__: c for node in back.walk() for c in node.components if isinstance(c, om.LightSource)}
    assert found["RectLight"].two_sided and found["RectLight"].intensity == pytest.approx(3.0)
    assert found["DiscLight"].radius == pytest.approx(0.25) and not found["DiscLight"].casts_shadows
    img_a = om.render(root, engine="gl", size=(48, 36), samples=0)
    img_b = om.render(back, engine="gl", size=(48, 36), samples=0)
    assert np.abs(img_a.array.astype(int) - img_b.array.astype(int)).mean() < 1.5
