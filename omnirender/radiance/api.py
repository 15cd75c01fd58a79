"""``render``, ``export``, ``available`` and ``scene_description``: what ``om.render``/``om.export`` dispatch to."""

from __future__ import annotations

import contextlib
import math
import numbers
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..attributes.environment import shown_background
from ..attributes.photometry import GLOBAL_AMBIENT, srgb_to_linear
from ..fileio import atomic_path
from ..image import Image, develop
from ..options import SizeLimits, check_image_size
from . import rad, runner
from .attributes import Options
from .build import Deadline, as_node, compile_octree, evaluate, locate, write_scene
from .engine import RadianceEngine
from .picture import FHUGE, read_depth
from .runner import RadianceError, environment, program, run

__all__ = ["render", "export", "available", "scene_description", "MAX_OVERSAMPLE"]

#: The largest ``oversample`` factor accepted (64 rays per pixel).
MAX_OVERSAMPLE = 8
#: The most rays (pixels times oversample squared) one picture may take: memory stays below a few GB.
MAX_RAYS = 1 << 25
#: The largest picture (before oversampling multiplies the rays).
SIZE_LIMITS = SizeLimits(32768, MAX_RAYS, "one ray per pixel at least, and at most MAX_RAYS rays")


def available() -> tuple[bool, str]:
    """Whether the Radiance programs can be run here (from pyradiance), and why not."""
    paths = runner.radiance_paths()
    if paths is None:
        return False, "the pyradiance package is not installed (pip install 'omnirender[radiance]')"
    try:
        exe = program("rpict")
        out = subprocess.run(
            [str(exe), "-version"], capture_output=True, timeout=20, stdin=subprocess.DEVNULL, env=environment()
        )
    except (RadianceError, OSError, subprocess.TimeoutExpired) as exc:
        return False, f"Radiance cannot be run: {exc}"
    text = (out.stdout + out.stderr).decode("latin-1").strip()
    if out.returncode != 0 or "RADIANCE" not in text:
        return False, f"rpict -version failed: {text[-200:]}"
    from importlib.metadata import PackageNotFoundError, version

    try:
        extra = f" (pyradiance {version('pyradiance')})"
    except PackageNotFoundError:  # pragma: no cover - found by spec, so installed
        extra = ""
    return True, text.splitlines()[0] + extra


def scene_description(
    scene: Any, size: tuple[int, int] = (640, 480), **engine_options: Any
) -> tuple[str, RadianceEngine]:
    """Evaluate ``scene``; returns (the ``.rad`` text, the engine listing its meshes and pictures)."""
    engine = evaluate(scene, size, **engine_options)
    return engine.description(), engine


def _check_options(options: Any) -> None:
    if options is not None and not isinstance(options, Options):
        raise TypeError(f"Radiance: options must be an om.radiance.Options, got {type(options).__name__}")


