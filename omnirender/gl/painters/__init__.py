"""GL painters: how the GL engine draws each shape and applies each attribute.

``shapes`` (meshes, points, lines, instance sets, levels of detail), ``splats`` (Gaussian splats), ``attributes``
(surface, GL state and clip-plane painters), ``text``, ``volume`` and ``nurbs``.
They register themselves with the core handler registry (``default_for(GLEngine)``)
when this package is imported; the ``GLEngine`` facade imports it by name the first
time an engine is made.  Painters use the engine's public surface; the engine never
imports them.
"""

from __future__ import annotations

import importlib

for _name in ("attributes", "shapes", "text", "volume", "nurbs", "splats"):  # the order they registered in before
    importlib.import_module(f".{_name}", __name__)
