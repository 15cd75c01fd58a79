"""Example 4: 5,000 balls moved by a physics thread while two viewers repaint from a shared render list.

The simulation state lives in numpy arrays (positions, velocities), stepped
all at once.  The swarm is one renderable (the om.IsRenderable protocol, as
in ArtiSynth): its ``prerender`` copies the positions into the array an
``om.InstanceSet`` is bound to (under the render list's lock) and touches
it; its ``render`` evaluates the instance set, which the GL engine draws as
one instanced call and updates in place.  So the viewers, which repaint
whenever they like, always draw a consistent state, and a frame costs about
the same whether one ball moved or all of them.  Writes 04-simulation.png:
four moments seen by the first viewer, then an orthogonal top view.

    python examples/04_simulation.py [OUTPUT_FOLDER] [--balls N]
"""

from __future__ import annotations

import argparse
import sys
import threading
import time

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om
from omnirender.progress import Progress

ROOM = 2.0  # balls stay in [-ROOM, ROOM] x [0, inf) x [-ROOM, ROOM]
DT = 1 / 120  # physics step (s); viewers see every second step
LOW = np.array([-ROOM, 0.0, -ROOM])
HIGH = np.array([ROOM, np.inf, ROOM])


class Swarm:
    """Thousands of bouncing balls: simulated as arrays, drawn as one instance set."""

    def __init__(self, n: int, rng: np.random.Generator) -> None:
        self.radius = rng.uniform(0.035, 0.07, n)
        self.position = rng.uniform((-1.8, 0.5, -1.8), (1.8, 3.5, 1.8), (n, 3))
        self.velocity = rng.uniform(-2.0, 2.0, (n, 3))
        self._drawn = self.position.copy()  # what the viewers draw: the InstanceSet holds this array, not a copy
        colors = rng.uniform(0.15, 0.95, (n, 3))
        self.instances = om.InstanceSet(om.Sphere(radius=1.0), self._drawn, colors=colors, scales=self.radius)
        self.material = om.Material(diffuse=(1, 1, 1), specular=(0.6, 0.6, 0.6), shininess=50)
        self.tessellation = om.Tessellation(1)  # balls a few pixels wide need few triangles

    def step(self, dt: float) -> None:
        self.velocity[:, 1] -= 9.81 * dt
        self.position += self.velocity * dt
        r = self.radius[:, None]
        below, above = self.position - r < LOW, self.position + r > HIGH
        self.position = np.where(below, LOW + r, np.where(above, HIGH - r, self.position))
        self.velocity = np.where(below, np.abs(self.velocity) * 0.92, self.velocity)
        self.velocity = np.where(above, -np.abs(self.velocity) * 0.92, self.velocity)

    # -- om.IsRenderable --------------------------------------------------------
    def prerender(self, render_list) -> None:
        self._drawn[:] = self.position  # the state render() will draw, written into the bound array
        self.instances.touch()

    def render(self, renderer, flags: int) -> None:
        renderer.push(self.tessellation)
        renderer.push(self.material)
        renderer.eval(self.instances)
        renderer.pop(om.Material)
        renderer.pop(om.Tessellation)

    def update_bounds(self, pmin, pmax) -> None:
        r = self.radius[:, None]
        np.minimum(pmin, (self._drawn - r).min(axis=0), out=pmin)
        np.maximum(pmax, (self._drawn + r).max(axis=0), out=pmax)

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
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", help="where the image goes (default examples/output)")
    parser.add_argument("--balls", type=int, default=5000, help="how many balls (default 5000)")
    args = parser.parse_args()
    sys.argv[1:] = [args.folder] if args.folder else []
    out = output_dir()
    swarm = Swarm(args.balls, np.random.default_rng(7))
    shared = om.RenderList()
    shared.prerender([swarm])
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
        while not stop.is_set():
            swarm.step(DT)
            steps[0] += 1
            if steps[0] % 2 == 0:
                shared.prerender([swarm])  # takes the lock: viewers never see a half-step
            time.sleep(DT / 4)

    thread = threading.Thread(target=physics, name="physics")
    thread.start()
    snapshots = []
    frames = 0
    painting = 0.0
    progress = Progress(round(1.0 / DT), "simulation", "step")  # a bar on a terminal, log lines elsewhere
    try:
        start = time.monotonic()
        for moment in (0.25, 0.5, 0.75, 1.0):  # simulated seconds
            while steps[0] < moment / DT:
                t0 = time.monotonic()
                front.repaint()
                top.repaint()
                painting += time.monotonic() - t0
                frames += 1
                progress.update(min(steps[0], progress.total))
                time.sleep(max(0.0, 1 / 30 - (time.monotonic() - t0)))  # the viewers' own pace: 30 fps
            snapshots.append(front.image())
        snapshots.append(top.image())
    finally:
        stop.set()
        thread.join()
        progress.close()
    print(
        f"{args.balls} balls, {steps[0]} physics steps (1/{round(1 / DT)} s each), {frames} frames per viewer in "
        f"{time.monotonic() - start:.2f} s; {1e3 * painting / max(frames, 1):.1f} ms per frame for both viewers"
    )
    path = side_by_side(snapshots).save(out / "04-simulation.png")
    for viewer in (front, top):
        viewer.close()
    print(path)
    return [path]


if __name__ == "__main__":
    main()
