"""om.compositing: renderer trees combining meshes, volumes and light fields in the GL engine.

Leaves are renderers (:class:`SceneRenderer`, :class:`VolumeRenderer`,
:class:`LightFieldRenderer`, your own :class:`Renderer` subclasses) and filters
(:class:`LuminanceFilter`, :class:`BufferDebugFilter`, :class:`GLSLFilter`);
inner nodes are renderer groups (:class:`DepthGroup`, :class:`OcclusionGroup`,
:class:`ShadowGroup`, :class:`DepthPeelGroup`,
:class:`DistanceGroup`, your own :class:`RendererGroup` subclasses).  A tree
renders with ``tree.render(size)`` or ``om.render(tree, engine="gl")``, or sits
in a scene graph as a technique.  :func:`check_rules` checks a renderer
against the four integration rules of DESIGN.md, :func:`check_tree` a tree
against the paper's structural guidelines.  Light fields are captured
with :func:`capture_light_field` or loaded with :meth:`LightField.load`.

The package builds on the GL engine (moderngl); it is imported on first use.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = [
    "Canvas",
    "Renderer",
    "Filter",
    "RendererGroup",
    "SceneRenderer",
    "VolumeRenderer",
    "DepthGroup",
    "OcclusionGroup",
    "ShadowGroup",
    "DepthPeelGroup",
    "DistanceGroup",
    "LuminanceFilter",
    "BufferDebugFilter",
    "GLSLFilter",
    "LightField",
    "LightFieldView",
    "LightFieldRenderer",
    "capture_light_field",
    "sphere_cap_cameras",
    "check_rules",
    "RuleReport",
    "RuleViolation",
    "check_tree",
    "TreeProblem",
]

_WHERE = {
    "Canvas": "canvas",
    "Renderer": "renderer",
    "Filter": "renderer",
    "RendererGroup": "renderer",
    "SceneRenderer": "scene_renderers",
    "VolumeRenderer": "scene_renderers",
    "DepthGroup": "groups",
    "OcclusionGroup": "groups",
    "ShadowGroup": "shadow",
    "DepthPeelGroup": "peeling",
    "DistanceGroup": "distance",
    "LuminanceFilter": "filters",
    "BufferDebugFilter": "filters",
    "GLSLFilter": "filters",
    "LightField": "lightfield.data",
    "LightFieldView": "lightfield.data",
    "LightFieldRenderer": "lightfield.renderer",
    "capture_light_field": "lightfield.capture",
    "sphere_cap_cameras": "lightfield.capture",
    "check_rules": "rules",
    "RuleReport": "rules",
    "RuleViolation": "rules",
    "check_tree": "guidelines",
    "TreeProblem": "guidelines",
}


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module 'omnirender.compositing' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{where}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
