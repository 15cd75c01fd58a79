"""``om.Animation``: time-varying parameters, kept in the scene graph itself.

An Animation holds tracks (:class:`~omnirender.animation.tracks.Keyframes`,
:class:`~omnirender.animation.orbit.Orbit`, or any Python callable
``f(t, scene)``) and sits in a node like any attribute, usually the root.
Engines ignore it (it is a passive poly attribute: no engine has a handler for
it), so an animated scene renders as its current state everywhere; because it
is part of the graph it travels with the scene into scene files, pickles and
worker processes.  Like lights and cameras it acts wherever it sits: its
tracks name their target components directly.

:func:`scene_at` gives the scene at time ``t`` as a new graph, leaving the
user's untouched; :func:`set_time` sets the user's graph itself to time ``t``
(cheaper: no copy, and engines recompile only what the tracks changed).
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

from ..core.component import PolyAttribute
from .tracks import Keyframes, Track, check_time

__all__ = ["Animation", "animations", "scene_at", "set_time", "frame_times", "AnimationError"]


class AnimationError(ValueError):
    """A track could not set its parameter at some time (the message names the track, time and node)."""


class Animation(PolyAttribute):
    """Tracks that drive component parameters over time; see the module docs.

    ``Animation(tracks=(), duration=None, fps=24)``: ``tracks`` is a list of
    tracks and callables ``f(t, scene)`` (``scene`` is the root the time is
    set on); ``duration`` in seconds defaults to the end of the last keyframe
    or orbit; ``fps`` is the frame rate frames are numbered with when no
    other is given.  :meth:`keyframes` adds a keyframe track.
    """

    __slots__ = ("_tracks", "_duration", "_fps")

    def __init__(
        self,
        tracks: Iterable[Track | Callable[[float, Any], Any]] = (),
        duration: float | None = None,
        fps: float = 24.0,
    ) -> None:
        super().__init__()
        self.tracks = tracks
        self.duration = duration
        self.fps = fps

    # -- parameters ------------------------------------------------------------
    @property
    def tracks(self) -> tuple[Track | Callable[[float, Any], Any], ...]:
        return self._tracks

    @tracks.setter
    def tracks(self, value: Iterable[Any]) -> None:
        if isinstance(value, Track) or callable(value) or not isinstance(value, Iterable):
            raise TypeError("Animation: tracks must be a list of tracks (om.Keyframes, om.Orbit or f(t, scene))")
        items = tuple(value)
        for i, track in enumerate(items):
            if not isinstance(track, Track) and not callable(track):
                raise TypeError(
                    f"Animation: tracks[{i}] is a {type(track).__name__}; expected om.Keyframes, om.Orbit or a "
                    "callable f(t, scene)"
                )
        object.__setattr__(self, "_tracks", items)

    @property
    def duration(self) -> float:
        """Length in seconds: as given, else where the last keyframe or orbit ends."""
        if self._duration is not None:
            return self._duration
        return max((t.end for t in self._tracks if isinstance(t, Track)), default=0.0)

    @duration.setter
    def duration(self, value: float | None) -> None:
        if value is not None:
            value = check_time("Animation", value, "duration", nonnegative=True)
        object.__setattr__(self, "_duration", value)

    @property
    def fps(self) -> float:
        return self._fps

    @fps.setter
    def fps(self, value: float) -> None:
        object.__setattr__(self, "_fps", _check_fps("Animation", value))

    def parameters(self) -> dict[str, Any]:
        return {"tracks": list(self._tracks), "duration": self._duration, "fps": self._fps}

    # -- building ---------------------------------------------------------------
    def add(self, track: Track | Callable[[float, Any], Any]) -> Any:
        """Append a track (or a callable ``f(t, scene)``); returns it."""
        self.tracks = (*self._tracks, track)
        return track

    def keyframes(
        self,
        target: Any,
        parameter: str,
        keys: dict[float, Any] | Sequence[tuple[float, Any]],
        interpolation: str = "linear",
    ) -> Keyframes:
        """Add a :class:`Keyframes` track from ``{time: value}`` (or ``[(time, value), ...]``); returns it."""
        pairs = sorted(keys.items() if isinstance(keys, dict) else keys, key=lambda kv: kv[0])
        times = [t for t, _ in pairs]
        values = [v for _, v in pairs]
        return self.add(Keyframes(target, parameter, times, values, interpolation))

    # -- evaluation -------------------------------------------------------------
    def frame_count(self, fps: float | None = None) -> int:
        """Frames in one run of the animation: ``round(duration * fps)``, at least 1."""
        rate = self._fps if fps is None else _check_fps("Animation.frame_count", fps)
        return max(1, int(round(self.duration * rate)))

    def apply(self, t: float, scene: Any = None) -> None:
        """Set every track's parameters for time ``t`` (seconds); ``scene`` is passed to callables."""
        t = check_time("Animation", t)
        for track in self._tracks:
            try:
                if isinstance(track, Track):
                    track.apply(t, scene)
                else:
                    track(t, scene)
            except (ValueError, TypeError, AttributeError) as exc:
                name = track.describe() if isinstance(track, Track) else getattr(track, "__name__", repr(track))
                raise AnimationError(f"Animation track {name} at t={t:g} s{_where(self)}: {exc}") from exc


