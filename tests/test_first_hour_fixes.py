"""What a new user met in the first hour: warnings, dir(om), the main guard, "did you mean", Mitsuba's preview."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import omnirender as om


def test_dir_lists_the_lazily_imported_names():
    names = dir(om)
    for name in ("gl", "mitsuba", "Viewer", "view", "load_gltf", "render_frames", "render", "Sphere"):
        assert name in names, name
    assert names == sorted(names)


def _python(code: str, *flags: str, env: dict | None = None, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, *flags, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=300,
        env=env, cwd=cwd,
    )  # fmt: skip


@pytest.mark.povray
@pytest.mark.radiance
def test_offline_engines_leave_no_file_unclosed():
    proc = _python(
        """
        import gc, omnirender as om
        scene = om.Node("s", [om.Camera.look_at((0, 0, 5)), om.PointLight(position=(2, 3, 4)), om.Sphere()])
        om.render(scene, engine="povray", size=(32, 24))
        om.render(scene, engine="radiance", size=(32, 24))
        gc.collect()
        print("rendered")
        """,
        "-X", "dev", "-W", "error::ResourceWarning",
    )  # fmt: skip
    assert proc.returncode == 0 and "rendered" in proc.stdout, proc.stderr
    assert "ResourceWarning" not in proc.stderr, proc.stderr


@pytest.mark.gl
def test_a_window_without_a_display_is_one_clear_message(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    scene = tmp_path / "s.json"
    om.save(om.Node("s", [om.Sphere()]), scene)
    proc = _python(f"from omnirender.cli import main; raise SystemExit(main(['view', {str(scene)!r}]))", env=env)
    assert proc.returncode == 1
    assert "GLFWError" not in proc.stderr and "Warning" not in proc.stderr, proc.stderr
    assert "glfw cannot initialise (" in proc.stderr and "Xvfb" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


SCRIPT = """
import omnirender as om
from omnirender.animation.mainguard import check_main_guard

def render():
    check_main_guard("om.render_frames(workers=2)")

