"""omnirender: one scene graph, many engines.

``import omnirender as om`` gives the scene graph, shapes, attributes, the
generic engine and the convenience functions (``om.render``, ``om.pick``,
``om.bounds``...).  Adapters (``om.gl``, ``om.povray``, ``om.mitsuba``, ``om.radiance``) and
functions that need them are imported lazily on first use, so importing
omnirender stays cheap and works without any graphics library.
"""

from __future__ import annotations

import importlib
from typing import Any

from . import data, formats  # formats registers mesh readers, scene readers, exporters
from .attributes import *  # noqa: F403
from .attributes import __all__ as _attributes_all
from .core import *  # noqa: F403
from .core import __all__ as _core_all
from .image import Image
from .render import engines, export, exporters, register_engine, register_exporter, render
from .scene import Node, Statistics, TraceEngine, Visitor, register_statistic, statistics, trace
from .shapes import *  # noqa: F403
from .shapes import __all__ as _shapes_all
from .techniques import Hit, attribute_search, bounds, collisions, image_info, node_origin, pick, screen_corners

__version__ = "0.1.0"

# Subpackages imported on first attribute access (om.gl, om.povray, ...).
_LAZY_MODULES = {
    "gl",
    "povray",
    "mitsuba",
    "radiance",
    "viewer",
    "techniques",
    "geometry",
    "rib",
    "cli",
    "animation",
    "compositing",
}

# Public functions and classes that live in lazily imported modules.
_LAZY_NAMES = {
    "Viewer": "viewer",
    "view": "viewer",
    "show": "viewer",
    "RenderList": "viewer",
    "AxisAlignedRotation": "viewer",
    "IsRenderable": "viewer",
    "TRANSPARENT": "viewer",
    "TWO_DIMENSIONAL": "viewer",
    "HIGHLIGHT": "viewer",
    "load": "scene.files",
    "save": "scene.files",
    "register_type": "scene.files",
    "embed_files": "scene.embed",
    "Animation": "animation",
    "Keyframes": "animation",
    "Orbit": "animation",
    "scene_at": "animation",
    "set_time": "animation",
    "orbit": "animation",
    "camera_path": "animation",
    "turntable": "animation",
    "render_frames": "animation",
    "video": "animation",
    "load_gltf": "formats.gltf",
    "render_to_file": "tiling",
    "load_usd": "formats.usd",
    "load_splats": "formats.splats",
    "save_splats": "formats.splats",
}

__all__ = [
    *_core_all,
    *_shapes_all,
    *_attributes_all,
    "data",
    "formats",
    "Node",
    "Visitor",
    "trace",
    "statistics",
    "Statistics",
    "TraceEngine",
    "register_statistic",
    "Image",
    "render",
    "export",
    "engines",
    "exporters",
    "register_engine",
    "register_exporter",
    "pick",
    "bounds",
    "collisions",
    "attribute_search",
    "image_info",
    "Hit",
    "screen_corners",
    "node_origin",
]


def __getattr__(name: str) -> Any:
    if name in _LAZY_MODULES:
        module = importlib.import_module(f".{name}", __name__)
        globals()[name] = module
        return module
    if name in _LAZY_NAMES:
        value = getattr(importlib.import_module(f".{_LAZY_NAMES[name]}", __name__), name)
        globals()[name] = value
        return value
    import difflib

    close = difflib.get_close_matches(name, [*__all__, *_LAZY_MODULES, *_LAZY_NAMES], n=1)
    hint = f"; did you mean om.{close[0]}?" if close else ""
    raise AttributeError(f"module 'omnirender' has no attribute {name!r}{hint}")


def __dir__() -> list[str]:
    """Every public name, the lazily imported ones included (``dir(om)``, tab completion)."""
    return sorted({*globals(), *_LAZY_MODULES, *_LAZY_NAMES})
