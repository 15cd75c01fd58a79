"""Screens and tracked eyes: the world geometry of guacamole's screen and eye nodes.

A *screen node* holds an ``om.Rectangle`` (the physical screen; its +y face
looks at the viewer, its -z edge is the top); :func:`screen_corners` gives its
world corners (lower-left, lower-right, upper-left), the form
``om.Camera.from_screen`` takes.  A *tracked node* (a head or an eye whose
transform a tracker updates) gives its world origin with :func:`node_origin`.
Both read the node as it sits in its graph: every transform from the root to
the node (first-parent occurrence) and the node's own transforms before the
shape (or all of them, for the origin).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.transform import Transform
from ..shapes import Rectangle
from .base import world_matrix_of

__all__ = ["screen_corners", "node_origin", "node_frame"]


def node_frame(node: Any, until: Any = None) -> np.ndarray:
    """The world matrix inside ``node``: where it starts, times its own transforms (those before ``until``)."""
    m = np.array(world_matrix_of(node), dtype=np.float64)
    for item in node.items:
        if item is until:
            break
        if isinstance(item, Transform):
            m = m @ item.matrix
    return m


def node_origin(node_or_point: Any) -> np.ndarray:
    """The world position of a tracked node's origin (its own transforms included), or a point as given."""
    if hasattr(node_or_point, "_compile_node"):
        return node_frame(node_or_point)[:3, 3].copy()
    p = np.asarray(node_or_point, dtype=np.float64).reshape(-1)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"node_origin: give an om.Node or a finite 3D point, got {node_or_point!r:.80}")
    return p


def screen_corners(screen: Any) -> np.ndarray:
    """World corners (lower-left, lower-right, upper-left) of a screen node's first ``om.Rectangle``.

    The rectangle lies in its local xz plane facing +y; seen from +y with its
    -z edge up, its corners are (-w/2, 0, d/2), (w/2, 0, d/2), (-w/2, 0, -d/2).
    Three corner points are returned as an array unchanged.
    """
    if not hasattr(screen, "_compile_node"):
        pts = np.asarray(screen, dtype=np.float64)
        if pts.shape != (3, 3):
            raise ValueError(
                f"screen_corners: give a screen node holding an om.Rectangle or three world points, got {screen!r:.80}"
            )
        return pts
    rect = next((item for item in screen.items if isinstance(item, Rectangle)), None)
    if rect is None:
        raise ValueError(
            f"screen_corners: the screen node {screen.path} holds no om.Rectangle; add one "
            "(om.Rectangle(size=(width, height)), facing the viewer with its +y side)"
        )
    m = node_frame(screen, until=rect)
    w, d = (float(v) for v in rect.size)
    local = np.array([[-w / 2, 0.0, d / 2, 1.0], [w / 2, 0.0, d / 2, 1.0], [-w / 2, 0.0, -d / 2, 1.0]])
    return (local @ m.T)[:, :3]
