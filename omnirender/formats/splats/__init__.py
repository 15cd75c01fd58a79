"""Gaussian splat files: ``om.load_splats`` reads the reference trainer's ``.ply`` (:mod:`.ply`).

glTF ``KHR_gaussian_splatting`` and USD ``ParticleField3DGaussianSplat`` are
read and written by the glTF and USD formats themselves
(:mod:`omnirender.formats.gltf.splats`, :mod:`omnirender.formats.usd.splats`):
``om.load_gltf``/``om.load_usd`` give ``om.GaussianSplats`` where the file has
splats, and ``om.export`` writes them.

A splat ``.ply`` is not a mesh: ``om.MeshFile`` refuses one (it names
``om.load_splats``) rather than reading its centres as a point cloud without
triangles.
"""

from __future__ import annotations

import os
from typing import Any

from .ply import MAX_HEADER, SplatFileError, is_splat_ply, read_splat_ply, write_splat_ply

__all__ = [
    "load_splats",
    "save_splats",
    "read_splat_ply",
    "write_splat_ply",
    "SplatFileError",
    "is_splat_ply",
    "MAX_HEADER",
]


def load_splats(path: str | os.PathLike[str]) -> Any:
    """The Gaussian splats of a ``.ply`` file (the reference trainer's layout) as an ``om.GaussianSplats``.

    Log scales become standard deviations (exp), opacity logits opacities
    (sigmoid), quaternions are normalised; see :mod:`omnirender.formats.splats.ply`.
    Malformed or hostile files raise :class:`SplatFileError` (a ValueError)
    naming the file and the row; oversized ones
    :class:`~omnirender.core.limits.ResourceLimitError`.
    """
    from ...shapes import GaussianSplats

    if not os.fspath(path).lower().endswith(".ply"):
        raise SplatFileError(
            f"load_splats {os.fspath(path)!r}: only .ply splat files are read here; "
            "read .glb/.gltf with om.load_gltf and .usd* with om.load_usd (their splats become om.GaussianSplats)"
        )
    arrays = read_splat_ply(path)
    try:
        return GaussianSplats(**arrays)
    except ValueError as exc:
        raise SplatFileError(f"load_splats {os.fspath(path)!r}: {exc}") from None


def save_splats(splats: Any, path: str | os.PathLike[str], *, binary: bool = True) -> None:
    """Write ``splats`` (an ``om.GaussianSplats``) as a trainer ``.ply`` file (log scales, logit opacities)."""
    write_splat_ply(path, splats.positions, splats.rotations, splats.scales, splats.opacities, splats.sh, binary=binary)
