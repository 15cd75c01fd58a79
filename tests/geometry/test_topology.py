"""Closed, outward-wound surfaces: what lets renderers cull back faces of user meshes."""

from __future__ import annotations

import numpy as np
import pytest

from omnirender.geometry import tessellate
from omnirender.geometry.topology import is_closed_outward


@pytest.mark.parametrize(
    "mesh",
    [
        tessellate.sphere(1.0, segments=16),
        tessellate.box((1.0, 2.0, 3.0)),
        tessellate.torus(1.0, 0.3, 24, 12),
        tessellate.cylinder(0.5, 1.0, 12),
        tessellate.cone(0.5, 1.0, 12),
    ],
    ids=["sphere", "box", "torus", "cylinder", "cone"],
)
def test_tessellated_solids_are_closed_and_outward(mesh):
    tris = mesh.indices.reshape(-1, 3)
    assert is_closed_outward(mesh.vertices, tris)
    assert not is_closed_outward(mesh.vertices, tris[:, ::-1])  # wound inwards
    assert not is_closed_outward(mesh.vertices, tris[1:])  # a hole
    flipped = tris.copy()
    flipped[0] = flipped[0, ::-1]
    assert not is_closed_outward(mesh.vertices, flipped)  # inconsistent winding


def test_open_and_non_manifold_meshes_are_not_closed():
    rect = tessellate.rectangle((1.0, 1.0))
    assert not is_closed_outward(rect.vertices, rect.indices)
    box = tessellate.box((1.0, 1.0, 1.0))
    tris = box.indices.reshape(-1, 3)
    assert not is_closed_outward(box.vertices, np.concatenate([tris, tris]))  # every edge used four times
    assert not is_closed_outward(np.zeros((3, 3)), [[0, 1, 2]])


@pytest.mark.gl
def test_gl_culls_the_back_faces_of_closed_opaque_triangle_sets_only():
    import omnirender as om
    from omnirender.gl import GLEngine

    box = tessellate.box((1.0, 1.0, 1.0))
    closed = om.TriangleSet(box.vertices, box.indices.reshape(-1, 3))
    opened = om.TriangleSet(box.vertices, box.indices.reshape(-1, 3)[2:])
    scene = om.Node("s", [om.Camera.look_at((2, 2, 3)), closed, om.Node("o", [om.Translation(2, 0, 0), opened])])
    scene.add(om.Node("glass", [om.Color(1, 1, 1, a=0.5), om.Translation(-2, 0, 0), closed]))
    with GLEngine(size=(32, 32), samples=0) as e:
        e.compile(scene)
        culls = [item.state.value(om.gl.CullFace) for item in e.draw_items]
    assert culls == ["back", "none", "none"]  # closed opaque, open, closed but transparent
