"""Scene files against hostile and large input: limits with JSON paths, compact arrays, the path policy,
definitions for deep graphs, and the JSON Schema."""

from __future__ import annotations

import json
import os
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender.scene import files
from omnirender.scene.files import SceneFileError, UntrustedContentError
from omnirender.scene.parse import ParseLimits

HEAD = "format: omnirender-scene\nversion: 1\n"


def doc(*contents, **extra) -> str:
    return json.dumps(
        {"format": "omnirender-scene", "version": 1, **extra, "root": {"node": "s", "contents": list(contents)}}
    )


# -- limits ----------------------------------------------------------------------------------------
def test_a_billion_laughs_is_refused_at_once_with_its_path():
    text = HEAD + "root: {node: x}\nbomb:\n  a: &a [x,x,x,x,x,x,x,x,x,x]\n"
    for level, prev in zip("bcdefghi", "abcdefgh", strict=True):
        text += f"  {level}: &{level} [{','.join(['*' + prev] * 10)}]\n"
    started = time.perf_counter()
    with pytest.raises(
        SceneFileError, match=r"bomb\.f\[\d\]: YAML aliases expand this document by more than 1,000,000"
    ):
        files.loads(text, "yaml")
    assert time.perf_counter() - started < 5  # refused while parsing, not after expanding 10^9 nodes


def test_aliases_within_the_limit_are_data_and_the_limit_is_a_parameter():
    text = HEAD + "root:\n  node: s\n  contents:\n  - &c {type: Color, r: 1, g: 0, b: 0}\n  - *c\n"
    loaded = files.loads(text, "yaml")
    assert [type(c) for c in loaded.components] == [om.Color, om.Color]
    with pytest.raises(SceneFileError, match="more than 3 nodes"):
        files.loads(text, "yaml", limits=ParseLimits(max_alias_nodes=3))


def test_a_document_that_contains_itself_is_refused():
    with pytest.raises(
        SceneFileError, match=r"root\.contents\[0\]: the alias \*r refers to a collection that contains it"
    ):
        files.loads(HEAD + "root: &r {node: s, contents: [*r]}\n", "yaml")


@pytest.mark.parametrize("fmt", ["json", "yaml"])
def test_deep_nesting_is_refused_with_the_path_where_it_passes_the_limit(fmt):
    text = "[" * 100000 + "]" * 100000 if fmt == "json" else "x: " + "[" * 100000 + "]" * 100000 + "\n"
    with pytest.raises(SceneFileError, match="nested deeper than 256 levels") as info:
        files.loads(text, fmt)
    assert info.value.path.count("[0]") >= 255
    assert len(str(info.value)) < 600  # the path is shortened in the message, kept whole in .path


def test_nesting_inside_a_value_is_refused_by_the_reader_with_its_path():
    plugin = {"a": 1}
    for _ in range(300):
        plugin = {"a": plugin}
    with pytest.raises(SceneFileError, match="nested deeper than 256") as info:
        files.loads(doc({"type": "mitsuba.BSDF", "plugin": plugin}))
    assert info.value.path.startswith("root.contents[0].plugin.a.a.a") and info.value.path.count(".a") > 250


@pytest.mark.parametrize(
    "text, fmt, where",
    [
        ('{"format": "omnirender-scene", "version": 1, "version": 1, "root": {"node": "s"}}', "json", "version"),
        (
            doc({"type": "Sphere", "radius": 1}).replace('"radius": 1', '"radius": 1, "radius": 3'),
            "json",
            r"root\.contents\[0\]\.radius",
        ),  # fmt: skip
        (
            HEAD + "root:\n  node: s\n  contents:\n  - type: Sphere\n    radius: 1\n    radius: 2\n",
            "yaml",
            r"root\.contents\[0\]\.radius",
        ),  # fmt: skip
    ],
)
def test_duplicate_keys_are_refused(text, fmt, where):
    with pytest.raises(SceneFileError, match=rf"{where}: duplicate key"):
        files.loads(text, fmt)


@pytest.mark.parametrize(
    "value, message",
    [
        ("2024-01-01", "timestamp"),
        ("!!binary aGVsbG8=", "binary"),
    ],
)
def test_yaml_values_json_does_not_have_are_refused(value, message):
    with pytest.raises(SceneFileError, match=message):
        files.loads(HEAD + f"root:\n  node: s\n  contents:\n  - {{type: Text, string: {value}}}\n", "yaml")


