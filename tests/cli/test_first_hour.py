"""A new user's first hour: exit codes, --trusted, mesh files, missing extras, lazy imports, the schema command."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from test_cli import run

import omnirender as om
from omnirender.cli import EXIT_CODES

OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\nf 1 2 3\nf 2 4 3\n"


def test_the_exit_codes_are_documented_in_help(capsys):
    code, out, _ = run(capsys, "--help")
    assert code == 0
    assert "exit codes: 0 success, 1 the work failed" in out and "2 bad command line" in out
    assert set(EXIT_CODES) == {0, 1, 2, 130}
    assert "exit codes" in sys.modules["omnirender.cli"].__doc__.lower()


@pytest.mark.parametrize(
    "args, code, words",
    [
        (["render", "{tmp}/missing.json"], 2, "scene file not found"),
        (["render", "{tmp}/scene.txt"], 2, "unknown extension '.txt'"),
        (["info", "{tmp}/missing.yaml"], 2, "scene file not found"),
        (["view", "{tmp}/missing.obj"], 2, "scene file not found"),
        (["export", "{tmp}/folder.json", "{tmp}/x.glb"], 2, "is a folder"),
        (["render", "{tmp}/bad.json"], 1, "invalid JSON"),
        (["info", "{tmp}/bad.json"], 1, "invalid JSON"),
    ],
)
def test_exit_codes_follow_the_docstring(capsys, tmp_path, args, code, words):
    (tmp_path / "scene.txt").write_text("{}")
    (tmp_path / "bad.json").write_text("{")
    (tmp_path / "folder.json").mkdir()
    got, _, err = run(capsys, *[a.format(tmp=tmp_path) for a in args])
    assert got == code, err
    assert words in err and err.count("\n") <= 2 and "Traceback" not in err


def test_trust_errors_name_the_command_line_flag(capsys, tmp_path):
    (tmp_path / "raw.json").write_text(
        json.dumps(
            {
                "format": "omnirender-scene",
                "version": 1,
                "root": {"node": "s", "contents": [{"type": "povray.Raw", "text": "// hi"}]},
            }
        )
    )
    code, _, err = run(capsys, "info", str(tmp_path / "raw.json"), "--no-engines")
    assert code == 1 and "--trusted" in err and "trusted=True" not in err
    code, out, err = run(capsys, "info", str(tmp_path / "raw.json"), "--no-engines", "--trusted")
    assert code == 0 and "Raw" in out


@pytest.mark.gl
def test_render_a_mesh_file_directly(capsys, tmp_path):
    mesh = tmp_path / "part.obj"
    mesh.write_text(OBJ)
    target = tmp_path / "part.png"
    code, out, err = run(capsys, "render", str(mesh), "-o", str(target), "--size", "96x72")
    assert code == 0, err
    from PIL import Image

    pixels = np.asarray(Image.open(target).convert("RGB")).astype(int)
    background = pixels[0, 0]
    covered = np.any(np.abs(pixels - background) > 10, axis=2)
    rows, cols = np.nonzero(covered)
    # the fitted camera shows the whole mesh, not touching the borders, filling a good part of the picture
    assert 0.05 < covered.mean() < 0.9
    assert rows.min() > 0 and cols.min() > 0 and rows.max() < 71 and cols.max() < 95


def test_a_scene_around_a_mesh_has_a_fitted_camera_and_lights(tmp_path):
    import trimesh

    from omnirender.scene.mesh_scene import mesh_scene

    mesh = tmp_path / "part.obj"
    mesh.write_text(OBJ)
    for source in (mesh, trimesh.creation.icosphere(radius=3.0)):
        scene = mesh_scene(source)
        lights, (camera, _) = scene.preevaluate()
        assert len(lights) == 3 and all(isinstance(light, om.DirectionalLight) for light, _ in lights)
        lo, hi = om.bounds(scene)
        centre = (lo + hi) / 2
        assert np.allclose(camera.center, centre)
        # every corner of the box projects inside the picture
        view, proj = camera.view_matrix(), camera.projection_matrix(4 / 3)
        for corner in np.array(np.meshgrid(*zip(lo, hi, strict=True))).T.reshape(-1, 3):
            clip = proj @ view @ np.append(corner, 1.0)
            assert np.all(np.abs(clip[:3] / clip[3]) <= 1.0)


def test_info_of_a_mesh_file(capsys, tmp_path):
    mesh = tmp_path / "part.obj"
    mesh.write_text(OBJ)
    code, out, err = run(capsys, "info", str(mesh), "--no-engines")
    assert code == 0, err
    assert "/scene/part" in out and "shapes: 1" in out


def test_schema_command_writes_the_schema(capsys, tmp_path):
    code, out, _ = run(capsys, "schema")
    assert code == 0 and json.loads(out)["title"] == "omnirender scene file"
    code, _, _ = run(capsys, "schema", "-o", str(tmp_path / "s.json"))
    assert code == 0 and "povray.Finish" in json.loads((tmp_path / "s.json").read_text())["$defs"]


# -- without extras: a fresh `pip install -e .` ---------------------------------------------------------
BLOCKER = textwrap.dedent(
    """
    import sys
    BLOCKED = {"moderngl", "PIL", "mitsuba", "drjit", "pyradiance", "trimesh", "yaml", "glfw", "tqdm", "scipy"}
    class _Block:
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in BLOCKED:
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return None
    sys.meta_path.insert(0, _Block())
    """
)


def _without_extras(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    (tmp_path / "site").mkdir(exist_ok=True)
    (tmp_path / "site" / "sitecustomize.py").write_text(BLOCKER)
    env = dict(os.environ, PYTHONPATH=str(tmp_path / "site"), PATH="/usr/bin:/bin")
    code = f"import sys; from omnirender.cli import main; sys.exit(main({list(args)!r}))"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=tmp_path,
                          timeout=120)  # fmt: skip


def test_engines_name_the_missing_packages_and_the_pip_command(tmp_path):
    proc = _without_extras(tmp_path, "engines")
    assert proc.returncode == 0, proc.stderr
    lines = {ln.split()[0]: ln for ln in proc.stdout.splitlines() if not ln.startswith("export")}
    assert "needs the Python packages moderngl, pillow: pip install 'omnirender[gl]'" in lines["gl"]
    assert "needs the Python package pillow: pip install 'omnirender[povray]'" in lines["povray"]
    assert "pip install 'omnirender[mitsuba]'" in lines["mitsuba"]
    assert "pip install 'omnirender[radiance]'" in lines["radiance"]


def test_demo_without_extras_says_what_it_skips_first_and_how_to_install_it(tmp_path):
    proc = _without_extras(tmp_path, "demo", "-o", "out")
    assert proc.returncode == 1, proc.stderr  # nothing could be rendered
    lines = proc.stdout.splitlines()
    assert lines[0] == "omnirender demo: rendering with no engine; skipped 4 of 4 engines:"
    assert lines[5] == "  install them with: pip install 'omnirender[gl,povray,mitsuba,radiance]'"
    assert "Traceback" not in proc.stderr


@pytest.mark.gl
def test_a_one_shot_gl_render_imports_no_heavy_library(tmp_path):
    (tmp_path / "m.obj").write_text(OBJ)  # a plain OBJ file: read without trimesh
    scene = om.Node("s", [om.Camera.look_at(eye=(0, 0, 3)), om.TriangleSet([(0, 0, 0), (1, 0, 0), (0, 1, 0)])])
    scene.add(om.Node("mesh", [om.MeshFile(tmp_path / "m.obj")]))
    om.save(scene, tmp_path / "s.json")
    code = textwrap.dedent(
        f"""
        import sys
        from omnirender.cli import main
        assert main(["render", {str(tmp_path / "s.json")!r}, "-e", "gl", "-o", {str(tmp_path / "o.png")!r},
                     "--size", "32x24"]) == 0
        heavy = {{"trimesh", "scipy", "mitsuba", "drjit", "pyradiance", "skimage", "dask", "imageio"}}
        print(sorted(m for m in sys.modules if m.split(".")[0] in heavy))
        """
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[-1] == "[]"
