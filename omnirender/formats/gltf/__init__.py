"""glTF 2.0: ``om.load_gltf`` (:mod:`.reader`) and the ``.glb`` exporter (:mod:`.writer`, :mod:`.instancing`)."""

from __future__ import annotations

from .reader import SUPPORTED_EXTENSIONS, GLTFImportError, flatten_gltf, light_from_gltf, load_gltf

__all__ = ["load_gltf", "GLTFImportError", "flatten_gltf", "SUPPORTED_EXTENSIONS", "light_from_gltf"]
