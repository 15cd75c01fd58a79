"""``om.render_frames``: an animation's frames rendered here, on a local process pool, or on Dask.

The scene (with its animations) is pickled once and sent once to every
worker; each worker keeps its own copy and engine and renders frames by
setting the copy to the frame's time (see :mod:`.worker`).  Frame files are
written atomically, so a file that exists is complete: a re-run skips the
frames already on disk (resume after a crash or a cancelled cluster job).  A
failing frame is retried once with a fresh engine and then reported with its
number and the engine's message while the other frames go on; at the end
:class:`FramesFailed` lists every failure.  A progress bar (tqdm) shows the
frames done and the estimated time left.

``workers``: ``0`` renders in this process; ``None`` (default) or an int
starts that many local processes (``None``: one per core); a
``distributed.Client``, a scheduler address (``"tcp://host:8786"``) or a
Dask cluster object (``LocalCluster``, ``dask_jobqueue.SLURMCluster``...) runs
the frames on Dask (``pip install 'omnirender[distributed]'``).
"""

from __future__ import annotations

import multiprocessing
import os
import time
import uuid
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .animation import frame_times
from .mainguard import check_main_guard
from .worker import FrameResult, Job, dump_job, install_job, release_all, run_frame

__all__ = ["render_frames", "FrameReport", "FrameFailure", "FramesFailed", "frame_paths", "load_scene"]

#: Extensions frames can be written as (what ``om.Image.save`` writes).
FRAME_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


@dataclass
class FrameFailure:
    """A frame that failed every attempt: its number, time and the engine's last message."""

    frame: int
    time: float
    message: str
    attempts: int

    def __str__(self) -> str:
        return f"frame {self.frame} (t={self.time:g} s, {self.attempts} attempts): {self.message}"


@dataclass
class FrameReport:
    """What :func:`render_frames` did: the files per frame, what was written, skipped and failed, timings."""

    paths: dict[int, Path]
    written: list[int] = field(default_factory=list)
    skipped: list[int] = field(default_factory=list)
    failed: list[FrameFailure] = field(default_factory=list)
    retried: list[int] = field(default_factory=list)
    seconds: float = 0.0
    render_seconds: dict[int, float] = field(default_factory=dict)
    workers: str = ""

    @property
    def files(self) -> list[Path]:
        """The frame files in frame order (written or skipped, not failed)."""
        bad = {f.frame for f in self.failed}
        return [p for n, p in sorted(self.paths.items()) if n not in bad]

    def summary(self) -> str:
        parts = [f"{len(self.written)} written", f"{len(self.skipped)} already there"]
        if self.retried:
            parts.append(f"{len(self.retried)} after a retry")
        if self.failed:
            parts.append(f"{len(self.failed)} FAILED")
        return f"{', '.join(parts)} in {self.seconds:.1f} s on {self.workers}"


class FramesFailed(RuntimeError):
    """Some frames failed every attempt; ``report`` has the rest (the others were rendered)."""

    def __init__(self, report: FrameReport) -> None:
        self.report = report
        shown = "\n  ".join(str(f) for f in report.failed[:10])
        more = f"\n  ... and {len(report.failed) - 10} more" if len(report.failed) > 10 else ""
        super().__init__(f"render_frames: {len(report.failed)} frame(s) failed:\n  {shown}{more}")


def load_scene(source: Any, trusted: bool = False) -> Any:
    """A Node from ``source``: a Node itself, a scene file (.json/.yaml) or a file with a registered scene reader.

    The readers (``.glb``/``.gltf`` through ``om.load_gltf``...) are registered
    by :mod:`omnirender.formats` in :mod:`omnirender.scene.readers`.
    """
    if hasattr(source, "walk"):
        return source
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        from ..scene.readers import scene_reader

        reader = scene_reader(path)
        if reader is not None:
            import inspect

            takes_trust = "trusted" in inspect.signature(reader).parameters
            return reader(path, trusted=trusted) if takes_trust else reader(path)
        from ..scene.files import load

        return load(path, trusted=trusted)
    raise TypeError(f"render_frames: scene must be an om.Node or a scene file path, got {type(source).__name__}")


