"""The POV-Ray adapter: scene graph -> POV-Ray 3.7 SDL -> the ``povray`` program -> ``om.Image``.

``om.render(scene, engine="povray", size=(w, h), quality=9, antialias=False)``
renders; ``om.export(scene, "scene.pov")`` writes the SDL alone.
``POVRayEngine`` is the engine (service ``"pov.paint"``); ``Finish``,
``Pigment``, ``Normal``, ``Interior``, ``GlobalSettings`` and ``Raw`` are
POV-Ray-specific attributes that other engines ignore (``Block`` writes nested
blocks with arguments).
"""

from __future__ import annotations

from .api import available, export, render, scene_sdl
from .attributes import Block, Finish, GlobalSettings, Interior, Normal, Pigment, Raw, SDLBlock
from .engine import POVRayEngine
from .runner import POVRayError
from .sdl import SDLError

__all__ = [
    "POVRayEngine",
    "render",
    "export",
    "available",
    "scene_sdl",
    "POVRayError",
    "SDLError",
    "SDLBlock",
    "Block",
    "Finish",
    "Pigment",
    "Normal",
    "Interior",
    "GlobalSettings",
    "Raw",
]
