"""Generic lights as Radiance light sources, in physical units that give GL's brightness.

Radiance lights are luminous surfaces.  The conversion (units: W/sr/m^2 for
radiance, W/sr for intensity, W/m^2 for irradiance, per RGB channel; Radiance's
luminous efficacy 179 lm/W turns them into cd/m^2, cd and lux):

- ``PointLight``: a small ``illum`` sphere (radius 1/1000 of its distance to the
  camera's centre of interest) of radiance ``I / (pi r^2)``, so its intensity
  is ``I = pi * color * intensity * att(d) * d^2`` (W/sr), matched to GL at
  that distance (:func:`omnirender.attributes.photometry.intensity_scale`); a
  light with attenuation ``(0, 0, 1)`` is a physical point light of intensity
  ``pi * color * intensity`` everywhere.  ``illum`` rather than ``light``:
  Radiance then treats it as a source but does not show it to camera rays, as
  GL, POV-Ray and Mitsuba do not show point lights.
- ``SpotLight``: the same sphere with a ``brightfunc`` pattern giving GL's
  ``cos^exponent`` inside the cone and 0 outside (Radiance's ``spotlight`` has
  no falloff and shows its sphere).
- ``DirectionalLight`` (and the headlight of scenes without lights): a
  ``source`` of angular diameter 0.1 degrees whose irradiance is ``pi * color``.
- ``AmbientLight``, the lights' ambient terms and GL's global ambient: Radiance's
  ambient value ``-av`` (reflected with the diffuse colour, like Mitsuba's
  constant environment) and a ``glow`` environment of the same radiance, which
  specular surfaces (metals) reflect as GL's ambient term makes them do.
- ``om.radiance.Sky``: a ``glow`` source over the hemisphere (lights through ``-ab``).

``LightSwitch`` cannot be expressed: Radiance lights everything with every source.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..attributes import AmbientLight, AreaLight, DirectionalLight, DiscLight, PointLight, SpotLight
from ..attributes.photometry import area_radiance, headlight_direction, intensity_scale
from . import rad
from .attributes import Sky

__all__ = ["lights_text", "SOURCE_ANGLE", "RADIUS_FRACTION", "spot_pattern"]

#: Angular diameter (degrees) of the Radiance source standing for a directional light.
SOURCE_ANGLE = 0.1
#: A point light's sphere radius as a fraction of its distance to the camera's centre of interest.
RADIUS_FRACTION = 1e-3


def _solid_angle(diameter_degrees: float) -> float:
    return 2.0 * math.pi * (1.0 - math.cos(math.radians(diameter_degrees) / 2.0))


def _source(engine: Any, towards: np.ndarray, irradiance: np.ndarray, angle: float = SOURCE_ANGLE) -> str:
    mat, ident = engine.new_id("l"), engine.new_id("s")
    radiance = np.asarray(irradiance, np.float64) / _solid_angle(angle)
    return rad.primitive("void", "light", mat, (), radiance) + rad.primitive(
        mat, "source", ident, (), [*towards, angle]
    )


def spot_pattern(axis: np.ndarray, cos_cutoff: float, exponent: float) -> str:
    """A calcomp expression of the ray direction (Dx, Dy, Dz): GL's spot factor for light leaving along -D."""
    a = [f"({rad.number(v)})" for v in axis]
    c = f"(-(Dx*{a[0]}+Dy*{a[1]}+Dz*{a[2]}))"
    inside = f"{c}^({rad.number(exponent)})" if exponent > 0.0 else "1"
    return f"if({c}-({rad.number(cos_cutoff - 1e-9)}),{inside},0)"


