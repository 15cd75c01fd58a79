"""om.GaussianSplats: arrays by reference, validation naming the row, helpers, the SH colour rule."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import omnirender as om
from omnirender.shapes import _sh


def make(n: int = 4, degree: int = 0, seed: int = 1) -> tuple[om.GaussianSplats, dict[str, np.ndarray]]:
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    arrays = {
        "positions": rng.uniform(-1, 1, (n, 3)),
        "rotations": q / np.linalg.norm(q, axis=1, keepdims=True),
        "scales": rng.uniform(0.05, 0.2, (n, 3)),
        "opacities": rng.uniform(0.2, 1.0, n),
        "sh": rng.normal(0, 0.3, (n, (degree + 1) ** 2, 3)),
    }
    return om.GaussianSplats(**arrays), arrays


def test_arrays_are_held_by_reference_and_touch_bumps_the_version():
    splats, arrays = make()
    for name, value in arrays.items():
        assert getattr(splats, name) is value
    assert splats.count == len(splats) == 4 and splats.sh_degree == 0
    v = splats.version
    arrays["positions"][0] = (5, 5, 5)
    splats.touch()
    assert splats.version > v
    assert splats.bounds()[1][0] > 4.5  # re-read after touch


def test_degree_is_inferred_or_checked_against_the_coefficient_count():
    splats, arrays = make(degree=3)
    assert splats.sh_degree == 3
    with pytest.raises(ValueError, match=r"sh_degree=2 needs 9 coefficients.*sh has 16.*sh_degree=3"):
        om.GaussianSplats(**arrays, sh_degree=2)
    arrays["sh"] = arrays["sh"][:, :5]
    with pytest.raises(ValueError, match="5 coefficients per channel.*1, 4, 9 or 16"):
        om.GaussianSplats(**arrays)
    with pytest.raises(ValueError, match="sh_degree must be 0, 1, 2 or 3"):
        splats.sh_degree = 4


@pytest.mark.parametrize(
    ("name", "row", "value", "message"),
    [
        ("positions", 2, (np.nan, 0, 0), "positions of splat 2 are not finite"),
        ("scales", 1, (0.1, 0.0, 0.1), "scales of splat 1 .* must be > 0 .*np.exp"),
        ("opacities", 3, 1.5, "opacity of splat 3 is 1.5.*logits"),
        ("rotations", 0, (2.0, 0, 0, 0), r"quaternion of splat 0 .* length 2.*q / np.linalg.norm"),
        ("sh", 1, np.inf, "sh of splat 1 are not finite"),
    ],
)
def test_bad_rows_are_named(name, row, value, message):
    _, arrays = make()
    arrays[name][row] = value
    with pytest.raises(ValueError, match=message):
        om.GaussianSplats(**arrays)


def test_shapes_are_checked():
    _, arrays = make()
    with pytest.raises(ValueError, match=r"rotations must have shape \(4, 4\).*got \(4, 3\)"):
        om.GaussianSplats(**{**arrays, "rotations": arrays["rotations"][:, :3]})
    with pytest.raises(ValueError, match=r"opacities must have shape \(4,\).*wrong length"):
        om.GaussianSplats(**{**arrays, "opacities": arrays["opacities"][:3]})
    with pytest.raises(ValueError, match=r"sh must have shape \(N, K, 3\)"):
        om.GaussianSplats(**{**arrays, "sh": np.zeros((4, 1, 4))})
    with pytest.raises(ValueError, match="must hold numbers"):
        om.GaussianSplats(**{**arrays, "positions": np.array([["a"] * 3] * 4)})


def test_assignment_checks_and_update_changes_the_length():
    splats, arrays = make()
    with pytest.raises(ValueError, match="update()"):
        splats.positions = np.zeros((7, 3))
    assert splats.positions is arrays["positions"]  # a refused assignment changes nothing
    _, new = make(7, degree=1)
    v = splats.version
    splats.update(**new)
    assert splats.count == 7 and splats.sh_degree == 1 and splats.version > v
    with pytest.raises(TypeError, match="unknown parameter"):
        splats.update(colours=None)


def test_in_place_writes_are_checked_when_read_after_touch():
    splats, arrays = make()
    arrays["opacities"][1] = -0.5
    splats.touch()
    with pytest.raises(ValueError, match="opacity of splat 1"):
        splats.checked()


def test_covariances_and_bounds():
    splats, arrays = make(6)
    cov = splats.covariances()
    for i in range(6):
        w, x, y, z = arrays["rotations"][i]
        # the rotation as the reference trainer builds it (build_rotation in utils/general_utils.py)
        r = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        assert np.allclose(r @ r.T, np.eye(3))
        s = np.diag(arrays["scales"][i])
        assert np.allclose(cov[i], r @ s @ s @ r.T)
        # the eigenvalues are the squared scales
        assert np.allclose(np.sort(np.linalg.eigvalsh(cov[i])), np.sort(arrays["scales"][i] ** 2))
    lo, hi = splats.bounds(sigma=3.0)
    half = 3 * np.sqrt(np.diagonal(cov, axis1=1, axis2=2))
    assert np.allclose(lo, (arrays["positions"] - half).min(axis=0))
    assert np.allclose(hi, (arrays["positions"] + half).max(axis=0))
    empty = om.GaussianSplats(np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, 1, 3)))
    assert empty.count == 0 and empty.bounds() is None


def test_sh_basis_is_orthonormal_on_the_sphere():
    # a Fibonacci sphere: equal-area points, the integral of Y_i Y_j is delta_ij
    m = 20000
    k = np.arange(m) + 0.5
    z = 1 - 2 * k / m
    phi = np.pi * (1 + 5**0.5) * k
    r = np.sqrt(1 - z * z)
    d = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    y = _sh.sh_basis(d, 3)
    gram = y.T @ y * (4 * np.pi / m)
    assert np.allclose(gram, np.eye(16), atol=2e-3)


def test_colours_follow_the_reference_rule():
    splats, arrays = make(5, degree=0)
    c = splats.colors(eye=(0, 0, 10))
    assert np.allclose(c, np.maximum(0.5 + _sh.C0 * arrays["sh"][:, 0], 0))
    # degree 1: the colour depends on the direction from the eye to the centre
    splats1, a1 = make(1, degree=1)
    a1["positions"][0] = 0
    a1["sh"][0] = 0
    a1["sh"][0, 2] = (0.5, 0, 0)  # the +C1*z term, red channel
    splats1.touch()
    from_below = splats1.colors(eye=(0, 0, -1))[0, 0]  # dir = +z
    from_above = splats1.colors(eye=(0, 0, 1))[0, 0]  # dir = -z
    assert from_below == pytest.approx(0.5 + _sh.C1 * 0.5) and from_above == pytest.approx(0.5 - _sh.C1 * 0.5)


def test_pickling_keeps_the_arrays():
    splats, arrays = make(3, degree=2)
    back = pickle.loads(pickle.dumps(splats))
    assert back.count == 3 and back.sh_degree == 2
    assert np.array_equal(back.positions, arrays["positions"]) and np.array_equal(back.sh, arrays["sh"])


def test_hit_reports_the_splat_index():
    splats, _ = make()
    hit = om.Hit(1.0, np.zeros(3), np.array([0, 0, 1.0]), splats, "/s", primitive=2)
    assert hit.splat == 2
    other = om.Hit(1.0, np.zeros(3), np.array([0, 0, 1.0]), om.Sphere(), "/s", primitive=2)
    assert other.splat == -1


def test_an_engine_without_a_splat_painter_refuses_clearly():
    splats, _ = make()

    class Collect(om.Engine):
        service = "test.collect"

    with pytest.raises(om.NoHandlerError, match=r"GaussianSplats at node /cloud.*splat painter"):
        Collect().evaluate(om.Node("cloud", [splats]))
    assert Collect(on_missing="skip").evaluate(om.Node("cloud", [splats])) is None