def test_integers_beyond_any_engine_and_nul_characters_are_refused():
    with pytest.raises(SceneFileError, match=r"root\.contents\[0\]\.radius: the integer 1000.* is out of range"):
        files.loads(doc({"type": "Sphere", "radius": 10**400}))
    with pytest.raises(SceneFileError, match=r"root\.node: Node: name must be .*control characters"):
        files.loads(json.dumps({"format": "omnirender-scene", "version": 1, "root": {"node": "a\u0000b"}}))
    with pytest.raises(SceneFileError, match=r"\$id: must be a non-empty string of printable"):
        files.loads(doc({"type": "Sphere", "$id": "x\n"}))


# -- compact arrays ----------------------------------------------------------------------------------
def _cloud(n: int) -> om.Node:
    rng = np.random.default_rng(7)
    return om.Node("s", [om.PointSet(rng.normal(size=(n, 3)).astype(np.float32), sizes=np.arange(n) % 5 + 1.0)])


def test_small_arrays_stay_lists_and_large_ones_are_base64():
    small = files.dumps(_cloud(10))
    assert "$base64" not in small and "[" in small
    big = json.loads(files.dumps(_cloud(2000)))
    vertices = big["root"]["contents"][0]["vertices"]
    assert set(vertices) == {"$base64", "dtype", "shape"} and vertices["shape"] == [2000, 3]
    assert vertices["dtype"] == "float32"
    listed = json.loads(files.dumps(_cloud(2000), arrays="lists"))
    assert isinstance(listed["root"]["contents"][0]["vertices"]["$array"], list)


@pytest.mark.parametrize("fmt", ["json", "yaml"])
@pytest.mark.parametrize("arrays", ["auto", "npz", "lists"])
def test_large_arrays_round_trip_bit_for_bit(tmp_path, fmt, arrays):
    scene = _cloud(3000)
    path = tmp_path / f"cloud.{fmt}"
    om.save(scene, path, arrays=arrays)
    assert (tmp_path / "cloud.arrays.npz").exists() == (arrays == "npz")
    back = om.load(path)
    before, after = scene.components[0], back.components[0]
    assert np.array_equal(before.vertex_array(), after.vertex_array())
    assert np.array_equal(before.size_array(), after.size_array())
    if arrays == "npz":
        assert "$file" in path.read_text() and "cloud.arrays.npz" in path.read_text()


def test_compact_arrays_are_checked():
    tri = {"type": "TriangleSet"}
    cases = [
        ({"$base64": "!!", "dtype": "float32", "shape": [1]}, "not valid base64"),
        ({"$base64": "AAAA", "dtype": "float32", "shape": [3, 3]}, "needs 36 bytes"),
        ({"$base64": "", "dtype": "object", "shape": [0]}, "dtype must be one of"),
        ({"$base64": "", "dtype": "float32", "shape": [-1]}, "shape must be"),
        ({"$base64": "AADAfw==", "dtype": "float32", "shape": [1]}, "non-finite"),
        ({"$file": "x.npz"}, "needs 'key'"),
        ({"$file": "../x.npy"}, "leads outside the file's folder"),
    ]
    for value, message in cases:
        with pytest.raises(SceneFileError, match=rf"root\.contents\[0\]\.vertices.*{message}"):
            files.loads(doc({**tri, "vertices": value}), base_dir=os.getcwd())


def test_side_car_arrays_load_without_pickles(tmp_path):
    np.save(tmp_path / "objects.npy", np.array([None], dtype=object), allow_pickle=True)
    (tmp_path / "s.json").write_text(doc({"type": "TriangleSet", "vertices": {"$file": "objects.npy"}}))
    with pytest.raises(SceneFileError, match=r"vertices: objects.npy holds Python objects \(a pickle\)"):
        om.load(tmp_path / "s.json")


# -- the path policy -------------------------------------------------------------------------------
OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


@pytest.fixture
def outside(tmp_path: Path) -> Path:
    (tmp_path / "mesh.obj").write_text(OBJ)
    (tmp_path / "scenes").mkdir()
    return tmp_path


@pytest.mark.parametrize(
    "path, kind",
    [
        ("../mesh.obj", "leads outside"),
        ("ABS", "is an absolute path"),
        ("link.obj", "is a symbolic link leading outside"),
    ],
)
def test_files_outside_the_scene_folder_need_trust(outside, path, kind):
    if path == "ABS":
        path = str(outside / "mesh.obj")
    if path == "link.obj":
        os.symlink(outside / "mesh.obj", outside / "scenes" / "link.obj")  # a link out of the folder
    scene_file = outside / "scenes" / "s.json"
    scene_file.write_text(doc({"type": "MeshFile", "path": path}))
    with pytest.raises(UntrustedContentError, match=rf"root\.contents\[0\]\.path: .* {kind}") as info:
        om.load(scene_file)
    assert "trusted=True" in str(info.value) and "--trusted" in info.value.cli_message
    loaded = om.load(scene_file, trusted=True)
    assert loaded.components[0].triangle_count == 1


