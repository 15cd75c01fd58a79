"""Instance rows: the one rule that turns an ``InstanceSet``'s arrays into rows of the named layout.

The compile uses it when it meets an instance set (``submit_instances``), and
the fast path uses it when only the application's arrays changed
(``instances.touch()``): the new rows replace the old ones in the instance
set's batch, with no traversal.  Both go through :func:`instance_rows`, so a
moved instance renders the same either way.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...attributes.photometry import srgb_to_linear
from ...shapes.instances import SINGULAR, determinants
from .layout import PBR, ROW

__all__ = [
    "InstanceRows",
    "instance_rows",
    "moved_instance_rows",
    "instance_world",
    "write_models",
    "set_arrays",
    "PROBE",
    "takes_instance_colours",
    "held",
    "mask_copies",
]

_MODEL = ROW.slice("model")
_COLOR = ROW.slice("color")
_ALPHA = ROW.at("color", "alpha")
_FOLLOWS_COLOR = ROW.at("ambient", "follows_color")
_SHADING_MODEL = ROW.at("emission", "model")


#: The colour an instance set's shape is captured under when the set has colours.  Parts that show it take
#: the instances' colours, as an ``om.Color`` before the shape would colour them; parts with their own
#: material (a mesh file's, a node's ``Material`` after the colour) keep it, as in every other engine.
PROBE = (0.1234567, 0.7654321, 0.3456789)
_PROBE_LINEAR = srgb_to_linear(PROBE).astype(np.float32)


def takes_instance_colours(row: np.ndarray) -> bool:
    """Whether a part captured under :data:`PROBE` shows it (its colour follows the context)."""
    return bool(np.array_equal(row[_COLOR.start : _COLOR.start + 3], _PROBE_LINEAR))


class InstanceRows:
    """Rows of one template drawn once per instance, with what decides how they may be drawn."""

    __slots__ = ("rows", "models", "transparent", "mirrored")

    def __init__(self, rows: np.ndarray, models: np.ndarray, transparent: bool, mirrored: bool) -> None:
        #: (N, ROW.stride) float32 rows
        self.rows = rows
        #: (N, 4, 4) matrices after the chain: instance matrix @ template local
        self.models = models
        #: some instance's colour is translucent (or the template is)
        self.transparent = transparent
        #: some instance's matrix mirrors (a negative determinant): face culling must be off
        self.mirrored = mirrored


def set_arrays(shape: Any) -> tuple[np.ndarray, np.ndarray | None, bool]:
    """The visible instances' (N, 4, 4) matrices, (N, 4) colours or None, and whether any may mirror."""
    matrices = shape.matrices()
    colors = shape.color_array()
    visible = shape.visible_array()
    if visible is not None:
        matrices = matrices[visible]
        colors = colors[visible] if colors is not None else None
    return matrices, colors, shape.may_mirror()


def held(value: Any) -> np.ndarray | None:
    """The array the application holds for an instance set's parameter (no copy; ``.array()`` of a sequence)."""
    if value is None:
        return None
    array = getattr(value, "array", None)
    return np.asarray(value.array() if callable(array) and not isinstance(value, np.ndarray) else value)


