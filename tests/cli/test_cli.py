"""The omnirender command end to end on a scene file."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import omnirender as om
from omnirender.cli import main


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_help_lists_every_command(capsys):
    code, out, _ = run(capsys, "--help")
    assert code == 0
    for command in ("render", "view", "export", "info", "engines", "demo"):
        assert command in out
    code, out, _ = run(capsys, "render", "--help")
    assert code == 0 and "--spp" in out and "--mask" in out and "WxH" in out


@pytest.mark.parametrize(
    "argv, message",
    [
        ([], "required"),
        (["paint", "x"], "invalid choice"),
        (["render", "SCENE", "--size", "big"], "WIDTHxHEIGHT"),
        (["render", "SCENE", "--spp", "0"], "positive"),
        (["render", "missing.json"], "not found"),
        (["render", "SCENE", "-e", "blender"], "unknown engine"),
        (["render", "SCENE", "--mask", "a &"], "bad --mask"),
        (["export", "SCENE", "out.xyz"], "cannot export"),
        (["render", "SCENE", "-o", "out.xyz"], "cannot write an image"),
        (["render", "SCENE", "-e", "povray", "-o", "x.bmpx"], "cannot write an image"),
        (["info", "missing.yaml"], "not found"),
    ],
)
def test_usage_errors_exit_2(capsys, scene_file, argv, message):
    argv = [str(scene_file) if a == "SCENE" else a for a in argv]
    code, _, err = run(capsys, *argv)
    assert code == 2
    assert message in err


def test_engines_lists_engines_and_exporters(capsys):
    code, out, _ = run(capsys, "engines")
    assert code == 0
    for name in ("gl", "povray", "mitsuba", "radiance", ".glb", ".pov", ".rib", ".rad"):
        assert name in out


def test_info_prints_tree_statistics_bounds_and_engines(capsys, scene_file):
    code, out, _ = run(capsys, "info", str(scene_file))
    assert code == 0, out
    assert "/scene/body" in out and "/scene/marker  groups=['debug']" in out
    assert "Sphere(" in out and "statistics:" in out
    line = next(ln for ln in out.splitlines() if ln.startswith("bounds:"))
    assert "min (-3, -0.1, -3)" in line and "max (3, 1.8, 3)" in line
    assert "engines:" in out and "povray" in out
    assert "can render it" in out


def test_loading_errors_exit_1_with_one_line(capsys, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": '
                   '[{"type": "Sphere", "radius": -1}]}}')  # fmt: skip
    code, _, err = run(capsys, "info", str(bad))
    assert code == 1
    assert len(err.strip().splitlines()) == 1 and "radius" in err and "Traceback" not in err
    with pytest.raises(ValueError, match="radius"):
        main(["--debug", "info", str(bad)])


@pytest.mark.povray
def test_render_with_povray_and_mask(capsys, scene_file, tmp_path):
    out_all = tmp_path / "all.png"
    out_masked = tmp_path / "masked.png"
    code, out, err = run(capsys, "render", str(scene_file), "-e", "povray", "-o", str(out_all), "--size", "80x60")
    assert code == 0, err
    assert out.strip() == str(out_all)
    code, _, err = run(capsys, "render", str(scene_file), "-e", "povray", "-o", str(out_masked), "--size", "80x60",
                       "--mask", "!debug")  # fmt: skip
    assert code == 0, err
    from PIL import Image

    full = np.asarray(Image.open(out_all).convert("RGB")).astype(int)
    masked = np.asarray(Image.open(out_masked).convert("RGB")).astype(int)
    assert full.shape == (60, 80, 3) and full.std() > 5  # not blank
    green = (full[:, :, 1] > full[:, :, 0] + 60).sum()
    assert green > 10 and (masked[:, :, 1] > masked[:, :, 0] + 60).sum() == 0  # the debug box is gone


@pytest.mark.povray
def test_export_pov_end_to_end(capsys, scene_file, tmp_path):
    target = tmp_path / "scene.pov"
    code, out, err = run(capsys, "export", str(scene_file), str(target))
    assert code == 0, err
    text = target.read_text()
    assert "camera" in text and "sphere" in text


@pytest.mark.slow
def test_console_entry_point_runs_as_a_process(scene_file):
    result = subprocess.run(
        [sys.executable, "-m", "omnirender.cli", "info", str(scene_file), "--no-engines"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert "/scene/floor" in result.stdout
    result = subprocess.run([sys.executable, "-m", "omnirender.cli", "render"], capture_output=True, text=True)
    assert result.returncode == 2 and "usage" in result.stderr


@pytest.mark.gl
def test_render_with_gl_size_spp_and_mask(capsys, scene_file, tmp_path):
    from PIL import Image

    target = tmp_path / "gl.png"
    code, out, err = run(capsys, "render", str(scene_file), "-o", str(target), "--size", "120x90", "--spp", "4")
    assert code == 0, err
    img = np.asarray(Image.open(target).convert("RGB")).astype(int)
    assert img.shape == (90, 120, 3)
    red = (img[:, :, 0] > img[:, :, 1] + 60).sum()
    green = (img[:, :, 1] > img[:, :, 0] + 60).sum()
    assert red > 100 and green > 10
    masked = tmp_path / "masked.png"
    code, _, err = run(capsys, "render", str(scene_file), "-o", str(masked), "--size", "120x90", "--mask", "!debug")
    assert code == 0, err
    img = np.asarray(Image.open(masked).convert("RGB")).astype(int)
    assert (img[:, :, 1] > img[:, :, 0] + 60).sum() == 0


@pytest.mark.gl
def test_default_output_name_and_info_engines(capsys, scene_file, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "render", str(scene_file), "--size", "40x30")
    assert code == 0, err
    assert (tmp_path / "scene-gl.png").is_file() and out.strip() == "scene-gl.png"
    code, out, _ = run(capsys, "info", str(scene_file))
    gl_line = next(ln for ln in out.splitlines() if ln.strip().startswith("gl "))
    assert "can render it" in gl_line


def test_export_glb_and_rib(capsys, scene_file, tmp_path):
    for ext, magic in ((".glb", b"glTF"), (".rib", None)):
        target = tmp_path / f"scene{ext}"
        code, out, err = run(capsys, "export", str(scene_file), str(target))
        assert code == 0, err
        data = target.read_bytes()
        assert len(data) > 100
        if magic:
            assert data.startswith(magic)


def test_rendering_error_exits_1_without_traceback(capsys, tmp_path, monkeypatch):
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 0, 5)))
    scene.add(om.Sphere())
    path = tmp_path / "ok.json"
    om.save(scene, path)
    monkeypatch.setenv("PATH", str(tmp_path))  # no povray program on the PATH
    code, _, err = run(capsys, "render", str(path), "-e", "povray", "--size", "20x20", "-o", str(tmp_path / "x.png"))
    assert code == 1
    assert err.count("\n") == 1 and "Traceback" not in err and "povray program was not found" in err
    assert "apt-get install povray" in err
    assert not (tmp_path / "x.png").exists()


def test_engines_says_why_an_engine_is_unavailable(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))  # an empty PATH: no povray program
    code, out, _ = run(capsys, "engines")
    assert code == 0
    line = next(ln for ln in out.splitlines() if ln.startswith("povray"))
    assert "unavailable" in line and "povray program is not installed" in line


def test_debug_is_accepted_after_the_command_and_usage_errors_still_exit_2(capsys, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": '
                   '[{"type": "Sphere", "radius": -1}]}}')  # fmt: skip
    with pytest.raises(ValueError, match="radius"):
        main(["info", str(bad), "--debug"])
    for argv in (["--debug", "render", "missing.json"], ["render", "missing.json", "--debug"]):
        code, _, err = run(capsys, *argv)
        assert code == 2 and "not found" in err and "Traceback" in err  # the traceback is allowed with --debug
    code, _, err = run(capsys, "render", "missing.json")
    assert code == 2 and "Traceback" not in err


def test_info_builds_the_path_of_every_instance_of_a_shared_node(capsys, tmp_path):
    wheel = om.Node("wheel", [om.Cylinder(radius=0.5, height=0.2)])
    scene = om.Node("car")
    scene.add(om.Node("left", [om.Translation(-2, 0, 0), wheel]))
    scene.add(om.Node("right", [om.Translation(2, 0, 0), wheel]))
    path = tmp_path / "car.json"
    om.save(scene, path)
    code, out, _ = run(capsys, "info", str(path), "--no-engines")
    assert code == 0
    tree = out.split("statistics:")[0]
    assert "/car/left/wheel\n" in tree
    assert "/car/right/wheel  (shared, listed above)" in tree


@pytest.mark.gl
def test_gl_spp_becomes_a_power_of_two(capsys, scene_file, tmp_path):
    from omnirender.cli import _msaa_samples

    target = tmp_path / "gl3.png"
    code, out, err = run(capsys, "render", str(scene_file), "-o", str(target), "--size", "40x30", "--spp", "3")
    assert code == 0, err
    assert target.is_file() and "uses 2 MSAA samples" in err
    assert [_msaa_samples(n) for n in (1, 2, 3, 4, 7, 8, 9)] == [0, 2, 2, 4, 4, 8, 8]


@pytest.mark.mitsuba
def test_render_with_mitsuba_and_spp(capsys, scene_file, tmp_path):
    from PIL import Image

    target = tmp_path / "mi.png"
    code, out, err = run(capsys, "render", str(scene_file), "-e", "mitsuba", "--spp", "4", "-o", str(target),
                         "--size", "32x24")  # fmt: skip
    assert code == 0, err
    assert out.strip() == str(target)
    img = np.asarray(Image.open(target).convert("RGB")).astype(int)
    assert img.shape == (24, 32, 3) and img.std() > 5  # not blank
    assert (img[:, :, 0] > img[:, :, 1] + 40).sum() > 5  # the red sphere


def test_engines_and_demo_explain_a_missing_radiance(capsys, tmp_path, monkeypatch):
    import omnirender.demo
    from omnirender.radiance import runner

    monkeypatch.setattr(runner, "radiance_paths", lambda: None)  # as if pyradiance were not installed
    code, out, _ = run(capsys, "engines")
    line = next(ln for ln in out.splitlines() if ln.startswith("radiance"))
    assert code == 0 and "unavailable" in line and "pip install 'omnirender[radiance]'" in line
    only_radiance = {"radiance": om.engines()["radiance"]}
    monkeypatch.setattr(omnirender.demo.om, "engines", lambda: only_radiance)
    code, out, _ = run(capsys, "demo", "-o", str(tmp_path / "demo"), "--size", "16x12")
    assert code == 1  # nothing could be rendered
    first, second = out.splitlines()[:2]  # said first, before any work
    assert first == "omnirender demo: rendering with no engine; skipped 1 of 1 engines:"
    assert second.split()[0] == "radiance" and "pip install 'omnirender[radiance]'" in second
    assert list((tmp_path / "demo").iterdir()) == []


@pytest.mark.radiance
def test_render_with_radiance_and_spp(capsys, scene_file, tmp_path):
    target = tmp_path / "rad.png"
    code, out, err = run(capsys, "render", str(scene_file), "-e", "radiance", "--spp", "4", "-o", str(target),
                         "--size", "32x24")  # fmt: skip
    assert code == 0, err
    from PIL import Image as PILImage

    img = np.asarray(PILImage.open(target).convert("RGB"))
    assert img.shape == (24, 32, 3) and img.std() > 5  # not blank (rendered 2 x 2 rays per pixel)


@pytest.mark.slow
@pytest.mark.gl
def test_demo_command_still_works(capsys, tmp_path):
    code, out, err = run(capsys, "demo", "-o", str(tmp_path / "demo"), "--size", "64x48")
    assert code == 0, err
    assert (tmp_path / "demo" / "demo-gl.png").is_file()


@pytest.mark.povray
def test_trusted_flag_allows_raw_sdl(tmp_path, capsys):
    scene = tmp_path / "raw.json"
    scene.write_text(
        '{"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": ['
        '{"type": "Camera", "eye": [0, 0, 5], "center": [0, 0, 0]},'
        '{"type": "povray.Raw", "text": "sphere { <0,0,0>, 1 pigment { rgb <1,0,0> } }"}]}}'
    )
    out = tmp_path / "raw.png"
    assert main(["render", str(scene), "-e", "povray", "-o", str(out), "--size", "32x24"]) == 1
    assert "trusted-only" in capsys.readouterr().err and not out.exists()
    assert main(["render", str(scene), "-e", "povray", "-o", str(out), "--size", "32x24", "--trusted"]) == 0
    assert out.exists()
