"""glTF export of 10,000 instances: ``EXT_mesh_gpu_instancing`` against one node per instance, in one run.

The scene is a simulation's state the way the README teaches it: an
``om.InstanceSet`` of balls (``om.Sphere``) bound to the application's
positions and colours (every ball its own colour, so the colours travel as
``_COLOR_0``), plus optionally random rotations and scales (``--rotated``).
Measured, best of ``--repeat``:

* ``om.export(scene, "x.glb")``: the instance set written once, instanced;
* the same with ``instancing=False``: one node (and mesh) per instance, what
  every exporter wrote before (the baseline);
* ``om.load_gltf`` of each file (one InstanceSet against 10,000 nodes).

Run: .venv/bin/python bench/gltf_instances.py [--instances 10000] [--repeat 3] [--rotated]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
from gltf_load import best  # bench/ is the script's folder

import omnirender as om


def scene(n: int, rotated: bool) -> om.Node:
    rng = np.random.default_rng(1)
    positions = rng.uniform(-10, 10, (n, 3))
    colors = rng.uniform(0.2, 1.0, (n, 3))
    transforms: np.ndarray = positions
    scales = None
    if rotated:
        angles, axes = rng.uniform(0, 360, n), rng.normal(size=(n, 3))
        transforms = np.stack([om.Rotation(a, ax).matrix for a, ax in zip(angles, axes, strict=True)])
        transforms[:, :3, 3] = positions
        scales = rng.uniform(0.5, 1.5, (n, 3))
    balls = om.InstanceSet(om.Sphere(radius=0.1), transforms, colors=colors, scales=scales)
    camera = om.Camera.look_at(eye=(0, 0, 40), center=(0, 0, 0))
    return om.Node("simulation", [camera, om.PointLight(position=(20, 20, 20)), balls])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--instances", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--rotated", action="store_true", help="random rotations and scales (TRS all written)")
    args = parser.parse_args()
    state = scene(args.instances, args.rotated)
    with tempfile.TemporaryDirectory() as tmp:
        native, nodes = Path(tmp) / "instanced.glb", Path(tmp) / "nodes.glb"
        t_native = best(lambda: om.export(state, native), args.repeat)
        t_nodes = best(lambda: om.export(state, nodes, instancing=False), args.repeat)
        l_native = best(lambda: om.load_gltf(native), args.repeat)
        l_nodes = best(lambda: om.load_gltf(nodes), args.repeat)
        s_native, s_nodes = native.stat().st_size, nodes.stat().st_size
    kind = "rotated and scaled " if args.rotated else ""
    print(f"{args.instances:,} {kind}instances of a sphere, each its own colour (best of {args.repeat})")
    print(f"{'':28}{'instanced':>12}{'per node':>12}{'ratio':>8}")
    print(f"{'file size (MB)':28}{s_native / 1e6:12.3f}{s_nodes / 1e6:12.3f}{s_native / s_nodes:8.4f}")
    print(f"{'export (s)':28}{t_native:12.4f}{t_nodes:12.4f}{t_native / t_nodes:8.4f}")
    print(f"{'om.load_gltf (s)':28}{l_native:12.4f}{l_nodes:12.4f}{l_native / l_nodes:8.4f}")


if __name__ == "__main__":
    main()
