"""UsdLux lights and UsdGeomCamera as omnirender's lights and camera (both placed by their node's transform).

USD lights emit radiance ``L = intensity * 2^exposure * color`` (linear); a
physical renderer shows a diffuse surface of albedo ``kd`` as ``kd * E / pi``
with ``E`` the irradiance.  omnirender's lights follow OpenGL
(:mod:`omnirender.attributes.photometry`: ``kd * c * att(d)``), the same
convention :func:`~omnirender.formats.gltf.reader.light_from_gltf` uses, so:

- ``DistantLight`` (along its -z): ``DirectionalLight`` of intensity ``E / pi``
  where ``E = L pi sin^2(angle / 2)`` is the irradiance of a sun disc of
  radiance ``L`` and angular diameter ``angle`` (USD's defaults, 50000 and
  0.53 degrees, give 1.07), ``L / pi`` with ``normalize``;
- ``SphereLight``: ``PointLight`` with ``1/d^2`` attenuation and intensity
  ``L r^2`` (radiant intensity ``L pi r^2`` over pi), ``L / (4 pi)`` with
  ``normalize`` or ``treatAsPoint``; with ``shaping:cone:angle`` a ``SpotLight``;
- ``RectLight`` and ``DiskLight``: ``om.RectLight`` (``width`` along x,
  ``height`` along y) and ``om.DiscLight`` facing -z, of radiance ``L``
  (``L / area`` with ``normalize``): the area lights' rule of
  :mod:`omnirender.attributes.photometry` is USD's radiance, so no factor;
  their shadows are soft in every engine;
- ``DomeLight``: an ``AmbientLight`` of the dome's colour (times the mean of
  its texture, when Pillow can read the texture; HDR/EXR files cannot be read
  and only the colour is used, with a warning); the dome is not drawn as
  a background;
- other lights (cylinder, portal, geometry, plugin lights) are left out
  with a warning naming them.

``UsdGeomCamera``: perspective cameras keep their vertical field of view
(``2 atan(verticalAperture / (2 focalLength))``) and clipping range;
orthographic ones their vertical aperture as height (apertures are in tenths
of a scene unit).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ...attributes import AmbientLight, DirectionalLight, DiscLight, PointLight, RectLight, SpotLight
from ...attributes.photometry import linear_to_srgb
from ...core.camera import Camera

__all__ = ["camera", "light"]


def camera(cam: Any, time: Any) -> Camera:
    """A UsdGeomCamera at the origin of its node looking along -z, y up."""
    gf = cam.GetCamera(time)
    near, far = gf.clippingRange.min, gf.clippingRange.max
    mask_attr = cam.GetPrim().GetAttribute("omnirender:mask")
    mask = mask_attr.Get() if mask_attr else None
    near = max(float(near), 1e-4)
    far = max(float(far), near * 1.001)
    if str(gf.projection) == "Orthographic" or str(cam.GetProjectionAttr().Get(time)) == "orthographic":
        height = float(gf.verticalAperture) * 0.1
        return Camera(
            eye=(0, 0, 0), center=(0, 0, -1), up=(0, 1, 0), fov=None, height=height, near=near, far=far, mask=mask
        )
    fov = math.degrees(2.0 * math.atan(float(gf.verticalAperture) / (2.0 * max(float(gf.focalLength), 1e-9))))
    return Camera(
        eye=(0, 0, 0), center=(0, 0, -1), up=(0, 1, 0), fov=min(max(fov, 1e-3), 179.0), near=near, far=far, mask=mask
    )


def _color(api: Any, time: Any) -> tuple[tuple[float, float, float], float]:
    """(display colour in [0, 1], scalar intensity) of a light: its linear colour split into hue and magnitude."""
    rgb = np.asarray(api.GetColorAttr().Get(time) or (1.0, 1.0, 1.0), np.float64)
    intensity = float(api.GetIntensityAttr().Get(time) or 0.0) * 2.0 ** float(api.GetExposureAttr().Get(time) or 0.0)
    peak = float(rgb.max()) if rgb.max() > 1.0 else 1.0  # colours above 1 go into the intensity
    srgb = np.clip(linear_to_srgb(rgb / peak), 0.0, 1.0)
    return (float(srgb[0]), float(srgb[1]), float(srgb[2])), intensity * peak


def light(prim: Any, time: Any, materials: Any, warn: Callable[[str], None]) -> Any:
    """The omnirender light of a UsdLux light prim; None for a light left out; False for a prim that is no light."""
    from pxr import UsdLux

    if (
        not prim.HasAPI(UsdLux.LightAPI)
        and not prim.IsA(UsdLux.BoundableLightBase)
        and not prim.IsA(UsdLux.NonboundableLightBase)
    ):
        return False
    own = _omnirender_light(prim)
    if own is not None:
        return own
    api = UsdLux.LightAPI(prim)
    color, intensity = _color(api, time)
    shadows = UsdLux.ShadowAPI(prim)
    casts = bool(shadows.GetShadowEnableAttr().Get(time)) if prim.HasAPI(UsdLux.ShadowAPI) else True
    normalize = bool(api.GetNormalizeAttr().Get(time))
    if api.GetEnableColorTemperatureAttr().Get(time):
        warn(f"{prim.GetPath()}: colour temperature is not supported; the light's colour is used")
    common = {"color": color, "casts_shadows": casts}
    if prim.IsA(UsdLux.DistantLight):
        half = math.radians(float(UsdLux.DistantLight(prim).GetAngleAttr().Get(time) or 0.0)) / 2.0
        value = intensity / math.pi if normalize or half <= 0.0 else intensity * math.sin(half) ** 2
        return DirectionalLight(direction=(0, 0, -1), intensity=value, **common)
    if prim.IsA(UsdLux.SphereLight):
        sphere = UsdLux.SphereLight(prim)
        r = float(sphere.GetRadiusAttr().Get(time) or 0.0)
        value = intensity / (4.0 * math.pi) if normalize or r == 0.0 else intensity * r * r
        shaping = UsdLux.ShapingAPI(prim)
        cone = shaping.GetShapingConeAngleAttr().Get(time) if prim.HasAPI(UsdLux.ShapingAPI) else None
        if cone is not None and 0.0 < float(cone) < 90.0:
            return SpotLight(
                position=(0, 0, 0), direction=(0, 0, -1), cutoff=float(cone), exponent=0.0, intensity=value,
                constant=0.0, quadratic=1.0, **common,
            )  # fmt: skip
        return PointLight(position=(0, 0, 0), intensity=value, constant=0.0, quadratic=1.0, **common)
    if prim.IsA(UsdLux.RectLight):
        rect = UsdLux.RectLight(prim)
        width, height = float(rect.GetWidthAttr().Get(time)), float(rect.GetHeightAttr().Get(time))
        if rect.GetTextureFileAttr().Get(time):
            warn(f"{prim.GetPath()}: a rect light's texture is not supported; its colour is used")
        if width <= 0.0 or height <= 0.0:
            warn(f"{prim.GetPath()}: a rect light of size {width} x {height} emits nothing; left out")
            return None
        value = intensity / (width * height) if normalize else intensity
        return RectLight(direction=(0, 0, -1), up=(0, 1, 0), width=width, height=height, intensity=value, **common)
    if prim.IsA(UsdLux.DiskLight):
        radius = float(UsdLux.DiskLight(prim).GetRadiusAttr().Get(time))
        if radius <= 0.0:
            warn(f"{prim.GetPath()}: a disk light of radius {radius} emits nothing; left out")
            return None
        value = intensity / (math.pi * radius * radius) if normalize else intensity
        return DiscLight(direction=(0, 0, -1), up=(0, 1, 0), radius=radius, intensity=value, **common)
    if prim.IsA(UsdLux.DomeLight):
        dome = UsdLux.DomeLight(prim)
        asset = dome.GetTextureFileAttr().Get(time)
        mean = np.ones(3)
        if asset is not None and asset.path:
            pixels = materials.pixels_of_asset(asset, str(prim.GetPath()))
            if pixels is not None:
                mean = _srgb_mean(pixels)
        rgb = np.clip(np.asarray(color) * mean, 0.0, 1.0)
        return AmbientLight(color=tuple(float(c) for c in rgb), intensity=intensity)
    warn(f"{prim.GetPath()}: {prim.GetTypeName()} lights are not supported; left out")
    return None


def _omnirender_light(prim: Any) -> Any:
    """The light an omnirender export kept as ``omnirender:*`` attributes (placed by the prim), or None."""
    kind = prim.GetAttribute("omnirender:type")
    classes = {"DirectionalLight": DirectionalLight, "PointLight": PointLight, "SpotLight": SpotLight,
               "AmbientLight": AmbientLight, "RectLight": RectLight, "DiscLight": DiscLight}  # fmt: skip
    if not kind or kind.Get() not in classes:
        return None
    values: dict[str, Any] = {}
    for attr in prim.GetAttributes():
        name = attr.GetName()
        if name.startswith("omnirender:") and name != "omnirender:type":
            value = attr.Get()
            values[name[len("omnirender:") :]] = tuple(value) if hasattr(value, "__len__") else value
    cls = classes[kind.Get()]
    if cls in (PointLight, SpotLight, RectLight, DiscLight):
        values["position"] = (0.0, 0.0, 0.0)
    if cls in (DirectionalLight, SpotLight, RectLight, DiscLight):
        values["direction"] = (0.0, 0.0, -1.0)
    if cls in (RectLight, DiscLight):
        values["up"] = (0.0, 1.0, 0.0)  # the prim's frame: x along the width, y along the height
    try:
        return cls(**values)
    except (TypeError, ValueError):
        return None


def _srgb_mean(pixels: np.ndarray) -> np.ndarray:
    """The mean colour of sRGB pixels, averaged in linear light, as a display colour."""
    from ...attributes.photometry import srgb_to_linear

    lin = srgb_to_linear(pixels[..., :3].reshape(-1, 3).astype(np.float64) / 255.0)
    return np.clip(linear_to_srgb(lin.mean(axis=0)), 0.0, 1.0)
