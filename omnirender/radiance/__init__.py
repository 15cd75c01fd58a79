"""The Radiance adapter: scene graph -> Radiance scene description -> ``oconv`` / ``rpict`` / ``rtrace``.

``om.render(scene, engine="radiance", size=(w, h))`` renders a picture;
``om.export(scene, "scene.rad")`` writes the description with its meshes and
pictures; :func:`irradiance`, :func:`illuminance`, :func:`radiance` and
:func:`luminance` compute lighting in physical units with ``rtrace``.
``RadianceEngine`` is the engine (service ``"rad.paint"``); ``Material``,
``Options``, ``Sky`` and ``Raw`` are Radiance-specific attributes that the
other engines ignore.  The Radiance programs come from the PyPI package
``pyradiance`` (``pip install 'omnirender[radiance]'``).
"""

from __future__ import annotations

from .analysis import LUMINOUS_EFFICACY, illuminance, irradiance, luminance, radiance
from .api import available, export, render, scene_description
from .attributes import Material, Options, Raw, Sky
from .engine import RadianceEngine
from .rad import RadError
from .runner import RadianceError

__all__ = [
    "RadianceEngine",
    "render",
    "export",
    "available",
    "scene_description",
    "irradiance",
    "illuminance",
    "radiance",
    "luminance",
    "LUMINOUS_EFFICACY",
    "RadianceError",
    "RadError",
    "Material",
    "Options",
    "Sky",
    "Raw",
]
