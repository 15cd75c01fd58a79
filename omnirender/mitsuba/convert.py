"""Conversions from generic attributes to Mitsuba plugin dicts (no Mitsuba import here).

Colours of materials are taken as sRGB display values (what the GL engine
writes to the screen) and converted to linear reflectances, so a fully lit
surface has the same colour in both engines.  Light colours are linear
radiance scales.  GL point and spot lights with constant attenuation do not
fall off with distance, physical ones always fall off as 1/d^2: the intensity
is chosen so both agree at a reference distance (the camera's centre of
interest by default).  Matrices are numpy 4x4 here; the engine turns them into
``mi.ScalarTransform4f``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..attributes import AmbientLight, AreaLight, Color, DirectionalLight, DiscLight, PointLight, SpotLight
from ..attributes.photometry import (
    GLOBAL_AMBIENT,
    HEADLIGHT,
    ambient_total,
    area_radiance,
    headlight_direction,
    intensity_scale,
    linear_to_srgb,
    phong_roughness,
    spot_beam,
    srgb_to_linear,
)
from ..core import Camera

__all__ = [
    "srgb_to_linear",
    "linear_to_srgb",
    "rgb",
    "material_bsdf",
    "pbr_bsdf",
    "color_bsdf",
    "wrap_bsdf",
    "light_emitter",
    "ambient_emitter",
    "headlight_emitter",
    "GLOBAL_AMBIENT",
    "ENVIRONMENTS",
    "HEADLIGHT",
    "sensor_matrix",
    "sensor_dict",
    "look_at",
    "GL_TO_MITSUBA_EYE",
]

#: GL eye space (looking down -z, +x right) to Mitsuba camera space (looking down +z, +x left).
GL_TO_MITSUBA_EYE = np.diag([-1.0, 1.0, -1.0, 1.0])


def rgb(value: Any, *, linearize: bool = True) -> dict[str, Any]:
    """An ``rgb`` spectrum plugin dict of 3 values (sRGB in, linear out unless ``linearize`` is False)."""
    v = np.asarray(value, dtype=np.float64).reshape(-1)[:3]
    if linearize:
        v = srgb_to_linear(v)
    return {"type": "rgb", "value": [float(x) for x in v]}


def material_bsdf(app: Any, reflectance: dict[str, Any] | None = None) -> dict[str, Any]:
    """A resolved Phong appearance -> ``diffuse``, or ``roughplastic`` when it has a specular colour.

    ``reflectance`` (a texture dict) replaces the diffuse colour when given.
    """
    diffuse = reflectance if reflectance is not None else rgb(app.base, linearize=False)
    spec = float(np.mean(app.specular))
    if spec <= 0.0:
        return {"type": "diffuse", "reflectance": diffuse}
    return {
        "type": "roughplastic",
        "distribution": "beckmann",
        "alpha": phong_roughness(app.shininess),
        "diffuse_reflectance": diffuse,
        "specular_reflectance": min(1.0, float(np.mean(linear_to_srgb(app.specular)))),
        "nonlinear": True,
    }


def pbr_bsdf(app: Any, base_color: dict[str, Any] | None = None) -> dict[str, Any]:
    """A resolved PBR appearance -> ``principled`` (the same metallic-roughness model)."""
    return {
        "type": "principled",
        "base_color": base_color if base_color is not None else rgb(app.base, linearize=False),
        "metallic": float(app.metallic),
        "roughness": float(max(app.roughness, 0.01)),
    }


def color_bsdf(color: Color | None, reflectance: dict[str, Any] | None = None) -> dict[str, Any]:
    """A plain ``Color`` (or the default grey 0.8) -> ``diffuse``."""
    if reflectance is None:
        reflectance = rgb(color.rgb if color is not None else (0.8, 0.8, 0.8))
    return {"type": "diffuse", "reflectance": reflectance}


def wrap_bsdf(bsdf: dict[str, Any], opacity: float, two_sided: bool = True) -> dict[str, Any]:
    """Make a converted BSDF two-sided (GL lights both faces) and translucent via ``mask``."""
    if two_sided:
        bsdf = {"type": "twosided", "material": bsdf}
    if opacity < 1.0:
        bsdf = {"type": "mask", "opacity": float(opacity), "material": bsdf}
    return bsdf


def look_at(origin: np.ndarray, target: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Mitsuba's ``look_at`` (local +z towards the target, +x to the image's left) as numpy."""
    d = np.asarray(target, np.float64) - np.asarray(origin, np.float64)
    d /= np.linalg.norm(d)
    left = np.cross(np.asarray(up, np.float64), d)
    n = np.linalg.norm(left)
    if n < 1e-9:  # up parallel to the direction: any perpendicular will do
        left = np.cross(np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0]), d)
        n = np.linalg.norm(left)
    left /= n
    new_up = np.cross(d, left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, new_up, d, origin
    return m


def light_emitter(light: Any, world: np.ndarray, reference: np.ndarray) -> dict[str, Any] | None:
    """An emitter dict for a generic light with world matrix ``world`` (None: nothing to emit).

    ``reference`` is the point where physical 1/d^2 falloff is made to match
    GL's attenuation.
    """
    if isinstance(light, AmbientLight):
        return None  # summed into the constant environment by the engine (see ambient_emitter)
    color = np.asarray(light.diffuse, dtype=np.float64)
    if isinstance(light, DirectionalLight):
        # irradiance E gives albedo * E / pi reflected radiance; GL: diffuse * color.
        d = light.world_direction(world)
        return {
            "type": "directional",
            "direction": [float(x) for x in d],
            "irradiance": rgb(color * math.pi, linearize=False),
        }
    if isinstance(light, (PointLight, SpotLight)):
        p = light.world_position(world)
        intensity = rgb(color * intensity_scale(light, p, reference), linearize=False)
        if isinstance(light, PointLight):
            return {"type": "point", "position": [float(x) for x in p], "intensity": intensity}
        axis = light.world_direction(world)
        up = np.array([0.0, 1.0, 0.0]) if abs(axis[1]) < 0.99 else np.array([1.0, 0.0, 0.0])
        cutoff = float(light.cutoff)
        beam = spot_beam(light)  # GL's cos^exponent falloff: full beam where it is above one half
        return {
            "type": "spot",
            "to_world": look_at(p, p + axis, up),
            "cutoff_angle": cutoff,
            "beam_width": float(min(beam, cutoff * 0.999)),
            "intensity": intensity,
        }
    return None


#: How far the two faces of a two-sided area light sit apart, as a fraction of its larger half extent.
TWO_SIDED_GAP = 1e-4


def area_light_shapes(light: AreaLight, world: np.ndarray) -> list[dict[str, Any]]:
    """A ``rectangle`` (or ``disk``) shape with an ``area`` emitter of the light's radiance, per lit side.

    The rule of :mod:`omnirender.attributes.photometry`: radiance ``diffuse``
    (linear RGB, W/(m^2 sr)).  Mitsuba's area emitters light the side their
    normal points to; a two-sided light is two shapes facing away from each
    other, ``TWO_SIDED_GAP`` apart.  The shape is black (it reflects nothing)
    and the camera sees it, as it sees any emitter.
    """
    centre, hu, hv, normal = light.world_frame(world)
    gap = TWO_SIDED_GAP * max(float(np.linalg.norm(hu)), float(np.linalg.norm(hv)))
    out = []
    for side in (1.0, -1.0) if light.two_sided else (1.0,):
        n = side * normal
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2] = hu, hv, n
        m[:3, 3] = centre + (n * gap if light.two_sided else 0.0)
        out.append(
            {
                "type": "disk" if isinstance(light, DiscLight) else "rectangle",
                "to_world": m,
                "emitter": {"type": "area", "radiance": rgb(area_radiance(light), linearize=False)},
                "bsdf": {"type": "diffuse", "reflectance": rgb((0.0, 0.0, 0.0), linearize=False)},
            }
        )
    return out


