"""The interactive window: a glfw window showing a :class:`Viewer`.

Mouse: left drag orbits around the viewing centre, right drag (or shift +
left, or middle) pans, the wheel zooms, a left click without dragging picks
the shape under the cursor (``om.pick``), highlights it and shows its node
path in the title.  Keys: 1/2/3 front/right/top axial views (shift: the
opposite ones), F auto-fit, R reset to the initial view, W wireframe, P
perspective/orthogonal, S screenshot, H help, Q or Esc close.

The window runs its own loop at its own frame rate; an application update
(``view(scene, update=fn)``) runs in a worker thread so a slow update never
slows the drawing: ``fn(t)`` computes without any lock and may return a
callable that applies the result, which the worker runs under the render
list's lock before asking the window to rerender.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .interaction import LEFT, MIDDLE, RIGHT, ViewControl

__all__ = ["Window", "view", "HELP"]

HELP = """omnirender viewer
  left drag        orbit around the centre
  right drag       pan (also shift + left drag, middle drag)
  wheel            zoom
  left click       pick: highlight the shape under the cursor, path in the title
  1 / 2 / 3        front / right / top view   (shift: back / left / bottom)
  F                auto-fit          R  reset view
  W                wireframe         P  perspective / orthogonal
  S                screenshot (omnirender-screenshot-N.png)
  H                this help         Q, Esc  close"""

_VERTEX = """
#version 330
out vec2 uv;
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    uv = vec2(p.x, 1.0 - p.y);
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
"""
_FRAGMENT = """
#version 330
uniform sampler2D image;
in vec2 uv;
out vec4 color;
void main() { color = texture(image, uv); }
"""


class _GLFWLoader:
    """moderngl loader for the window's context: GL functions from glfw, entering makes the window current."""

    def __init__(self, glfw: Any, handle: Any) -> None:
        self._glfw = glfw
        self._handle = handle
        self.load_opengl_function = lambda name: glfw.get_proc_address(name) or 0

    def __enter__(self) -> None:
        if self._handle is not None:
            self._glfw.make_context_current(self._handle)

    def __exit__(self, *args: Any) -> None:
        pass

    def release(self) -> None:
        self._handle = None


def _attach_context(glfw: Any, handle: Any) -> Any:
    """A moderngl context wrapping the window's (like ``moderngl.init_context``, without making it global)."""
    import moderngl

    ctx = moderngl.Context.__new__(moderngl.Context)
    ctx.mglo, ctx.version_code = moderngl.mgl.create_context(context=_GLFWLoader(glfw, handle))
    ctx._info = None
    ctx._extensions = None
    ctx.extra = None
    ctx._gc_mode = None
    ctx._objects = deque()
    ctx._screen = ctx.detect_framebuffer(0)
    ctx.fbo = ctx.detect_framebuffer()
    ctx.mglo.fbo = ctx.fbo.mglo
    return ctx


def _init_glfw(glfw: Any) -> tuple[bool, str]:
    """``glfw.init()`` with its error (no display...) returned as text, not printed as a GLFWError warning."""
    previous = glfw.ERROR_REPORTING
    glfw.ERROR_REPORTING = "raise"
    try:
        return bool(glfw.init()), ""
    except glfw.GLFWError as exc:
        text = str(exc)
        return False, text.split(") ", 1)[-1].strip("b'\"") if text.startswith("(") else text
    finally:
        glfw.ERROR_REPORTING = previous


