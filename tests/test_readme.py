"""The README's "Ten lines" example runs as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).parent.parent / "README.md"


def _block(heading: str) -> str:
    text = README.read_text()
    section = text.split(heading, 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
@pytest.mark.mitsuba
@pytest.mark.radiance
def test_ten_lines_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    exec(compile(_block("## Ten lines"), "README.md", "exec"), {})
    for name in ("gl.png", "pov.png", "mitsuba.png", "radiance.png", "scene.glb"):
        assert (tmp_path / name).stat().st_size > 1000, name
    assert "/scene/body" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
def test_animation_example_runs(tmp_path, monkeypatch):
    """The animation block, with 2 frames instead of 48 and small images."""
    monkeypatch.chdir(tmp_path)
    code = _block("## Animation: frames on one machine or a cluster").replace("range(48)", "range(2), size=(80, 60)")
    namespace = {"__name__": "__main__"}
    exec(compile(code, "README.md", "exec"), namespace)
    assert sorted(p.name for p in (tmp_path / "final").iterdir()) == ["00000.png", "00001.png"]
    assert (tmp_path / "out.mp4").stat().st_size > 500
    later = namespace["later"]
    assert later["/scene/torus"].components[0].offset[1] > 0.3  # the torus rose


@pytest.mark.radiance
def test_radiance_example_prints_what_its_comments_say(tmp_path, monkeypatch, capsys):
    import math

    monkeypatch.chdir(tmp_path)
    exec(compile(_block("## Radiance: pictures and lighting in physical units"), "README.md", "exec"), {})
    printed = capsys.readouterr().out
    lux = [float(v) for v in re.findall(r"[\d.]+", printed.split("]")[0])]
    for value, (x, z) in zip(lux, [(0, 0), (2, 1)], strict=True):  # 179 * (10 pi cos / d^2 + 20 pi)
        d2 = x * x + 9 + z * z
        assert value == pytest.approx(179 * (10 * math.pi * 3 / math.sqrt(d2) / d2 + 20 * math.pi), rel=0.02)
    assert (tmp_path / "room.rad").read_text().startswith("# omnirender scene for Radiance")


@pytest.mark.slow
@pytest.mark.gl
@pytest.mark.povray
def test_techniques_example_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    exec(compile(_block("## Techniques: shadows, mirrors, line styles, CSG"), "README.md", "exec"), {})
    for name in ("techniques-gl.png", "techniques-pov.png", "techniques-volumes.png"):
        assert (tmp_path / name).stat().st_size > 1000, name


def test_renderer_tree_example_runs(tmp_path, monkeypatch, capsys):
    import numpy as np
    from PIL import Image

    monkeypatch.chdir(tmp_path)
    exec(compile(_block("## Renderer trees: meshes, volumes and light fields together"), "README.md", "exec"), {})
    assert "ShadowGroup follows the four integration rules" in capsys.readouterr().out
    for name in ("tree.png", "statue.png", "graph.png"):
        rgb = np.asarray(Image.open(tmp_path / name).convert("RGB")).astype(int)
        assert rgb.std() > 10, name
    statue = np.asarray(Image.open(tmp_path / "statue.png").convert("RGB")).astype(int)
    drawn = statue.max(axis=2) > 100
    assert drawn.sum() > 2000 and np.all(statue[drawn].max(axis=1) - statue[drawn].min(axis=1) <= 2)  # grey


@pytest.mark.gl
def test_post_processing_example_runs(tmp_path, monkeypatch):
    import numpy as np
    from PIL import Image

    monkeypatch.chdir(tmp_path)
    exec(compile(_block("## Post-processing: a chain of effects in linear HDR"), "README.md", "exec"), {})
    forward = np.asarray(Image.open(tmp_path / "post.png").convert("RGB"), dtype=int)
    deferred = np.asarray(Image.open(tmp_path / "post-deferred.png").convert("RGB"), dtype=int)
    assert forward.shape == (360, 480, 3) and forward.std() > 20
    assert np.abs(forward - deferred).mean() < 2.0  # the two pipelines agree under the chain


@pytest.mark.gl
def test_render_threads_example_runs(tmp_path, monkeypatch):
    """The render-threads block, on a small scene with a moving body, 10 application frames."""
    import omnirender as om

    monkeypatch.chdir(tmp_path)
    text = README.read_text().split("**Render threads on immutable snapshots.**", 1)[1]
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1).replace("range(60)", "range(10)")
    scene = om.Node("scene", [om.Camera.look_at((0, 0, 6))])
    body = om.Translation(0, 0, 0)
    scene.add(om.Node("body", [body, om.Sphere()]))
    namespace = {"om": om, "scene": scene, "body": body}
    exec(compile(code, "README.md", "exec"), namespace)
    assert (tmp_path / "frame.png").stat().st_size > 500
    clients = namespace["clients"]
    assert all(c.error is None and c.frames >= 1 for c in clients)
    assert all(c.last.frame == 10 for c in clients)  # both drew the last snapshot before they stopped


@pytest.mark.gl
def test_frame_stage_example_runs(tmp_path, monkeypatch, capsys):
    """The README's stage of one's own: it joins the frame where it was added and darkens the corners."""
    import numpy as np

    import omnirender as om

    monkeypatch.chdir(tmp_path)
    exec(compile(_block("### A stage of your own in every GL frame"), "README.md", "exec"), {"__name__": "__main__"})
    assert "'mirrors', 'dark edges', 'stereo'" in capsys.readouterr().out
    from PIL import Image

    image = np.asarray(Image.open(tmp_path / "stage.png").convert("RGB"), float)
    plain = om.gl.render(om.Node("scene", [om.PointLight(position=(2, 3, 4)), om.Sphere()]), (160, 120)).array[..., :3]
    assert image[:6, :6, :3].mean() < 0.7 * plain[:6, :6, :3].mean()  # the corners darkened by the stage
    assert abs(image[60, 80, :3].mean() - plain[60, 80, :3].mean()) < 8  # the centre about as it was


def test_usd_example_runs(tmp_path, monkeypatch):
    pytest.importorskip("pxr")
    monkeypatch.chdir(tmp_path)
    exec(compile(_block("### OpenUSD stages"), "README.md", "exec"), {})
    assert "def Sphere" in (tmp_path / "ball.usda").read_text()
