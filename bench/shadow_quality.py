"""GL shadow quality on the demo scene against POV-Ray (issue 23): region agreement, speckles, stair steps.

Run: ``python bench/shadow_quality.py [--size 640x480] [--out folder]``.

Each engine renders the demo twice, with shadows and with nothing casting
them (``om.Shadowing(cast=False)``); a floor pixel (GL depth of the floor
alone) is in shadow where it is darker than ``THRESHOLD`` of its unshadowed
value.  Printed: the IoU of GL's and POV-Ray's shadow regions, GL's isolated
lit pixels inside its shadows (a lit pixel whose 8 neighbours are shadow)
and the same for POV-Ray; with ``--out``, 4x nearest-neighbour crops of both
engines around the knot's contact with the floor and the torus's shadow.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import omnirender as om
from omnirender.demo import demo_scene

THRESHOLD = 0.8
#: (x0, y0, w, h) as fractions of the image: the knot's contact shadow, the torus and its long shadow
CROPS = {"knot": (0.43, 0.56, 0.15, 0.12), "torus": (0.56, 0.6, 0.4, 0.3), "ball": (0.14, 0.55, 0.25, 0.15)}


def _scene(cast: bool) -> om.Node:
    scene = demo_scene()
    if not cast:
        scene.insert(0, om.Shadowing(cast=False))
    return scene


def _floor_only() -> om.Node:
    scene = demo_scene()
    for name in ("knot", "torus", "ball"):
        scene.remove(scene.child(name))
    return scene


def luminance(img: om.Image) -> np.ndarray:
    return img.array[..., :3].astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])


def shadow_region(engine: str, size: tuple[int, int], floor: np.ndarray, **options) -> tuple[np.ndarray, om.Image]:
    shaded = om.render(_scene(True), engine=engine, size=size, **options)
    lit = luminance(om.render(_scene(False), engine=engine, size=size, **options))
    return floor & (lit > 20) & (luminance(shaded) < THRESHOLD * lit), shaded


def isolated_lit(region: np.ndarray) -> int:
    """Lit pixels whose 8 neighbours are all in shadow."""
    r = np.pad(region, 1)
    around = sum(np.roll(np.roll(r, dy, 0), dx, 1) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx)[1:-1, 1:-1]
    return int(np.count_nonzero(~region & (around == 8)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    full = om.render(_scene(False), engine="gl", size=size)
    alone = om.render(_floor_only(), engine="gl", size=size)
    with np.errstate(invalid="ignore"):
        floor = np.isfinite(full.depth) & (np.abs(full.depth - alone.depth) < 1e-3)
    gl, gl_img = shadow_region("gl", size, floor)
    pov, pov_img = shadow_region("povray", size, floor, antialias=True)
    iou = (gl & pov).sum() / max((gl | pov).sum(), 1)
    print(f"demo {size[0]}x{size[1]}: GL vs POV-Ray shadow regions IoU {iou:.3f} ({gl.sum()} / {pov.sum()} pixels)")
    print(f"isolated lit pixels inside shadows: GL {isolated_lit(gl)}, POV-Ray {isolated_lit(pov)}")
    if args.out:
        from PIL import Image

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        w, h = size
        for name, img in (("gl", gl_img), ("povray", pov_img)):
            img.save(out / f"demo_{name}.png")
            for crop, (fx, fy, fw, fh) in CROPS.items():
                x0, y0, cw, ch = int(fx * w), int(fy * h), int(fw * w), int(fh * h)
                part = Image.fromarray(img.rgb[y0 : y0 + ch, x0 : x0 + cw])
                part.resize((cw * 4, ch * 4), Image.NEAREST).save(out / f"{crop}_{name}_4x.png")
        Image.fromarray(np.stack([gl & ~pov, gl & pov, pov & ~gl], -1).astype(np.uint8) * 255).save(
            out / "shadow_regions.png"
        )  # red: GL only, green: both, blue: POV-Ray only
        print("wrote", out)


if __name__ == "__main__":
    main()
