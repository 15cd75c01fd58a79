"""Texture work done on the CPU, once, for engines that cannot do it per pixel.

Offline engines (POV-Ray, Mitsuba, Radiance) and the glTF exporter have one
texture per slot and one set of texture coordinates; the GL engine does these
things in its shaders.  Everything here works on (H, W, 4) uint8 RGBA images
whose row 0 is the top, with omnirender's texture coordinates (v = 0 at the
bottom row):

- :func:`sample`: bilinear look-up with a texture's wrap mode;
- :func:`scaled_image`: a texture multiplied by a colour factor (glTF's
  ``baseColorFactor * texture``), for engines that cannot multiply;
- :func:`height_to_normal_map` and :func:`normal_to_height`: a bump map's
  tangent-space normal map, and back (Frankot-Chellappa integration: POV-Ray
  bumps with heights, not normals);
- :func:`bake_layers`: a :class:`~.appearance.MultiTexture` composited into one
  image in the coordinates of UV set 0;
- :func:`luminance`, :func:`channel_mean`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .photometry import linear_to_srgb, srgb_to_linear

__all__ = [
    "sample",
    "scaled_image",
    "height_to_normal_map",
    "normal_to_height",
    "bake_layers",
    "luminance",
    "channel_mean",
    "BAKE_LIMIT",
]

#: Largest side of a baked image.
BAKE_LIMIT = 2048


def _wrap(coord: np.ndarray, size: int, mode: str) -> np.ndarray:
    if mode == "clamp":
        return np.clip(coord, 0, size - 1)
    if mode == "mirror":
        period = 2 * size
        c = np.mod(coord, period)
        return np.where(c >= size, period - 1 - c, c)
    return np.mod(coord, size)


def sample(image: np.ndarray, uv: np.ndarray, wrap: str = "repeat", nearest: bool = False) -> np.ndarray:
    """Bilinear (or nearest) look-up of ``image`` (H, W, C) at ``uv`` (..., 2); float64 (..., C) in image units."""
    img = np.asarray(image, np.float64)
    h, w = img.shape[:2]
    uv = np.asarray(uv, np.float64)
    x = uv[..., 0] * w - 0.5
    y = (1.0 - uv[..., 1]) * h - 0.5  # v = 0 is the bottom row
    if nearest:
        xi = _wrap(np.floor(x + 0.5).astype(np.int64), w, wrap)
        yi = _wrap(np.floor(y + 0.5).astype(np.int64), h, wrap)
        return img[yi, xi]
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    x0, y0 = x0.astype(np.int64), y0.astype(np.int64)
    xa, xb = _wrap(x0, w, wrap), _wrap(x0 + 1, w, wrap)
    ya, yb = _wrap(y0, h, wrap), _wrap(y0 + 1, h, wrap)
    top = img[ya, xa] * (1 - fx) + img[ya, xb] * fx
    bottom = img[yb, xa] * (1 - fx) + img[yb, xb] * fx
    return top * (1 - fy) + bottom * fy


def scaled_image(rgba8: np.ndarray, factor: Any) -> np.ndarray:
    """``rgba8`` times an RGBA ``factor`` (display values; the product is taken on linear light), uint8."""
    f = np.asarray(factor, np.float64).reshape(-1)
    if f.size == 3:
        f = np.append(f, 1.0)
    if np.allclose(f, 1.0, atol=1e-6):
        return rgba8
    img = np.asarray(rgba8, np.float64) / 255.0
    rgb = linear_to_srgb(srgb_to_linear(img[..., :3]) * srgb_to_linear(f[:3]))
    alpha = img[..., 3:4] * f[3]
    return np.clip(np.round(np.concatenate([rgb, alpha], axis=-1) * 255.0), 0, 255).astype(np.uint8)


def luminance(rgba8: np.ndarray) -> np.ndarray:
    """(H, W) float64 in [0, 1]: Rec. 709 weights of the encoded values (a height map's height)."""
    img = np.asarray(rgba8, np.float64)[..., :3] / 255.0
    return img @ np.array([0.2126, 0.7152, 0.0722])


def height_to_normal_map(height: np.ndarray, scale: float, wrap: str = "repeat") -> np.ndarray:
    """A tangent-space normal map (H, W, 4) uint8 from heights (H, W) in [0, 1].

    The surface is ``scale * height`` over texture coordinates in [0, 1]
    (v up): the normal is ``normalize(-dz/du, -dz/dv, 1)``, encoded as
    ``(n + 1) / 2`` (OpenGL convention: green is +v).
    """
    h = np.asarray(height, np.float64)
    rows, cols = h.shape
    mode = "wrap" if wrap in ("repeat", "mirror") else "edge"
    p = np.pad(h, 1, mode=mode)
    dz_du = (p[1:-1, 2:] - p[1:-1, :-2]) / 2.0 * cols * scale
    dz_dv = (p[:-2, 1:-1] - p[2:, 1:-1]) / 2.0 * rows * scale  # row 0 is the top: v grows upwards
    n = np.stack([-dz_du, -dz_dv, np.ones_like(h)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    rgb = np.clip(np.round((n + 1.0) * 0.5 * 255.0), 0, 255).astype(np.uint8)
    return np.concatenate([rgb, np.full((rows, cols, 1), 255, np.uint8)], axis=-1)


def normal_to_height(normal_rgba8: np.ndarray, scale: float = 1.0) -> tuple[np.ndarray, float]:
    """Heights whose slopes best match a tangent-space normal map (Frankot-Chellappa, periodic).

    Returns (heights in [0, 1], the height range in texture-coordinate
    units); ``scale`` scales the map's x and y first (glTF's normal scale).
    POV-Ray's ``bump_map`` takes heights, so normal maps reach it this way.
    """
    n = np.asarray(normal_rgba8, np.float64)[..., :3] / 255.0 * 2.0 - 1.0
    rows, cols = n.shape[:2]
    nz = np.maximum(n[..., 2], 0.05)
    p = -n[..., 0] * scale / nz / cols  # dz per column
    q = n[..., 1] * scale / nz / rows  # dz per row (rows grow downwards, v upwards)
    wx = np.fft.fftfreq(cols) * 2.0 * np.pi
    wy = np.fft.fftfreq(rows) * 2.0 * np.pi
    u, v = np.meshgrid(wx, wy)
    denom = u * u + v * v
    denom[0, 0] = 1.0
    z = (-1j * u * np.fft.fft2(p) - 1j * v * np.fft.fft2(q)) / denom
    z[0, 0] = 0.0
    height = np.real(np.fft.ifft2(z))
    lo, hi = float(height.min()), float(height.max())
    span = hi - lo
    if span <= 1e-12:
        return np.zeros((rows, cols)), 0.0
    return (height - lo) / span, span


def channel_mean(rgba8: np.ndarray, channel: int) -> float:
    """Mean of one channel in [0, 1] (a texture's average metallic or roughness)."""
    return float(np.asarray(rgba8)[..., channel].mean()) / 255.0


def _composite(under: np.ndarray, over: np.ndarray, blend: str, opacity: float) -> np.ndarray:
    """Blend linear RGBA ``over`` onto ``under`` (both (..., 4) float64) as the GL shader does."""
    a = over[..., 3:4] * opacity
    if blend == "over":
        rgb = under[..., :3] * (1.0 - a) + over[..., :3] * a
        alpha = under[..., 3:4]
    elif blend == "multiply":
        rgb = under[..., :3] * (1.0 - opacity + opacity * over[..., :3])
        alpha = under[..., 3:4]
    else:  # add
        rgb = under[..., :3] + over[..., :3] * a
        alpha = under[..., 3:4]
    return np.concatenate([rgb, alpha], axis=-1)


def bake_layers(base: np.ndarray | None, layers: Any, limit: int = BAKE_LIMIT) -> np.ndarray:
    """Composite texture layers into one RGBA8 image over UV set 0's [0, 1] square.

    ``base`` is the image below the layers (an (H, W, 4) uint8 texture) or
    None (white).  Each layer is sampled at its own transformed coordinates
    (its ``uv_set`` is taken to equal set 0: engines with one coordinate set
    warn when it does not).  The result is as large as the largest layer
    times its tiling, at most ``limit`` pixels a side.
    """
    sizes = [] if base is None else [base.shape[:2]]
    for layer in layers:
        img = layer.texture.image_array()
        su, sv = (abs(x) for x in layer.texture.scale)
        sizes.append((img.shape[0] * max(sv, 1.0), img.shape[1] * max(su, 1.0)))
    rows = int(min(limit, max(16, max(s[0] for s in sizes))))
    cols = int(min(limit, max(16, max(s[1] for s in sizes))))
    u = (np.arange(cols) + 0.5) / cols
    v = 1.0 - (np.arange(rows) + 0.5) / rows
    uu, vv = np.meshgrid(u, v)
    uv = np.stack([uu, vv], axis=-1)
    if base is None:
        out = np.ones((rows, cols, 4))
    else:
        out = sample(base, uv, "repeat") / 255.0
        out[..., :3] = srgb_to_linear(out[..., :3])
    for layer in layers:
        tex = layer.texture
        m = tex.uv_matrix()
        tuv = uv @ m[:2, :2].T + m[:2, 2]
        texel = sample(tex.image_array(), tuv, tex.wrap, nearest=tex.filter == "nearest") / 255.0
        texel[..., :3] = srgb_to_linear(texel[..., :3])
        out = _composite(out, texel, layer.blend, float(layer.opacity))
    rgb = linear_to_srgb(out[..., :3])
    result = np.concatenate([rgb, np.clip(out[..., 3:4], 0.0, 1.0)], axis=-1)
    return np.clip(np.round(result * 255.0), 0, 255).astype(np.uint8)


_BUMP_CACHE: dict[int, tuple[Any, Any, Any]] = {}


def bump_normal_texture(bump: Any) -> Any:
    """The tangent-space normal map of a ``BumpMap`` as an ``om.Texture`` (made once per bump and texture version).

    It keeps the height texture's wrap, filter, UV set and transform, so every
    engine's normal-map code draws the bump.
    """
    from .appearance import Texture

    tex = bump.texture
    key = id(bump)
    found = _BUMP_CACHE.get(key)
    stamp = (bump.version, id(tex), tex.version)
    if found is not None and found[0] is bump and found[1] == stamp:
        return found[2]
    normals = height_to_normal_map(luminance(tex.image_array()), float(bump.scale), tex.wrap)
    result = Texture(
        normals,
        wrap=tex.wrap,
        filter=tex.filter,
        mipmap=tex.mipmap,
        uv_set=tex.uv_set,
        offset=tex.offset,
        scale=tex.scale,
        rotation=tex.rotation,
    )
    if len(_BUMP_CACHE) > 256:
        _BUMP_CACHE.clear()
    _BUMP_CACHE[key] = (bump, stamp, result)
    return result


__all__ += ["bump_normal_texture"]
