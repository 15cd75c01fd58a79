"""Shape declarations (``om.Sphere``, ``om.TriangleSet``...): parameters only, validated at construction.

Every shape has a default simplifier (registered for every engine in
:mod:`omnirender.shapes.simplifiers`) that ends in TriangleSets, LineSets or
PointSets, so any engine can show any shape; painters are optional speed-ups.
"""

from . import simplifiers  # noqa: E402,F401  (registers the default simplifiers)
from .base import DeclaredShape
from .csg import CSG
from .files import MeshFile
from .grids import Heightfield, TransferFunction, Volume
from .instances import InstanceId, InstanceSet
from .lod import LevelOfDetail
from .meshes import LineSet, PointSet, Polygon, Polyline, TriangleSet
from .nurbs import NURBSSurface, TrimCurve
from .primitives import Arrow, Box, Cone, Cylinder, Disk, Rectangle, Sphere, Torus
from .splats import GaussianSplats
from .text import Text

__all__ = [
    "Sphere",
    "Box",
    "Cylinder",
    "Cone",
    "Torus",
    "Disk",
    "Rectangle",
    "Arrow",
    "TriangleSet",
    "Polygon",
    "LineSet",
    "Polyline",
    "PointSet",
    "Heightfield",
    "Volume",
    "TransferFunction",
    "Text",
    "MeshFile",
    "CSG",
    "InstanceId",
    "InstanceSet",
    "GaussianSplats",
    "LevelOfDetail",
    "NURBSSurface",
    "TrimCurve",
    "DeclaredShape",
]

from . import (
    csg_simplifier,  # noqa: E402,F401  (registers the CSG's mesh-boolean simplifier)
    nurbs_simplifier,  # noqa: E402,F401  (registers the NURBS surface's mesh simplifier)
)
