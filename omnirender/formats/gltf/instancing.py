"""``InstanceSet`` in glTF: the shape written once, drawn once per instance through ``EXT_mesh_gpu_instancing``.

The instance set's shape is evaluated through the exporting engine like any
shape (a ``Sphere``, a ``MeshFile`` with its materials, an ``Arrow`` whose
simplification moves its parts), but in *capture* mode: its primitives are
collected in the instance set's frame (transforms met inside the shape are
baked into the vertices) instead of becoming nodes.  They form one mesh, and
one node carries the visible instances as ``TRANSLATION`` / ``ROTATION``
(unit quaternions, x y z w) / ``SCALE`` accessors, the node placed like any
mesh node, so the transforms above the instance set apply.

Colours: glTF has no per-instance colour, and a colour that replaces the
material's must produce that material.  So instances are grouped by what the
material must hold: with at most :data:`COLOR_GROUPS` distinct colours, one
material and one instanced node per colour (standard glTF: right in every
viewer); with more, one node per distinct alpha whose material is white, and
the colours (linear RGB) in the ``_COLOR_0`` instance attribute, which
three.js multiplies in (its ``instanceColor``) and ``om.load_gltf`` reads.
Shapes whose own materials ignore an ``om.Color`` (as in every engine's
per-instance simplification) get no colours.

Not representable, so the set falls back to one node per instance (the
default simplification, with a warning naming the reason): a matrix that is
not translation x rotation x positive scale (sheared, mirrored, degenerate
or projective: :func:`omnirender.geometry.trs.decompose_trs`), and shapes
with lines or points (viewers instance triangle meshes only).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...attributes import Color, PBRMaterial
from ...geometry.trs import TRS, decomposable, decompose_trs
from ..colors import srgb_to_linear

__all__ = ["INSTANCING_EXTENSION", "INSTANCE_COLOR", "COLOR_GROUPS", "Capture", "write_instance_set"]

INSTANCING_EXTENSION = "EXT_mesh_gpu_instancing"
#: The custom instance attribute of per-instance colours (linear RGB), as three.js's GLTFLoader reads it.
INSTANCE_COLOR = "_COLOR_0"
#: Instance sets with at most this many distinct colours get one material per colour (standard glTF).
COLOR_GROUPS = 16
_TRIANGLES = 4


class Capture:
    """The primitives of one evaluation of an instance set's shape, in the set's frame; no nodes are written."""

    def __init__(self, frame: np.ndarray, color: Color | None) -> None:
        self.frame = np.asarray(frame, np.float64)
        #: the Color pushed for the evaluation (an instance's colour), or None
        self.color = color
        self.primitives: list[dict[str, Any]] = []
        #: per primitive: whether its material took the pushed colour
        self.colored: list[bool] = []
        #: why the shape cannot be instanced, or None
        self.problem: str | None = None

    def relative(self, model: np.ndarray) -> np.ndarray:
        """``model`` (the engine's model matrix inside the shape) relative to the instance set's frame."""
        return np.linalg.solve(self.frame, model)

    def add(self, primitive: dict[str, Any], surface: tuple[Any, Any]) -> None:
        """Keep ``primitive``; ``surface`` is the engine's (material, colour) it was written with."""
        if primitive.get("mode", _TRIANGLES) != _TRIANGLES:
            self.fail("its shape has lines or points, which viewers do not instance")
            return
        material, color = surface
        # per-vertex colours replace a Phong colour (appearance rule 3): the instance's colour is lost there
        replaced = "COLOR_0" in primitive["attributes"] and not isinstance(material, PBRMaterial)
        self.colored.append(self.color is not None and color is self.color and not replaced)
        self.primitives.append(primitive)

    def fail(self, problem: str) -> None:
        if self.problem is None:
            self.problem = problem


def write_instance_set(engine: Any, shape: Any) -> str | None:
    """Write ``shape`` (an InstanceSet) natively; returns why it cannot be (nothing written), or None."""
    matrices = shape.matrices()
    colors = shape.color_array()
    index = np.arange(len(matrices))
    visible = shape.visible_array()
    if visible is not None:
        matrices, index = matrices[visible], index[visible]
        colors = None if colors is None else colors[visible]
    if len(matrices) == 0:
        return None
    if not decomposable(engine.local_matrix()):  # instances apply before it: it cannot go to the vertices
        return "the transform above it is sheared, which a glTF node cannot hold"
    trs = decompose_trs(matrices)
    if not trs.valid.all():
        bad = int(np.argmin(trs.valid))
        return (
            f"the matrix of instance {int(index[bad])} is {trs.reason[bad]}, and EXT_mesh_gpu_instancing holds "
            "translations, rotations and positive scales only"
        )
    mark = engine.checkpoint()
    engine.gltf.shared = {}  # the shape's geometry is written once, whatever number of materials it gets
    try:
        problem = _write_groups(engine, shape.shape, trs, colors)
    finally:
        engine.gltf.shared = None
    if problem is not None:
        engine.rollback(mark)
    return problem


def _write_groups(engine: Any, base: Any, trs: TRS, colors: np.ndarray | None) -> str | None:
    """One instanced node per group of instances whose material is the same (see the module docs)."""
    name = type(base).__name__
    mark = engine.checkpoint()
    probe = engine.capture(base, None if colors is None else Color(colors[0]))
    if probe.problem is not None:
        return probe.problem
    if not probe.primitives:
        return None  # the shape draws nothing here (a Text)
    if colors is None or not any(probe.colored):  # the colours change nothing: one node
        _instanced_node(engine, name, probe.primitives, trs, np.ones(len(trs.valid), bool))
        return None
    distinct, group = np.unique(colors, axis=0, return_inverse=True)
    group = group.reshape(-1)
    if all(probe.colored) and len(distinct) > COLOR_GROUPS:
        engine.rollback(mark)  # the probe's material is not used: white materials, colours per instance
        alphas, by_alpha = np.unique(colors[:, 3], return_inverse=True)
        by_alpha = by_alpha.reshape(-1)
        linear = srgb_to_linear(colors[:, :3])
        for k, alpha in enumerate(alphas):
            rows = by_alpha == k
            capture = engine.capture(base, Color(1.0, 1.0, 1.0, float(alpha)))
            _instanced_node(engine, name, capture.primitives, trs, rows, linear[rows])
        return None
    for k, rgba in enumerate(distinct):
        capture = probe if k == group[0] else engine.capture(base, Color(rgba))
        _instanced_node(engine, name, capture.primitives, trs, group == k)
    return None


def _instanced_node(
    engine: Any, name: str, primitives: list[dict[str, Any]], trs: TRS, rows: np.ndarray, linear: Any = None
) -> None:
    """A mesh of ``primitives`` and a node instancing it at ``rows`` of ``trs`` (with linear colours)."""
    g = engine.gltf
    rotation, scale = trs.rotation[rows], trs.scale[rows]
    attributes = {"TRANSLATION": g.accessor(trs.translation[rows].astype(np.float32))}
    if not (rotation == (0.0, 0.0, 0.0, 1.0)).all():  # identity rotations and unit scales are the defaults
        attributes["ROTATION"] = g.accessor(rotation.astype(np.float32))
    if not (scale == 1.0).all():
        attributes["SCALE"] = g.accessor(scale.astype(np.float32))
    if linear is not None:
        attributes[INSTANCE_COLOR] = g.accessor(np.asarray(linear, np.float32))
    g.use_extension(INSTANCING_EXTENSION)
    mesh = g.append("meshes", {"name": name, "primitives": primitives})
    engine.mesh_node("InstanceSet", mesh, {INSTANCING_EXTENSION: {"attributes": attributes}})
