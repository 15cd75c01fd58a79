"""The deferred shading pipeline (guacamole): G-buffer, light proxies, shading models with four stages.

``om.gl.Deferred()`` at the top of a scene, or ``GLEngine(pipeline="deferred")`` /
``om.render(scene, engine="gl", pipeline="deferred")`` for every frame.  Materials are
:class:`ShadingModel` objects (four programmable GLSL stages with typed outputs) plus values
(:class:`MaterialDescription`); the built-in :data:`PHONG`, :data:`PBR` and :data:`UNLIT` models
shade ``om.Material``, ``om.Color`` and ``om.PBRMaterial`` as the forward pipeline does.  The
G-buffer and L-buffer layout (:class:`BufferLayout`) is computed from the models a frame uses.
"""

from .layout import BufferLayout
from .materials import MaterialTable
from .models import PBR, PHONG, UNLIT, MaterialDescription, ShadingModel, ShadingModelError
from .pipeline import Deferred, DeferredRenderer, in_gbuffer

__all__ = [
    "Deferred",
    "DeferredRenderer",
    "ShadingModel",
    "MaterialDescription",
    "ShadingModelError",
    "BufferLayout",
    "MaterialTable",
    "PHONG",
    "PBR",
    "UNLIT",
    "in_gbuffer",
]
