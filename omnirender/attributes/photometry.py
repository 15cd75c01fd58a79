"""From OpenGL display values to physical quantities: the one rule physically based engines share.

omnirender's colours are sRGB display values and its lights follow OpenGL: a
diffuse surface of colour ``kd`` lit head-on by a light of colour ``c`` shows
``kd * c`` (linear), without Lambert's ``1 / pi``.  A physically based engine
reflects ``kd * E / pi`` of an irradiance ``E``, so the same picture needs

- a directional light of colour ``c``: irradiance ``E = pi * c`` (W/m^2 per RGB channel);
- a point or spot light: radiant intensity ``I = pi * c * att(d) * d^2`` (W/sr), which
  gives the GL brightness exactly at the distance ``d`` from the light where it is
  matched (:func:`intensity_scale`); a light with OpenGL attenuation ``(0, 0, Q)``
  already falls off as ``1 / d^2`` and gets ``I = pi * c / Q`` at every distance;
- a rectangle or disc light (``om.RectLight``, ``om.DiscLight``) of colour ``c``: a surface of
  uniform radiance ``L = c`` (W/(m^2 sr); one side, or both when ``two_sided``), so a
  diffuse surface shows ``kd * c * F`` with ``F`` the light's form factor
  (:func:`area_form_factor`; 1 under an infinite light, as a head-on directional light
  of the same colour) and one side emits the power ``pi * c * area`` (:func:`area_power`).
  No OpenGL attenuation: the falloff is the form factor's, the same in every engine;
- ambient light: the global ambient (0.2) plus every light's ambient term is a uniform
  environment radiance, reflected with the diffuse colour (:func:`ambient_total`);
- Phong shininess ``n`` (the exponent of the reflected-light lobe, as in POV-Ray's
  ``phong_size`` and the GL engine) becomes a microfacet slope ``sqrt(2 / (4 n + 2))``
  (:func:`phong_roughness`).

Mitsuba and Radiance convert with these functions, so the same scene has the
same brightness in both and in GL.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = [
    "GLOBAL_AMBIENT",
    "HEADLIGHT",
    "srgb_to_linear",
    "linear_to_srgb",
    "linear_rgb",
    "intensity_scale",
    "ambient_total",
    "headlight_direction",
    "phong_roughness",
    "spot_beam",
    "area_radiance",
    "area_power",
    "area_form_factor",
]

#: OpenGL's global ambient light, added to the lights' ambient terms.
GLOBAL_AMBIENT = 0.2
#: The GL engine's headlight for scenes without lights: direction towards the light in eye space.
HEADLIGHT = np.array([-0.25, 0.35, 1.0]) / np.linalg.norm([-0.25, 0.35, 1.0])


def srgb_to_linear(c: Any) -> np.ndarray:
    """sRGB-encoded values in [0, 1] to linear values (the IEC 61966-2-1 curve)."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, None)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: Any) -> np.ndarray:
    """Linear values to sRGB encoding (clamped to [0, 1] first)."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def _channel(c: float) -> float:
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def linear_rgb(rgb: Any) -> tuple[float, float, float]:
    """The first three values of an sRGB colour as a linear (r, g, b) tuple of Python floats (no numpy: fast).

    Colours given as tuples (what the attributes hold) are remembered: a material's ambient, specular and
    emission are most often the same few (a Material replaced per frame converts only its new colour)."""
    if rgb.__class__ is tuple:
        found = _LINEAR.get(rgb)
        if found is not None:
            return found
    r, g, b = rgb[:3]
    # (+ 0.0: a -0.0 gives 0.0, as the 0.0 it equals as a key does, whichever was remembered first)
    out = (_channel(float(r)) + 0.0, _channel(float(g)) + 0.0, _channel(float(b)) + 0.0)
    if rgb.__class__ is tuple:
        if len(_LINEAR) >= 256:
            _LINEAR.clear()
        _LINEAR[rgb] = out
    return out


#: sRGB tuple -> its linear_rgb (bounded: cleared when full)
_LINEAR: dict[tuple, tuple[float, float, float]] = {}


def intensity_scale(light: Any, position: np.ndarray, reference: np.ndarray) -> float:
    """Radiant intensity (W/sr) per unit of light colour for a point or spot light at ``position``.

    ``pi * att(d) * d^2`` with ``d`` the distance to ``reference`` (the point
    where the GL brightness is matched, usually the camera's centre of
    interest).  Lights with purely quadratic attenuation are matched
    everywhere: the result is ``pi / Q`` whatever ``reference`` is.
    """
    if float(light.constant) == 0.0 and float(light.linear) == 0.0:
        return math.pi / float(light.quadratic)
    d = max(float(np.linalg.norm(np.asarray(reference, np.float64) - np.asarray(position, np.float64))), 1e-6)
    return math.pi * d * d * float(light.attenuation(d))


def ambient_total(lights: Iterable[tuple[Any, Any]], global_ambient: float = GLOBAL_AMBIENT) -> np.ndarray:
    """RGB ambient radiance: ``global_ambient`` plus the ambient term of every (light, matrix) pair."""
    total = np.full(3, float(global_ambient))
    for light, _ in lights:
        amb = getattr(light, "ambient", None)
        if amb is not None:
            total += np.asarray(amb, dtype=np.float64)
    return total


def headlight_direction(camera: Any, camera_world: np.ndarray) -> np.ndarray:
    """World direction of travel of the GL headlight (white, from a little above-left of the eye)."""
    eye_to_world = np.asarray(camera_world, np.float64) @ np.linalg.inv(camera.view_matrix())
    towards = eye_to_world[:3, :3] @ HEADLIGHT
    return -towards / np.linalg.norm(towards)


def phong_roughness(shininess: float) -> float:
    """Phong exponent to a microfacet RMS slope, in [0.01, 1].

    ``shininess`` is the exponent of Phong's lobe (reflected light against the
    eye), whose highlight is half as wide in angle as the Blinn-Phong lobe of
    the same exponent: it equals Blinn-Phong ``4 n``, and Walter et al.'s
    Beckmann slope of a Blinn-Phong exponent ``m`` is ``sqrt(2 / (m + 2))``.
    Shininess below 1 acts as 1 in every engine.
    """
    n = max(float(shininess), 1.0)
    return float(min(1.0, max(0.01, math.sqrt(2.0 / (4.0 * n + 2.0)))))


def spot_beam(light: Any) -> float:
    """Half angle (degrees) of a spot light's full beam: where ``cos^exponent`` is above one half."""
    cutoff = float(light.cutoff)
    if light.exponent <= 0:
        return cutoff
    return min(cutoff, math.degrees(math.acos(0.5 ** (1.0 / float(light.exponent)))))


