"""Engine availability for tests that pick engines by name (parametrised over engines).

``require(name)`` skips a test whose engine is missing, except in CI
(``OMNIRENDER_REQUIRE_ENGINES=1``), where it fails: CI must never pass by
skipping.  ``marks(*names)`` gives the pytest markers of those engines.
"""

from __future__ import annotations

import os

import pytest

import omnirender as om


def require(name: str) -> None:
    """Skip (or, in CI, fail) unless the engine ``name`` works on this machine."""
    ok, why = om.engines().get(name, (False, "not registered"))
    if not ok:
        if os.environ.get("OMNIRENDER_REQUIRE_ENGINES") == "1":
            pytest.fail(f"engine {name!r} is required in CI but unavailable: {why}", pytrace=False)
        pytest.skip(f"engine {name!r} unavailable: {why}")


def marks(*names: str) -> list:
    """The pytest markers of the engines ``names`` (``gl``, ``povray``, ...)."""
    return [getattr(pytest.mark, n) for n in names]
