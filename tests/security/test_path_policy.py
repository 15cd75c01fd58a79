"""The one path policy (omnirender.core.paths), the decoded-size limits (core.limits) and no silent drops."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender.core import limits
from omnirender.core.paths import PathPolicy, RemoteReferenceError, UntrustedReferenceError, resolve_reference


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    (tmp_path / "models" / "tex").mkdir(parents=True)
    (tmp_path / "shared").mkdir()
    (tmp_path / "models" / "tex" / "a.png").write_bytes(b"x")
    (tmp_path / "shared" / "b.png").write_bytes(b"x")
    (tmp_path / "secret").write_bytes(b"x")
    return tmp_path


def test_references_inside_the_folder_resolve(tree):
    referrer = tree / "models" / "m.gltf"
    assert resolve_reference("tex/a.png", referrer) == tree / "models" / "tex" / "a.png"
    assert resolve_reference("tex/../tex/a.png", referrer) == tree / "models" / "tex" / "a.png"
    assert resolve_reference("tex\\a.png", referrer) == tree / "models" / "tex" / "a.png"  # written on Windows
    assert resolve_reference("tex/a%20b.png", referrer, uri=True).name == "a b.png"


@pytest.mark.parametrize(
    "reference, words",
    [
        ("../secret", "leads outside"),
        ("tex/../../secret", "leads outside"),
        ("..\\secret", "leads outside"),
        ("/etc/passwd", "is an absolute path"),
        ("C:\\Windows\\win.ini", "is an absolute path"),
        ("\\\\host\\share\\x", "is an absolute path"),
        ("file:///etc/passwd", "is an absolute path"),
        ("", "empty file name"),
        ("a\x00b", "NUL"),
    ],
)
def test_references_outside_are_refused_naming_the_file_the_reference_and_the_fix(tree, reference, words):
    referrer = tree / "models" / "m.gltf"
    with pytest.raises(UntrustedReferenceError, match=words) as info:
        resolve_reference(reference, referrer, "images[0].uri")
    text = str(info.value)
    assert str(referrer) in text and "trusted=True" in text and "allowed_roots" in text
    assert "--trusted" in info.value.cli_message
    assert isinstance(info.value, ValueError)


def test_percent_escapes_cannot_hide_a_traversal(tree):
    with pytest.raises(UntrustedReferenceError, match="leads outside"):
        resolve_reference("%2e%2e/secret", tree / "models" / "m.gltf", uri=True)
    # without uri=True the escapes are a file name, and that file is inside the folder
    assert resolve_reference("%2e%2e/secret", tree / "models" / "m.gltf").parent.name == "%2e%2e"


def test_symbolic_links_out_of_the_folder_are_refused(tree):
    os.symlink(tree / "secret", tree / "models" / "link")
    os.symlink(tree / "shared", tree / "models" / "linkdir")
    for reference in ("link", "linkdir/b.png"):
        with pytest.raises(UntrustedReferenceError, match="symbolic link leading outside"):
            resolve_reference(reference, tree / "models" / "m.obj")
    os.symlink(tree / "models" / "tex" / "a.png", tree / "models" / "inside")
    assert resolve_reference("inside", tree / "models" / "m.obj").name == "inside"  # a link that stays inside


def test_urls_are_never_fetched_even_when_trusted(tree):
    for url in ("http://example.com/x.png", "HTTPS://example.com/x", "ftp://x/y", "file://evil/etc/passwd"):
        with pytest.raises(RemoteReferenceError, match="download|copy it"):
            resolve_reference(url, tree / "m.gltf", trusted=True)


def test_trusted_and_allowed_roots_lift_the_rule(tree):
    referrer = tree / "models" / "m.gltf"
    assert resolve_reference("../secret", referrer, trusted=True) == tree / "secret"
    assert resolve_reference("/etc/passwd", referrer, trusted=True) == Path("/etc/passwd")
    assert resolve_reference("../shared/b.png", referrer, allowed_roots=[tree / "shared"]) == tree / "shared" / "b.png"
    assert resolve_reference(str(tree / "shared" / "b.png"), referrer, allowed_roots=[tree / "shared"]).exists()
    with pytest.raises(UntrustedReferenceError):
        resolve_reference("../secret", referrer, allowed_roots=[tree / "shared"])
    policy = PathPolicy.of(allowed_roots=[tree / "shared"])
    assert policy.allowed_roots == (os.path.realpath(tree / "shared"),)
    with pytest.raises(TypeError, match="allowed_roots"):
        PathPolicy.of(allowed_roots=[3])


def test_an_obj_file_reads_its_material_library_under_the_policy(tree):
    obj = "mtllib ../shared/m.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    (tree / "shared" / "m.mtl").write_text("newmtl m\nKd 1 0 0\n")
    (tree / "models" / "m.obj").write_text(obj)
    with pytest.raises(om.UntrustedReferenceError, match="the material library '../shared/m.mtl' leads outside"):
        om.MeshFile(tree / "models" / "m.obj").load()
    for mesh in (om.MeshFile(tree / "models" / "m.obj", allowed_roots=[tree / "shared"]),
                 om.MeshFile(tree / "models" / "m.obj", trusted=True)):  # fmt: skip
        material, _ = mesh.parts()[0]
        assert material["diffuse"] == pytest.approx((1.0, 0.0, 0.0))


def test_a_scene_file_passes_its_policy_to_the_mesh_files_it_names(tree):
    (tree / "shared" / "m.mtl").write_text("newmtl m\nKd 1 0 0\n")
    (tree / "models" / "m.obj").write_text("mtllib ../shared/m.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    doc = '{"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": [%s]}}'
    (tree / "s.json").write_text(doc % '{"type": "MeshFile", "path": "models/m.obj"}')
    material, _ = om.load(tree / "s.json").components[0].parts()[0]  # the mtl is inside the scene's folder
    assert material["diffuse"] == pytest.approx((1.0, 0.0, 0.0))
    (tree / "models" / "s.json").write_text(doc % '{"type": "MeshFile", "path": "m.obj"}')
    with pytest.raises(om.UntrustedReferenceError, match="leads outside"):
        om.load(tree / "models" / "s.json").components[0].load()
    loaded = om.load(tree / "models" / "s.json", allowed_roots=[tree / "shared"]).components[0]
    assert loaded.parts()[0][0]["diffuse"] == pytest.approx((1.0, 0.0, 0.0))
    (tree / "models" / "t.json").write_text(doc % '{"type": "MeshFile", "path": "m.obj", "trusted": true}')
    with pytest.raises(om.SceneFileError if hasattr(om, "SceneFileError") else ValueError, match="trusted"):
        om.load(tree / "models" / "t.json")


def test_the_cli_has_the_same_rule(tree, capsys):
    from omnirender.cli import main

    (tree / "models" / "m.obj").write_text("mtllib ../shared/m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (tree / "shared" / "m.mtl").write_text("newmtl m\nKd 1 0 0\n")
    assert main(["info", str(tree / "models" / "m.obj")]) != 0
    assert "--trusted" in capsys.readouterr().err
    assert main(["info", str(tree / "models" / "m.obj"), "--allowed-root", str(tree / "shared")]) == 0
    assert main(["info", str(tree / "models" / "m.obj"), "--trusted"]) == 0


# -- limits -------------------------------------------------------------------------------------------
def test_image_limits_name_the_file_and_the_limit():
    limits.check_image_size("f.png", "it", 8192, 8192)
    with pytest.raises(om.ResourceLimitError, match=r"f\.png: it is 30000x30000 .*MAX_IMAGE_PIXELS"):
        limits.check_image_size("f.png", "it", 30000, 30000)
    with pytest.raises(om.ResourceLimitError, match="MAX_IMAGE_SIDE"):
        limits.check_image_size("f.png", "it", 40000, 1)
    with pytest.raises(om.ResourceLimitError, match="MAX_VERTICES"):
        limits.check_count("m.ply", "the header", 2**40)
    with pytest.raises(om.ResourceLimitError, match="MAX_NESTING"):
        limits.check_nesting("m.gltf", "nodes[3]", 10_000)


def test_a_texture_file_beyond_the_limits_is_refused_before_decoding(tmp_path, monkeypatch):
    from PIL import Image

    Image.new("RGB", (64, 32)).save(tmp_path / "t.png")
    assert om.Texture(str(tmp_path / "t.png")).image_array().shape == (32, 64, 4)
    monkeypatch.setattr(limits, "MAX_IMAGE_PIXELS", 1000)
    with pytest.raises(om.ResourceLimitError, match=r"t\.png.*64x32 = 2,048 pixels.*MAX_IMAGE_PIXELS"):
        om.Texture(str(tmp_path / "t.png")).image_array()


# -- drops ----------------------------------------------------------------------------------------------
def test_report_drop_warns_or_raises_when_strict():
    from omnirender.core.drops import report_drop

    with pytest.warns(om.DroppedContentWarning, match="f.obj: texture 'x' dropped"):
        report_drop("f.obj", "texture 'x' dropped")
    with pytest.raises(om.DroppedContentError, match="strict=True"):
        report_drop("f.obj", "texture 'x' dropped", strict=True)


def test_a_texture_without_texture_coordinates_is_reported(tmp_path):
    (tmp_path / "ok.png").write_bytes((Path(__file__).parents[1] / "data_files" / "checker.png").read_bytes())
    (tmp_path / "m.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd ok.png\n")
    (tmp_path / "m.obj").write_text("mtllib m.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        om.MeshFile(tmp_path / "m.obj").load()
    assert any("no texture coordinates" in str(w.message) for w in caught), [str(w.message) for w in caught]


# -- values that passed silently ----------------------------------------------------------------------------
def test_bad_values_that_used_to_pass_silently_are_refused():
    with pytest.raises(ValueError, match=r"point_size must be <= 4096"):
        om.DrawStyle(point_size=1e9)
    with pytest.raises(ValueError, match=r"line_width must be <= 4096"):
        om.DrawStyle(line_width=1e6)
    assert om.DrawStyle(point_size=64).point_size == 64
    with pytest.raises(ValueError, match=r"Sphere: center must be a flat list of 3 numbers.*shape \(1, 3\)"):
        om.Sphere(center=[[1, 2, 3]])
    with pytest.raises(ValueError, match=r"Box: center must be a flat list"):
        om.Box(center=np.zeros((3, 1)))
    with pytest.raises(ValueError, match=r"Torus: minor_radius \(1.0\) must not exceed major_radius \(0.2\)"):
        om.Torus(major_radius=0.2, minor_radius=1)
    assert om.Torus(major_radius=1, minor_radius=1).minor_radius == 1.0  # a horn torus closes its hole


def test_an_empty_scene_warns():
    camera = om.Camera.look_at((0, 0, 5))
    with pytest.warns(UserWarning, match="the scene holds no shapes"):
        om.render(om.Node("s", [camera, om.Node("empty")]), size=(16, 16))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        om.render(om.Node("s", [camera, om.Node("a", [om.Sphere()])]), size=(16, 16))
