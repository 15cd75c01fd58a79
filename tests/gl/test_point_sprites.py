"""Points are round discs of the requested diameter, centred on their projection, on every driver.

The disc is cut out of a square a pixel wider on each side by each pixel centre's distance to the projected
centre: neither which pixels a driver's point square covers nor its gl_PointCoord decides (llvmpipe's
gl_PointCoord is a pixel off with multisampling: 20-pixel points were 19 pixels wide and shifted).
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

SIZE = (64, 48)


def disc(diameter: float, samples: int, centre=(0.0, 0.0)) -> np.ndarray:
    """The coverage mask of one point of ``diameter`` pixels at ``centre`` (pixels from the image centre)."""
    from omnirender.gl import GLEngine

    engine = GLEngine(size=SIZE, samples=samples)
    try:
        camera = om.Camera(fov=None, height=SIZE[1])  # orthographic, one unit per pixel
        scene = om.Node("s", [camera, om.Color(1, 1, 1), om.PointSet([(*centre, 0.0)], sizes=[diameter])])
        return engine.render(scene, background=(0, 0, 0)).mask
    finally:
        engine.release()


@pytest.mark.parametrize("samples", [0, 4])
@pytest.mark.parametrize("diameter", [6.0, 11.0, 20.0, 33.0])
def test_a_point_is_a_disc_of_its_diameter_at_its_projection(diameter, samples):
    centre = (0.25, -0.25)  # off pixel boundaries: no pixel centre lies on the circle
    mask = disc(diameter, samples, centre)
    rows, cols = np.nonzero(mask)
    assert rows.size, "the point was not drawn"
    width, height = cols.max() - cols.min() + 1, rows.max() - rows.min() + 1
    assert abs(width - diameter) <= 1 and abs(height - diameter) <= 1, f"{width}x{height} pixels for {diameter}"
    # the centre of the covered pixels is the projected centre (window y runs up, image rows down)
    cx, cy = SIZE[0] / 2 + centre[0], SIZE[1] / 2 - centre[1]
    assert abs((cols + 0.5).mean() - cx) <= 0.5 and abs((rows + 0.5).mean() - cy) <= 0.5
    area = np.pi * (diameter / 2) ** 2  # a disc, not the square: the pixel count is the area within its rim
    assert abs(mask.sum() - area) <= np.pi * diameter / 2, f"{mask.sum()} pixels for a disc of area {area:.0f}"


def test_multisampling_does_not_move_or_resize_points():
    assert np.array_equal(disc(20.0, 0), disc(20.0, 4))  # (equal also where the driver has no multisampling)
