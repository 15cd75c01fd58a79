"""Scene files: JSON/YAML round trips of every component type, sharing, paths and error paths."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender import attributes, core, shapes
from omnirender.scene import files
from omnirender.scene.files import SceneFileError

OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n"


def _samples(tmp: Path) -> dict[str, list]:
    """At least one instance per built-in type name (non-default parameters where it matters)."""
    mesh = tmp / "meshes" / "tet.obj"
    mesh.parent.mkdir(exist_ok=True)
    mesh.write_text(OBJ)
    tri = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    return {
        "Sphere": [om.Sphere(center=(1, 2, 3), radius=0.5)],
        "CSG": [om.CSG("difference", om.Sphere(radius=1.5), om.Box(size=1, center=(1, 0, 0)))],
        "Shadowing": [om.Shadowing(cast=False, receive=True)],
        "Mirror": [om.Mirror(0.4, plane=((0, 0, 2), 0.5))],
        "Box": [om.Box(size=(1, 2, 3), center=(0, 1, 0))],
        "Cylinder": [om.Cylinder(radius=0.3, height=1.5)],
        "Cone": [om.Cone(radius=0.4, height=1.0)],
        "Torus": [om.Torus(major_radius=2, minor_radius=0.5)],
        "Disk": [om.Disk(radius=2)],
        "Rectangle": [om.Rectangle(size=(2, 3))],
        "Arrow": [om.Arrow(start=(0, 0, 0), end=(1, 1, 0), radius=0.1)],
        "TriangleSet": [
            om.TriangleSet(
                np.array(tri, np.float32),
                indices=np.array([[0, 1, 2], [0, 1, 3]], np.uint32),
                colors=[(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)],
                texcoords=[(0, 0), (1, 0), (0, 1), (1, 1)],
            ),
            om.TriangleSet(tri[:3], normals=[(0, 0, 1)] * 3),
            om.TriangleSet(om.data.Array(np.array(tri[:3], float))),
        ],
        "Polygon": [om.Polygon([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], colors=(1, 0, 0))],
        "LineSet": [om.LineSet(tri, indices=[(0, 1), (2, 3)])],
        "Polyline": [om.Polyline(tri, closed=True)],
        "PointSet": [om.PointSet(tri, sizes=[1, 2, 3, 4])],
        "Heightfield": [om.Heightfield(np.arange(6.0).reshape(2, 3), spacing=(0.5, 2.0))],
        "Volume": [om.Volume(np.arange(8.0).reshape(2, 2, 2), spacing=(1, 2, 3), iso=3.5)],
        "Text": [om.Text("hello", position=(1, 2, 3), size=12)],
        "MeshFile": [om.MeshFile(mesh)],
        "Color": [om.Color(0.1, 0.2, 0.3, 0.4)],
        "Material": [om.Material(diffuse=(1, 0.4, 0.6), specular=(1, 1, 1), shininess=40, opacity=0.5)],
        "PBRMaterial": [
            om.PBRMaterial(base_color=(0.9, 0.1, 0.1), metallic=1, roughness=0.2),
            om.PBRMaterial(normal_texture=om.Texture(np.full((2, 2, 3), 0.5), uv_set=1), alpha_mode="blend"),
        ],
        "BumpMap": [om.BumpMap(om.Texture(np.full((2, 2, 3), 0.25), scale=(2, 2)), scale=0.1)],
        "TextureLayer": [om.TextureLayer(om.Texture(np.full((2, 2, 3), 0.25)), blend="multiply", opacity=0.5)],
        "MultiTexture": [om.MultiTexture([om.TextureLayer(om.Texture(np.full((2, 2, 3), 0.5)), opacity=0.25)])],
        "Texture": [
            om.Texture(str(tmp / "textures" / "wood.png"), wrap="mirror", filter="nearest", mipmap=False),
            om.Texture(np.arange(24, dtype=np.uint8).reshape(2, 3, 4)),
            om.Texture(np.full((2, 2, 3), 0.25)),
        ],
        "DrawStyle": [om.DrawStyle(mode="wireframe", line_width=2, cull="back", shading="flat")],
        "DirectionalLight": [om.DirectionalLight(direction=(1, -1, 0), intensity=2)],
        "PointLight": [om.PointLight(position=(1, 2, 3), linear=0.1, diffuse=(0.5, 0.5, 0.5))],
        "SpotLight": [om.SpotLight(position=(0, 5, 0), direction=(0, -1, 0), cutoff=20, exponent=4)],
        "RectLight": [om.RectLight(position=(0, 3, 0), direction=(0, -1, 0), width=2, height=0.5, two_sided=True)],
        "DiscLight": [om.DiscLight(position=(0, 3, 0), direction=(0, -1, 0), radius=0.4, up=(1, 0, 0))],
        "AmbientLight": [om.AmbientLight(color=(0.2, 0.3, 0.4), intensity=0.5)],
        "LookAt": [om.LookAt(eye=(1, 2, 3), center=(0, 0, 0), up=(0, 0, 1))],
        "Reflection": [om.Reflection(normal=(0, 1, 0), point=(0, 2, 0))],
        "DirectionOfFlight": [om.DirectionOfFlight(velocity=(1, 0, 1), up=(0, 1, 0), position=(1, 2, 3))],
        "Polar": [om.Polar(radius=2, azimuth=30, elevation=10, orient=True)],
        "Billboard": [om.Billboard(), om.Billboard(axis=(0, 1, 0))],
        "BillboardSimplifier": [om.BillboardSimplifier()],
        "ClipPlane": [om.ClipPlane(normal=(0, 0, 1), offset=0.5)],
        "Fog": [om.Fog(color=(1, 1, 1), start=2, end=20, mode="exp2", density=0.3)],
        "Background": [om.Background((0.1, 0.2, 0.3, 0.0))],
        "Tessellation": [om.Tessellation(5)],
        "Highlight": [om.Highlight((0, 1, 1))],
        "PickId": [om.PickId(42), om.PickId("door")],
        "Collidable": [om.Collidable(False)],
        "Camera": [
            om.Camera.look_at(eye=(4, 3, 6), center=(0, 1, 0), fov=40, mask="!debug"),
            om.Camera.orthographic(eye=(0, 0, 5), height=3),
        ],
        "LightSwitch": [om.LightSwitch(on=True)],
        "Matrix": [om.Matrix([[1, 2, 3, 4], [0, 5, 6, 7], [0, 0, 8, 9], [0, 0, 0, 1]])],
        "Translation": [om.Translation(1, 2, 3)],
        "Rotation": [om.Rotation(30, (0, 1, 0)), om.Rotation(45, (1, 1, 0))],
        "Scaling": [om.Scaling(1, 2, 3)],
        "Technique": [om.Technique(service="analysis", passes=2)],
        "InstanceSet": [
            om.InstanceSet(om.Box(size=0.5), np.array([(0, 0, 0), (1, 2, 3)], float)),
            om.InstanceSet(
                om.Sphere(),
                np.stack([np.eye(4), np.eye(4)]),
                colors=[(1, 0, 0), (0, 1, 0)],
                scales=[1.0, 2.0],
                visible=[True, False],
            ),
        ],
        "InstanceId": [om.InstanceId(7)],
        "GaussianSplats": [
            om.GaussianSplats(
                np.array([(0, 0, 0), (1, 2, 3)], float),
                np.array([(1, 0, 0, 0), (0, 1, 0, 0)], float),
                np.full((2, 3), 0.1),
                np.array([0.5, 1.0]),
                np.zeros((2, 4, 3)),
            )
        ],
        "LevelOfDetail": [
            om.LevelOfDetail([om.Sphere(), om.Box()], distances=[10], center=(1, 0, 0), offline="distance")
        ],
        "NURBSSurface": [
            om.NURBSSurface(
                np.arange(48.0).reshape(4, 4, 3),
                weights=np.full((4, 4), 0.5),
                knots_v=[0, 0, 0, 0, 2, 2, 2, 2],
                trim=[
                    [(0.2, 0.2), (0.2, 0.8), (0.8, 0.5)],
                    om.TrimCurve([(0.5, 0.1), (0.9, 0.5), (0.5, 0.9), (0.5, 0.1)]),
                ],
            ),
            om.NURBSSurface(np.arange(36.0).reshape(3, 4, 3), degree_u=2, degree_v=1),
        ],
        "TrimCurve": [om.TrimCurve([(0.5, 0.1), (0.9, 0.5), (0.1, 0.5), (0.5, 0.1)], weights=[1, 2, 2, 1], degree=3)],
    }


def _equal(a, b) -> bool:
    if isinstance(a, om.Node) or isinstance(b, om.Node):  # a render texture's scene: the same graph
        return (type(a) is type(b) and a.name == b.name and len(a.items) == len(b.items)
                and all(_equal(p, q) for p, q in zip(a.items, b.items, strict=True)))  # fmt: skip
    if isinstance(a, om.RenderingComponent) or isinstance(b, om.RenderingComponent):
        return type(a) is type(b) and _params_equal(a.parameters(), b.parameters())
    if isinstance(a, (str, os.PathLike)) and isinstance(b, (str, os.PathLike)):
        return os.path.abspath(a) == os.path.abspath(b) if ("/" in str(a) or "/" in str(b)) else str(a) == str(b)
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if a is None or b is None or isinstance(a, (bool, str)) or isinstance(b, (bool, str)):
        return a == b
    if hasattr(a, "array") and not isinstance(a, np.ndarray):
        a = a.array()
    try:
        x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    except (TypeError, ValueError):
        return len(a) == len(b) and all(_equal(p, q) for p, q in zip(a, b, strict=True))
    return x.shape == y.shape and np.allclose(x, y, rtol=1e-12, atol=1e-15)


def _params_equal(p: dict, q: dict) -> bool:
    return p.keys() == q.keys() and all(_equal(p[k], q[k]) for k in p)


def test_builtin_types_are_discovered():
    types = files.registered_types()
    for module in (shapes, attributes):
        for name in module.__all__:
            cls = getattr(module, name)
            if isinstance(cls, type) and issubclass(cls, om.RenderingComponent):
                if name in ("DeclaredShape", "LightSource"):
                    continue
                assert types.get(name) is cls, name
    for cls in (om.Camera, om.LightSwitch, om.Matrix, om.Translation, om.Rotation, om.Scaling):
        assert types[cls.__name__] is cls
    for abstract in ("Shape", "Attribute", "Transform", "Light", "DeclaredShape", "Handler"):
        assert abstract not in types
    assert core.__all__  # the core is walked too


@pytest.mark.parametrize("fmt", ["json", "yaml"])
def test_every_registered_type_round_trips(tmp_path, fmt):
    samples = _samples(tmp_path)
    builtin = {n: c for n, c in files.registered_types().items() if "." not in n}
    for name in sorted(set(builtin) - set(samples)):  # a type added later: its defaults must round-trip
        try:
            samples[name] = [builtin[name]()]
        except (TypeError, ValueError) as exc:
            pytest.fail(f"add a sample for the new scene-file type {name} to _samples() ({exc})")
    scene = om.Node("scene")
    expected = []
    for name in sorted(builtin):
        node = scene.add(om.Node(f"n_{name}"))
        for comp in samples[name]:
            assert type(comp) is builtin[name]
            node.add(comp)
            expected.append(comp)
    path = tmp_path / f"all.{fmt}"
    assert om.save(scene, path) == path
    loaded = om.load(path)
    got = [c for child in loaded.children for c in child.components]
    assert len(got) == len(expected)
    for a, b in zip(expected, got, strict=True):
        assert type(a) is type(b)
        assert _params_equal(a.parameters(), b.parameters()), (type(a).__name__, a.parameters(), b.parameters())
    # uint8 texture data comes back bit for bit, float32 vertices too
    tex = loaded["/scene/n_Texture"].components[1]
    assert tex.image.dtype == np.uint8 and np.array_equal(tex.image_array(), samples["Texture"][1].image_array())
    ts = loaded["/scene/n_TriangleSet"].components[0]
    assert np.array_equal(ts.vertex_array(), samples["TriangleSet"][0].vertex_array())
    # saving what was loaded gives the same document (up to the last bit: om.Rotation renormalises its axis)
    again = files.loads(files.dumps(loaded, fmt, base_dir=tmp_path), fmt, base_dir=tmp_path)
    for a, b in zip(expected, [c for child in again.children for c in child.components], strict=True):
        assert _params_equal(a.parameters(), b.parameters())


def _dag_scene():
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(4, 3, 6)))
    lamp = scene.add(om.PointLight(position=(5, 5, 5)))
    mat = om.Material(diffuse=(1, 0, 0))
    wheel = om.Node("wheel", [mat, om.Torus(1, 0.2)], groups=["parts", "round"])
    left = scene.add(om.Node("left", [om.Translation(-2, 0, 0), wheel]))
    right = scene.add(om.Node("right", [om.Translation(2, 0, 0), wheel, om.LightSwitch(False, [lamp])]))
    scene.add(om.Node("debug", [mat, om.Sphere()], groups=["debug"]))
    return scene, left, right


@pytest.mark.parametrize("fmt", ["json", "yaml"])
def test_shared_nodes_and_components_round_trip(fmt):
    scene, _, _ = _dag_scene()
    text = files.dumps(scene, fmt)
    loaded = files.loads(text, fmt)
    left, right, debug = loaded["/scene/left"], loaded["/scene/right"], loaded["/scene/debug"]
    assert left.children[0] is right.children[0]  # the DAG is kept
    wheel = left.children[0]
    assert wheel.groups == frozenset({"parts", "round"})
    assert wheel.components[0] is debug.components[0]  # shared material
    switch = right.components[-1]
    assert switch.lights[0] is loaded.components[1]  # LightSwitch refers to the scene's light
    assert [type(x).__name__ for x in right] == ["Translation", "Node", "LightSwitch"]
    assert files.dumps(loaded, fmt) == text
    assert text.count('"$ref"' if fmt == "json" else "$ref:") == 3


def test_loaded_scene_evaluates_like_the_original():
    scene, _, _ = _dag_scene()
    loaded = files.loads(files.dumps(scene))
    assert [(op, type(o).__name__) for op, o in om.trace(loaded)] == [
        (op, type(o).__name__) for op, o in om.trace(scene)
    ]


def test_document_layout():
    doc = json.loads(files.dumps(om.Node("s", [om.Sphere(radius=2), om.Node("child", groups=["g"])])))
    assert doc["format"] == "omnirender-scene" and doc["version"] == 1
    assert doc["root"] == {
        "node": "s",
        "contents": [
            {"type": "Sphere", "center": [0.0, 0.0, 0.0], "radius": 2.0},
            {"node": "child", "groups": ["g"], "contents": []},
        ],
    }


def test_mesh_and_texture_paths_are_relative_to_the_scene_file(tmp_path):
    project = tmp_path / "project"
    (project / "meshes").mkdir(parents=True)
    (project / "meshes" / "tet.obj").write_text(OBJ)
    scene = om.Node("scene", [om.Texture(project / "tex" / "wood.png"), om.MeshFile(project / "meshes" / "tet.obj")])
    om.save(scene, project / "scene.yaml")
    doc = json.loads(files.dumps(scene, base_dir=project))
    assert doc["root"]["contents"][0]["image"] == "tex/wood.png"
    assert doc["root"]["contents"][1]["path"] == "meshes/tet.obj"
    moved = tmp_path / "moved"
    shutil.copytree(project, moved)
    shutil.rmtree(project)
    loaded = om.load(moved / "scene.yaml")
    assert loaded.components[1].path == str(moved / "meshes" / "tet.obj")
    assert loaded.components[1].triangle_count == 2
    assert loaded.components[0].path == str(moved / "tex" / "wood.png")


def _doc(*contents) -> str:
    return json.dumps({"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": list(contents)}})


@pytest.mark.parametrize(
    "text, where, message",
    [
        (
            _doc({"type": "Sphere"}, {"node": "a", "contents": [{"type": "Teapot"}]}),
            r"root.contents\[1\].contents\[0\].type",
            "unknown type 'Teapot'",
        ),
        (
            _doc(
                {"type": "Sphere"},
                {"type": "Box"},
                {"node": "a", "contents": [{"type": "Disk"}, {"type": "Sphere", "radius": -1}]},
            ),
            r"root.contents\[2\].contents\[1\].radius",
            r"must be > 0.*\(Sphere\)",
        ),
        (_doc({"type": "Sphere", "radiu": 1}), r"root.contents\[0\].radiu", r"Sphere has no parameter 'radiu'"),
        (_doc({"type": "Material", "shininess": -2}), r"root.contents\[0\].shininess", r"must be >= 0"),
        (
            _doc({"type": "Material", "diffuse": [2, 0, 0]}),
            r"root.contents\[0\].diffuse",
            r"values must be in \[0, 1\]",
        ),
        (_doc({"$ref": "nothing"}), r"root.contents\[0\].\$ref", "unknown id 'nothing'"),
        (_doc({"node": "a", "$id": "x"}, {"node": "b", "$id": "x"}), r"root.contents\[1\].\$id", "duplicate id"),
        (_doc(42), r"root.contents\[0\]", "expected a node, component or reference"),
        (_doc({"radius": 1}), r"root.contents\[0\]", "expected 'node', 'type' or '\\$ref'"),
        (_doc({"node": "a", "colour": 1}), r"root.contents\[0\].colour", "unknown key in a node"),
        (_doc({"node": "a/b"}), r"root.contents\[0\].node", "name"),
        (_doc({"node": "a", "groups": "g"}), r"root.contents\[0\].groups", "list of group names"),
        (_doc({"type": "nosuchpkg.Thing"}), r"root.contents\[0\].type", "no omnirender package 'nosuchpkg'"),
        (_doc({"type": "formats.Thing"}), r"root.contents\[0\].type", "defines no component 'Thing'"),
        (_doc({"type": "../evil"}), r"root.contents\[0\].type", "invalid type name"),
        (_doc({"type": "MeshFile", "path": "missing.obj"}), r"root.contents\[0\].path", "no such file"),
        (
            _doc({"type": "Texture", "image": {"$array": [[1, 2]], "dtype": "object"}}),
            r"root.contents\[0\].image.dtype",
            "not numeric",
        ),
        (
            _doc({"type": "LightSwitch", "lights": [{"type": "Sphere"}]}),
            r"root.contents\[0\].lights\[0\]",
            "must be a light, got Sphere \\(LightSwitch\\)",
        ),
        ('{"format": "other", "version": 1, "root": {}}', "format", "expected 'omnirender-scene'"),
        ('{"format": "omnirender-scene", "version": 7, "root": {}}', "version", "unsupported version 7"),
        ('{"format": "omnirender-scene", "version": 1}', "root", "missing"),
        ('{"format": "omnirender-scene", "version": 1, "root": {"type": "Sphere"}}', "root", "must be a node"),
        (
            _doc({"type": "Sphere", "radius": 1}).replace(": 1}", ": NaN}"),
            "",
            "NaN is not allowed",
        ),
        ('{"format": "omnirender-scene", "version": 1, "root": {', "", "invalid JSON at line 1"),
    ],
)
def test_errors_name_the_json_path(text, where, message):
    with pytest.raises(SceneFileError, match=message) as info:
        files.loads(text)
    assert isinstance(info.value, ValueError)
    import re

    assert re.fullmatch(where, info.value.path), (info.value.path, str(info.value))


def test_error_message_format(tmp_path):
    text = _doc(
        {"type": "Sphere"},
        {"type": "Box"},
        {"node": "a", "contents": [{"type": "Disk"}, {"type": "Sphere", "radius": -1}]},
    )
    with pytest.raises(SceneFileError) as info:
        files.loads(text)
    assert str(info.value) == "root.contents[2].contents[1].radius: must be > 0, got -1.0 (Sphere)"
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(SceneFileError) as info:
        om.load(path)
    assert str(info.value) == f"{path}: root.contents[2].contents[1].radius: must be > 0, got -1.0 (Sphere)"
    assert info.value.path == "root.contents[2].contents[1].radius" and info.value.source == str(path)


def test_yaml_never_executes_code_and_reports_bad_keys(tmp_path):
    evil = tmp_path / "evil.yaml"
    evil.write_text("format: omnirender-scene\nversion: 1\nroot: !!python/object/apply:os.system ['echo pwned']\n")
    with pytest.raises(SceneFileError, match="invalid YAML") as info:
        om.load(evil)
    assert str(evil) in str(info.value)
    bad = "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  contents:\n  - type: LightSwitch\n    on: false\n"
    with pytest.raises(SceneFileError, match="quote keys like 'on'"):
        files.loads(bad, "yaml")
    good = bad.replace("    on:", "    'on':")
    assert files.loads(good, "yaml").components[0].on is False


def test_extensions_and_formats(tmp_path):
    scene = om.Node("s", [om.Sphere()])
    for ext in (".json", ".yaml", ".yml", ".JSON"):
        om.save(scene, tmp_path / f"a{ext}")
        assert isinstance(om.load(tmp_path / f"a{ext}").components[0], om.Sphere)
    assert (tmp_path / "a.json").read_text().lstrip().startswith("{")
    assert (tmp_path / "a.yml").read_text().startswith("format: omnirender-scene")
    with pytest.raises(ValueError, match=r"unknown scene file extension '.txt' \(use .json, .yaml or .yml\)"):
        om.save(scene, tmp_path / "a.txt")
    with pytest.raises(ValueError, match="unknown scene file extension"):
        om.load(tmp_path / "a.txt")
    with pytest.raises(FileNotFoundError, match="nothere.json"):
        om.load(tmp_path / "nothere.json")
    with pytest.raises(ValueError, match="format must be 'json' or 'yaml'"):
        files.dumps(scene, "xml")


class Gadget(om.MonoAttribute):
    """A third-party attribute used to test registration."""

    __slots__ = ("level",)

    def __init__(self, level: int = 1) -> None:
        super().__init__()
        if level < 0:
            raise ValueError(f"Gadget: level must be >= 0, got {level}")
        self.level = level


def test_saving_an_unregistered_type_fails_cleanly_and_atomically(tmp_path):
    target = tmp_path / "scene.json"
    target.write_text("old")
    with pytest.raises(ValueError, match=r"call om.register_type\('<name>', Gadget\)"):
        om.save(om.Node("s", [Gadget()]), target)
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.json"]


def test_register_type_for_third_party_components():
    try:
        assert om.register_type("acme.Gadget", Gadget) is Gadget
        text = files.dumps(om.Node("s", [Gadget(3)]))
        assert '"type": "acme.Gadget"' in text
        assert files.loads(text).components[0].level == 3
        with pytest.raises(SceneFileError, match=r"root.contents\[0\].level: must be >= 0, got -1 \(Gadget\)"):
            files.loads(text.replace("3", "-1"))
        assert files.registered_types()["acme.Gadget"] is Gadget
        with pytest.raises(ValueError, match="already .*Gadget.*override=True"):
            om.register_type("acme.Gadget", Color2)
        om.register_type("acme.Gadget", Color2, override=True)
        assert files.registered_types()["acme.Gadget"] is Color2
        with pytest.raises(ValueError, match="not a valid type name"):
            om.register_type("acme gadget", Gadget)
        with pytest.raises(ValueError, match="not a RenderingComponent"):
            om.register_type("acme.Int", int)
    finally:
        files.unregister_type("acme.Gadget")
    assert "acme.Gadget" not in files.registered_types()
    with pytest.raises(SceneFileError, match="no omnirender package 'acme'"):
        files.loads(_doc({"type": "acme.Gadget"}))


class Color2(om.MonoAttribute):
    """Another third-party attribute."""

    __slots__ = ()


def test_qualified_engine_types_resolve_lazily():
    from omnirender import povray

    finish = povray.Finish
    sample = finish(phong=0.8)
    text = files.dumps(om.Node("s", [sample]))
    assert '"type": "povray.Finish"' in text
    loaded = files.loads(text).components[0]
    assert type(loaded) is finish and _params_equal(loaded.parameters(), sample.parameters())


def test_example_scene_files_hold_the_demo_scene():
    from omnirender.demo import KNOT_PATH, demo_scene

    root = Path(__file__).resolve().parents[2] / "examples" / "scenes"
    from_json = om.load(root / "demo.json")
    from_yaml = om.load(root / "demo.yaml")
    assert files.dumps(from_json) == files.dumps(from_yaml)
    demo = demo_scene()
    for node in demo.walk():  # the files name the copy of the knot next to them
        for item in node.items:
            if isinstance(item, om.MeshFile):
                item.path = str(root / "meshes" / "knot.obj")
    assert files.dumps(from_json) == files.dumps(demo)
    assert (root / "meshes" / "knot.obj").read_bytes() == KNOT_PATH.read_bytes()
    features = om.load(root / "features.yaml")
    assert features["/demo/wheels/left"].children[0] is features["/demo/wheels/right"].children[0]


def test_trusted_only_types_are_refused_unless_the_caller_trusts_the_file(tmp_path):
    from omnirender import povray

    text = json.dumps(
        {
            "format": "omnirender-scene",
            "version": 1,
            "root": {"node": "s", "contents": [{"type": "povray.Raw", "text": '#fopen F "x" write'}]},
        }
    )
    with pytest.raises(SceneFileError, match=r"root\.contents\[0\]\.type: povray\.Raw is trusted-only") as info:
        files.loads(text)
    assert "trusted=True" in str(info.value)  # the message names the fix
    path = tmp_path / "raw.json"
    path.write_text(text)
    with pytest.raises(SceneFileError, match="trusted-only"):
        om.load(path)
    # nested inside a parameter value it is refused too
    nested = (
        text.replace('"contents": [', '"contents": [{"type": "Technique", "service": "x"}, ')
        .replace('{"type": "povray.Raw"', '{"node": "inner", "contents": [{"type": "povray.Raw"')
        .replace('write"}]', 'write"}]}]')
    )
    with pytest.raises(SceneFileError, match=r"root\.contents\[1\]\.contents\[0\]\.type"):
        files.loads(nested)
    for loaded in (files.loads(text, trusted=True), om.load(path, trusted=True)):
        raw = loaded.components[0]
        assert type(raw) is povray.Raw and raw.text == '#fopen F "x" write'
    # saving still works (the author trusts their own scene)
    assert '"type": "povray.Raw"' in files.dumps(om.Node("s", [povray.Raw("// hi")]))


def test_any_class_can_declare_itself_trusted_only():
    class Script(om.MonoAttribute):
        __slots__ = ("code",)
        scene_file_trusted_only = True

        def __init__(self, code: str = "") -> None:
            super().__init__()
            self.code = code

    om.register_type("tests.Script", Script)
    try:
        text = files.dumps(om.Node("s", [Script("x")]))
        with pytest.raises(SceneFileError, match="tests.Script is trusted-only"):
            files.loads(text)
        assert files.loads(text, trusted=True).components[0].code == "x"
    finally:
        files.unregister_type("tests.Script")


@pytest.mark.parametrize("fmt", ["json", "yaml"])
def test_mitsuba_plugin_dicts_round_trip_as_data(fmt):
    from omnirender import mitsuba

    nested = {"type": "dielectric", "int_ior": 1.5, "specular_reflectance": {"type": "rgb", "value": [1, 0.5, 0]}}
    samples = [
        mitsuba.BSDF(nested),
        mitsuba.Emitter({"type": "constant", "radiance": {"type": "rgb", "value": [0.2, 0.2, 0.2]}}),
        mitsuba.Integrator({"type": "path", "max_depth": 8, "hide_emitters": True}),
    ]
    text = files.dumps(om.Node("s", samples), fmt)
    loaded = files.loads(text, fmt).components
    assert [type(c) for c in loaded] == [type(c) for c in samples]
    for a, b in zip(samples, loaded, strict=True):
        assert b.plugin == a.plugin
    # saved again: the same document
    assert files.dumps(om.Node("s", loaded), fmt) == text
    # a plain dict parameter without marker keys stays a plain mapping in the file
    assert '"$dict"' not in files.dumps(om.Node("s", [om.Technique()]))


def test_dict_wrapper_errors_name_the_json_path():
    doc = {
        "format": "omnirender-scene",
        "version": 1,
        "root": {"node": "s", "contents": [{"type": "mitsuba.BSDF", "plugin": {"$dict": 3}}]},
    }
    with pytest.raises(SceneFileError, match=r"root\.contents\[0\]\.plugin: a '\$dict' wrapper"):
        files.loads(json.dumps(doc))