def mask_copies(shape: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Copies of the set's scales and visibility mask as the application holds them (None where it has none):
    compared after a plain ``touch()`` to know whether the rows' 3x3 parts and visible instances still hold."""
    scales, visible = held(shape.scales), held(shape.visible)
    return (None if scales is None else scales.copy()), (None if visible is None else visible.copy())


def instance_rows(
    row: np.ndarray,
    local: np.ndarray | None,
    transparent: bool,
    model: np.ndarray,
    matrices: np.ndarray,
    colors: np.ndarray | None,
    may_mirror: bool,
) -> InstanceRows:
    """Rows for ``matrices`` (after ``model``, the chain's matrix) of the template ``row`` and ``local``.

    ``colors`` (display RGBA) replace the template's colour as ``om.Color``
    would (ambient follows it for Phong materials) when the template was
    captured showing :data:`PROBE`; other templates keep their material.  Determinants are taken
    only when ``may_mirror`` (positions and positive scales never mirror).
    """
    n = len(matrices)
    models, world = instance_world(local, model, matrices)
    rows = np.empty((n, ROW.stride), np.float32)
    rows[:] = row
    write_models(rows, world)
    if colors is not None and takes_instance_colours(row):
        rows[:, _COLOR.start : _COLOR.start + 3] = srgb_to_linear(colors[:, :3])
        rows[:, _ALPHA] = colors[:, 3] * row[_ALPHA]
        if int(row[_SHADING_MODEL]) != PBR:
            rows[:, _FOLLOWS_COLOR] = 1.0
        transparent = transparent or bool((rows[:, _ALPHA] < 1.0).any())
    may_mirror = may_mirror or model_mirrors(model) or (local is not None and model_mirrors(local))
    mirrored = bool(n) and may_mirror and bool((determinants(world[:, :3, :3]) < 0.0).any())
    return InstanceRows(rows, models, transparent, mirrored)


def moved_instance_rows(
    before: np.ndarray,
    local: np.ndarray | None,
    transparent: bool,
    model: np.ndarray,
    matrices: np.ndarray,
) -> InstanceRows | None:
    """Rows for new ``matrices`` of a set whose rows ``before`` were made from the same colours, count, scales
    and visibility mask: a copy of them with the model columns written, so the colours are converted once, not
    on every move.

    None when the full path must decide (it names the instance and the node): a matrix not finite, singular
    (as :meth:`InstanceSet.matrices` refuses) or beyond float32 after ``model``.  The mirroring is the sign of
    the determinants of ``matrices`` times those of ``model`` and ``local``: one product per instance.
    """
    n = len(matrices)
    if n != len(before):
        return None
    det = determinants(matrices[:, :3, :3])
    if not np.isfinite(det).all() or (np.abs(det) < SINGULAR).any():
        return None
    models, world = instance_world(local, model, matrices)
    rows = before.copy()
    try:
        write_models(rows, world)
    except ValueError:
        return None
    sign = -1.0 if model_mirrors(model) != (local is not None and model_mirrors(local)) else 1.0
    mirrored = bool(n) and bool((det * sign < 0.0).any())
    return InstanceRows(rows, models, transparent, mirrored)


def instance_world(local: np.ndarray | None, model: np.ndarray, matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The instances' matrices after the template's ``local`` (what ``InstanceRows.models`` holds) and their
    world matrices after the chain's ``model``: the one rule both row makers follow."""
    n = len(matrices)
    if local is None or _is_identity(local):
        models = matrices
    else:  # one (4N, 4) @ (4, 4) product: numpy's stacked matmul of small matrices takes 5x longer
        models = (np.ascontiguousarray(matrices).reshape(4 * n, 4) @ local).reshape(n, 4, 4)
    return models, models if _is_identity(model) else model @ models


def write_models(rows: np.ndarray, world: np.ndarray) -> None:
    """Write ``world`` (N, 4, 4) into the rows' model columns (transposed, float32); ValueError naming the first
    instance beyond float32's range."""
    with np.errstate(over="ignore"):
        rows[:, _MODEL] = world.transpose(0, 2, 1).reshape(len(world), 16)
    if len(world) and not (-_FLOAT32_MAX <= world.min() and world.max() <= _FLOAT32_MAX):  # NaN compares False
        _check_float32(rows[:, _MODEL], world)


#: float32's largest finite value: a float64 beyond it becomes infinite in the rows
_FLOAT32_MAX = float(np.finfo(np.float32).max)


def _check_float32(models: np.ndarray, world: np.ndarray) -> None:
    """ValueError naming the first instance whose matrix (finite in float64) is beyond float32's range."""
    finite = np.isfinite(models).all(axis=1)
    if not finite.all():
        bad = int(np.argmin(finite))
        raise ValueError(
            f"InstanceSet: the transform of instance {bad} is beyond float32's range (|x| > 3.4e38) after the "
            f"transforms above it: translation {world[bad, :3, 3].tolist()}; GL draws float32, keep it in range"
        )


def model_mirrors(m: np.ndarray) -> bool:
    """Whether the matrix ``m`` mirrors (a negative determinant)."""
    return bool(np.linalg.det(m[:3, :3]) < 0.0)


def _is_identity(m: np.ndarray) -> bool:
    return bool((m == _EYE).all())


_EYE = np.eye(4)
