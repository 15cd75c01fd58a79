"""Animation: tracks in the scene graph, scenes at any time, frames rendered locally or on a cluster.

- :class:`Animation` (a passive attribute kept in the graph) with
  :class:`Keyframes` (step / linear / cubic, quaternion slerp), :class:`Orbit`
  and Python callables ``f(t, scene)``; :func:`orbit`, :func:`camera_path`,
  :func:`turntable`.
- :func:`scene_at` (a copy at time t) and :func:`set_time` (in place).
- :func:`render_frames` on a local process pool, in this process, or on a Dask
  cluster (``workers=`` a ``distributed.Client`` or a scheduler address), with
  resume, one retry per frame and a progress bar; :func:`video` makes MP4/GIF.
"""

from __future__ import annotations

from .animation import Animation, AnimationError, animations, frame_times, parse_frames, scene_at, set_time
from .frames import FrameFailure, FrameReport, FramesFailed, render_frames
from .orbit import ORBIT_PARAMETERS, Orbit, camera_path, orbit, turntable
from .tracks import SETTERS, Keyframes, Track, register_setter
from .video import video

__all__ = [
    "Animation",
    "AnimationError",
    "Keyframes",
    "Orbit",
    "Track",
    "SETTERS",
    "ORBIT_PARAMETERS",
    "register_setter",
    "animations",
    "scene_at",
    "set_time",
    "frame_times",
    "parse_frames",
    "orbit",
    "camera_path",
    "turntable",
    "render_frames",
    "FrameReport",
    "FrameFailure",
    "FramesFailed",
    "video",
]
