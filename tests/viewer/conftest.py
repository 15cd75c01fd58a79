"""Fixtures for viewer tests."""

from __future__ import annotations

import pytest
from viewer_helpers import RecordingEngine


@pytest.fixture
def recorder() -> RecordingEngine:
    return RecordingEngine()