def test_files_inside_the_folder_load_and_save_warns_about_outside_ones(outside):
    (outside / "scenes" / "meshes").mkdir()
    (outside / "scenes" / "meshes" / "m.obj").write_text(OBJ)
    inside = om.Node("s", [om.MeshFile(outside / "scenes" / "meshes" / "m.obj")])
    om.save(inside, outside / "scenes" / "in.json")
    assert om.load(outside / "scenes" / "in.json").components[0].path.endswith("meshes/m.obj")
    with pytest.warns(UserWarning, match="outside the file's folder.*trusted=True"):
        om.save(om.Node("s", [om.MeshFile(outside / "mesh.obj")]), outside / "scenes" / "out.json")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        om.save(inside, outside / "scenes" / "in2.json")  # nothing to warn about


# -- deep graphs -------------------------------------------------------------------------------------
def chain(levels: int) -> om.Node:
    node = om.Node("n0", [om.Sphere(radius=0.5)])
    for i in range(1, levels):
        node = om.Node(f"n{i}", [om.Translation(0.001, 0, 0), node])
    return node


def _depth(node: om.Node) -> int:
    depth = 0
    while node.children:
        node, depth = node.children[0], depth + 1
    return depth


def _nesting(value, depth: int = 0) -> int:
    if isinstance(value, dict):
        return max([depth] + [_nesting(v, depth + 1) for v in value.values()])
    if isinstance(value, list):
        return max([depth] + [_nesting(v, depth + 1) for v in value])
    return depth


@pytest.mark.parametrize("fmt", ["json", "yaml"])
def test_deep_graphs_are_written_as_shallow_definitions(fmt):
    root = chain(1000)
    text = files.dumps(root, fmt)
    data = json.loads(text) if fmt == "json" else __import__("yaml").safe_load(text)
    assert len(data["definitions"]) == 999 // 32
    assert _nesting(data) <= 2 * 32 + 12
    back = files.loads(text, fmt)
    assert _depth(back) == 999
    assert files.dumps(back, fmt) == text
    assert "definitions" not in files.dumps(chain(20))  # shallow graphs look as before


def test_definitions_keep_shared_nodes_shared():
    shared = chain(70)
    root = om.Node("root", [om.Node("a", [shared]), om.Node("b", [shared])])
    back = files.loads(files.dumps(root))
    assert back["/root/a"].children[0] is back["/root/b"].children[0]
    assert _depth(back["/root/a"].children[0]) == 69


@pytest.mark.slow
def test_100000_levels_save_and_load(tmp_path):
    root = chain(100_000)
    om.save(root, tmp_path / "deep.json")
    back = om.load(tmp_path / "deep.json")
    assert _depth(back) == 99_999 and back.name == "n99999"
    from omnirender.cli import _tree

    lines: list[str] = []
    _tree(back, lines, "", set(), "/n99999")  # the tree of ``omnirender info``
    assert len(lines) < 200 and "99960 node(s) from here down, not listed" in lines[-1]


# -- the schema -------------------------------------------------------------------------------------
SCHEMA_FILE = Path(__file__).resolve().parents[2] / "docs" / "scene-file.schema.json"


def test_the_checked_in_schema_is_the_generated_one():
    assert json.loads(SCHEMA_FILE.read_text()) == files.json_schema(), (
        "regenerate it: omnirender schema -o docs/scene-file.schema.json"
    )


def test_the_schema_validates_example_files_and_catches_mistakes():
    import jsonschema
    import yaml

    validator = jsonschema.Draft202012Validator(files.json_schema())
    root = Path(__file__).resolve().parents[2] / "examples" / "scenes"
    for name in ("demo.yaml", "demo.json", "features.yaml"):
        text = (root / name).read_text()
        data = json.loads(text) if name.endswith(".json") else yaml.safe_load(text)
        assert not list(validator.iter_errors(data)), name
    deep = json.loads(files.dumps(chain(100)))
    assert not list(validator.iter_errors(deep))
    bad = json.loads(doc({"type": "Sphere", "radus": 1}))
    assert list(validator.iter_errors(bad))
    assert list(validator.iter_errors(json.loads(doc({"type": "Spere"}))))
    assert list(validator.iter_errors(json.loads(doc({"type": "Sphere", "radius": "big"}))))
