"""om.video: MP4 through imageio-ffmpeg and GIF through Pillow, read back and compared."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import omnirender as om

COLORS = [(220, 40, 40), (40, 200, 60), (40, 60, 220), (230, 230, 40)]


def _frames(size=(64, 48)) -> list[np.ndarray]:
    w, h = size
    out = []
    for k, color in enumerate(COLORS):
        a = np.zeros((h, w, 3), np.uint8)
        a[:] = color
        a[: h // 2, : w // 4 * (k + 1) // 2] = 255  # a white bar growing frame by frame
        out.append(a)
    return out


def test_mp4_frames_come_back_in_order(tmp_path):
    imageio = pytest.importorskip("imageio.v2")
    pytest.importorskip("imageio_ffmpeg")
    path = om.video(_frames(), tmp_path / "clip.mp4", fps=12)
    reader = imageio.get_reader(path, format="FFMPEG")
    assert reader.get_meta_data()["fps"] == pytest.approx(12)
    frames = [f for f in reader]
    reader.close()
    assert len(frames) == len(COLORS) and frames[0].shape == (48, 64, 3)
    for frame, color in zip(frames, COLORS, strict=True):  # H.264 is lossy: colours within a few levels
        assert np.abs(frame[40, 50].astype(int) - color).max() < 16
    assert [p.name for p in tmp_path.iterdir()] == ["clip.mp4"]  # no temporary file left behind


def test_odd_sizes_and_frame_files(tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    import imageio.v2 as imageio

    folder = tmp_path / "frames"
    folder.mkdir()
    for k, frame in enumerate(_frames(size=(33, 25))):
        Image.fromarray(frame).save(folder / f"{k:03d}.png")
    om.video(folder / "%03d.png", tmp_path / "odd.mp4", fps=5)  # a pattern like render_frames' out
    frames = [f for f in imageio.get_reader(tmp_path / "odd.mp4", format="FFMPEG")]  # (list() asks len(): inf)
    assert len(frames) == 4 and frames[0].shape == (26, 34, 3)  # yuv420p needs even sizes: an edge is repeated


def test_gif_is_exact_for_flat_colours_and_loops(tmp_path):
    path = om.video([om.Image(np.dstack([f, np.full(f.shape[:2], 255, np.uint8)])) for f in _frames()],
                    tmp_path / "clip.gif", fps=10)  # fmt: skip
    with Image.open(path) as gif:
        assert gif.n_frames == 4 and gif.info["loop"] == 0 and gif.info["duration"] == 100
        for k, color in enumerate(COLORS):
            gif.seek(k)
            assert gif.convert("RGB").getpixel((50, 40)) == color


def test_bad_input_is_refused(tmp_path):
    with pytest.raises(ValueError, match="use one of .mp4"):
        om.video(_frames(), tmp_path / "clip.avi")
    frames = _frames()
    frames[2] = frames[2][:10]
    with pytest.raises(ValueError, match="frame 2 is 64x10, frame 0 64x48"):
        om.video(frames, tmp_path / "clip.gif")
    with pytest.raises(FileNotFoundError, match="no frame files match"):
        om.video(tmp_path / "none" / "%05d.png", tmp_path / "clip.gif")
    with pytest.raises(ValueError, match="fps must be a positive number"):
        om.video(_frames(), tmp_path / "clip.gif", fps=0)
    assert not (tmp_path / "clip.gif").exists()