def _sphere_light(engine: Any, light: Any, world: np.ndarray) -> str:
    p = light.world_position(world)
    reference = engine.reference_point()
    radius = RADIUS_FRACTION * max(float(np.linalg.norm(reference - p)), 1e-3)
    intensity = np.asarray(light.diffuse, np.float64) * intensity_scale(light, p, reference)
    radiance = intensity / (math.pi * radius * radius)
    out = ""
    modifier = "void"
    if isinstance(light, SpotLight):
        modifier = engine.new_id("b")
        expr = spot_pattern(light.world_direction(world), light.cos_cutoff, float(light.exponent))
        out += rad.primitive("void", "brightfunc", modifier, (expr, "."))
    mat, ident = engine.new_id("l"), engine.new_id("s")
    out += rad.primitive(modifier, "illum", mat, (), radiance)
    return out + rad.primitive(mat, "sphere", ident, (), [*p, radius])


def _area_light(engine: Any, light: AreaLight, world: np.ndarray) -> str:
    centre, hu, hv, normal = light.world_frame(world)
    lu, lv = float(np.linalg.norm(hu)), float(np.linalg.norm(hv))
    gap = 1e-4 * max(lu, lv)
    mat = engine.new_id("l")
    out = rad.primitive("void", "light", mat, (), area_radiance(light))
    for side in (1.0, -1.0) if light.two_sided else (1.0,):
        shift = side * normal * gap if light.two_sided else np.zeros(3)
        ident = engine.new_id("s")
        if isinstance(light, DiscLight) and abs(lu - lv) <= 1e-9 * max(lu, lv) and abs(float(np.dot(hu, hv))) < 1e-9:
            out += rad.primitive(mat, "ring", ident, (), [*(centre + shift), *(side * normal), 0.0, lu])
            continue
        pts = light.world_polygon(world, 48) + shift
        if side < 0.0:
            pts = pts[::-1]
        out += rad.primitive(mat, "polygon", ident, (), pts.reshape(-1))
    return out


def _sky(engine: Any, sky: Sky, world: np.ndarray) -> str:
    up = np.asarray(world, np.float64)[:3, :3] @ np.asarray(sky.up)
    up /= np.linalg.norm(up)
    mat, ident = engine.new_id("l"), engine.new_id("s")
    return rad.primitive("void", "glow", mat, (), [*sky.radiance, 0]) + rad.primitive(
        mat, "source", ident, (), [*up, 180]
    )


#: The coverage pass's environment: white, seen only by rays that pass through surfaces (negative radius).
COVERAGE_ENVIRONMENT = "void glow om_bg\n0\n0\n4 1 1 1 -1\nom_bg source om_bgs\n0\n0\n4 0 1 0 360\n"


def lights_text(engine: Any) -> str:
    """All queued lights of ``engine`` as Radiance text (plus the headlight when the scene has no light)."""
    if engine.coverage:
        return COVERAGE_ENVIRONMENT
    parts = []
    for light, world in engine.pending_lights:
        if isinstance(light, AmbientLight):
            continue  # in the ambient value
        if isinstance(light, Sky):
            parts.append(_sky(engine, light, world))
        elif isinstance(light, AreaLight):
            parts.append(_area_light(engine, light, world))
        elif isinstance(light, DirectionalLight):
            towards = -light.world_direction(world)
            parts.append(_source(engine, towards, math.pi * np.asarray(light.diffuse, np.float64)))
        elif isinstance(light, (PointLight, SpotLight)):
            parts.append(_sphere_light(engine, light, world))
    ambient = engine.ambient_value()
    if np.any(ambient > 0.0):
        mat, ident = engine.new_id("l"), engine.new_id("s")
        parts.append(rad.comment("ambient light: a uniform environment") + "\n")
        parts.append(
            rad.primitive("void", "glow", mat, (), [*ambient, 0])
            + rad.primitive(mat, "source", ident, (), [0, 1, 0, 360])
        )
    if not engine.pending_lights and engine.headlight:  # any light, even an ambient one, turns it off (as in GL)
        towards = -headlight_direction(*engine.camera_or_default())
        parts.append(rad.comment("headlight (the scene has no light)") + "\n")
        parts.append(_source(engine, towards, np.full(3, math.pi)))
    return "".join(parts)
