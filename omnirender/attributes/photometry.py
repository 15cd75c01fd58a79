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
    """The first three values of an sRGB colour as a linear (r, g, b) tuple of Python floats (no numpy: fast)."""
    r, g, b = rgb[:3]
    return (_channel(float(r)), _channel(float(g)), _channel(float(b)))


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
