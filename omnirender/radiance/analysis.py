"""Lighting simulation: irradiance, illuminance, radiance and luminance at given points, through ``rtrace``.

An analysis engine in the paper's sense: it evaluates the scene graph into a
Radiance scene and returns numbers in physical units, not a picture.

- :func:`irradiance` (W/m^2 per RGB channel) and :func:`illuminance` (lux) on
  surfaces at ``points`` facing ``normals`` (``rtrace -I``);
- :func:`radiance` (W/sr/m^2 per channel) and :func:`luminance` (cd/m^2) seen
  along rays (``rtrace``).

Light units are those of :mod:`.lights` (a ``PointLight`` with attenuation
``(0, 0, 1)`` has the intensity ``pi * color * intensity`` W/sr); luminous
quantities use Radiance's efficacy of 179 lm/W and its RGB weights.  Unlike
pictures, the analysis adds no GL global ambient and no headlight unless asked
(``global_ambient=``), so the numbers come from the scene's own lights.
Interreflection needs ``om.radiance.Options(ab=...)`` (in the scene or as
``options=``); ``processes`` runs that many ``rtrace`` processes.
"""

from __future__ import annotations

import numbers
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from . import rad
from .api import _check_options
from .attributes import Options
from .build import Deadline, compile_octree, evaluate, locate, write_scene
from .runner import RadianceError, program, run

__all__ = ["irradiance", "illuminance", "radiance", "luminance", "LUMINOUS_EFFICACY", "RGB_WEIGHTS", "to_luminous"]

#: Radiance's luminous efficacy of its white light (lm/W).
LUMINOUS_EFFICACY = 179.0
#: Radiance's weights of its RGB primaries in luminance.
RGB_WEIGHTS = (0.265, 0.670, 0.065)
#: Largest number of rtrace processes.
MAX_PROCESSES = 64


def to_luminous(rgb: np.ndarray) -> np.ndarray:
    """Radiometric RGB (W/...) to the luminous quantity (lm/...): ``179 * (0.265 R + 0.670 G + 0.065 B)``."""
    return LUMINOUS_EFFICACY * (np.asarray(rgb, np.float64) @ np.asarray(RGB_WEIGHTS))


def _vectors(value: Any, what: str, nonzero: bool = False) -> np.ndarray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"Radiance analysis: {what} must be (N, 3) numbers, got {type(value).__name__}") from None
    if arr.ndim == 1 and arr.size == 3:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] == 0:
        raise ValueError(f"Radiance analysis: {what} must be (N, 3) with N >= 1, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.argwhere(~np.isfinite(arr))[0][0])
        raise ValueError(f"Radiance analysis: {what}[{bad}] is not finite: {arr[bad].tolist()}")
    if nonzero:
        zero = np.flatnonzero(~np.any(arr != 0.0, axis=1))
        if zero.size:
            raise ValueError(f"Radiance analysis: {what}[{int(zero[0])}] is the zero vector; give a direction")
    return arr


def _trace(
    scene: Any,
    origins: np.ndarray,
    directions: np.ndarray,
    irradiance_mode: bool,
    options: Options | None,
    timeout: float | None,
    processes: int,
    global_ambient: float,
    engine_options: dict[str, Any],
) -> np.ndarray:
    _check_options(options)
    if (
        isinstance(processes, bool)
        or not isinstance(processes, numbers.Integral)
        or not 1 <= processes <= MAX_PROCESSES
    ):
        raise ValueError(f"Radiance analysis: processes must be a whole number 1..{MAX_PROCESSES}, got {processes!r}")
    deadline = Deadline(timeout)
    for name in ("oconv", "rtrace"):
        program(name)
    engine = evaluate(scene, (64, 64), global_ambient=global_ambient, headlight=False, **engine_options)
    chosen = options if options is not None else engine.options if engine.options is not None else Options()
    args = ["-h", "-fdd", "-ov", "-av", *rad.numbers(engine.ambient_value()).split(), *chosen.arguments()]
    if irradiance_mode:
        args.append("-I")
    if processes > 1:
        args += ["-n", str(int(processes))]
    with tempfile.TemporaryDirectory(prefix="omnirender-radiance-") as tmp:
        folder = Path(tmp)
        try:
            write_scene(engine, folder, "scene.rad", deadline)
            octree = compile_octree(folder, "scene.rad", deadline)
            np.ascontiguousarray(np.column_stack([origins, directions]), dtype=np.float64).tofile(folder / "rays.bin")
            what = "irradiance" if irradiance_mode else "radiance"
            run("rtrace", [*args, octree], folder, stdin="rays.bin", stdout="values.bin", **deadline.limits(),
                what=f"{what} at {len(origins)} point(s)")  # fmt: skip
            values = np.fromfile(folder / "values.bin", dtype=np.float64)
        except RadianceError as exc:
            locate(exc, engine, keep=False)
            raise
    if values.size != 3 * len(origins):
        raise RadianceError(f"Radiance: rtrace returned {values.size // 3} values for {len(origins)} rays")
    return values.reshape(-1, 3)


def irradiance(
    scene: Any,
    points: Any,
    normals: Any,
    *,
    options: Options | None = None,
    timeout: float | None = 600.0,
    processes: int = 1,
    global_ambient: float = 0.0,
    **engine_options: Any,
) -> np.ndarray:
    """(N, 3) irradiance in W/m^2 (per RGB channel) on surfaces at ``points`` facing ``normals`` ((N, 3) each)."""
    p = _vectors(points, "points")
    n = _vectors(normals, "normals", nonzero=True)
    if len(n) != len(p):
        raise ValueError(f"Radiance analysis: {len(p)} points but {len(n)} normals; give one normal per point")
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    return _trace(scene, p, n, True, options, timeout, processes, global_ambient, engine_options)


def illuminance(scene: Any, points: Any, normals: Any, **options: Any) -> np.ndarray:
    """(N,) illuminance in lux at ``points`` facing ``normals`` (see :func:`irradiance` for the options)."""
    return to_luminous(irradiance(scene, points, normals, **options))


def _rays(rays: Any) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(rays, tuple) and len(rays) == 2:
        origins, directions = rays
    else:
        try:
            arr = np.array(rays, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"Radiance analysis: rays must be (N, 6) numbers, got {type(rays).__name__}") from None
        if arr.ndim == 1 and arr.size == 6:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != 6:
            raise ValueError(
                f"Radiance analysis: rays must be (N, 6) (origin, direction) or a tuple (origins, directions), "
                f"got shape {arr.shape}"
            )
        origins, directions = arr[:, :3], arr[:, 3:]
    o = _vectors(origins, "ray origins")
    d = _vectors(directions, "ray directions", nonzero=True)
    if len(o) != len(d):
        raise ValueError(f"Radiance analysis: {len(o)} ray origins but {len(d)} directions")
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


def radiance(
    scene: Any,
    rays: Any,
    *,
    options: Options | None = None,
    timeout: float | None = 600.0,
    processes: int = 1,
    global_ambient: float = 0.0,
    **engine_options: Any,
) -> np.ndarray:
    """(N, 3) radiance in W/sr/m^2 seen along ``rays``: (N, 6) origin + direction rows, or (origins, directions)."""
    o, d = _rays(rays)
    return _trace(scene, o, d, False, options, timeout, processes, global_ambient, engine_options)


def luminance(scene: Any, rays: Any, **options: Any) -> np.ndarray:
    """(N,) luminance in cd/m^2 seen along ``rays`` (see :func:`radiance` for the arguments)."""
    return to_luminous(radiance(scene, rays, **options))
