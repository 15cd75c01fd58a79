"""``om.render(scene, engine="mitsuba")``: traverse, load, render, develop into an ``om.Image``."""

from __future__ import annotations

import math
import sys
import time
from typing import Any

import numpy as np

from ..attributes.environment import shown_background
from ..core.camera import Camera
from ..image import Image, develop
from ..options import SizeLimits, check_image_size, check_integer, check_real
from ..scene import Node
from . import convert, painters  # noqa: F401  (painters registers the default handlers)
from ._mi import VARIANT, mitsuba
from .engine import MitsubaEngine

__all__ = ["render", "develop", "eye_depth", "SIZE_LIMITS", "MAX_SPP"]

#: Mitsuba's film keeps several float channels per pixel, twice over while developing.
SIZE_LIMITS = SizeLimits(16384, 1 << 25, "the film needs about 40 bytes per pixel")
#: Samples per pixel accepted (Mitsuba's sampler counts them in 32 bits).
MAX_SPP = 1 << 20


def render(
    scene: Any,
    size: tuple[int, int] = (640, 480),
    spp: int = 64,
    *,
    integrator: dict[str, Any] | None = None,
    depth: bool = True,
    rfilter: str = "box",
    seed: int = 0,
    progress: bool | None = None,
    on_missing: str = "raise",
    mask: str | None = None,
    global_ambient: float = 0.2,
    headlight: bool = True,
) -> Image:
    """Render ``scene`` (a Node or a list of components) with Mitsuba 3 (``scalar_rgb``).

    ``spp`` samples per pixel; ``integrator`` a Mitsuba plugin dict overriding
    the scene's ``om.mitsuba.Integrator`` and the default path tracer;
    ``depth`` adds the eye-space depth (from a cheap first-hit pass with
    Mitsuba's ``depth`` integrator that also gives the coverage alpha); ``rfilter``
    the film's reconstruction filter (``"box"`` keeps edges where the GL
    engine has them); ``progress`` shows a tqdm bar (default: when stderr is
    a terminal and the render is long); ``global_ambient`` (GL's 0.2, added to
    the lights' ambient terms as a constant environment) and ``headlight`` (for
    scenes without lights) light the scene like the GL engine.  The image has tone-mapped (clamped)
    sRGB with straight alpha in ``.array``, linear radiance RGBA in ``.hdr``.
    """
    size = check_image_size("mitsuba.render", size, SIZE_LIMITS)
    spp = check_integer("mitsuba.render", "spp", spp, 1, MAX_SPP)
    seed = check_integer("mitsuba.render", "seed", seed, 0, 2**32 - 1)
    global_ambient = check_real("mitsuba.render", "global_ambient", global_ambient, 0.0, 1e6)
    if integrator is not None and not (isinstance(integrator, dict) and isinstance(integrator.get("type"), str)):
        raise ValueError(
            f"mitsuba.render: integrator must be a Mitsuba plugin dict such as {{'type': 'path', 'max_depth': 8}}, "
            f"got {integrator!r}"
        )
    if not isinstance(scene, Node):
        scene = Node("scene", scene)
    t0 = time.perf_counter()
    engine = MitsubaEngine(size, on_missing=on_missing, mask=mask)
    engine.global_ambient = float(global_ambient)
    engine.headlight = bool(headlight)
    engine.run(scene)
    chosen = engine.integrator_dict(integrator)
    mi_scene = engine.load(integrator=chosen, rfilter=rfilter)
    t1 = time.perf_counter()
    data = _render(mi_scene, spp, seed, progress, size)
    t2 = time.perf_counter()
    # Coverage and depth from a cheap first-hit pass: the main integrator's
    # alpha is 1 wherever an environment is visible.
    mi = mitsuba()
    hits = np.array(
        mi.render(mi_scene, integrator=mi.load_dict(engine.coverage_integrator()), spp=min(spp, 64), seed=seed),
        dtype=np.float32,
    )
    alpha = np.clip(hits[:, :, 3], 0.0, 1.0)
    premultiplied = bool(chosen.get("hide_emitters", False)) or not engine.has_environment()
    hdr = np.concatenate([data[:, :, :3], alpha[..., None]], axis=2)
    camera, _ = engine.camera_or_default()
    image = develop(hdr, background=shown_background(engine.background), premultiplied=premultiplied)
    dmap = eye_depth(hits[:, :, 4 if hits.shape[2] > 4 else 0], alpha, camera, size) if depth else None
    info = {
        "spp": spp,
        "variant": VARIANT,
        "integrator": chosen.get("type"),
        "build_seconds": t1 - t0,
        "render_seconds": t2 - t1,
        "coverage_seconds": time.perf_counter() - t2,
        "shapes": len(engine.shapes),
    }
    return Image(image, depth=dmap, hdr=hdr, engine="mitsuba", info=info, coverage=alpha)


def _render(mi_scene: Any, spp: int, seed: int, progress: bool | None, size: tuple[int, int]) -> np.ndarray:
    mi = mitsuba()
    w, h = size
    if progress is None:
        progress = sys.stderr.isatty() and w * h * spp >= 4_000_000
    if not progress:
        return np.array(mi.render(mi_scene, spp=spp, seed=seed), dtype=np.float32)
    from tqdm import tqdm

    chunks = min(spp, 16)
    counts = [spp // chunks + (1 if i < spp % chunks else 0) for i in range(chunks)]
    total = None
    with tqdm(total=spp, unit="spp", desc="mitsuba", file=sys.stderr) as bar:
        for i, n in enumerate(counts):
            part = np.array(mi.render(mi_scene, spp=n, seed=seed * 1000 + i), dtype=np.float64) * n
            total = part if total is None else total + part
            bar.update(n)
    return (total / spp).astype(np.float32)


def eye_depth(ray_depth: np.ndarray, alpha: np.ndarray, camera: Camera, size: tuple[int, int]) -> np.ndarray:
    """Mitsuba's ``depth`` integrator output -> eye-space z (distance along the viewing axis), inf for background.

    It is the ray distance from the near plane (Mitsuba's camera rays
    start there), 0 for misses, averaged over the pixel.  Averaging over a
    partly covered pixel mixes in the misses' zeros, so it is divided by
    the coverage; pixels less than half covered are background.
    """
    w, h = size
    cover = np.clip(alpha, 0.0, 1.0)
    hit = cover >= 0.5
    t = np.where(hit, ray_depth / np.maximum(cover, 1e-6), np.inf)
    if camera.is_orthographic:
        return (t + camera.near).astype(np.float32)
    # cosine between each pixel's central ray and the viewing axis
    ty = math.tan(math.radians(camera.fov) / 2.0)
    tx = ty * w / h
    xs = ((np.arange(w) + 0.5) / w * 2.0 - 1.0) * tx
    ys = ((np.arange(h) + 0.5) / h * 2.0 - 1.0) * ty
    cos = 1.0 / np.sqrt(1.0 + xs[None, :] ** 2 + ys[:, None] ** 2)
    return np.where(hit, t * cos + camera.near, np.inf).astype(np.float32)
