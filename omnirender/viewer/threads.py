"""Render threads on immutable snapshots: the application loop never waits for a renderer.

guacamole's app/render decoupling.  The application thread changes the
scene and, at the end of each of its frames, calls :meth:`RenderThreads.publish`:
a :class:`~omnirender.scene.Snapshot` is taken (incrementally, see
:mod:`omnirender.scene.snapshot`) and handed to every :class:`RenderClient`.
Each client has its own thread, its own GL context and its own copy of the
scene (a :class:`~omnirender.scene.SceneMirror`), and draws the newest
snapshot it was given: *latest wins*, a snapshot that arrives while the client
is still drawing replaces the waiting one, which is dropped (counted in
``client.dropped``).  ``publish`` only stores a reference per client, so a
slow renderer never slows the application; every image a client makes shows
exactly one snapshot.

A client draws with an ``om.gl.GLEngine`` made in its thread (the default),
or with what ``renderer`` makes there: an engine (``render(scene)``) or an
``om.Viewer`` (an offscreen one, or a window).  ``on_frame(image, snapshot)``
gets every image, in the client's thread.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from ..scene import Node, SceneMirror, Snapshot, Snapshotter

__all__ = ["RenderThreads", "RenderClient"]


class RenderClient:
    """One render thread: its own GL context, scene mirror and renderer, drawing the newest snapshot.

    ``size`` and ``samples`` are the default engine's; ``renderer`` (called
    once, in the thread) makes another renderer instead; ``on_frame(image,
    snapshot)`` receives each image; ``name`` names the thread.  ``frames``
    counts the images made, ``dropped`` the snapshots replaced before they
    were drawn, ``error`` holds an exception that stopped the thread.
    """

    def __init__(
        self,
        size: tuple[int, int] = (640, 480),
        *,
        samples: int = 4,
        renderer: Callable[[], Any] | None = None,
        on_frame: Callable[[Any, Snapshot], Any] | None = None,
        name: str = "render client",
    ) -> None:
        if renderer is not None and not callable(renderer):
            raise TypeError(f"RenderClient {name!r}: renderer must be a function making an engine or a viewer")
        if on_frame is not None and not callable(on_frame):
            raise TypeError(f"RenderClient {name!r}: on_frame must be a function (image, snapshot)")
        self.size, self.samples, self.name = size, samples, name
        self._make = renderer
        self.on_frame = on_frame
        self.frames = 0
        self.dropped = 0
        self.error: BaseException | None = None
        self.last: Snapshot | None = None
        self._waiting: Snapshot | None = None
        self._cond = threading.Condition()
        self._stop = False
        self._thread: threading.Thread | None = None

    # -- the application side ----------------------------------------------------------
    def submit(self, snapshot: Snapshot) -> None:
        """Hand ``snapshot`` to the thread (O(1)): it replaces one still waiting, which is dropped."""
        with self._cond:
            if self._waiting is not None:
                self.dropped += 1
            self._waiting = snapshot
            self._cond.notify()

    def start(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._loop, name=self.name, daemon=True)
            self._thread.start()

    def stop(self, timeout: float = 30.0) -> None:
        """Draw the newest snapshot if it is still waiting, then end the thread (releasing its renderer)."""
        with self._cond:
            self._stop = True
            self._cond.notify()
        if self._thread is not None:
            self._thread.join(timeout)
            if self._thread.is_alive():
                raise TimeoutError(f"RenderClient {self.name!r}: the render thread did not stop in {timeout} s")
            self._thread = None

    def wait_for(self, frame: int, timeout: float = 30.0) -> bool:
        """Wait until an image of snapshot ``frame`` or later was made; False on timeout or error."""
        end = time.perf_counter() + timeout
        with self._cond:
            while (self.last is None or self.last.frame < frame) and self.error is None:
                left = end - time.perf_counter()
                if left <= 0 or not self._cond.wait(left):
                    return False
        return self.error is None

    # -- the render thread -------------------------------------------------------------
    def _loop(self) -> None:
        renderer = None
        try:
            renderer = self._make() if self._make is not None else _default_engine(self.size, self.samples)
            mirror = SceneMirror()
            while True:
                with self._cond:
                    while self._waiting is None and not self._stop:
                        self._cond.wait()
                    if self._waiting is None:  # stopped, and the newest snapshot is drawn
                        return
                    snapshot, self._waiting = self._waiting, None
                scene = mirror.apply(snapshot)
                image = _draw(renderer, scene, self.frames == 0)
                if self.on_frame is not None:
                    self.on_frame(image, snapshot)
                with self._cond:
                    self.frames += 1
                    self.last = snapshot
                    self._cond.notify_all()
        except BaseException as exc:  # reported to the application through .error and RenderThreads.publish
            with self._cond:
                self.error = exc
                self._cond.notify_all()
        finally:
            if renderer is not None:
                _release(renderer)


def _default_engine(size: tuple[int, int], samples: int) -> Any:
    from ..gl import GLEngine

    return GLEngine(size=size, samples=samples)  # its own context, current in this thread


def _draw(renderer: Any, scene: Node, first: bool) -> Any:
    """An image of ``scene`` from an engine (``render(scene)``) or a viewer (its renderable, re-rendered)."""
    if hasattr(renderer, "add_renderable"):
        if first:
            from .window import open_scene

            open_scene(renderer, scene)
        return renderer.rerender()
    return renderer.render(scene)


def _release(renderer: Any) -> None:
    for name in ("close", "release"):
        method = getattr(renderer, name, None)
        if method is not None:
            method()
            return


class RenderThreads:
    """Render clients fed with snapshots of ``scene``: call :meth:`publish` at the end of each application frame.

    ``with RenderThreads(scene, [RenderClient(...), ...]) as threads:`` starts
    the clients and stops them at the end; :meth:`publish` returns the
    snapshot it handed out (``snapshot.built`` / ``.shared`` say what it cost).
    """

    def __init__(self, scene: Node, clients: list[RenderClient] | tuple[RenderClient, ...] = ()) -> None:
        self.snapshots = Snapshotter(scene)
        self.clients: list[RenderClient] = []
        for client in clients:
            self.add(client)

    def add(self, client: RenderClient) -> RenderClient:
        if not isinstance(client, RenderClient):
            raise TypeError(f"RenderThreads: clients must be om.viewer.RenderClient objects, got {client!r:.60}")
        self.clients.append(client)
        return client

    def start(self) -> RenderThreads:
        for client in self.clients:
            client.start()
        return self

    def publish(self, data: Any = None) -> Snapshot:
        """Snapshot the scene and hand it to every client (never waits for them); ``data`` rides along."""
        for client in self.clients:
            if client.error is not None:
                raise RuntimeError(f"RenderThreads: render client {client.name!r} failed: {client.error!r}") from (
                    client.error
                )
        snapshot = self.snapshots.take(data)
        for client in self.clients:
            client.submit(snapshot)
        return snapshot

    def stop(self) -> None:
        for client in self.clients:
            client.stop()

    def __enter__(self) -> RenderThreads:
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.stop()
