"""Viewer test helpers: a recording engine and simple renderables."""

from __future__ import annotations

import numpy as np

import omnirender as om


class Dot(om.Shape):
    """A test shape: a labelled point."""

    __slots__ = ("label", "position")

    def __init__(self, label: str, position=(0.0, 0.0, 0.0)) -> None:
        super().__init__()
        self.label = label
        self.position = tuple(position)


class RecordingEngine(om.Engine):
    """Records passes, drawn dots (with the active model matrix) and the frame's lights and camera."""

    service = "record.paint"

    def __init__(self) -> None:
        super().__init__(on_missing="skip")
        self.log: list[tuple] = []
        self.install(DotPainter())

    def begin_pass(self, name: str) -> None:
        self.log.append(("pass", name))

    def begin_frame(self, viewer) -> None:
        self.log.append(("frame",))

    def end_frame(self):
        self.log.append(("lights", len(self.lights())))
        return None

    def drawn(self) -> list[str]:
        return [entry[1] for entry in self.log if entry[0] == "dot"]


class DotPainter(om.ShapePainter):
    __slots__ = ()
    service = "record.paint"
    target = Dot

    def exec(self, shape: Dot, engine: RecordingEngine) -> None:
        p = engine.model_matrix() @ np.array([*shape.position, 1.0])
        engine.log.append(("dot", shape.label, tuple(p[:3]), engine.camera))


class Item:
    """A renderable drawing one Dot; counts prerender and render calls."""

    def __init__(self, label: str, hints: int = 0, position=(0.0, 0.0, 0.0), z_order: int = 0) -> None:
        self.dot = Dot(label, position)
        self.hints = hints
        self.z_order = z_order
        self.visible = True
        self.prerenders = 0
        self.renders: list[int] = []
        self.lo = np.array(position, dtype=float) - 0.5
        self.hi = np.array(position, dtype=float) + 0.5

    def prerender(self, render_list) -> None:
        self.prerenders += 1

    def render(self, renderer, flags: int) -> None:
        self.renders.append(flags)
        renderer.eval(self.dot)

    def update_bounds(self, pmin, pmax) -> None:
        np.minimum(pmin, self.lo, out=pmin)
        np.maximum(pmax, self.hi, out=pmax)

    def render_hints(self) -> int:
        return self.hints


def start_xvfb():
    """Start Xvfb on a free display; returns (process, display string)."""
    import os
    import shutil
    import subprocess
    import time

    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        raise RuntimeError("Xvfb is not installed")
    for n in range(73, 140):
        if os.path.exists(f"/tmp/.X{n}-lock") or os.path.exists(f"/tmp/.X11-unix/X{n}"):
            continue
        proc = subprocess.Popen(
            [xvfb, f":{n}", "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            if os.path.exists(f"/tmp/.X11-unix/X{n}"):
                return proc, f":{n}"
            if proc.poll() is not None:
                break
            time.sleep(0.05)
        proc.kill()
    raise RuntimeError("could not start Xvfb on any display :73-:139")
