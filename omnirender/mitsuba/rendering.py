"""``om.render(scene, engine="mitsuba")``: traverse, load, render, develop into an ``om.Image``."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..attributes.environment import shown_background
from ..core.camera import Camera
from ..image import Image, develop
from ..options import SizeLimits, check_image_size, check_integer, check_real
from ..scene import Node
from . import convert, painters  # noqa: F401  (painters registers the default handlers)
from . import denoise as denoiser
from ._mi import VARIANT, mitsuba
from .engine import MitsubaEngine

__all__ = ["render", "develop", "eye_depth", "SIZE_LIMITS", "MAX_SPP", "Quality", "QUALITY"]

#: Mitsuba's film keeps several float channels per pixel, twice over while developing.
SIZE_LIMITS = SizeLimits(16384, 1 << 25, "the film needs about 40 bytes per pixel")
#: Samples per pixel accepted (Mitsuba's sampler counts them in 32 bits).
MAX_SPP = 1 << 20


@dataclass(frozen=True)
class Quality:
    """What ``quality=`` chooses when the call does not: samples per pixel, the default path tracer's
    bounces (``max_depth``; a scene's ``om.mitsuba.Integrator`` or ``integrator=`` keep theirs) and
    whether the image is denoised (Intel Open Image Denoise, when ``pyoidn`` is installed)."""

    spp: int
    max_depth: int
    denoise: bool


#: ``"preview"`` (the default): a few samples, denoised: a clean image in about a second or two at 640x480
#: on two cores (``bench/mitsuba_preview.py`` measures it against a 1024-spp reference);
#: ``"final"``: many samples and every bounce, no denoiser.
QUALITY = {
    "preview": Quality(spp=8, max_depth=4, denoise=True),
    "final": Quality(spp=256, max_depth=8, denoise=False),
}


def render(
    scene: Any,
    size: tuple[int, int] = (640, 480),
    spp: int | None = None,
    *,
    quality: str = "preview",
    denoise: bool | None = None,
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

    ``quality`` chooses the samples, the default path tracer's bounces and the denoiser together
    (:data:`QUALITY`): ``"preview"`` (default) renders a few samples per pixel and denoises them
    with Intel Open Image Denoise (``pyoidn``; without it the preview stays grainy); ``"final"``
    renders many samples with every bounce.  ``spp`` (samples per pixel) overrides the quality's;
    given explicitly, the image is not denoised unless ``denoise=True`` (``denoise=False`` turns the
    preview's denoiser off).  ``integrator`` a Mitsuba plugin dict overriding
    the scene's ``om.mitsuba.Integrator`` and the default path tracer;
    ``depth`` adds the eye-space depth (from a cheap first-hit pass with
    Mitsuba's ``depth`` integrator that also gives the coverage alpha); ``rfilter``
    the film's reconstruction filter (``"box"`` keeps edges where the GL
    engine has them); ``progress`` for a long render (default): a tqdm bar on a terminal, log lines
    elsewhere (:mod:`omnirender.progress`), True a bar, False nothing; ``global_ambient`` (GL's 0.2, added to
    the lights' ambient terms as a constant environment) and ``headlight`` (for
    scenes without lights) light the scene like the GL engine.  The image has tone-mapped (clamped)
    sRGB with straight alpha in ``.array``, linear radiance RGBA in ``.hdr``.
    """
    size = check_image_size("mitsuba.render", size, SIZE_LIMITS)
    preset = QUALITY.get(quality) if isinstance(quality, str) else None
    if preset is None:
        from ..options import did_you_mean

        raise ValueError(
            f"mitsuba.render: quality must be one of {', '.join(map(repr, QUALITY))}, got {quality!r}"
            f"{did_you_mean(quality, QUALITY)}"
        )
    if denoise is None:
        denoise = preset.denoise and spp is None and denoiser.available()
    elif denoise and not denoiser.available():
        raise ImportError(f"mitsuba.render: denoise=True needs Intel Open Image Denoise: {denoiser.INSTALL}")
    spp = check_integer("mitsuba.render", "spp", preset.spp if spp is None else spp, 1, MAX_SPP)
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
    if integrator is None and engine.integrator is None:
        chosen["max_depth"] = preset.max_depth
        if getattr(engine, "splat_depth", 0):  # Gaussian splats' shells: one bounce each (mitsuba/splats.py)
            chosen["max_depth"] = max(int(chosen["max_depth"]), engine.splat_depth)
            chosen["rr_depth"] = chosen["max_depth"]
    # The denoiser gets the colour alone: Mitsuba's aov integrator (albedo and normal for OIDN) made the
    # scalar path tracer several times slower here, more than the auxiliary images gain (docs/NOTES.md).
    mi_scene = engine.load(integrator=chosen, rfilter=rfilter)
    t1 = time.perf_counter()
    data = _render(mi_scene, spp, seed, progress, size)
    t2 = time.perf_counter()
    if denoise:
        data[:, :, :3] = denoiser.denoise(data[:, :, :3])
    t3 = time.perf_counter()
    # Coverage and depth from a cheap first-hit pass: the main integrator's
    # alpha is 1 wherever an environment is visible.
    mi = mitsuba()
    if getattr(engine, "splat_depth", 0):
        hits = _splat_coverage(mi, engine, mi_scene, max(min(spp, 64), SPLAT_COVERAGE_SPP), seed)
    else:
        hits = np.array(
            mi.render(mi_scene, integrator=mi.load_dict(engine.coverage_integrator()), spp=min(spp, 64), seed=seed),
            dtype=np.float32,
        )
    t4 = time.perf_counter()
    alpha = np.clip(hits[:, :, 3], 0.0, 1.0)
    premultiplied = bool(chosen.get("hide_emitters", False)) or not engine.has_environment()
    if denoise and premultiplied:  # the denoiser blurs light a pixel past silhouettes: no hit, no light
        data[:, :, :3][alpha <= 0.0] = 0.0
    hdr = np.concatenate([data[:, :, :3], alpha[..., None]], axis=2)
    camera, _ = engine.camera_or_default()
    image = develop(hdr, background=shown_background(engine.background), premultiplied=premultiplied)
    dmap = eye_depth(hits[:, :, 4 if hits.shape[2] > 4 else 0], alpha, camera, size) if depth else None
    info = {
        "spp": spp,
        "quality": quality,
        "denoised": bool(denoise),
        "variant": VARIANT,
        "integrator": chosen.get("type"),
        "max_depth": chosen.get("max_depth"),
        "build_seconds": t1 - t0,
        "render_seconds": t2 - t1,
        "denoise_seconds": t3 - t2,
        "coverage_seconds": t4 - t3,
        "shapes": len(engine.shapes),
    }
    return Image(image, depth=dmap, hdr=hdr, engine="mitsuba", info=info, coverage=alpha)


#: Samples per pixel of the coverage pass of a scene with splats at least (their faint halos are covered by a few
#: per cent: at 8 samples most of their pixels counted no hit, and the rule "no hit, no light" blackened them).
SPLAT_COVERAGE_SPP = 32


def _splat_coverage(mi: Any, engine: Any, mi_scene: Any, spp: int, seed: int) -> np.ndarray:
    """RGBA + depth of the coverage pass for scenes with Gaussian splats (see omnirender.mitsuba.splats).

    The alpha of a path tracer as deep as the splats' shells need, over the
    splats' coverage shells (``mask`` surfaces that stop a path with the shell's
    alpha: a splat covers what its shells stop, not its outer shell's
    footprint), and the ``depth`` integrator's distances over the colour
    scene.  The ``aov`` integrator of the masked coverage pass took about 15x
    as long as the colour itself over ``ellipsoids``.
    """
    depth = int(engine.splat_depth)
    deep = {"type": "path", "max_depth": depth, "rr_depth": depth, "hide_emitters": False}
    plugins = engine.scene_dict(integrator=deep)
    plugins.update(engine.splat_coverage_shapes)
    cover = mi.load_dict(plugins)
    alpha = np.array(mi.render(cover, spp=spp, seed=seed), dtype=np.float32)
    dist = np.array(mi.render(mi_scene, integrator=mi.load_dict({"type": "depth"}), spp=spp, seed=seed), np.float32)
    return np.concatenate([dist[:, :, :3], alpha[:, :, 3:4], dist[:, :, :1]], axis=2)


def _render(mi_scene: Any, spp: int, seed: int, progress: bool | None, size: tuple[int, int]) -> np.ndarray:
    """Trace ``spp`` samples per pixel; a long render is traced in up to 16 passes that report progress
    (a bar on a terminal, log lines elsewhere: :mod:`omnirender.progress`)."""
    from ..progress import Progress, wants_progress

    mi = mitsuba()
    w, h = size
    if progress is None:
        progress = None if w * h * spp >= 4_000_000 and wants_progress(None) else False
    if progress is False or spp == 1:
        return np.array(mi.render(mi_scene, spp=spp, seed=seed), dtype=np.float32)
    chunks = min(spp, 16)
    counts = [spp // chunks + (1 if i < spp % chunks else 0) for i in range(chunks)]
    total = None
    with Progress(spp, "mitsuba", "spp", show=progress) as bar:
        for i, n in enumerate(counts):
            part = np.array(mi.render(mi_scene, spp=n, seed=seed * 1000 + i), dtype=np.float64) * n
            total = part if total is None else total + part
            bar.advance(n)
    assert total is not None
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
    xs, ys = camera.pixel_grid((w, h))
    cos = 1.0 / np.sqrt(1.0 + xs[None, :] ** 2 + ys[:, None] ** 2)
    return np.where(hit, t * cos + camera.near, np.inf).astype(np.float32)
