"""Fixtures of the compositing tests: light fields captured once per session."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def small_light_field():
    """12 views of the textured scene at 200x150 (quick to capture; for properties, not accuracy)."""
    import omnirender as om

    from .scenes import capture_cameras, textured_scene

    return om.compositing.capture_light_field(textured_scene(), capture_cameras(12), size=(200, 150))
