"""The generic rendering system: components, handlers, techniques, engines.

This package imports no graphics library and nothing else of omnirender.
"""

from .camera import Camera, look_at_matrix, orthographic_matrix, perspective_matrix
from .component import (
    Attribute,
    ChangeJournal,
    MonoAttribute,
    PolyAttribute,
    RenderingComponent,
    Shape,
    category_of,
    version_key,
)
from .context import RenderingContext
from .drops import DroppedContentError, DroppedContentWarning
from .engine import Engine
from .errors import EvaluationError, NoHandlerError, OmnirenderError
from .handler import (
    SIMPLIFY,
    AttributePainter,
    AttributeSimplifier,
    Handler,
    HandlerRegistry,
    RayIntersector,
    ShapePainter,
    ShapeSimplifier,
    default_for,
    registry,
)
from .light import Light, LightSwitch
from .limits import ResourceLimitError
from .mask import MaskError, compile_mask
from .paths import PathPolicy, RemoteReferenceError, UntrustedReferenceError, resolve_reference
from .technique import Technique
from .transform import Matrix, Rotation, Scaling, Transform, Translation, TranslationArray, finite_vector

__all__ = [
    "PathPolicy",
    "resolve_reference",
    "UntrustedReferenceError",
    "RemoteReferenceError",
    "ResourceLimitError",
    "DroppedContentWarning",
    "DroppedContentError",
    "ChangeJournal",
    "RenderingComponent",
    "Shape",
    "Attribute",
    "MonoAttribute",
    "PolyAttribute",
    "category_of",
    "version_key",
    "Handler",
    "ShapePainter",
    "ShapeSimplifier",
    "AttributePainter",
    "AttributeSimplifier",
    "RayIntersector",
    "HandlerRegistry",
    "registry",
    "default_for",
    "SIMPLIFY",
    "Technique",
    "Engine",
    "RenderingContext",
    "NoHandlerError",
    "EvaluationError",
    "OmnirenderError",
    "Transform",
    "Matrix",
    "Translation",
    "TranslationArray",
    "Rotation",
    "Scaling",
    "finite_vector",
    "Light",
    "LightSwitch",
    "Camera",
    "look_at_matrix",
    "perspective_matrix",
    "orthographic_matrix",
    "compile_mask",
    "MaskError",
]