def frame_paths(out: str | os.PathLike[str], frames: list[int]) -> dict[int, Path]:
    """Frame number -> file from the pattern ``out`` (``"frames/%05d.png"`` or ``"frames/{frame:05d}.png"``)."""
    text = os.fspath(out)
    suffix = Path(text).suffix.lower()
    if suffix not in FRAME_EXTENSIONS:
        raise ValueError(
            f"render_frames: out={text!r} must name image files ({', '.join(FRAME_EXTENSIONS)}) with the frame "
            "number in it, e.g. 'frames/%05d.png'"
        )
    try:
        if "{" in text:
            paths = {n: Path(text.format(frame=n)) for n in frames}
        else:
            paths = {n: Path(text % n) for n in frames}
    except (TypeError, ValueError, KeyError, IndexError):
        raise ValueError(
            f"render_frames: out={text!r} needs one frame-number field, e.g. 'frames/%05d.png' or "
            "'frames/{frame:05d}.png'"
        ) from None
    if len(set(paths.values())) != len(paths):
        raise ValueError(f"render_frames: out={text!r} gives several frames the same file name; add %05d")
    return paths


def render_frames(
    scene: Any,
    frames: Any = None,
    engine: str = "gl",
    size: tuple[int, int] = (640, 480),
    out: str | os.PathLike[str] = "frames/%05d.png",
    workers: Any = None,
    *,
    fps: float | None = None,
    overwrite: bool = False,
    retries: int = 1,
    progress: bool | None = None,
    trusted: bool = False,
    **options: Any,
) -> FrameReport:
    """Render the frames of an animated scene to image files; returns a :class:`FrameReport`.

    ``scene`` is an ``om.Node`` or a scene/glTF file.  ``frames``: None (every
    frame of the scene's animation at ``fps``), frame numbers (``range(120)``,
    ``"0-119"``) or times in seconds (floats, numbered 0, 1, ...).  ``fps``
    defaults to the animation's.  ``engine``, ``size`` and ``options`` are
    those of ``om.render``.  ``out`` is a file pattern with the frame number
    (``"frames/%05d.png"``); its folder is created.  Existing frame files are
    kept unless ``overwrite=True``.  ``workers``: see the module docs.
    ``progress`` shows a progress bar (default: when stderr is a terminal).
    Frames that fail ``1 + retries`` times raise :class:`FramesFailed` after
    all others are done.  The user's scene is never changed.
    """
    from ..render import _check_size, _engines, engines

    start = time.perf_counter()
    node = load_scene(scene, trusted)
    if engine not in _engines:
        raise ValueError(f"render_frames: unknown engine {engine!r}; registered engines: {sorted(_engines)}")
    ok, why = engines()[engine]
    if not ok:
        raise RuntimeError(f"render_frames: engine {engine!r} is not available here: {why}")
    size = _check_size(size)
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise ValueError(f"render_frames: retries must be an integer >= 0, got {retries!r}")
    specs = frame_times(node, frames, fps)
    paths = frame_paths(out, [n for n, _ in specs])
    for folder in {p.parent for p in paths.values()}:
        folder.mkdir(parents=True, exist_ok=True)
    report = FrameReport(paths=paths)
    todo = []
    for n, t in specs:
        if not overwrite and paths[n].is_file():
            report.skipped.append(n)
        else:
            todo.append((n, t, str(paths[n])))
    if todo:
        key = uuid.uuid4().hex
        payload = dump_job(Job(node, engine, size, dict(options)))
        backend, report.workers = _backend(workers, len(todo))
        bar = _progress(len(todo), engine, progress)
        try:
            for result in backend(key, payload, todo, retries):
                report.render_seconds[result.frame] = result.seconds
                if result.error is None:
                    report.written.append(result.frame)
                    if result.attempts > 1:
                        report.retried.append(result.frame)
                else:
                    report.failed.append(FrameFailure(result.frame, result.time, result.error, result.attempts))
                    bar.set_postfix_str(f"{len(report.failed)} failed", refresh=False)
                bar.advance()
        finally:
            bar.close()
    else:
        report.workers = "nothing to do"
    report.written.sort()
    report.retried.sort()
    report.failed.sort(key=lambda f: f.frame)
    report.seconds = time.perf_counter() - start
    if report.failed:
        raise FramesFailed(report)
    return report


