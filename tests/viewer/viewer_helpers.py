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
    """Start Xvfb on a display it chooses itself (``-displayfd``); returns (process, display string)."""
    import os
    import shutil
    import subprocess

    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        raise RuntimeError("Xvfb is not installed")
    read, write = os.pipe()
    try:
        proc = subprocess.Popen(
            [xvfb, "-displayfd", str(write), "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            pass_fds=(write,),
        )
    finally:
        os.close(write)
    with os.fdopen(read) as pipe:
        number = pipe.readline().strip()  # written once the server accepts connections
    if not number.isdigit():
        proc.kill()
        proc.wait(timeout=10)
        raise RuntimeError(f"Xvfb did not report a display (exit code {proc.poll()})")
    return proc, f":{number}"


class XInput:
    """Real X input events through the XTest extension (libXtst via ctypes), delivered to a glfw window.

    Positions are in the window's coordinates; after each event the X
    connection is flushed and the window's loop runs until glfw has seen it.
    """

    KEYSYMS = {"shift": 0xFFE1, "escape": 0xFF1B}

    def __init__(self, display: str, window) -> None:
        import ctypes

        self.window = window
        self.x11 = ctypes.CDLL("libX11.so.6")
        self.xtst = ctypes.CDLL("libXtst.so.6")
        self.x11.XOpenDisplay.restype = ctypes.c_void_p
        self.x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
        for fn in (self.x11.XFlush, self.x11.XSync, self.x11.XCloseDisplay):
            fn.argtypes = [ctypes.c_void_p] + ([ctypes.c_int] if fn is self.x11.XSync else [])
        self.x11.XKeysymToKeycode.argtypes = [ctypes.c_void_p, ctypes.c_ulong]
        self.x11.XKeysymToKeycode.restype = ctypes.c_ubyte
        self.xtst.XTestFakeMotionEvent.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.c_int,
                                                   ctypes.c_ulong]  # fmt: skip
        self.xtst.XTestFakeButtonEvent.argtypes = [ctypes.c_void_p, ctypes.c_uint, ctypes.c_int, ctypes.c_ulong]
        self.xtst.XTestFakeKeyEvent.argtypes = [ctypes.c_void_p, ctypes.c_uint, ctypes.c_int, ctypes.c_ulong]
        self.dpy = self.x11.XOpenDisplay(display.encode())
        if not self.dpy:
            raise RuntimeError(f"cannot open X display {display}")

    def close(self) -> None:
        if self.dpy:
            self.x11.XCloseDisplay(self.dpy)
            self.dpy = None

    def pump(self, seconds: float = 0.15) -> None:
        """Send what is queued and let the window process it (a few loop iterations)."""
        import time

        self.x11.XSync(self.dpy, 0)
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.window.step()
            time.sleep(0.01)

    def move(self, x: float, y: float) -> None:
        import glfw

        wx, wy = glfw.get_window_pos(self.window.handle)
        self.xtst.XTestFakeMotionEvent(self.dpy, -1, int(wx + x), int(wy + y), 0)
        self.pump(0.05)

    def button(self, button: int, down: bool) -> None:
        """X buttons: 1 left, 2 middle, 3 right, 4/5 wheel up/down."""
        self.xtst.XTestFakeButtonEvent(self.dpy, button, bool(down), 0)
        self.pump(0.05)

    def click(self, x: float, y: float, button: int = 1) -> None:
        self.move(x, y)
        self.button(button, True)
        self.button(button, False)
        self.pump()

    def drag(self, start, end, button: int = 1, steps: int = 10) -> None:
        self.move(*start)
        self.button(button, True)
        for i in range(1, steps + 1):
            t = i / steps
            self.move(start[0] + t * (end[0] - start[0]), start[1] + t * (end[1] - start[1]))
        self.button(button, False)
        self.pump()

    def wheel(self, notches: int) -> None:
        """Positive: wheel up (zoom in), negative: wheel down."""
        button = 4 if notches > 0 else 5
        for _ in range(abs(notches)):
            self.xtst.XTestFakeButtonEvent(self.dpy, button, True, 0)
            self.xtst.XTestFakeButtonEvent(self.dpy, button, False, 0)
            self.pump(0.05)
        self.pump()

    def key(self, name: str, shift: bool = False) -> None:
        """Press and release a key (a character like "w" or a name in KEYSYMS), optionally with shift."""
        keysym = self.KEYSYMS.get(name, ord(name) if len(name) == 1 else None)
        code = self.x11.XKeysymToKeycode(self.dpy, keysym)
        shift_code = self.x11.XKeysymToKeycode(self.dpy, self.KEYSYMS["shift"])
        if shift:
            self.xtst.XTestFakeKeyEvent(self.dpy, shift_code, True, 0)
        self.xtst.XTestFakeKeyEvent(self.dpy, code, True, 0)
        self.xtst.XTestFakeKeyEvent(self.dpy, code, False, 0)
        if shift:
            self.xtst.XTestFakeKeyEvent(self.dpy, shift_code, False, 0)
        self.pump()