def _view_depth(rot: np.ndarray, engine: RadianceEngine, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(eye-space depth along the viewing axis, distance from the eye) from ``rpict -z`` ray lengths.

    Rays start on the fore (near) plane: a perspective ray through image
    position (x, y) has the direction ``(x tan_h, y tan_v, -1)`` of length
    ``L`` and starts ``near * L`` from the eye, so its depth is
    ``near + t / L``; an orthographic one ``near + t``.
    """
    camera, _ = engine.camera_or_default()
    x, y = np.meshgrid(*camera.pixel_grid(size))
    if camera.is_orthographic:
        z = camera.near + rot
        return z, np.sqrt(x * x + y * y + z * z)
    length = np.sqrt(1.0 + x * x + y * y)
    z = camera.near + rot / length
    return z, z * length


def _downsample(a: np.ndarray, k: int) -> np.ndarray:
    """Mean over k x k blocks of an (H k, W k, ...) array."""
    if k == 1:
        return a
    h, w = a.shape[0] // k, a.shape[1] // k
    return a.reshape(h, k, w, k, *a.shape[2:]).mean(axis=(1, 3))


def _read_picture(folder: Path, name: str, size: tuple[int, int], deadline: Deadline) -> np.ndarray:
    """(H, W, 3) float radiance of a picture, through ``pvalue``; channels stored as 0 read as 0."""
    run("pvalue", ["-h", "-H", "-df", "-o", name], folder, stdout="image.raw", **deadline.limits(), what=name)
    w, h = size
    data = np.fromfile(folder / "image.raw", dtype=np.float32)
    if data.size != w * h * 3:
        raise RadianceError(f"Radiance: rpict wrote {data.size // 3} pixels, expected {w}x{h}")
    return zero_floor(data.reshape(h, w, 3))


def zero_floor(rgb: np.ndarray) -> np.ndarray:
    """Undo RGBE decoding's half step on channels whose mantissa was 0.

    Radiance decodes a mantissa ``m`` as ``(m + 0.5) * f`` with ``f`` the
    pixel's step (``2^(e - 8)`` for its largest channel in ``[2^(e-1), 2^e)``),
    so a pure red pixel reads with green and blue ``0.5 f`` instead of 0.
    """
    top = rgb.max(axis=2, keepdims=True).astype(np.float64)
    step = np.exp2(np.floor(np.log2(np.where(top > 0.0, top, 1.0))) - 7.0)
    return np.where(rgb.astype(np.float64) <= 0.5 * step * (1.0 + 1e-6), 0.0, rgb).astype(np.float32)


def render(
    scene: Any,
    size: tuple[int, int] = (640, 480),
    *,
    options: Options | None = None,
    oversample: int = 1,
    timeout: float | None = 600.0,
    progress: Any = None,
    keep: str | os.PathLike[str] | None = None,
    global_ambient: float = GLOBAL_AMBIENT,
    headlight: bool = True,
    exposure: float = 1.0,
    **engine_options: Any,
) -> Image:
    """Render ``scene`` with Radiance's ``rpict`` and return an :class:`om.Image`.

    One ray through the centre of each pixel (``-ps 1 -pj 0``), or
    ``oversample`` x ``oversample`` rays averaged (anti-aliasing, soft edges in
    the alpha channel).  ``options`` (an ``om.radiance.Options``) overrides the
    scene's; ``timeout`` seconds for the whole job (None: no limit);
    ``progress`` None (a bar on a terminal), True/False, or a callable
    ``(done_pixels, total_pixels)`` (as for POV-Ray); ``keep`` a folder to copy the description, meshes
    and pictures into; ``global_ambient`` (GL's 0.2, part of Radiance's
    ambient value ``-av``) and ``headlight`` (for scenes without lights) light
    the scene like the GL engine.  ``exposure`` scales the radiance before
    it is encoded as sRGB (for scenes in physical units, e.g. ``1 / L`` under
    a sky of radiance ``L``); ``.hdr`` keeps the physical values.  The image has sRGB in ``.array`` (the
    background the scene's ``om.Background`` or the shared default), linear
    radiance (W/sr/m^2, premultiplied by coverage) and alpha in ``.hdr`` and
    the eye-space depth in ``.depth`` (inf on the background).
    """
    if (
        isinstance(oversample, bool)
        or not isinstance(oversample, numbers.Integral)
        or not 1 <= oversample <= MAX_OVERSAMPLE
    ):
        raise ValueError(f"Radiance: oversample must be a whole number 1..{MAX_OVERSAMPLE}, got {oversample!r}")
    _check_options(options)
    size = check_image_size("Radiance", size, SIZE_LIMITS)
    if isinstance(exposure, bool) or not isinstance(exposure, numbers.Real) or not (0 < exposure < math.inf):
        raise ValueError(f"Radiance: exposure must be a positive finite number, got {exposure!r}")
    deadline = Deadline(timeout)
    for name in ("oconv", "rpict", "pvalue"):
        program(name)  # a clear error before any work when Radiance is missing
    k = int(oversample)
    started = time.perf_counter()
    scene = as_node(scene)
    engine = evaluate(scene, size, global_ambient=global_ambient, headlight=headlight, **engine_options)
    w, h = engine.size
    if w * h * k * k > MAX_RAYS:
        raise ValueError(
            f"Radiance: {w}x{h} pixels with oversample={k} need {w * h * k * k:,} rays, more than {MAX_RAYS:,}; "
            "use a smaller size or oversample"
        )
    chosen = options if options is not None else engine.options if engine.options is not None else Options()
    big = (w * k, h * k)
    view = [*engine.view_arguments(big), "-x", str(big[0]), "-y", str(big[1]), "-pa", "0", "-ps", "1", "-pt", "0",
            "-pj", "0"]  # fmt: skip
    args = [*view, "-av", *rad.numbers(engine.ambient_value()).split(), *chosen.arguments()]
    if progress is not False:
        args += ["-t", "1"]
    timings = {"description_seconds": time.perf_counter() - started}
    radiance, rot, through = _passes(scene, engine, view, args, deadline, progress, keep, timings, engine_options)
    hdr, depth = _film(engine, radiance, rot, through, k)
    shown = hdr if exposure == 1.0 else np.concatenate([hdr[:, :, :3] * float(exposure), hdr[:, :, 3:]], axis=2)
    array = develop(shown, shown_background(engine.background))
    info = {
        **timings,
        "oversample": k,
        "meshes": len(engine.meshes),
        "pictures": len(engine.pictures),
        "options": " ".join(chosen.arguments()),
    }
    return Image(array, depth=depth, hdr=hdr, engine="radiance", info=info, coverage=hdr[:, :, 3])


def _passes(
    scene: Any,
    engine: RadianceEngine,
    view: list[str],
    args: list[str],
    deadline: Deadline,
    progress: Any,
    keep: Any,
    timings: dict[str, float],
    engine_options: dict[str, Any],
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Write the files and run rpict: (radiance, ray lengths, fraction seen through or None) at ``view``'s size.

    Scenes with see-through surfaces get a second, unlit coverage pass
    (:class:`RadianceEngine` ``coverage=True``) measuring how much of each
    pixel shows the background.  Everything happens in a temporary folder.
    """
    big = (int(view[view.index("-x") + 1]), int(view[view.index("-y") + 1]))
    with tempfile.TemporaryDirectory(prefix="omnirender-radiance-") as tmp:
        folder = Path(tmp)
        current = engine
        try:
            t0 = time.perf_counter()
            write_scene(engine, folder, "scene.rad", deadline)
            covering = None
            if engine.transparent:
                covering = current = evaluate(scene, engine.size, coverage=True, shared=engine, **engine_options)
                write_scene(covering, folder, "coverage.rad", deadline)
                current = engine
            if keep is not None:
                _copy_all(folder, Path(keep))
            octree = compile_octree(folder, "scene.rad", deadline)
            t1 = time.perf_counter()
            run("rpict", [*args, "-z", "depth.raw", octree], folder, stdout="image.hdr", **deadline.limits(),
                progress=progress, pixels=big[0] * big[1], what="rendering")  # fmt: skip
            timings.update(compile_seconds=t1 - t0, render_seconds=time.perf_counter() - t1)
            radiance = _read_picture(folder, "image.hdr", big, deadline).astype(np.float64)
            rot = read_depth(folder / "depth.raw", big)
            if covering is None:
                return radiance, rot, None
            current = covering
            octree = compile_octree(folder, "coverage.rad", deadline)
            # no aft plane here: it would hide the environment (the main pass keeps it: rays passing
            # through surfaces stop there, and so add nothing where the background goes)
            unbounded = [*view, "-va", "0", "-ab", "0", octree]
            run("rpict", unbounded, folder, stdout="coverage.hdr", **deadline.limits(), what="coverage pass")
            through = np.clip(_read_picture(folder, "coverage.hdr", big, deadline).mean(axis=2), 0.0, 1.0)
            return radiance, rot, through
        except RadianceError as exc:
            locate(exc, current, keep)
            raise


def _film(
    engine: RadianceEngine, radiance: np.ndarray, rot: np.ndarray, through: np.ndarray | None, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """(linear RGBA premultiplied by coverage, eye-space depth) at the final size from the oversampled passes.

    Coverage is 1 where a ray hit something (less what shows through); fog
    mixes the fog colour in by GL's equation of the eye distance; k x k blocks
    are averaged, depth over the covered rays (inf where less than half is covered).
    """
    hit = rot < FHUGE / 2
    cover = hit.astype(np.float64) if through is None else np.where(hit, 1.0 - through, 0.0)
    z, distance = _view_depth(np.where(hit, rot, 0.0), engine, (rot.shape[1], rot.shape[0]))
    radiance = np.where(hit[:, :, None], radiance, 0.0)
    if engine.fog is not None:
        f = np.asarray(engine.fog.factor(distance), np.float64)[:, :, None]
        fog = srgb_to_linear(engine.fog.color) * cover[:, :, None]
        radiance = np.where(hit[:, :, None], f * radiance + (1.0 - f) * fog, 0.0)
    alpha = _downsample(cover, k)
    count = _downsample(hit.astype(np.float64), k)
    depth_sum = _downsample(np.where(hit, z, 0.0), k)
    depth = np.where((alpha >= 0.5) & (count > 0), depth_sum / np.maximum(count, 1e-9), np.inf).astype(np.float32)
    hdr = np.concatenate([_downsample(radiance, k), alpha[:, :, None]], axis=2).astype(np.float32)
    return hdr, depth


def _copy_all(source: Path, target: Path) -> None:
    """Copy every file of ``source`` into ``target`` (created), all or nothing."""
    target.mkdir(parents=True, exist_ok=True)
    files = sorted(p for p in source.iterdir() if p.is_file())
    with contextlib.ExitStack() as stack:
        for path in files:
            shutil.copyfile(path, stack.enter_context(atomic_path(target / path.name)))


def export(
    scene: Any, path: str | os.PathLike[str], size: tuple[int, int] = (640, 480), *, timeout: float | None = 600.0,
    **engine_options: Any,
) -> Path:  # fmt: skip
    """Write ``scene`` as a Radiance description to ``path``; its meshes (``.rtm``) and pictures go next to it.

    File names start with the (sanitised) stem of ``path``; the description
    refers to them by name, so run ``oconv`` in that folder.  Everything is
    prepared in a temporary folder first and then moved into place together:
    on any failure nothing is left behind and existing files stay unchanged.
    """
    target = Path(path)
    stem = "".join(ch if ch.isalnum() or ch in "_-" else "_" for ch in target.stem) or "scene"
    prefix = stem + "_" if stem[0].isalpha() or stem[0] == "_" else "om_" + stem + "_"
    engine = evaluate(scene, size, resource_prefix=prefix, **engine_options)
    deadline = Deadline(timeout)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise FileNotFoundError(f"cannot write {target}: the folder {folder} does not exist")
    with tempfile.TemporaryDirectory(prefix="omnirender-radiance-") as tmp:
        try:
            files = write_scene(engine, Path(tmp), "scene.rad", deadline)
        except RadianceError as exc:
            locate(exc, engine, keep=False)
            raise
        with contextlib.ExitStack() as stack:
            for file in files:
                name = target.name if file.name == "scene.rad" else file.name
                shutil.copyfile(file, stack.enter_context(atomic_path(folder / name)))
    return target
