"""Every Python block of README.md and docs/*.md runs as written, pasted in order into one session as a
reader would, and prints what the text says.

Blocks written as an interactive session (``>>>``) are run by doctest in the same namespace, so their
shown output is compared too.  The session runs in a temporary folder (the blocks write images there).
"""

from __future__ import annotations

import contextlib
import doctest
import io
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).parent.parent
README = ROOT / "README.md"
DOCS = sorted((ROOT / "docs").glob("*.md"))


def python_blocks(path: Path) -> list[tuple[int, str]]:
    """(line number, code) of every ```python block of ``path``, in order."""
    text = path.read_text()
    return [(text[: m.start()].count("\n") + 2, m.group(1)) for m in re.finditer(r"```python\n(.*?)```", text, re.S)]


def run_session(path: Path, namespace: dict) -> dict[int, str]:
    """Run every block of ``path`` in ``namespace``, in order; returns what each block printed, by line.

    A block that warns fails: the README's examples print no warning on a clean run.
    """
    printed: dict[int, str] = {}
    for line, code in python_blocks(path):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            printed[line] = _run_block(path, line, code, namespace)
        shown = [f"{w.category.__name__}: {w.message}" for w in caught if w.category is not DeprecationWarning]
        assert not shown, f"{path.name}:{line}: the block warns:\n" + "\n".join(shown)
    return printed


def _run_block(path: Path, line: int, code: str, namespace: dict) -> str:
    """Run one block (a doctest session or plain code) in ``namespace``; returns what it printed."""
    out = io.StringIO()
    where = f"{path.name}:{line}"
    if code.lstrip().startswith(">>>"):
        test = doctest.DocTestParser().get_doctest(code, namespace, where, str(path), line - 1)
        runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
        with contextlib.redirect_stdout(out):
            result = runner.run(test, clear_globs=False)
        assert result.failed == 0, f"{where}: the session's output differs from the text:\n{out.getvalue()}"
        return out.getvalue()
    with contextlib.redirect_stdout(out):
        try:
            exec(compile(code, where, "exec"), namespace)
        except Exception as exc:
            raise AssertionError(f"{where}: the block fails as written: {type(exc).__name__}: {exc}") from exc
    return out.getvalue()


def printed_by(printed: dict[int, str], path: Path, marker: str) -> str:
    """What the block containing ``marker`` printed."""
    for line, code in python_blocks(path):
        if marker in code:
            return printed[line]
    raise AssertionError(f"no block of {path.name} contains {marker!r}")


