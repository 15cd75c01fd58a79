"""The worker side of frame rendering: one scene copy and one engine per worker, one frame per task.

A *job* is the pickled scene with the engine name, image size and options.
Each worker process receives it once (the local pool's initializer, or a
Dask scatter) and unpickles it once per thread into its own scene copy, which
tasks set to their frame's time in place; engines that can stay alive between
frames (the GL engine) are kept per thread as well.  A task never raises: it
tries a frame ``1 + retries`` times (a fresh engine after a failure) and
returns a :class:`FrameResult` with the engine's message when every attempt
failed, so the other frames go on.
"""

from __future__ import annotations

import pickle
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["Job", "FrameResult", "dump_job", "install_job", "run_frame"]

#: Options of the GL engine that a persistent ``GLEngine`` takes at construction / per render.
_GL_ENGINE_OPTIONS = ("samples", "background", "on_missing", "technique")
_GL_RENDER_OPTIONS = ("mask", "read_depth")


@dataclass
class Job:
    """What every frame of one ``render_frames`` call shares."""

    scene: Any
    engine: str
    size: tuple[int, int]
    options: dict[str, Any]


@dataclass
class FrameResult:
    """The outcome of one frame: ``error`` is None on success, else the last attempt's message."""

    frame: int
    time: float
    path: str
    seconds: float
    attempts: int
    error: str | None = None
    worker: str = ""


def dump_job(job: Job) -> bytes:
    """The job as bytes for worker processes: cloudpickle when installed (lambdas as tracks), else pickle."""
    try:
        import cloudpickle
    except ImportError:  # pragma: no cover - cloudpickle comes with the distributed extra and with 'all'
        dumps = pickle.dumps
    else:
        dumps = cloudpickle.dumps
    try:
        return dumps(job, protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, TypeError, AttributeError) as exc:
        raise TypeError(
            f"render_frames: the scene cannot be sent to worker processes: {exc}; callable tracks must be "
            "importable functions (or install cloudpickle), or render with workers=0 (this process)"
        ) from None


# -- per-process and per-thread state ---------------------------------------------
_payloads: dict[str, bytes] = {}
_local = threading.local()
#: Scene copies unpickled in this process (one per job and thread; tests check that jobs travel once).
unpickled = 0


def install_job(key: str, payload: bytes) -> None:
    """Keep ``payload`` (a dumped :class:`Job`) in this process under ``key`` (the pool initializer)."""
    _payloads[key] = payload


class _Renderer:
    """Renders scenes with one engine, keeping the engine alive between frames where that pays."""

    def __init__(self, engine: str, size: tuple[int, int], options: dict[str, Any]) -> None:
        self.engine = engine
        self.size = size
        self.options = options
        self._gl: Any = None
        persistent = engine == "gl" and set(options) <= {*_GL_ENGINE_OPTIONS, *_GL_RENDER_OPTIONS}
        self._persistent = persistent

    def render(self, scene: Any) -> Any:
        if not self._persistent:
            from ..render import render

            return render(scene, engine=self.engine, size=self.size, **self.options)
        if self._gl is None:
            from ..gl import GLEngine

            kwargs = {k: v for k, v in self.options.items() if k in _GL_ENGINE_OPTIONS}
            self._gl = GLEngine(size=self.size, **kwargs)
        render_kwargs = {"read_depth": False, **{k: v for k, v in self.options.items() if k in _GL_RENDER_OPTIONS}}
        return self._gl.render(scene, **render_kwargs)

    def close(self) -> None:
        if self._gl is not None:
            self._gl.release()
            self._gl = None


class _State:
    def __init__(self, job: Job) -> None:
        self.scene = job.scene
        self.renderer = _Renderer(job.engine, tuple(job.size), dict(job.options))


def _state(key: str, payload: bytes | None) -> _State:
    global unpickled
    states: dict[str, _State] = getattr(_local, "states", None) or {}
    _local.states = states
    state = states.get(key)
    if state is None:
        data = payload if payload is not None else _payloads.get(key)
        if data is None:
            raise RuntimeError(f"render_frames: job {key} was not installed in this worker")
        state = states[key] = _State(pickle.loads(data))
        unpickled += 1
    return state


def run_frame(key: str, payload: bytes | None, frame: int, t: float, path: str, retries: int = 1) -> FrameResult:
    """Render frame ``frame`` (time ``t``) of job ``key`` to ``path``; see the module docs."""
    import os
    import socket

    from .animation import set_time

    worker = f"{socket.gethostname()}:{os.getpid()}"
    start = time.perf_counter()
    error = ""
    attempts = 0
    for attempts in range(1, retries + 2):
        try:
            state = _state(key, payload)
            set_time(state.scene, t)
            image = state.renderer.render(state.scene)
            image.save(Path(path))
            return FrameResult(frame, t, path, time.perf_counter() - start, attempts, None, worker)
        except Exception as exc:  # reported with the frame number; the other frames go on
            error = " ".join(f"{type(exc).__name__}: {exc}".split())
            _forget(key)  # the next attempt starts from a fresh scene copy and engine
    return FrameResult(frame, t, path, time.perf_counter() - start, attempts, error, worker)


def _forget(key: str) -> None:
    states: dict[str, _State] = getattr(_local, "states", None) or {}
    state = states.pop(key, None)
    if state is not None:
        try:
            state.renderer.close()
        except Exception:  # a broken engine may fail to release; it is dropped either way
            pass


def release_all() -> None:
    """Release this thread's engines (called when a local run in this process ends)."""
    for key in list(getattr(_local, "states", {}) or {}):
        _forget(key)
