"""Engine-independent techniques: picking, bounds, collisions, attribute search, image information.

Each is an analysis engine over the generic engine, with handlers for its own
service (``"ray.intersect"``, ``"bounds"``, ``"collide"``, ``"attribute.search"``,
``"image.info"``, ``"count.triangles"``) and the shapes' simplifiers as the
fallback for everything else.  Importing this package also adds the
``triangles`` figure to ``om.statistics``.
"""

from . import csg_picking  # noqa: F401  (registers the CSG intersector)
from . import splats as _splats  # noqa: F401  (registers the Gaussian splats' bounds and intersector)
from .base import AnalysisEngine, evaluate_in_place, world_matrix_of
from .bounds import BoundsEngine, BoundsHandler, analytic_bounds, bounds
from .collision import CollisionEngine, bodies_collide, collisions
from .image_info import ImageInfo, ImageInfoEngine, image_info
from .picking import (
    AnalyticIntersector,
    ClipPlaneTracker,
    Hit,
    PickEngine,
    TriangleSetIntersector,
    pick,
    pixel_ray,
)
from .screen import node_origin, screen_corners
from .search import AttributeSearch, AttributeSearchEngine, attribute_search
from .statistics import TriangleCountEngine, count_triangles

__all__ = [
    "pick",
    "bounds",
    "collisions",
    "attribute_search",
    "image_info",
    "count_triangles",
    "Hit",
    "ImageInfo",
    "AttributeSearch",
    "AnalysisEngine",
    "PickEngine",
    "BoundsEngine",
    "CollisionEngine",
    "AttributeSearchEngine",
    "ImageInfoEngine",
    "TriangleCountEngine",
    "AnalyticIntersector",
    "TriangleSetIntersector",
    "ClipPlaneTracker",
    "BoundsHandler",
    "analytic_bounds",
    "bodies_collide",
    "pixel_ray",
    "world_matrix_of",
    "evaluate_in_place",
    "screen_corners",
    "node_origin",
]
