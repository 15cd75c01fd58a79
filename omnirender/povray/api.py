"""``render``, ``export`` and ``available``: the functions ``om.render``/``om.export`` dispatch to."""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..attributes.environment import shown_background
from ..fileio import atomic_path
from ..image import Image
from ..options import SizeLimits, check_image_size, check_timeout
from . import painters as _painters  # noqa: F401  (registers the default handlers)
from .engine import POVRayEngine, coverage, decode_depth
from .runner import POVRayError, find_povray, read_png, read_ppm, run_povray

__all__ = ["render", "export", "available", "scene_sdl", "node_at_line"]

_ENGINE_OPTIONS = {"mask", "on_missing", "technique", "resource_prefix", "resource_dir"}
#: POV-Ray holds the image in memory as floats (and we read it back as RGBA bytes).
SIZE_LIMITS = SizeLimits(32768, 1 << 26, "POV-Ray keeps about 20 bytes per pixel in memory")


def available() -> tuple[bool, str]:
    """Whether the ``povray`` program can be run here, and why not."""
    exe = find_povray()
    if exe is None:
        return False, "the povray program is not installed (apt-get install povray)"
    try:
        out = subprocess.run([exe, "--version"], capture_output=True, timeout=20, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return False, f"povray cannot be run: {exc}"
    text = (out.stdout + out.stderr).decode("latin-1")
    version = next((ln.strip() for ln in text.splitlines() if ln.startswith("POV-Ray")), "POV-Ray")
    return True, version


def scene_sdl(scene: Any, size: tuple[int, int] = (640, 480), **engine_options: Any) -> tuple[str, POVRayEngine]:
    """Evaluate ``scene`` with a POVRayEngine; returns (SDL text, engine) — the engine lists the resources."""
    unknown = set(engine_options) - _ENGINE_OPTIONS
    if unknown:
        from ..options import options_hint

        raise TypeError(
            f"POV-Ray: unknown option(s) {sorted(unknown)}; render() takes size, quality, antialias, timeout, "
            f"progress, threads, keep, depth and the engine options {sorted(_ENGINE_OPTIONS)}"
            + options_hint(
                unknown,
                ["size", "quality", "antialias", "timeout", "progress", "threads", "keep", "depth", *_ENGINE_OPTIONS],
            )  # fmt: skip
        )
    if not hasattr(scene, "preevaluate"):  # a list of components
        from ..scene import Node

        scene = Node("scene", list(scene))
    engine = POVRayEngine(size, **engine_options)
    engine.run(scene)
    return engine.sdl(), engine


def _write_resource(data: Any, tmp: Path) -> None:
    if isinstance(data, str):
        if not os.path.exists(data):  # checked when the texture was met; it may have gone since
            raise FileNotFoundError(f"POV-Ray: texture image {data!r} does not exist; check the path or pass an array")
        shutil.copyfile(data, tmp)
    else:
        from PIL import Image as PILImage

        arr = np.asarray(data, dtype=np.uint8)
        PILImage.fromarray(arr, "RGBA" if arr.shape[2] == 4 else "RGB").save(tmp, format="PNG")


def _write_files(folder: Path, text: str, name: str, resources: list[tuple[str, Any]]) -> list[Path]:
    """Write the SDL ``text`` as ``folder/name`` and the texture images, all or nothing.

    Every file is first written to a temporary file next to its target; only
    when all of them are complete do they replace their targets, so a failure
    (a texture that vanished, a full disk) leaves neither new files nor
    half-written ones behind, and existing files unchanged.
    """
    targets = [folder / res_name for res_name, _ in resources] + [folder / name]
    with contextlib.ExitStack() as stack:
        for (_, data), target in zip(resources, targets, strict=False):
            _write_resource(data, stack.enter_context(atomic_path(target)))
        with open(stack.enter_context(atomic_path(targets[-1])), "w", encoding="utf-8") as fh:
            fh.write(text)
    return targets


def export(scene: Any, path: str | os.PathLike[str], size: tuple[int, int] = (640, 480), **options: Any) -> Path:
    """Write ``scene`` as POV-Ray SDL to ``path``; texture images go next to it.

    The SDL is generated first; then the SDL file and the images are written
    together atomically: on any failure nothing is left behind.
    """
    target = Path(path)
    prefix = "".join(ch if ch.isalnum() or ch in "_-" else "_" for ch in target.stem) + "_"
    folder = (target.parent if str(target.parent) else Path(".")).resolve()
    # textures are named with their absolute folder, so ``povray scene.pov`` finds them from any working folder
    # (a folder whose name SDL cannot hold safely falls back to names relative to the file's folder)
    where = str(folder) if _SAFE_DIR.match(str(folder)) else None
    _, engine = scene_sdl(scene, size, resource_prefix=prefix, resource_dir=where, **options)
    _write_files(folder, engine.sdl(standalone=True), target.name, engine.resources)
    return target


_SAFE_DIR = re.compile(r"[A-Za-z0-9_./\-]+\Z")


_LINE = re.compile(r"File '(scene|depth)\.pov' line (\d+)")


def node_at_line(text: str, line: int) -> str | None:
    """The node path of the ``// /node/path`` comment nearest before 1-based ``line`` of generated SDL."""
    lines = text.splitlines()
    for i in range(min(line, len(lines)) - 1, -1, -1):
        if lines[i].startswith("// /"):
            return lines[i][3:].strip()
    return None


def _locate_error(exc: POVRayError, texts: dict[str, str], keep: Any) -> None:
    """Add the scene-graph node that produced the failing SDL line (and the keep= hint) to ``exc``."""
    message = str(exc)
    found = _LINE.search(message)
    if found:
        node = node_at_line(texts.get(found.group(1), ""), int(found.group(2)))
        if node is not None:
            message += f"\n  {found.group(1)}.pov line {found.group(2)} was written for node {node}"
    if keep is None and "Error" in message:
        message += "\n  (pass keep='<folder>' to keep scene.pov for inspection)"
    exc.args = (message,)


def _background(engine: POVRayEngine) -> np.ndarray:
    c = np.asarray(shown_background(engine.background), dtype=np.float64)
    return np.array([*c[:3], c[3] if len(c) > 3 else 1.0])


def render(
    scene: Any,
    size: tuple[int, int] = (640, 480),
    quality: int = 9,
    antialias: bool | float = False,
    timeout: float | None = 600.0,
    progress: Any = None,
    threads: int | None = None,
    keep: str | os.PathLike[str] | None = None,
    depth: bool = False,
    **engine_options: Any,
) -> Image:
    """Render ``scene`` with POV-Ray and return an :class:`om.Image`.

    ``quality`` 0-11 is POV-Ray's ``+Q``; ``antialias`` True (threshold 0.3)
    or a threshold turns on adaptive anti-aliasing; ``timeout`` seconds (None:
    no limit); ``progress`` None (a bar on a terminal), True/False, or a
    callable ``(done_pixels, total_pixels)``; ``threads`` limits POV-Ray's
    render threads; ``keep`` a folder to write the scene file and its texture
    images into (atomically, for debugging); ``depth`` True adds ``image.depth`` (eye-space depth along the
    viewing axis, inf on the background) from a second quick pass, else it is
    None.  The background is transparent in the alpha channel (so
    ``image.mask`` marks the objects) unless an ``om.Background`` with alpha
    sets it.
    """
    w, h = check_image_size("POV-Ray", size, SIZE_LIMITS)
    timeout = check_timeout("POV-Ray", timeout)
    if isinstance(quality, bool) or not isinstance(quality, (int, np.integer)) or not 0 <= quality <= 11:
        raise ValueError(f"POV-Ray: quality must be a whole number 0..11 (9 = full quality), got {quality!r}")
    if antialias is None or (not isinstance(antialias, bool) and antialias == 0):
        antialias = False
    if not isinstance(antialias, bool):
        try:
            threshold = float(antialias)
        except (TypeError, ValueError):
            threshold = float("nan")
        if not 0 < threshold <= 3:  # POV-Ray's +A threshold: colour difference that triggers supersampling
            raise ValueError(
                f"POV-Ray: antialias must be True, False or a threshold in (0, 3] (True means 0.3), got {antialias!r}"
            )
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1):
        raise ValueError(f"POV-Ray: threads must be a whole number >= 1 or None (all cores), got {threads!r}")
    if find_povray() is None:
        raise POVRayError("POV-Ray: the povray program was not found on PATH; install it with `apt-get install povray`")
    depth_map = None
    started = time.perf_counter()
    text, engine = scene_sdl(scene, (w, h), **engine_options)
    sdl_seconds = time.perf_counter() - started
    with tempfile.TemporaryDirectory(prefix="omnirender-povray-") as tmp:
        folder = Path(tmp)
        _write_files(folder, text, "scene.pov", engine.resources)
        if keep is not None:  # the scene file and its textures, so the kept scene renders on its own
            Path(keep).mkdir(parents=True, exist_ok=True)  # a debugging folder: create it rather than fail
            _write_files(Path(keep), text, "scene.pov", engine.resources)
        args = [
            "+Iscene.pov",
            "+Oimage.png",
            f"+W{w}",
            f"+H{h}",
            "-D",
            "-P",
            "+FN8",
            "+UA",
            f"+Q{int(quality)}",
            "File_Gamma=sRGB",
            "-GS",  # no statistics
            "-GD",  # no debug stream
            "+GR",  # render stream: progress lines
            "+V",
        ]
        if antialias:
            threshold = 0.3 if antialias is True else float(antialias)
            args += [f"+A{threshold:g}", "+AM2", "+R3"]
        else:
            args.append("-A")
        if threads is not None:
            args.append(f"+WT{int(threads)}")
        t0 = time.perf_counter()
        try:
            run_povray(args, folder, timeout=timeout, progress=progress, total_pixels=w * h)
        except POVRayError as exc:
            _locate_error(exc, {"scene": text}, keep)
            raise
        out = folder / "image.png"
        if not out.exists():
            raise POVRayError("POV-Ray finished without writing an image (see its output above)")
        array = read_png(out)
        if depth or engine.fog is not None:
            # A second, quick pass (quality 0, no anti-aliasing, 16 bits, linear) with every object
            # self-lit by a pigment that encodes its eye-space depth.  Its alpha is also the
            # coverage: POV-Ray fogs the background too, making it opaque in the colour pass.
            depth_text = engine.sdl(depth=True)
            (folder / "depth.pov").write_text(depth_text, encoding="utf-8")
            pass_args = [
                "+Idepth.pov", "+Odepth.ppm", f"+W{w}", f"+H{h}", "-D", "-P", "+FP16", "+Q0", "-A",
                "File_Gamma=1.0", "-GS", "-GD", "-GR", "-V",
            ]  # fmt: skip
            if threads is not None:
                pass_args.append(f"+WT{int(threads)}")
            try:
                run_povray(pass_args, folder, timeout=timeout, progress=False, total_pixels=w * h)
            except POVRayError as exc:
                _locate_error(exc, {"depth": depth_text}, keep)
                raise
            rgb16 = read_ppm(folder / "depth.ppm")
            if depth:
                depth_map = decode_depth(rgb16, engine.depth_range())
            if engine.fog is not None:
                array = array.copy()
                array[:, :, 3] = np.where(coverage(rgb16) > 0, np.maximum(array[:, :, 3], 1), 0)
        render_seconds = time.perf_counter() - t0
    if array.shape[:2] != (h, w):
        raise POVRayError(f"POV-Ray wrote a {array.shape[1]}x{array.shape[0]} image, expected {w}x{h}")
    cover = array[:, :, 3].astype(np.float32) / 255.0
    bg = _background(engine)
    if bg[3] > 0:
        # straight-alpha "over": the objects over the background colour
        alpha = array[:, :, 3:4].astype(np.float64) / 255.0
        bg_rgb = np.clip(bg[:3], 0.0, 1.0) * 255.0
        out_alpha = alpha + bg[3] * (1.0 - alpha)
        rgb = (array[:, :, :3] * alpha + bg_rgb * bg[3] * (1.0 - alpha)) / np.maximum(out_alpha, 1e-9)
        array = np.clip(np.round(np.concatenate([rgb, out_alpha * 255.0], axis=2)), 0, 255).astype(np.uint8)
    info = {
        "sdl_seconds": sdl_seconds,
        "render_seconds": render_seconds,
        "quality": int(quality),
        "antialias": bool(antialias),
        "objects": len(engine.objects),
    }
    return Image(array, depth=depth_map, engine="povray", info=info, coverage=cover)
