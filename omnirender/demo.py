"""The demo scene and the main job: render it with every available engine."""

from __future__ import annotations

from pathlib import Path

import omnirender as om

__all__ = ["demo_scene", "run_demo"]


def demo_scene() -> om.Node:
    """A small scene exercising the core: camera, lights, transforms, nested nodes."""
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(4, 3, 6), center=(0, 0.6, 0), up=(0, 1, 0), fov=35))
    body = scene.add(om.Node("body"))
    body.add(om.Translation(0, 1, 0))
    body.add(om.Rotation(30, (0, 1, 0)))
    return scene


def run_demo(output: Path, size: tuple[int, int] = (640, 480)) -> list[Path]:
    """Render the demo scene with each available engine into ``output``; returns the files."""
    output.mkdir(parents=True, exist_ok=True)
    scene = demo_scene()
    program = om.trace(scene)
    print(f"demo scene: micro program of {len(program)} ops")
    for op, obj in program:
        print(f"  {op:9s} {obj!r}")
    print("statistics:", dict(om.statistics(scene)))
    written: list[Path] = []
    for name, (ok, why) in om.engines().items():
        if not ok:
            print(f"{name}: skipped ({why})")
            continue
        path = output / f"demo-{name}.png"
        om.render(scene, engine=name, size=size).save(path)
        written.append(path)
        print(f"{name}: wrote {path}")
    return written