{body}
print("passed")
"""


@pytest.mark.parametrize(
    "body, passes",
    [
        ("render()", False),
        ('if __name__ == "__main__":\n    render()', True),
        ('if "__main__" == __name__:\n    for _ in range(1):\n        render()', True),
        ('if __name__ != "__main__":\n    pass\nelse:\n    render()', False),  # conservative: only the plain guard
    ],
)
def test_worker_processes_need_the_main_guard_and_the_message_says_so(tmp_path, body, passes):
    script = tmp_path / "script.py"
    script.write_text(SCRIPT.format(body=body))
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    if passes:
        assert proc.returncode == 0 and "passed" in proc.stdout, proc.stderr
    else:
        assert proc.returncode == 1 and "MainGuardError" in proc.stderr
        assert 'if __name__ == "__main__":' in proc.stderr and "workers=0" in proc.stderr
        assert f"{script} again" in proc.stderr and "line" in proc.stderr


def test_render_frames_refuses_before_starting_any_process(tmp_path):
    script = tmp_path / "frames.py"
    script.write_text(
        "import omnirender as om\n"
        "scene = om.Node('s', [om.Camera.look_at((0, 0, 5)), om.Sphere()])\n"
        "scene.add(om.Animation(fps=2)).add(om.orbit(scene.components[0], seconds=1))\n"
        "om.render_frames(scene, range(2), engine='gl', size=(16, 12), out='f/%03d.png', workers=2)\n"
    )
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 1 and "MainGuardError" in proc.stderr
    assert "bootstrapping" not in proc.stderr and not list(tmp_path.glob("f/*.png"))


@pytest.mark.parametrize(
    "engine, option, hint",
    [
        ("gl", "sampels", "did you mean 'samples' for 'sampels'?"),
        ("povray", "qualty", "did you mean 'quality' for 'qualty'?"),
        ("radiance", "oversampel", "did you mean 'oversample' for 'oversampel'?"),
    ],
)
def test_unknown_options_suggest_the_closest(engine, option, hint):
    if not om.engines()[engine][0]:
        pytest.skip(f"{engine} is not available")
    with pytest.raises(TypeError, match=hint):
        om.render(om.Node("s", [om.Sphere()]), engine=engine, size=(8, 6), **{option: 1})
    with pytest.raises(ValueError, match="did you mean 'mitsuba'"):
        om.render(om.Node("s", [om.Sphere()]), engine="mitsba")


@pytest.mark.parametrize(
    "component, words",
    [
        ({"type": "Sphre", "radius": 1}, "unknown type 'Sphre' - did you mean 'Sphere'?"),
        ({"type": "Sphere", "radus": 1}, "has no parameter 'radus' - did you mean 'radius'?"),
        ({"type": "povray.Finsh"}, "defines no component 'Finsh'; did you mean 'Finish'?"),
    ],
)
def test_scene_files_suggest_the_closest_name(component, words):
    from omnirender.scene import files

    text = json.dumps({"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": [component]}})
    with pytest.raises(files.SceneFileError) as info:
        files.loads(text)
    assert words in str(info.value)


# -- Mitsuba: a fast, clean preview by default, final quality on request ---------------------------------
def _psnr(a: np.ndarray, b: np.ndarray) -> float:
    diff = a[..., :3].astype(np.float64) - b[..., :3].astype(np.float64)
    return 10 * np.log10(255.0**2 / max(float(np.mean(diff * diff)), 1e-12))


@pytest.mark.mitsuba
@pytest.mark.slow
def test_the_mitsuba_preview_is_denoised_and_close_to_a_converged_render():
    from omnirender.demo import demo_scene
    from omnirender.mitsuba import rendering

    pytest.importorskip("pyoidn")
    scene, size = demo_scene(), (160, 120)
    preview = om.render(scene, engine="mitsuba", size=size)
    assert preview.info["denoised"] and preview.info["spp"] == rendering.QUALITY["preview"].spp
    grainy = om.render(scene, engine="mitsuba", size=size, denoise=False)
    assert not grainy.info["denoised"]
    reference = om.render(scene, engine="mitsuba", size=size, quality="final", spp=256, seed=3)
    assert not reference.info["denoised"] and reference.info["max_depth"] == 8
    clean, noisy = _psnr(preview.array, reference.array), _psnr(grainy.array, reference.array)
    assert clean > noisy + 4 and clean > 30, (clean, noisy)
    # the mask and the depth are the same as without the denoiser (it only touches colours)
    assert np.array_equal(preview.mask, grainy.mask)


@pytest.mark.mitsuba
def test_mitsuba_quality_and_denoise_options():
    from omnirender.mitsuba import rendering

    scene = om.Node("s", [om.Camera.look_at((0, 0, 5)), om.PointLight(position=(2, 3, 4)), om.Sphere()])
    explicit = om.render(scene, engine="mitsuba", size=(16, 12), spp=2)
    assert explicit.info["spp"] == 2 and not explicit.info["denoised"]  # samples chosen: no denoiser unless asked
    final = om.render(scene, engine="mitsuba", size=(16, 12), quality="final", spp=2)
    assert final.info["quality"] == "final" and final.info["max_depth"] == rendering.QUALITY["final"].max_depth
    with pytest.raises(ValueError, match="quality must be one of 'preview', 'final'.*did you mean 'final'"):
        om.render(scene, engine="mitsuba", size=(16, 12), quality="finale")


# -- progress: a bar on a terminal, log lines elsewhere ---------------------------------------------------
def test_progress_logs_lines_when_stderr_is_no_terminal(caplog, monkeypatch):
    import logging

    from omnirender import progress

    monkeypatch.setattr(progress, "LOG_INTERVAL", 0.0)
    with caplog.at_level(logging.INFO, logger="omnirender"):
        with progress.Progress(4, "work", "step") as bar:  # pytest's stderr is no terminal
            for _ in range(4):
                bar.advance()
    lines = [r.getMessage() for r in caplog.records if r.name == "omnirender"]
    assert lines[0].startswith("work: 1/4 step (25%)") and "left" in lines[0]
    assert lines[-1].startswith("work: 4/4 step done in")


@pytest.mark.gl
def test_render_frames_reports_progress_in_the_log(caplog, monkeypatch, tmp_path):
    import logging

    from omnirender import progress

    monkeypatch.setattr(progress, "LOG_INTERVAL", 0.0)
    scene = om.Node("s", [om.Camera.look_at((0, 0, 5)), om.Sphere()])
    scene.add(om.Animation(fps=4)).add(om.orbit(scene.components[0], seconds=1))
    with caplog.at_level(logging.INFO, logger="omnirender"):
        om.render_frames(scene, range(3), engine="gl", size=(16, 12), out=str(tmp_path / "%03d.png"), workers=0)
    lines = [r.getMessage() for r in caplog.records if r.name == "omnirender"]
    assert any(line.startswith("gl frames: 3/3 frame done") for line in lines), lines


def test_the_command_shows_progress_lines_on_a_stderr_that_is_no_terminal(tmp_path):
    code = """
import logging, sys
from omnirender.cli import main
from omnirender.progress import Progress
main(["engines"])
with Progress(2, "job", "px", interval=0) as bar:
    bar.update(1)
    bar.update(2)
"""
    proc = _python(code)
    assert "omnirender: job: 1/2 px (50%)" in proc.stderr and "omnirender: job: 2/2 px done" in proc.stderr


def test_slow_mesh_loading_is_reported_in_the_log(caplog, monkeypatch, tmp_path):
    import logging

    from omnirender.shapes import files

    monkeypatch.setattr(files, "SLOW_LOAD", 0.0)  # every load counts as slow here
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with caplog.at_level(logging.INFO, logger="omnirender"):
        om.MeshFile(tmp_path / "t.obj").load()
    messages = [r.getMessage() for r in caplog.records]
    assert any("t.obj: 1 triangles in" in m for m in messages), messages
