"""The reference trainer's ``.ply`` files: activations, the channel-major f_rest layout, hostile files refused."""

from __future__ import annotations

import math

import numpy as np
import pytest
from splat_files import cloud_arrays, degree1_names, trainer_ply

import omnirender as om
from omnirender.core import limits
from omnirender.formats.splats import SplatFileError, read_splat_ply, save_splats


def _row() -> list[float]:
    # x y z, normals, f_dc, f_rest (channel-major: R coefficients 1..3, then G, then B), logit, log scales, quat
    rest = [0.11, 0.12, 0.13, 0.21, 0.22, 0.23, 0.31, 0.32, 0.33]
    return [1, 2, 3, 0, 0, 0, 0.5, -0.5, 0.25, *rest, 0.0, math.log(0.1), math.log(0.2), math.log(0.3), 2, 0, 0, 0]


@pytest.mark.parametrize("fmt", ["binary_little_endian", "binary_big_endian", "ascii"])
def test_trainer_layout_is_activated_and_reordered(tmp_path, fmt):
    path = trainer_ply(tmp_path / "s.ply", [_row(), _row()], degree1_names(), fmt)
    splats = om.load_splats(path)
    assert isinstance(splats, om.GaussianSplats) and splats.count == 2 and splats.sh_degree == 1
    np.testing.assert_allclose(splats.positions[0], [1, 2, 3])
    np.testing.assert_allclose(splats.opacities, [0.5, 0.5], atol=1e-7)  # sigmoid(0)
    np.testing.assert_allclose(splats.scales[0], [0.1, 0.2, 0.3], rtol=1e-6)  # exp(log s)
    np.testing.assert_allclose(splats.rotations[0], [1, 0, 0, 0])  # (2, 0, 0, 0) normalised
    np.testing.assert_allclose(splats.sh[0, 0], [0.5, -0.5, 0.25])
    # coefficient j of channel c is f_rest_[c * 3 + j - 1]
    np.testing.assert_allclose(
        splats.sh[0, 1:], [[0.11, 0.21, 0.31], [0.12, 0.22, 0.32], [0.13, 0.23, 0.33]], rtol=1e-6
    )


@pytest.mark.parametrize("degree", [0, 1, 2, 3])
@pytest.mark.parametrize("binary", [True, False])
def test_write_then_read_gives_the_arrays_back(tmp_path, degree, binary):
    arrays = cloud_arrays(25, degree)
    save_splats(om.GaussianSplats(**arrays), tmp_path / "c.ply", binary=binary)
    back = read_splat_ply(tmp_path / "c.ply")
    for name, value in arrays.items():
        np.testing.assert_allclose(back[name], value, rtol=2e-6, atol=2e-7, err_msg=name)


def test_colour_only_files_get_the_dc_term_of_their_rgb(tmp_path):
    names = ["x", "y", "z", "red", "green", "blue", "opacity", "scale_0", "scale_1", "scale_2"]
    names += ["rot_0", "rot_1", "rot_2", "rot_3"]
    path = tmp_path / "rgb.ply"
    head = "ply\nformat ascii 1.0\nelement vertex 1\n"
    head += "".join(f"property {'uchar' if n in ('red', 'green', 'blue') else 'float'} {n}\n" for n in names)
    path.write_text(head + "end_header\n0 0 0 255 128 0 3 -2 -2 -2 1 0 0 0\n")
    splats = om.load_splats(path)
    np.testing.assert_allclose(splats.colors((0, 0, 5))[0], [1.0, 128 / 255, 0.0], atol=1e-6)


def _hostile(tmp_path, text: bytes) -> object:
    path = tmp_path / "bad.ply"
    path.write_bytes(text)
    return path


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (b"not a ply file", "not a PLY file"),
        (b"ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + b"comment x\n" * 8000, "end_header"),
        (b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nend_header\n", "lacks the splat"),
        (b"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int v\nend_header\n", "list"),
        (b"ply\nformat wavefront 1.0\nend_header\n", "unknown PLY format"),
    ],
)
def test_malformed_headers_are_refused_with_the_reason(tmp_path, body, message):
    with pytest.raises(SplatFileError, match=message):
        om.load_splats(_hostile(tmp_path, body))


def test_a_truncated_binary_file_is_refused_before_reading(tmp_path):
    path = trainer_ply(tmp_path / "t.ply", [_row()] * 4, degree1_names())
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(SplatFileError, match="truncated"):
        om.load_splats(path)


def test_a_header_claiming_billions_of_splats_hits_the_vertex_limit(tmp_path):
    names = degree1_names()
    head = f"ply\nformat binary_little_endian 1.0\nelement vertex {2**40}\n"
    path = _hostile(tmp_path, (head + "".join(f"property float {n}\n" for n in names) + "end_header\n").encode())
    with pytest.raises(limits.ResourceLimitError, match="MAX_VERTICES"):
        om.load_splats(path)


@pytest.mark.parametrize(
    ("column", "value", "message"),
    [
        ("x", float("nan"), "splat row 1: x y z are not finite"),
        ("rot_0", 0.0, "splat row 1: the rotation quaternion rot_0..3 is zero"),
        ("scale_1", 200.0, "splat row 1: the log scales"),
    ],
)
def test_bad_rows_are_named(tmp_path, column, value, message):
    names = degree1_names()
    bad = _row()
    bad[names.index(column)] = value
    if column == "rot_0":
        bad[names.index("rot_0") : names.index("rot_0") + 4] = [0, 0, 0, 0]
    path = trainer_ply(tmp_path / "r.ply", [_row(), bad], names)
    with pytest.raises(SplatFileError, match=message):
        om.load_splats(path)


def test_an_odd_number_of_sh_coefficients_is_refused(tmp_path):
    names = degree1_names()
    names.remove("f_rest_8")
    path = trainer_ply(tmp_path / "o.ply", [_row()[:-9] + _row()[-8:]], names)
    with pytest.raises(SplatFileError, match="0, 9, 24 or 45"):
        om.load_splats(path)


def test_other_suffixes_point_at_their_loaders(tmp_path):
    path = tmp_path / "s.glb"
    path.write_bytes(b"x")
    with pytest.raises(SplatFileError, match="om.load_gltf"):
        om.load_splats(path)
    with pytest.raises(FileNotFoundError):
        om.load_splats(tmp_path / "missing.ply")


def test_mesh_file_refuses_a_splat_ply_naming_load_splats(tmp_path):
    path = trainer_ply(tmp_path / "s.ply", [_row()], degree1_names())
    with pytest.raises(ValueError, match=r"holds Gaussian splats .* om.load_splats"):
        om.MeshFile(path).load()