class Window:
    """A glfw window bound to ``viewer``; ``run()`` loops until closed, ``step()`` runs one iteration."""

    def __init__(self, viewer: Any, title: str = "omnirender", visible: bool = True) -> None:
        import glfw

        self._glfw = glfw
        ok, reason = _init_glfw(glfw)
        if not ok:
            raise RuntimeError(
                f"omnirender window: glfw cannot initialise ({reason or 'no display?'}); set DISPLAY or run "
                "under Xvfb, or use om.Viewer(window=False) for offscreen images"
            )
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        glfw.window_hint(glfw.VISIBLE, bool(visible))
        # EGL, like the headless contexts: mixing GLX and EGL contexts in one process makes
        # glXMakeCurrent fail with BadAccess once an EGL context existed.
        glfw.window_hint(glfw.CONTEXT_CREATION_API, glfw.EGL_CONTEXT_API)
        w, h = viewer.size
        self.handle = glfw.create_window(w, h, title, None, None)
        if not self.handle:
            raise RuntimeError("omnirender window: glfw could not create an OpenGL 3.3 window on this display")
        glfw.make_context_current(self.handle)
        glfw.swap_interval(0)
        self.ctx = _attach_context(glfw, self.handle)
        self.viewer = viewer
        self.base_title = title
        self.title = title
        self.scene: Any = None
        self.picked: Any = None
        self.last_frame: Any = None
        self.frames = 0
        self.screenshots: list[Path] = []
        self.screenshot_dir = Path.cwd()
        self._program = self.ctx.program(vertex_shader=_VERTEX, fragment_shader=_FRAGMENT)
        self._vao = self.ctx.vertex_array(self._program, [])
        self._texture: Any = None
        self.control = ViewControl(viewer)  # mouse and keys -> camera (shared with the notebook widget)
        self._dirty = True
        self._needs_prerender = True
        self._external_generation = -1
        self._closed = False
        self._update_thread: threading.Thread | None = None
        self._stop = threading.Event()
        fw, fh = glfw.get_framebuffer_size(self.handle)
        if (fw, fh) != tuple(viewer.size) and fw > 0 and fh > 0:
            viewer.set_size(fw, fh)
        glfw.set_mouse_button_callback(self.handle, self.on_mouse_button)
        glfw.set_cursor_pos_callback(self.handle, self.on_cursor_pos)
        glfw.set_scroll_callback(self.handle, self.on_scroll)
        glfw.set_key_callback(self.handle, self.on_key)
        glfw.set_framebuffer_size_callback(self.handle, self.on_resize)
        glfw.set_window_refresh_callback(self.handle, lambda handle: self.request_repaint())

    # -- state ---------------------------------------------------------------
    def remember_view(self) -> None:
        """Store the current camera as the one R resets to."""
        self.control.remember_view()

    def request_repaint(self) -> None:
        self._dirty = True

    def request_rerender(self) -> None:
        self._needs_prerender = True
        self._dirty = True

    @property
    def should_close(self) -> bool:
        return self._closed or bool(self._glfw.window_should_close(self.handle))

    # -- loop ------------------------------------------------------------------
    def run(self, fps: float = 60.0, duration: float | None = None) -> None:
        """Loop until the window is closed (or ``duration`` seconds pass), at most ``fps`` frames a second."""
        start = time.monotonic()
        period = 1.0 / fps
        while not self.should_close:
            t0 = time.monotonic()
            self.step()
            if duration is not None and t0 - start >= duration:
                break
            spare = period - (time.monotonic() - t0)
            if spare > 0:
                self._glfw.wait_events_timeout(spare)

    def step(self) -> bool:
        """Poll events and draw if anything changed; returns whether a frame was drawn."""
        self._glfw.poll_events()
        if self.should_close:
            return False
        external = self.viewer.get_external_render_list()
        if external is not None and external.generation != self._external_generation:
            self._external_generation = external.generation
            self._dirty = True
        if not self._dirty:
            return False
        self.draw()
        return True

    def draw(self) -> Any:
        """Render the viewer's frame and show it; returns the frame (an om.Image)."""
        self._glfw.make_context_current(self.handle)
        if self._needs_prerender:
            self._needs_prerender = False
            image = self.viewer.rerender()
        else:
            image = self.viewer.repaint()
        self._dirty = False
        self._show(image)
        return image

    def _show(self, image: Any) -> None:
        w, h = self.viewer.size
        array = np.ascontiguousarray(image.array)
        if self._texture is None or self._texture.size != (image.width, image.height):
            if self._texture is not None:
                self._texture.release()
            self._texture = self.ctx.texture((image.width, image.height), 4, array.tobytes())
        else:
            self._texture.write(array.tobytes())
        self.ctx.screen.use()
        self.ctx.viewport = (0, 0, w, h)
        self.ctx.disable(self.ctx.DEPTH_TEST | self.ctx.BLEND)
        self._texture.use(0)
        self._vao.render(self.ctx.TRIANGLES, vertices=3)
        self.last_frame = image
        self.frames += 1
        self._glfw.swap_buffers(self.handle)

    def screenshot(self) -> Any:
        """What the window shows, read back from its framebuffer, as an om.Image."""
        from ..image import Image

        self._glfw.make_context_current(self.handle)
        w, h = self.viewer.size
        # redraw into the back buffer and read it: exactly what the last swap put on screen
        if self._texture is not None:
            self.ctx.screen.use()
            self.ctx.viewport = (0, 0, w, h)
            self._texture.use(0)
            self._vao.render(self.ctx.TRIANGLES, vertices=3)
        data = self.ctx.screen.read(viewport=(0, 0, w, h), components=4)
        # moderngl selects GL_COLOR_ATTACHMENT0 as read buffer, which the default framebuffer
        # rejects (GL_INVALID_OPERATION) while keeping GL_BACK, the buffer just drawn: clear the flag.
        _ = self.ctx.error
        array = np.frombuffer(data, np.uint8).reshape(h, w, 4)[::-1].copy()
        return Image(array, engine="window", info={"frames": self.frames})

    def save_screenshot(self, path: str | Path | None = None) -> Path:
        if path is None:
            path = self.screenshot_dir / f"omnirender-screenshot-{len(self.screenshots) + 1}.png"
        saved = self.screenshot().save(path)
        self.screenshots.append(saved)
        return saved

    # -- application update ------------------------------------------------------
    def start_updates(self, update: Callable[[float], Any], interval: float = 0.0) -> None:
        """Run ``update(t)`` repeatedly in a worker thread (see the module docs)."""
        render_list = self.viewer.render_list
        start = time.monotonic()

        def loop() -> None:
            while not self._stop.is_set():
                apply = update(time.monotonic() - start)
                with render_list.lock:
                    if callable(apply):
                        apply()
                    self.request_rerender()
                if interval > 0:
                    self._stop.wait(interval)

        self._update_thread = threading.Thread(target=loop, name="omnirender-update", daemon=True)
        self._update_thread.start()

    # -- event handlers (glfw callbacks) --------------------------------------------
    def _button(self, button: int) -> str | None:
        glfw = self._glfw
        return {glfw.MOUSE_BUTTON_LEFT: LEFT, glfw.MOUSE_BUTTON_RIGHT: RIGHT, glfw.MOUSE_BUTTON_MIDDLE: MIDDLE}.get(
            button
        )

    def on_mouse_button(self, handle: Any, button: int, action: int, mods: int) -> None:
        glfw = self._glfw
        name = self._button(button)
        if name is None:
            return
        # where the button went down, not where the last motion event left the cursor
        x, y = glfw.get_cursor_pos(self.handle) if self.handle else self.control.cursor
        if action == glfw.PRESS:
            self.control.press(name, x, y)
        elif action == glfw.RELEASE and self.control.release(name, x, y):
            self.click(x, y)

    def on_cursor_pos(self, handle: Any, x: float, y: float) -> None:
        glfw = self._glfw
        shift = glfw.get_key(self.handle, glfw.KEY_LEFT_SHIFT) == glfw.PRESS if self.handle else False
        # cursor positions are in window coordinates
        if self.control.move(x, y, self.window_size()[1], shift):
            self.request_repaint()

    def on_scroll(self, handle: Any, dx: float, dy: float) -> None:
        self.control.wheel(dy)
        self.request_repaint()

    def on_key(self, handle: Any, key: int, scancode: int, action: int, mods: int) -> None:
        glfw = self._glfw
        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        names = {glfw.KEY_1: "1", glfw.KEY_2: "2", glfw.KEY_3: "3", glfw.KEY_F: "f", glfw.KEY_R: "r"}
        names.update({glfw.KEY_W: "w", glfw.KEY_P: "p"})
        if key in names:
            self.control.key(names[key], shift=bool(mods & glfw.MOD_SHIFT))
        elif key == glfw.KEY_S:
            path = self.save_screenshot()
            print(f"screenshot: {path}")
        elif key == glfw.KEY_H:
            print(HELP)
        elif key in (glfw.KEY_Q, glfw.KEY_ESCAPE):
            glfw.set_window_should_close(self.handle, True)
            return
        else:
            return
        self.request_repaint()

    def on_resize(self, handle: Any, width: int, height: int) -> None:
        if width > 0 and height > 0:
            self.viewer.set_size(width, height)
            self.request_repaint()

    # -- view helpers -------------------------------------------------------------
    def reset_view(self) -> None:
        """Back to the view remembered when the scene was opened (auto-fit if none)."""
        self.control.reset_view()

    def window_size(self) -> tuple[int, int]:
        """The window's size in window coordinates (cursor units; framebuffer pixels differ on HiDPI screens)."""
        if self.handle:
            w, h = self._glfw.get_window_size(self.handle)
            if w > 0 and h > 0:
                return w, h
        return self.viewer.size

    def to_pixel(self, x: float, y: float) -> tuple[int, int] | None:
        """The image pixel under window position (x, y) (framebuffer pixels), or None outside the image."""
        ww, wh = self.window_size()
        fw, fh = self.viewer.size
        px, py = int(x * fw / ww), int(y * fh / wh)
        if not (0 <= px < fw and 0 <= py < fh):
            return None
        return px, py

    def click(self, x: float, y: float) -> Any:
        """A click at window position (x, y): pick there (ignored outside the image, e.g. a drag out of it)."""
        pixel = self.to_pixel(x, y)
        if pixel is None:
            return self.picked
        return self.pick(*pixel)

    def pick(self, x: int, y: int) -> Any:
        """Pick at image pixel (x, y) (origin top left): highlight the nearest shape, show its path."""
        from .picking import pick_in_viewer

        w, h = self.viewer.size
        hit = pick_in_viewer(self.viewer, self.scene, min(max(int(x), 0), w - 1), min(max(int(y), 0), h - 1))
        self.picked = hit
        self.viewer.set_picked(hit)
        self.set_title(f"{self.base_title} - {hit.path}" if hit is not None else self.base_title)
        self.request_rerender()
        return hit

    def set_title(self, title: str) -> None:
        self.title = title
        self._glfw.set_window_title(self.handle, title)

    def close(self) -> None:
        """Stop the update thread, release the window's GPU objects and destroy it (the viewer's engine first)."""
        self._stop.set()
        if self._update_thread is not None:
            self._update_thread.join(timeout=5)
        if self._closed:
            return
        self._closed = True
        driver = getattr(self.viewer, "_driver", None)
        if driver is not None and getattr(driver.engine, "ctx", None) is self.ctx:
            driver.release()
            self.viewer._driver = None
        self._glfw.make_context_current(self.handle)
        for obj in (self._texture, self._vao, self._program):
            if obj is not None:
                obj.release()
        self._texture = None
        self._glfw.make_context_current(None)
        self._glfw.destroy_window(self.handle)
        self.handle = None