def _where(animation: Animation) -> str:
    owners = animation.owners
    return f" (in node {owners[0].path})" if owners else ""


def _check_fps(owner: str, value: Any) -> float:
    return check_time(owner, value, "fps (frames per second)", positive=True)


def animations(scene: Any) -> list[Animation]:
    """Every Animation in ``scene`` (each once, in traversal order)."""
    found: list[Animation] = []
    seen: set[int] = set()
    for node in scene.walk():
        for component in node.components:
            if isinstance(component, Animation) and id(component) not in seen:
                seen.add(id(component))
                found.append(component)
    return found


def set_time(scene: Any, t: float) -> Any:
    """Set ``scene`` itself to time ``t`` (seconds): every Animation in it applies its tracks; returns ``scene``."""
    _check_node("om.set_time", scene)
    for animation in animations(scene):
        animation.apply(t, scene)
    return scene


def scene_at(scene: Any, t: float) -> Any:
    """A new graph: ``scene`` at time ``t`` (seconds).  The user's graph is not changed.

    The copy is deep (components, nodes and the animation's references to
    them); mesh files are read again where the copy is rendered.  To render
    many times, copy once and call :func:`set_time` on the copy.
    """
    _check_node("om.scene_at", scene)
    return set_time(copy.deepcopy(scene), t)


def frame_times(scene: Any, frames: Any = None, fps: float | None = None) -> list[tuple[int, float]]:
    """``[(frame number, time), ...]`` for ``frames``: see :func:`omnirender.animation.render_frames`.

    ``frames`` may be None (every frame of the scene's animations), an int
    sequence (frame numbers at ``fps``), a float sequence (times in seconds,
    numbered 0, 1, ...) or a string like ``"0-119"`` / ``"0-119:2"`` / ``"3,5,8"``.
    ``fps`` defaults to the first animation's, else 24.
    """
    found = animations(scene) if scene is not None else []
    rate = _check_fps("frames", fps) if fps is not None else (found[0].fps if found else 24.0)
    if frames is None:
        count = max((a.frame_count(rate) for a in found), default=1)
        return [(i, i / rate) for i in range(count)]
    if isinstance(frames, str):
        frames = parse_frames(frames)
    items = list(frames)
    if not items:
        raise ValueError("frames: the list of frames is empty")
    if all(isinstance(f, (int, np.integer)) and not isinstance(f, bool) for f in items):
        numbers = [int(f) for f in items]
        if min(numbers) < 0:
            raise ValueError(f"frames: frame numbers must be >= 0, got {min(numbers)}")
        if len(set(numbers)) != len(numbers):
            raise ValueError("frames: a frame number is listed twice")
        return [(n, n / rate) for n in numbers]
    return [(i, check_time(f"frames[{i}]", t)) for i, t in enumerate(items)]


def parse_frames(text: str) -> list[int]:
    """Frame numbers from ``"0-119"``, ``"0-119:2"`` (every second) or ``"3,5,10-12"``."""
    out: list[int] = []
    for part in text.replace(" ", "").split(","):
        try:
            span, _, step = part.partition(":")
            first, dash, last = span.partition("-")
            a = int(first)
            b = int(last) if dash else a
            s = int(step) if step else 1
        except ValueError:
            raise ValueError(f"frames: cannot read {part!r} in {text!r}; write e.g. 0-119, 0-119:2 or 3,5,8") from None
        if a < 0 or b < a or s <= 0:
            raise ValueError(f"frames: {part!r} is not an increasing range of frame numbers >= 0")
        out.extend(range(a, b + 1, s))
    return out


def _check_node(function: str, scene: Any) -> None:
    if not hasattr(scene, "walk") or not hasattr(scene, "preevaluate"):
        raise TypeError(f"{function}: scene must be an om.Node, got {type(scene).__name__}")
