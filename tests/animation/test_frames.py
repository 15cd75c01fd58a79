"""render_frames: in this process, on local processes and on Dask; resume, retry, failures, videos."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender.animation import FramesFailed, render_frames, scene_at
from omnirender.animation.frames import frame_paths

SIZE = (64, 48)


def _scene() -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(0, 1.5, 6), center=(0, 0.5, 0), fov=40))
    scene.add(om.PointLight(position=(4, 6, 6)))
    body = scene.add(om.Node("body"))
    move = body.add(om.Translation(-1.5, 0.5, 0))
    body.add(om.Material(diffuse=(0.9, 0.3, 0.2)))
    body.add(om.Sphere(radius=0.6))
    scene.add(om.Animation([om.Keyframes(move, "offset", [0, 1], [(-1.5, 0.5, 0), (1.5, 0.5, 0)])], fps=4))
    return scene


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def _centroid_x(rgb: np.ndarray) -> float:
    red = (rgb[:, :, 0] > 120) & (rgb[:, :, 1] < 110)
    return float(np.nonzero(red)[1].mean())


def test_frame_paths_patterns():
    assert frame_paths("out/%03d.png", [1, 12])[12] == Path("out/012.png")
    assert frame_paths("out/f{frame:04d}.jpg", [7])[7] == Path("out/f0007.jpg")
    with pytest.raises(ValueError, match="needs one frame-number field"):
        frame_paths("out/frame.png", [1, 2])
    with pytest.raises(ValueError, match="same file name"):
        frame_paths("out/%.0f.png", [0.2, 0.4])
    with pytest.raises(ValueError, match="image files"):
        frame_paths("out/%05d.mp4", [1])


@pytest.mark.gl
def test_frames_in_this_process_resume_and_leave_the_scene_alone(tmp_path):
    scene = _scene()
    version = scene.version
    out = tmp_path / "frames" / "%03d.png"
    report = render_frames(scene, engine="gl", size=SIZE, out=out, workers=0)
    assert report.written == [0, 1, 2, 3] and not report.skipped and scene.version == version
    xs = [_centroid_x(_read(p)) for p in report.files]
    assert all(a < b for a, b in zip(xs, xs[1:], strict=False))  # the ball moves right, frame after frame
    expected = om.render(scene_at(scene, 0.5), engine="gl", size=SIZE).array[:, :, :3]
    assert np.abs(_read(report.paths[2]) - expected).max() <= 2  # frame 2 is the scene at t = 2 / 4 fps
    # resume: only the missing frame is rendered again, the others are left as they are
    report.paths[1].unlink()
    stamp = os.stat(report.paths[3]).st_mtime_ns
    again = render_frames(scene, engine="gl", size=SIZE, out=out, workers=0)
    assert again.written == [1] and again.skipped == [0, 2, 3]
    assert os.stat(report.paths[3]).st_mtime_ns == stamp
    assert render_frames(scene, "2-3", engine="gl", size=SIZE, out=out, workers=0, overwrite=True).written == [2, 3]
    assert sorted(p.name for p in (tmp_path / "frames").iterdir()) == ["000.png", "001.png", "002.png", "003.png"]


@pytest.mark.gl
def test_a_failing_frame_is_retried_then_reported_while_the_others_go_on(tmp_path):
    scene = _scene()
    marker = tmp_path / "failed-once"  # outside the scene: every attempt starts from a fresh copy of it

    def track(t: float, root: om.Node) -> None:
        if t == 0.25 and not marker.exists():  # frame 1 fails once, then works
            marker.touch()
            raise RuntimeError("flaky")
        if t == 0.5:  # frame 2 always fails
            root["/scene/body"].components[2].radius = -1

    scene.components[-1].add(track)
    with pytest.raises(FramesFailed, match=r"frame 2 \(t=0.5 s, 2 attempts\): AnimationError: .*radius.*> 0") as info:
        render_frames(scene, engine="gl", size=SIZE, out=tmp_path / "frames" / "%02d.png", workers=0)
    report = info.value.report
    assert report.written == [0, 1, 3] and report.retried == [1]
    assert [f.frame for f in report.failed] == [2]
    assert sorted(p.name for p in (tmp_path / "frames").iterdir()) == ["00.png", "01.png", "03.png"]  # no partials


def test_bad_arguments_are_refused_before_any_work(tmp_path):
    scene = _scene()
    with pytest.raises(ValueError, match="unknown engine 'blender'"):
        render_frames(scene, engine="blender", out=tmp_path / "%d.png")
    with pytest.raises(ValueError, match="workers must be >= 0"):
        render_frames(scene, out=tmp_path / "%d.png", workers=-1)
    with pytest.raises(TypeError, match="scheduler address"):
        render_frames(scene, out=tmp_path / "%d.png", workers=2.5)
    with pytest.raises(TypeError, match="om.Node or a scene file"):
        render_frames(42, out=tmp_path / "%d.png")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.gl
def test_local_processes_render_the_same_frames(tmp_path):
    scene = _scene()
    scene.components[-1].add(lambda t, root: setattr(root["/scene/body"].components[2], "radius", 0.3 + 0.4 * t))
    here = render_frames(scene, engine="gl", size=SIZE, out=tmp_path / "here" / "%d.png", workers=0)
    pool = render_frames(scene, engine="gl", size=SIZE, out=tmp_path / "pool" / "%d.png", workers=2)
    assert pool.written == [0, 1, 2, 3] and pool.workers == "2 local processes"
    for n in range(4):  # a lambda track travelled too (cloudpickle): the ball grows in both
        assert np.abs(_read(here.paths[n]) - _read(pool.paths[n])).max() <= 2


@pytest.mark.slow
@pytest.mark.gl
def test_a_crashing_worker_process_is_replaced_and_its_frame_reported(tmp_path):
    scene = _scene()

    def crash(t: float, root: om.Node) -> None:
        if t == 0.5:
            os._exit(3)  # the worker process dies without a Python exception

    scene.components[-1].add(crash)
    with pytest.raises(FramesFailed, match=r"frame 2 .*worker process died") as info:
        render_frames(scene, engine="gl", size=SIZE, out=tmp_path / "%d.png", workers=2)
    assert info.value.report.written == [0, 1, 3]


@pytest.fixture(scope="module")
def dask_cluster():
    pytest.importorskip("distributed")
    from omnirender.animation.dask import local_cluster

    with local_cluster(workers=2) as cluster:
        yield cluster


@pytest.mark.slow
@pytest.mark.gl
def test_dask_ships_the_scene_once_per_worker_and_renders_the_same_frames(tmp_path, dask_cluster):
    from distributed import Client

    from omnirender.animation import worker

    scene = _scene()
    here = render_frames(scene, "0-3", engine="gl", size=SIZE, out=tmp_path / "here" / "%d.png", workers=0)
    with Client(dask_cluster) as client:
        before = sum(client.run(lambda: worker.unpickled).values())
        report = render_frames(scene, "0-3", engine="gl", size=SIZE, out=tmp_path / "dask" / "%d.png", workers=client)
        copies = sum(client.run(lambda: worker.unpickled).values()) - before
    assert report.written == [0, 1, 2, 3] and report.workers.startswith("Dask at tcp://")
    assert 1 <= copies <= 2  # one scene copy per worker (thread), not one per frame
    for n in range(4):
        assert np.abs(_read(here.paths[n]) - _read(report.paths[n])).max() <= 2
    # a scheduler address works as well, and a failing frame is reported by number
    scene.components[-1].add(lambda t, root: 1 / 0 if t == 0.25 else None)
    with pytest.raises(FramesFailed, match=r"frame 1 .*ZeroDivisionError"):
        render_frames(
            scene, engine="gl", size=SIZE, out=tmp_path / "d2" / "%d.png", workers=dask_cluster.scheduler_address
        )


def test_an_unreachable_scheduler_is_reported(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    from omnirender.animation import dask

    monkeypatch.setattr(dask, "CONNECT_TIMEOUT", "1s")
    with pytest.raises(RuntimeError, match="cannot reach the Dask scheduler"):
        render_frames(_scene(), engine="gl", out=tmp_path / "%d.png", workers="tcp://127.0.0.1:9")


def test_the_slurm_job_script_is_valid_for_a_configuration():
    pytest.importorskip("dask_jobqueue")
    import shutil
    import subprocess
    import sys

    from omnirender.animation.dask import slurm_cluster

    with slurm_cluster(
        queue="render", account="vislab", cores=4, memory="8GB", walltime="02:30:00",
        setup=["module load povray", "source /opt/venv/bin/activate"],
    ) as cluster:  # fmt: skip
        script = cluster.job_script()
        address = cluster.scheduler_address
    lines = script.splitlines()
    assert lines[0].startswith("#!") and "bash" in lines[0]
    directives = [line.split(None, 1)[1] for line in lines if line.startswith("#SBATCH")]
    for expected in ("-p render", "-A vislab", "-n 1", "--cpus-per-task=4", "--mem=8G", "-t 02:30:00"):
        assert expected in directives, (expected, directives)
    # every directive comes before the first command, as sbatch requires
    first_command = next(i for i, line in enumerate(lines[1:], 1) if line.strip() and not line.startswith("#"))
    assert all(i < first_command for i, line in enumerate(lines) if line.startswith("#SBATCH"))
    assert lines[first_command : first_command + 2] == ["module load povray", "source /opt/venv/bin/activate"]
    worker = next(line for line in lines if "distributed.cli.dask_worker" in line)
    assert worker.startswith(sys.executable) and address in worker
    assert "--nthreads 4" in worker  # one worker process per job, a frame per reserved core
    if shutil.which("bash"):
        check = subprocess.run(["bash", "-n"], input=script, text=True, capture_output=True)
        assert check.returncode == 0, check.stderr
