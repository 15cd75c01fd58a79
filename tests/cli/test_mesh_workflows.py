"""Mesh files through every command (render, animate --turntable, export), demo -e, help texts, "did you mean"."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_cli import run

from omnirender.cli import build_parser

OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\nf 1 2 3\nf 2 4 3\n"


def _help(*command: str) -> str:
    parser = build_parser()
    if not command:
        return parser.format_help()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    return sub.choices[command[0]].format_help()


def test_help_texts_list_every_engine_and_exporter():
    from omnirender.render import _engines, exporters

    for command in ("render", "animate", "demo"):
        text = " ".join(_help(command).split())
        assert all(name in text for name in _engines), command
    text = " ".join(_help("export").split())
    assert all(ext in text for ext in exporters())
    assert all(ext in _help() for ext in (".rad", ".html"))


def test_trusted_is_offered_only_where_a_scene_file_is_read():
    for command in ("render", "animate", "view", "export", "info"):
        assert "--trusted" in _help(command), command
    for command in ("schema", "engines", "demo"):
        assert "--trusted" not in _help(command), command


@pytest.mark.parametrize(
    "argv, words",
    [
        (["render", "SCENE", "-e", "mitsba"], "did you mean 'mitsuba'?"),
        (["demo", "-e", "gl", "povary"], "did you mean 'povray'?"),
        (["render", "SCENE", "-e", "gl", "--quality", "final"], "--quality is an option of the mitsuba engine"),
    ],
)
def test_command_line_mistakes_are_explained(capsys, scene_file, argv, words):
    code, _, err = run(capsys, *[str(scene_file) if a == "SCENE" else a for a in argv])
    assert code == 2 and words in err


@pytest.mark.gl
def test_animate_turns_a_mesh_file_on_a_turntable(capsys, tmp_path):
    mesh = tmp_path / "part.obj"
    mesh.write_text(OBJ)
    pattern = tmp_path / "spin" / "%03d.png"
    code, _, err = run(
        capsys, "animate", str(mesh), "--turntable", "--fps", "2", "--frames", "0,5", "--size", "64x48",
        "--workers", "0", "-q", "-o", str(pattern),
    )  # fmt: skip
    assert code == 0, err
    from PIL import Image

    first, later = (np.asarray(Image.open(tmp_path / "spin" / f"{n:03d}.png"), dtype=int) for n in (0, 5))
    assert np.abs(first - later).mean() > 1  # the mesh turned (5 of 10 frames: half a turn)
    args = build_parser().parse_args(["animate", str(mesh), "--turntable"])
    assert args.turntable == 5.0  # --turntable alone: five seconds


@pytest.mark.gl
def test_demo_renders_with_the_chosen_engines_only(capsys, tmp_path):
    code, out, err = run(capsys, "demo", "-e", "gl", "-o", str(tmp_path), "--size", "64x48")
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo-gl.png"]
    assert out.startswith("omnirender demo: rendering with gl (every engine)")


@pytest.mark.mitsuba
@pytest.mark.radiance
def test_path_tracers_render_a_mesh_file_without_warnings_about_lights_the_command_made(capsys, tmp_path):
    mesh = tmp_path / "part.obj"
    mesh.write_text(OBJ)
    for engine, extra in (("mitsuba", ["--spp", "2"]), ("radiance", [])):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            code, _, err = run(
                capsys, "render", str(mesh), "-e", engine, "--size", "32x24", "-o", str(tmp_path / "m.png"), *extra
            )
        assert code == 0 and "casts_shadows" not in err, err


@pytest.mark.parametrize("ext", [".obj", ".ply", ".stl"])
def test_export_writes_mesh_files_that_read_back(capsys, tmp_path, ext):
    import trimesh

    import omnirender as om

    scene = om.Node("s", [om.Camera.look_at((0, 0, 5))])
    scene.add(om.Node("a", [om.Translation(2, 0, 0), om.Box(size=1)]))
    scene.add(om.Node("b", [om.Sphere(radius=0.5)]))
    om.save(scene, tmp_path / "s.json")
    target = tmp_path / f"out{ext}"
    code, out, err = run(capsys, "export", str(tmp_path / "s.json"), str(target))
    assert code == 0, err
    mesh = trimesh.load(target, force="mesh")
    lo, hi = om.bounds(scene)
    assert np.allclose(mesh.bounds, [lo, hi], atol=0.02)  # both shapes, in world coordinates
    assert len(mesh.faces) > 12
