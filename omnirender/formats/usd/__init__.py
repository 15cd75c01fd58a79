"""OpenUSD through ``usd-core``: ``om.load_usd`` (:mod:`.reader`) and ``om.export(scene, "x.usda")`` (:mod:`.writer`).

``usd-core`` (the ``usd`` extra) is imported when a stage is read or written,
not when omnirender is imported.
"""

from __future__ import annotations

from .reader import USDImportError, flatten_usd, load_usd, mesh_parts

__all__ = ["load_usd", "flatten_usd", "mesh_parts", "USDImportError"]
