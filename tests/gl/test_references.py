"""Reference images: every shape, light type and GL feature against a checked-in PNG.

Tolerance: a pixel matches when every channel differs by at most ``TOLERANCE``
(8 of 255); a render passes when at most ``ALLOWED`` (0.5%) of its pixels do
not match (anti-aliased edges may vary between drivers).  On failure the
message gives the largest difference and where it is.  The actual image is
always written to ``tests/gl/actual/`` (git-ignored).  Set
``OMNIRENDER_UPDATE_REFERENCES=1`` to regenerate the references.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from .scenes import SCENES

pytestmark = pytest.mark.gl

SIZE = (96, 72)
TOLERANCE = 8
ALLOWED = 0.005
HERE = Path(__file__).resolve().parent
REFERENCES = HERE / "references"
ACTUAL = HERE / "actual"


@pytest.fixture(scope="module")
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=SIZE)
    yield e
    e.release()


def compare(name: str, image) -> None:
    from PIL import Image as PILImage

    ACTUAL.mkdir(exist_ok=True)
    image.save(ACTUAL / f"{name}.png")
    reference = REFERENCES / f"{name}.png"
    if os.environ.get("OMNIRENDER_UPDATE_REFERENCES") == "1":
        REFERENCES.mkdir(exist_ok=True)
        image.save(reference)
        return
    assert reference.exists(), f"no reference {reference}; run with OMNIRENDER_UPDATE_REFERENCES=1"
    expected = np.asarray(PILImage.open(reference).convert("RGBA"), dtype=np.int16)
    actual = image.array.astype(np.int16)
    assert expected.shape == actual.shape, f"{name}: size {actual.shape} differs from reference {expected.shape}"
    diff = np.abs(expected - actual).max(axis=2)
    bad = diff > TOLERANCE
    y, x = np.unravel_index(int(np.argmax(diff)), diff.shape)
    assert bad.mean() <= ALLOWED, (
        f"{name}: {int(bad.sum())} pixels ({bad.mean():.2%}) differ by more than {TOLERANCE}; largest difference "
        f"{int(diff.max())} at (x={x}, y={y}); actual image in {ACTUAL / (name + '.png')}"
    )


@pytest.mark.parametrize("name", sorted(SCENES))
def test_reference_image(engine, name):
    image = engine.render(SCENES[name]())
    assert image.mask.any(), f"{name}: nothing was drawn"
    compare(name, image)
