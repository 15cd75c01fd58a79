"""Attribute declarations common to all engines (issue 3).

Appearance (``Color``, ``Material``, ``PBRMaterial``, ``Texture``,
``DrawStyle``, ``BumpMap``, ``MultiTexture``; combined by the one appearance
model of :mod:`.surface`), lights with OpenGL's parameters (``DirectionalLight``,
``PointLight``, ``SpotLight``, ``RectLight``, ``DiscLight``, ``AmbientLight``), transforms (``LookAt``,
``Billboard``) and environment attributes (``ClipPlane``, ``Fog``,
``Background``, ``Tessellation``, ``Highlight``, ``PickId``, ``Collidable``).
Every class validates at construction and rebuilds from ``parameters()``.

The core's ``Camera``, ``LightSwitch``, ``Light`` and transforms are importable
from here too but stay in the core's ``__all__`` (they are ``om.X`` already).
"""

from ..core.camera import Camera
from ..core.light import Light, LightSwitch
from ..core.transform import Matrix, Rotation, Scaling, Transform, Translation
from .appearance import BumpMap, Color, DrawStyle, Material, MultiTexture, PBRMaterial, Texture, TextureLayer
from .environment import Background, ClipPlane, Collidable, Fog, Highlight, PickId, Tessellation
from .lights import (
    AmbientLight,
    AreaLight,  # noqa: F401 - the area lights' base, for engines' isinstance tests (not om.X)
    DirectionalLight,
    DiscLight,
    LightSource,
    PointLight,
    RectLight,
    SpotLight,
)
from .shadowing import Mirror, Shadowing
from .transforms import Billboard, BillboardSimplifier, DirectionOfFlight, LookAt, Polar, Reflection

__all__ = [
    "Color",
    "Material",
    "PBRMaterial",
    "Texture",
    "DrawStyle",
    "BumpMap",
    "TextureLayer",
    "MultiTexture",
    "LightSource",
    "DirectionalLight",
    "PointLight",
    "SpotLight",
    "RectLight",
    "DiscLight",
    "AmbientLight",
    "LookAt",
    "Reflection",
    "DirectionOfFlight",
    "Polar",
    "Billboard",
    "BillboardSimplifier",
    "ClipPlane",
    "Fog",
    "Background",
    "Tessellation",
    "Highlight",
    "PickId",
    "Collidable",
    "Shadowing",
    "Mirror",
]

# Re-exported from the core (already om.X through omnirender.core).
_CORE_REEXPORTS = (Camera, Light, LightSwitch, Matrix, Rotation, Scaling, Transform, Translation)