def test_every_readme_and_docs_block_is_collected():
    assert len(python_blocks(README)) >= 17
    assert sum(len(python_blocks(p)) for p in DOCS) >= 2


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
@pytest.mark.mitsuba
@pytest.mark.radiance
def test_the_readme_runs_as_one_session(tmp_path, monkeypatch):
    import omnirender as om

    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__main__"}
    printed = run_session(README, namespace)

    # Ten lines: four images, a glTF file and the path of the picked shape
    for name in ("gl.png", "povray.png", "mitsuba.png", "radiance.png", "scene.glb"):
        assert (tmp_path / name).stat().st_size > 1000, name
    assert printed_by(printed, README, 'om.export(scene, "scene.glb")').strip() == "/scene/body"

    # the custom shape's bounds, as the text says
    text = printed_by(printed, README, "class Star(om.Shape)")
    numbers = [float(v) for v in re.findall(r"-?\d+\.?\d*(?:e-?\d+)?", text)]
    assert np.allclose(numbers, [-0.951, -0.809, 0, 0.951, 1, 0], atol=1e-3), text

    # techniques
    for name in ("techniques-gl.png", "techniques-pov.png", "techniques-volumes.png"):
        assert (tmp_path / name).stat().st_size > 1000, name

    # renderer trees: the rules hold, pictures have content, the statue is grey, the floor is not white
    assert "ShadowGroup follows the four integration rules" in printed_by(printed, README, "C.check_rules(tree)")
    from PIL import Image

    for name in ("tree.png", "statue.png", "graph.png"):
        rgb = np.asarray(Image.open(tmp_path / name).convert("RGB")).astype(int)
        assert rgb.std() > 10, name
    statue = np.asarray(Image.open(tmp_path / "statue.png").convert("RGB")).astype(int)
    drawn = statue.max(axis=2) > 100
    assert drawn.sum() > 2000 and np.all(statue[drawn].max(axis=1) - statue[drawn].min(axis=1) <= 2)  # grey
    graph = np.asarray(Image.open(tmp_path / "graph.png").convert("RGB")).astype(int)
    assert (graph.min(axis=2) >= 250).mean() < 0.01  # the floor is lit once, not over-exposed to white

    # Gaussian splats: the picture has the planet's blue and green and the box's orange
    splat_image = np.asarray(Image.open(tmp_path / "splats.png").convert("RGB"), dtype=int)
    assert splat_image.std() > 20 and (splat_image[..., 2] > splat_image[..., 0] + 60).mean() > 0.05
    assert (splat_image[..., 0] > splat_image[..., 2] + 80).mean() > 0.05

    # post-processing: forward and deferred agree under the chain
    forward = np.asarray(Image.open(tmp_path / "post.png").convert("RGB"), dtype=int)
    deferred = np.asarray(Image.open(tmp_path / "post-deferred.png").convert("RGB"), dtype=int)
    assert forward.shape == (360, 480, 3) and forward.std() > 20
    assert np.abs(forward - deferred).mean() < 2.0

    # the toon model, dynamic scenes, instances, chained pipelines, render threads
    for name in ("toon.png", "moved.png", "balls.png", "portal.png", "frame.png"):
        assert (tmp_path / name).stat().st_size > 500, name
    clients = namespace["clients"]
    assert all(c.error is None and c.frames >= 1 for c in clients)

    # Radiance: lux as the comment's formula says, and the description file
    lux_text = printed_by(printed, README, "om.radiance.illuminance(room, points, up)")
    lux = [float(v) for v in re.findall(r"[\d.]+", lux_text.split("]")[0])]
    for value, (x, z) in zip(lux, [(0, 0), (2, 1)], strict=True):  # 179 * (10 pi cos / d^2 + 20 pi)
        d2 = x * x + 9 + z * z
        assert value == pytest.approx(179 * (10 * math.pi * 3 / math.sqrt(d2) / d2 + 20 * math.pi), rel=0.02)
    assert (tmp_path / "room.rad").read_text().startswith("# omnirender scene for Radiance")

    # animation: both frame sets, the video, the scene at t = 1.5 s
    for folder in ("preview", "final"):
        assert len(list((tmp_path / folder).glob("*.png"))) == 48, folder
    assert (tmp_path / "out.mp4").stat().st_size > 500
    assert namespace["later"]["/scene/torus"].components[0].offset[1] > 0.3  # the torus rose

    # Slurm: the job script is printed
    assert "#SBATCH" in printed_by(printed, README, "slurm_cluster(")

    # a stage of one's own: it joins the frame where it was added and darkens the corners
    assert "'mirrors', 'dark edges', 'stereo'" in printed_by(printed, README, "add_stage")
    stage = np.asarray(Image.open(tmp_path / "stage.png").convert("RGB"), float)
    plain = om.gl.render(om.Node("scene", [om.PointLight(position=(2, 3, 4)), om.Sphere()]), (160, 120)).array[..., :3]
    assert stage[:6, :6, :3].mean() < 0.7 * plain[:6, :6, :3].mean()  # the corners darkened by the stage
    assert abs(stage[60, 80, :3].mean() - plain[60, 80, :3].mean()) < 8  # the centre about as it was

    # OpenUSD (the block needs usd-core, in the 'all' extra)
    assert "def Sphere" in (tmp_path / "ball.usda").read_text()


@pytest.mark.gl
@pytest.mark.povray
def test_the_docs_run_as_sessions(tmp_path, monkeypatch):

    monkeypatch.chdir(tmp_path)
    for path in DOCS:
        if python_blocks(path):
            run_session(path, {"__name__": "__main__"})
    assert (tmp_path / "pov.png").stat().st_size > 1000
