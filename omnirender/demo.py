"""The demo scene and the main job: render it with every available engine."""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path

import omnirender as om

__all__ = ["demo_scene", "run_demo", "KNOT_PATH"]

#: The demo's "mesh loaded from a file": a trefoil-knot tube (see assets/make_assets.py).
KNOT_PATH = Path(__file__).parent / "assets" / "knot.obj"


def demo_scene() -> om.Node:
    """Floor, a mesh from a file, a torus, a sphere and two point lights."""
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(4.2, 3.2, 6.0), center=(0, 0.75, 0), up=(0, 1, 0), fov=35))
    scene.add(om.Background((0.12, 0.13, 0.16)))
    lights = scene.add(om.Node("lights"))
    lights.add(om.PointLight(position=(4, 6, 5), color=(1.0, 0.95, 0.9), intensity=0.9))
    lights.add(om.PointLight(position=(-5, 4, 1), color=(0.55, 0.65, 1.0), intensity=0.5))

    floor = scene.add(om.Node("floor"))
    floor.add(om.Translation(0, -0.05, 0))
    floor.add(om.Material(diffuse=(0.75, 0.75, 0.72), specular=(0.1, 0.1, 0.1), shininess=8))
    floor.add(om.Box(size=(8, 0.1, 8)))

    knot = scene.add(om.Node("knot"))
    knot.add(om.Translation(0, 1.05, 0))
    knot.add(om.Material(diffuse=(0.85, 0.35, 0.15), specular=(0.9, 0.9, 0.9), shininess=60))
    knot.add(om.MeshFile(KNOT_PATH))

    torus = scene.add(om.Node("torus"))
    torus.add(om.Translation(1.9, 0.3, 0.9))
    torus.add(om.Rotation(20, (0, 0, 1)))
    torus.add(om.Material(diffuse=(0.2, 0.45, 0.9), specular=(1, 1, 1), shininess=40))
    torus.add(om.Torus(major_radius=0.55, minor_radius=0.2))

    ball = scene.add(om.Node("ball"))
    ball.add(om.Material(diffuse=(0.3, 0.75, 0.35), specular=(0.6, 0.6, 0.6), shininess=30))
    ball.add(om.Sphere(center=(-1.8, 0.45, 0.8), radius=0.45))
    return scene


def run_demo(
    output: Path,
    size: tuple[int, int] = (640, 480),
    engines: Sequence[str] | None = None,
    quality: str = "preview",
) -> list[Path]:
    """Render the demo scene with each available engine (or each of ``engines``) into ``output``;
    returns the files.

    What cannot run here is said first, with the command(s) that install it;
    an engine that fails is reported and the others go on.  ``quality`` is
    Mitsuba's (``"preview"``: a few samples, denoised; ``"final"``).
    """
    from .render import install_commands

    status = om.engines()
    if engines is not None:
        unknown = [name for name in engines if name not in status]
        if unknown:
            raise ValueError(f"run_demo: unknown engine(s) {unknown}; choose from {', '.join(status)}")
        status = {name: status[name] for name in dict.fromkeys(engines)}
    usable = [name for name, (ok, _) in status.items() if ok]
    skipped = [name for name, (ok, _) in status.items() if not ok]
    print(f"omnirender demo: rendering with {', '.join(usable) or 'no engine'}", end="")
    print(f"; skipped {len(skipped)} of {len(status)} engines:" if skipped else " (every engine)")
    for name in skipped:
        print(f"  {name:8s} {status[name][1]}")
    commands = install_commands(skipped)
    if commands:
        print("  install them with: " + " && ".join(commands))
    output.mkdir(parents=True, exist_ok=True)
    scene = demo_scene()
    stats = om.statistics(scene)
    print(f"demo scene: {stats['nodes']} nodes, {stats['shapes']} shapes, {stats['attributes']} attributes", end="")
    print(f", {stats['triangles']} triangles" if "triangles" in stats else "", flush=True)
    written: list[Path] = []
    for name in usable:
        path = output / f"demo-{name}.png"
        start = time.perf_counter()
        options = {"quality": quality} if name == "mitsuba" else {}
        try:
            image = om.render(scene, engine=name, size=size, **options)
            image.save(path)
        except Exception as exc:  # one engine failing must not hide the others' pictures
            print(f"{name:8s} failed: {' '.join(str(exc).split()) or type(exc).__name__}", flush=True)
            continue
        written.append(path)
        note = ""
        if name == "mitsuba" and quality == "preview" and not image.info.get("denoised"):
            from .mitsuba.denoise import INSTALL

            note = f"; grainy: no denoiser, {INSTALL}"
        print(f"{name:8s} wrote {path} ({time.perf_counter() - start:.1f} s{note})", flush=True)
    print(f"{len(written)} image(s) in {output.resolve()}")
    return written
