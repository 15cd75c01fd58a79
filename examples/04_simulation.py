"""Example 4: a simulation loop with viewers repainting from a shared, external render list.

A physics thread steps bouncing balls and, after each step, prerenders a
shared ``om.RenderList``: each ball's ``prerender`` copies its position (under
the list's lock), so the viewers, which repaint whenever they like, always
draw a consistent state, never a half-updated one.  Two viewers (a
perspective one and an orthogonal top view) share the list.  Writes
04-simulation.png: four moments seen by the first viewer, then the top view.

    python examples/04_simulation.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import threading
import time

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om

ROOM = 2.0  # balls stay in [-ROOM, ROOM] x [0, inf) x [-ROOM, ROOM]


class Ball:
    """A simulated body that is its own renderable (the om.IsRenderable protocol)."""

    def __init__(self, position, velocity, radius, color) -> None:
        self.position = np.array(position, dtype=float)
        self.velocity = np.array(velocity, dtype=float)
        self.radius = radius
        self.material = om.Material(diffuse=color, specular=(0.8, 0.8, 0.8), shininess=50)
        self.sphere = om.Sphere(radius=radius)
        self._drawn = self.position.copy()

    def step(self, dt: float) -> None:
        self.velocity[1] -= 9.81 * dt
        self.position += self.velocity * dt
        for axis, low in ((0, -ROOM), (1, 0.0), (2, -ROOM)):
            if self.position[axis] - self.radius < low:
                self.position[axis] = low + self.radius
                self.velocity[axis] = abs(self.velocity[axis]) * 0.92
            if axis != 1 and self.position[axis] + self.radius > ROOM:
                self.position[axis] = ROOM - self.radius
                self.velocity[axis] = -abs(self.velocity[axis]) * 0.92

    # -- om.IsRenderable --------------------------------------------------------
    def prerender(self, render_list) -> None:
        self._drawn = self.position.copy()  # the state render() will draw

    def render(self, renderer, flags: int) -> None:
        renderer.push(om.Translation(*self._drawn))
        renderer.push(self.material)
        renderer.eval(self.sphere)
        renderer.pop(om.Material)
        renderer.pop(om.Transform)

    def update_bounds(self, pmin, pmax) -> None:
        np.minimum(pmin, self._drawn - self.radius, out=pmin)
        np.maximum(pmax, self._drawn + self.radius, out=pmax)

    def render_hints(self) -> int:
        return 0


def room() -> om.Node:
    node = om.Node("room")
    node.add(om.Material(diffuse=(0.8, 0.8, 0.78)))
    node.add(om.Box(size=(2 * ROOM, 0.1, 2 * ROOM), center=(0, -0.05, 0)))
    node.add(om.Material(diffuse=(0.45, 0.5, 0.6)))
    node.add(om.Box(size=(2 * ROOM, 1.0, 0.1), center=(0, 0.5, -ROOM - 0.05)))
    node.add(om.Box(size=(0.1, 1.0, 2 * ROOM), center=(-ROOM - 0.05, 0.5, 0)))
    return node


def main() -> list:
    out = output_dir()
    rng = np.random.default_rng(7)
    balls = [
        Ball(rng.uniform((-1.5, 1, -1.5), (1.5, 3, 1.5)), rng.uniform(-2, 2, 3), r, c)
        for r, c in zip(rng.uniform(0.15, 0.35, 12), rng.uniform(0.15, 0.95, (12, 3)), strict=True)
    ]
    shared = om.RenderList()
    shared.prerender(balls)
    scene = room()
    front = om.Viewer(size=(320, 240))
    top = om.Viewer(size=(240, 240))
    for viewer in (front, top):
        viewer.add_renderable(scene)
        viewer.set_external_render_list(shared)
    front.set_eye_to_world((0.5, 3.5, 7.0), (0, 0.8, 0), (0, 1, 0))
    front.auto_fit()
    top.set_axial_view(om.AxisAlignedRotation.X_NZ)  # looking down: x right, -z up
    top.auto_fit_ortho()
    for viewer in (front, top):
        viewer.rerender()

    stop = threading.Event()
    steps = [0]

    def physics() -> None:
        dt = 1 / 240
        while not stop.is_set():
            for ball in balls:
                ball.step(dt)
            steps[0] += 1
            if steps[0] % 4 == 0:
                shared.prerender(balls)  # takes the lock: viewers never see a half-step
            time.sleep(dt / 2)

    thread = threading.Thread(target=physics, name="physics")
    thread.start()
    snapshots = []
    frames = 0
    try:
        start = time.monotonic()
        for moment in (0.25, 0.5, 0.75, 1.0):  # simulated seconds
            while steps[0] < moment * 240:
                t0 = time.monotonic()
                front.repaint()
                top.repaint()
                frames += 1
                time.sleep(max(0.0, 1 / 30 - (time.monotonic() - t0)))  # the viewers' own pace: 30 fps
            snapshots.append(front.image())
        snapshots.append(top.image())
    finally:
        stop.set()
        thread.join()
    print(f"{steps[0]} physics steps (1/240 s each), {frames} frames per viewer in {time.monotonic() - start:.2f} s")
    path = side_by_side(snapshots).save(out / "04-simulation.png")
    for viewer in (front, top):
        viewer.close()
    print(path)
    return [path]


if __name__ == "__main__":
    main()
