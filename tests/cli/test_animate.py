"""omnirender animate: frames and a video from a scene file, resume, and usage errors."""

from __future__ import annotations

from pathlib import Path

import pytest

import omnirender as om
from omnirender.cli import main


def _scene_file(path: Path, animated: bool) -> Path:
    """The scene file of conftest.py, with the red ball moving from left to right in half a second."""
    if not animated:
        return path
    scene = om.load(path)
    move = scene["/scene/body"].components[0]
    scene.add(om.Animation([om.Keyframes(move, "offset", [0, 0.5], [(-1, 1, 0), (1, 1, 0)])], fps=6))
    out = path.with_name("anim.yaml")
    om.save(scene, out)
    return out


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.gl
def test_animate_a_scene_file_into_a_gif_and_resume(tmp_path, capsys, scene_file):
    scene = _scene_file(scene_file, animated=True)
    out = tmp_path / "out" / "anim.gif"
    code, stdout, stderr = run(capsys, "animate", str(scene), "-o", str(out), "--size", "64x48", "--workers", "0")
    assert code == 0, stderr
    assert stdout.strip() == str(out) and "frames: 3 written" in stderr
    from PIL import Image

    with Image.open(out) as gif:
        assert gif.n_frames == 3 and gif.size == (64, 48)
    frames = sorted((tmp_path / "out" / "anim-frames").iterdir())
    assert [p.name for p in frames] == ["00000.png", "00001.png", "00002.png"]
    frames[1].unlink()
    code, _, stderr = run(capsys, "animate", str(scene), "-o", str(out), "--size", "64x48", "--workers", "0", "-q")
    assert code == 0 and "frames: 1 written, 2 already there" in stderr


@pytest.mark.gl
def test_turntable_frames_only(tmp_path, capsys, scene_file):
    scene = _scene_file(scene_file, animated=False)
    pattern = tmp_path / "spin" / "f%03d.png"
    code, stdout, stderr = run(
        capsys, "animate", str(scene), "--turntable", "1", "--fps", "4", "--frames", "0-3:2", "-o", str(pattern),
        "--size", "48x36", "--workers", "0",
    )  # fmt: skip
    assert code == 0, stderr
    assert sorted(p.name for p in (tmp_path / "spin").iterdir()) == ["f000.png", "f002.png"]


@pytest.mark.parametrize(
    "extra, message",
    [
        ([], "holds no animation; add an om.Animation or use --turntable"),
        (["--frames", "9-2"], "not an increasing range"),
        (["-o", "x.avi"], "use a video"),
        (["--workers", "2", "--scheduler", "tcp://h:1"], "either --workers"),
        (["-e", "blender"], "unknown engine"),
        (["--fps", "0"], "positive number"),
    ],
)
def test_usage_errors(tmp_path, capsys, extra, message, scene_file):
    scene = _scene_file(scene_file, animated=False)
    code, _, err = run(capsys, "animate", str(scene), *extra)
    assert code == 2 and message in err


def test_help_lists_animate(capsys):
    code, out, _ = run(capsys, "--help")
    assert code == 0 and "animate" in out
    code, out, _ = run(capsys, "animate", "--help")
    assert code == 0 and "--scheduler" in out and "--turntable" in out and "--frames" in out
