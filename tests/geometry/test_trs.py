"""Model matrices as translation x rotation x scale (glTF's nodes and instances) and back."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender.geometry.trs import compose_trs, decomposable, decompose_trs


def _random_matrices(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    angles, axes = rng.uniform(-360, 360, n), rng.normal(size=(n, 3))
    scales = rng.uniform(0.05, 20.0, (n, 3))
    m = np.stack([om.Rotation(a, ax).matrix for a, ax in zip(angles, axes, strict=True)])
    m[:, :3, :3] *= scales[:, None, :]
    m[:, :3, 3] = rng.uniform(-100, 100, (n, 3))
    return m, angles, axes


def test_decomposition_composes_back_and_quaternions_are_the_rotations():
    m, angles, axes = _random_matrices(2000)
    # the four branches of the quaternion extraction: rotations by 180 degrees about each axis, and none
    special = np.stack([om.Rotation(180, ax).matrix for ax in np.eye(3)] + [np.eye(4)])
    m = np.concatenate([m, special])
    trs = decompose_trs(m)
    assert trs.valid.all() and set(trs.reason) == {""}
    np.testing.assert_allclose(compose_trs(trs.translation, trs.rotation, trs.scale), m, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(trs.rotation, axis=1), 1.0, atol=1e-12)
    assert (trs.rotation[:, 3] >= 0).all()  # w >= 0: one of the two quaternions of each rotation
    for k in range(0, 2000, 97):  # the same rotation as om.Rotation's own quaternion (w, x, y, z)
        x, y, z, w = trs.rotation[k]
        rotation = om.Rotation.from_quaternion(w, x, y, z).matrix[:3, :3]
        np.testing.assert_allclose(rotation * trs.scale[k], m[k, :3, :3], atol=1e-9)
    np.testing.assert_array_equal(decompose_trs(np.eye(4)[None]).rotation, [[0.0, 0.0, 0.0, 1.0]])


@pytest.mark.parametrize(
    ("edit", "reason"),
    [
        (lambda m: m.__setitem__((0, 1), 0.3), "sheared"),
        (lambda m: m.__setitem__((slice(0, 3), 0), -m[:3, 0]), "mirrored"),
        (lambda m: m.__setitem__((slice(0, 3), 2), 0.0), "degenerate"),
        (lambda m: m.__setitem__((3, 2), 0.5), "projective"),
    ],
)
def test_what_translation_rotation_scale_cannot_hold_is_named(edit, reason):
    m, _, _ = _random_matrices(5, seed=1)
    edit(m[3])
    trs = decompose_trs(m)
    assert trs.valid.tolist() == [True, True, True, False, True]
    assert trs.reason[3] == reason
    # one matrix, as glTF nodes need it: a mirroring one is allowed (a negative scale)
    assert [decomposable(x) for x in m] == [True, True, True, reason == "mirrored", True]


def test_float32_rounding_is_not_shear():
    m, _, _ = _random_matrices(500, seed=2)
    assert decompose_trs(m.astype(np.float32)).valid.all()