def area_radiance(light: Any) -> np.ndarray:
    """The emitted radiance of an area light (W/(m^2 sr) per channel): its ``diffuse`` colour, unscaled."""
    return np.asarray(light.diffuse, dtype=np.float64)


def area_power(light: Any, matrix: np.ndarray) -> np.ndarray:
    """Total power (W per channel) an area light under world ``matrix`` emits: ``pi * L * area`` per lit side."""
    sides = 2.0 if light.two_sided else 1.0
    return sides * math.pi * area_radiance(light) * light.world_area(matrix)


def area_form_factor(points: Any, normals: Any, polygon: Any, two_sided: bool = False) -> np.ndarray:
    """Form factor from surface points to a flat emitting polygon (Lambert's exact contour integral).

    ``points`` and ``normals`` are ``(..., 3)`` (normals of unit length),
    ``polygon`` ``(k, 3)`` counter-clockwise seen from its lit side (as
    ``AreaLight.world_polygon`` gives it).  ``F = 1/(2 pi) sum_i theta_i
    (n . (v_i x v_{i+1}) / |v_i x v_{i+1}|)`` over the edges as seen from the point, with
    the polygon clipped to the point's horizon first; points behind the lit
    side get 0 (unless ``two_sided``).  A diffuse surface of colour ``kd`` under a
    light of colour ``c`` shows ``kd * c * F`` in every engine.
    """
    p = np.asarray(points, np.float64)
    nrm = np.asarray(normals, np.float64)
    poly = np.asarray(polygon, np.float64)
    shape = p.shape[:-1]
    nrm = np.broadcast_to(nrm, p.shape).reshape(-1, 3)
    p = p.reshape(-1, 3)
    light_n = np.cross(poly[1] - poly[0], poly[2] - poly[0])
    light_n /= np.linalg.norm(light_n)
    out = np.zeros(p.shape[0])
    for i in range(p.shape[0]):
        side = float(np.dot(p[i] - poly[0], light_n))
        if side <= 0.0 and not two_sided:
            continue
        verts = _clip_to_horizon(poly - p[i], nrm[i])
        if len(verts) < 3:
            continue
        total = 0.0
        for a, b in zip(verts, np.roll(verts, -1, axis=0), strict=True):
            a_n, b_n = a / np.linalg.norm(a), b / np.linalg.norm(b)
            cross = np.cross(a_n, b_n)
            length = float(np.linalg.norm(cross))
            if length < 1e-15:
                continue
            theta = math.atan2(length, float(np.dot(a_n, b_n)))
            total += theta * float(np.dot(cross, nrm[i])) / length
        out[i] = abs(total) / (2.0 * math.pi)
    return out.reshape(shape)


def _clip_to_horizon(verts: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The part of a polygon (relative to the point) above the plane through the point with ``normal``."""
    h = verts @ normal
    out = []
    k = len(verts)
    for i in range(k):
        a, b = verts[i], verts[(i + 1) % k]
        ha, hb = h[i], h[(i + 1) % k]
        if ha > 0.0:
            out.append(a)
        if (ha > 0.0) != (hb > 0.0):
            t = ha / (ha - hb)
            out.append(a + t * (b - a))
    return np.asarray(out)
