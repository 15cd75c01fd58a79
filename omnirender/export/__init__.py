"""Engines that write files (glTF, RenderMan RIB) and ``om.export`` itself.

``om.export(scene, path)`` picks the exporter from the file extension (see
:mod:`omnirender.render`).  Because Python binds a subpackage to its parent's
attribute of the same name, this package *is* ``om.export``: calling the module
exports, and ``om.export.gltf`` / ``om.export.rib`` are the exporters.
"""

from __future__ import annotations

import sys
import types
from typing import Any

from ..render import export as _export
from ..render import exporters

__all__ = ["exporters"]


class _ExportModule(types.ModuleType):
    def __call__(self, scene: Any, path: Any, **options: Any) -> Any:
        return _export(scene, path, **options)


sys.modules[__name__].__class__ = _ExportModule