def view(
    scene: Any,
    size: tuple[int, int] = (960, 720),
    *,
    title: str = "omnirender",
    update: Callable[[float], Any] | None = None,
    update_interval: float = 0.0,
    duration: float | None = None,
    fps: float = 60.0,
    stereo: Any = None,
) -> Any:
    """Open a window on ``scene`` and loop until it is closed (or ``duration`` seconds pass).

    The scene's camera (if any) is the initial view, and its group mask the
    window's (hidden subgraphs are neither drawn nor picked), else the view fits the
    scene; scenes with their own lights replace the viewer's default lights,
    and the scene's ``om.Background`` colour (if any) is the window's.
    ``update(t)`` runs in a worker thread (see the module docs); ``stereo`` (an
    ``om.gl.Stereo``) shows the scene as a stereo pair.  Returns the viewer.
    """
    from .viewer import Viewer

    viewer = Viewer(size=size, window=True, title=title, stereo=stereo)
    try:
        open_scene(viewer, scene)
        if update is not None:
            viewer.window.start_updates(update, update_interval)
        viewer.window.run(fps=fps, duration=duration)
    finally:
        viewer.close()
    return viewer


def open_scene(viewer: Any, scene: Any) -> None:
    """Add ``scene`` to ``viewer`` with its camera (or an auto-fit view), lights and ``om.Background``."""
    viewer.add_renderable(scene)
    window = viewer.window
    if window is not None:
        window.scene = scene
    background = _scene_background(scene)
    if background is not None:
        viewer.background = background.color
    if hasattr(scene, "preevaluate"):
        lights, camera = scene.preevaluate()
        if lights:
            viewer.clear_lights()
        if camera is not None:
            viewer.set_camera(*camera)
            viewer.mask = camera[0].mask  # what the scene's camera shows, the window shows and picks
        else:
            viewer.set_eye_to_world((3, 2, 4), (0, 0, 0), (0, 1, 0))
            viewer.auto_fit()
    else:
        viewer.auto_fit()
    if window is not None:
        window.remember_view()
        window.request_rerender()


def _scene_background(scene: Any) -> Any:
    """The scene's ``om.Background`` (what its pre-evaluation declares, as in every engine), or None."""
    if not hasattr(scene, "declarations"):
        return None
    from ..attributes import Background

    found = scene.declarations().first(Background)
    return None if found is None else found[0]
