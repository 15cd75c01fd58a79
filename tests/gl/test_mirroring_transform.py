"""A mirroring model matrix (negative determinant) reverses triangle winding: GL must still light the front."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl


def box_scene(matrix: np.ndarray, engine_kw: dict | None = None) -> om.Node:
    s = om.Node("s", [om.Camera.look_at((1.5, 1.2, 5), (0, 0, 0)), om.PointLight(position=(2, 3, 6)),
                      om.Background((0, 0, 0))])  # fmt: skip
    s.add(om.Node("b", [om.Matrix(matrix), om.Material(diffuse=(0.8, 0.8, 0.8)), om.Box(size=(1.5, 1.5, 1.5))]))
    return s


@pytest.mark.parametrize("pipeline", ["forward", "deferred"])
@pytest.mark.parametrize("diag", [(-1, 1, 1), (1, -1, 1), (-1, -1, -1)])
def test_a_box_under_a_mirroring_matrix_looks_like_the_box(diag, pipeline):
    """The box is symmetric, so mirroring it changes nothing visible (it drew its faces dark: mean 7/255)."""
    plain = om.render(box_scene(np.eye(4)), engine="gl", size=(96, 72), pipeline=pipeline).array[..., :3]
    mirrored = om.render(box_scene(np.diag([*diag, 1.0])), engine="gl", size=(96, 72), pipeline=pipeline).array[..., :3]
    lit = plain.sum(axis=-1) > 0
    assert plain[lit].mean() > 100
    assert np.abs(plain.astype(int) - mirrored.astype(int)).mean() < 1.0


def test_mirrored_instances_and_double_sided_surfaces_keep_their_lit_side():
    """A single triangle facing the light, mirrored in its own plane: the lit side still faces the light."""
    tri = om.TriangleSet([(-1, -1, 0), (1, -1, 0), (0, 1, 0)], [(0, 1, 2)])
    s = om.Node("s", [om.Camera.look_at((0, 0, 4), (0, 0, 0)), om.DirectionalLight(direction=(0, 0, -1)),
                      om.Background((0, 0, 0))])  # fmt: skip
    s.add(om.Node("t", [om.Matrix(np.diag([-1.0, 1, 1, 1])), om.Material(diffuse=(1, 1, 1)), tri]))
    a = om.render(s, engine="gl", size=(64, 64)).array[..., :3]
    assert a[32, 32].mean() > 150
