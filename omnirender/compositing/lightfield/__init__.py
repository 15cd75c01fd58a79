"""Light fields for renderer trees: calibrated views with depth maps, capture, and lumigraph rendering."""

from __future__ import annotations

from .capture import capture_light_field, sphere_cap_cameras
from .data import LightField, LightFieldView

__all__ = ["LightField", "LightFieldView", "capture_light_field", "sphere_cap_cameras", "LightFieldRenderer"]


def __getattr__(name: str):  # the renderer needs the GL adapter: imported on first use
    if name == "LightFieldRenderer":
        from .renderer import LightFieldRenderer

        return LightFieldRenderer
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