# -- backends: each yields FrameResults as frames finish ------------------------------
Backend = Any


def _backend(workers: Any, count: int) -> tuple[Backend, str]:
    if workers is None:
        n = min(os.cpu_count() or 1, count)
        check_main_guard("om.render_frames (workers=None: one process per core)")
        return _pool(n), f"{n} local processes"
    if isinstance(workers, bool):
        raise TypeError("render_frames: workers must be None, an int, a Dask client or a scheduler address")
    if isinstance(workers, int):
        if workers < 0:
            raise ValueError(f"render_frames: workers must be >= 0, got {workers}")
        if workers == 0:
            return _here, "this process"
        n = min(workers, count)
        check_main_guard(f"om.render_frames(workers={workers})")
        return _pool(n), f"{n} local process{'es' if n > 1 else ''}"
    from .dask import dask_backend

    return dask_backend(workers)


def _here(key: str, payload: bytes, todo: list[tuple[int, float, str]], retries: int) -> Iterator[FrameResult]:
    try:
        for n, t, path in todo:
            yield run_frame(key, payload, n, t, path, retries)
    finally:
        release_all()


def _pool(n: int) -> Backend:
    def run(key: str, payload: bytes, todo: list[tuple[int, float, str]], retries: int) -> Iterator[FrameResult]:
        # spawn: a fresh interpreter per worker (forking a process that holds GL contexts or threads is unsafe)
        context = multiprocessing.get_context("spawn")
        queue = list(todo)
        crashes: dict[int, int] = {}
        alone: set[int] = set()  # frames that were running when a worker died: retried one at a time
        while queue:
            with ProcessPoolExecutor(n, mp_context=context, initializer=install_job, initargs=(key, payload)) as pool:
                running: dict[Any, tuple[int, float, str]] = {}
                broken = False
                while (queue or running) and not broken:
                    # at most one frame per worker in flight, so a crash is blamed on the frames that were running
                    while queue and len(running) < n and not (alone & {spec[0] for spec in running.values()}):
                        if queue[0][0] in alone and running:
                            break
                        spec = queue.pop(0)
                        running[pool.submit(run_frame, key, None, *spec, retries)] = spec
                    done, _ = wait(running, return_when=FIRST_COMPLETED)
                    for future in done:
                        spec = running.pop(future)
                        try:
                            yield future.result()
                        except BrokenProcessPool:
                            broken = True
                            running[future] = spec
                if not broken:
                    return
            # A worker process died.  Alone, a frame is to blame: retried up to `retries` times, then reported.
            # With others, every frame that was running is retried alone to find out which one it was.
            suspects = list(running.values())
            if len(suspects) == 1:
                spec = suspects[0]
                crashes[spec[0]] = crashes.get(spec[0], 0) + 1
                if crashes[spec[0]] > retries:
                    yield FrameResult(spec[0], spec[1], spec[2], 0.0, crashes[spec[0]], "the worker process died")
                    suspects = []
            alone.update(spec[0] for spec in suspects)
            queue[:0] = suspects

    return run


def _progress(total: int, engine: str, show: bool | None) -> Any:
    """A bar on a terminal, log lines elsewhere (``show`` None), a bar (True) or nothing (False)."""
    from ..progress import Progress

    return Progress(total, f"{engine} frames", "frame", show=show)