#: Emitter plugins that are environments (Mitsuba allows one per scene).
ENVIRONMENTS = ("constant", "envmap", "sunsky")


def ambient_emitter(lights: list[tuple[Any, np.ndarray]], global_ambient: float = GLOBAL_AMBIENT) -> dict | None:
    """A ``constant`` environment for GL's ambient light: the global ambient plus every light's ambient term.

    A constant environment of radiance L lights an unoccluded diffuse surface
    to albedo * L; GL's ambient term is material ambient * total ambient, so
    both agree where the material's ambient colour equals its diffuse one (and
    for plain ``Color``s); Mitsuba adds the occlusion GL does not have.
    """
    total = ambient_total(lights, global_ambient)
    if not np.any(total > 0.0):
        return None
    return {"type": "constant", "radiance": rgb(total, linearize=False)}


def headlight_emitter(camera: Camera, camera_world: np.ndarray) -> dict[str, Any]:
    """The GL engine's headlight (white, from a little above-left of the eye) as a ``directional`` emitter."""
    d = headlight_direction(camera, camera_world)
    return {
        "type": "directional",
        "direction": [float(x) for x in d],
        "irradiance": rgb((math.pi,) * 3, linearize=False),
    }


def _translation(t: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = t
    return m


def sensor_matrix(camera: Camera, camera_world: np.ndarray, aspect: float) -> np.ndarray:
    """Mitsuba sensor ``to_world`` reproducing the camera's GL view exactly.

    The GL eye looks down -z with +x to the right; Mitsuba's camera looks down
    +z with +x to the left: a half turn about y.  Mitsuba's orthographic camera
    sees x in [-1, 1] and y in [-1/aspect, 1/aspect]; scaling x and y by
    ``height * aspect / 2`` makes the view ``height`` tall.
    """
    eye_to_world = np.asarray(camera_world, np.float64) @ np.linalg.inv(camera.view_matrix())
    m = eye_to_world @ GL_TO_MITSUBA_EYE
    if camera.is_orthographic:
        if camera.is_off_axis:  # parallel rays: the off-axis window moves with the eye
            m = eye_to_world @ _translation(np.array([*camera.shift, 0.0]) * camera.height) @ GL_TO_MITSUBA_EYE
        s = camera.height * aspect / 2.0
        m = m @ np.diag([s, s, 1.0, 1.0])
    return m


def sensor_dict(camera: Camera, camera_world: np.ndarray, size: tuple[int, int], film: dict[str, Any]) -> dict:
    """A ``perspective`` or ``orthographic`` sensor dict (with ``film``) for the camera."""
    w, h = size
    sensor: dict[str, Any] = {
        "type": "orthographic" if camera.is_orthographic else "perspective",
        "to_world": sensor_matrix(camera, camera_world, w / h),
        "near_clip": float(camera.near),
        "far_clip": float(camera.far),
        "film": film,
    }
    if not camera.is_orthographic:
        sensor["fov"] = float(camera.fov)
        sensor["fov_axis"] = "y"
        if camera.is_off_axis:
            # Mitsuba's principal point offset is in film widths (x, to the right) and film heights (y, down)
            sensor["principal_point_offset_x"] = float(camera.shift[0] * h / w)
            sensor["principal_point_offset_y"] = float(-camera.shift[1])
    return sensor
