"""Mitsuba's default preview of the demo scene: time and PSNR against a 1024-spp reference.

Run: .venv/bin/python bench/mitsuba_preview.py [--size 640x480] [--repeat 3] [--reference FILE.npy]

The scene is the one ``omnirender demo`` renders, built by ``omnirender.demo.demo_scene``.
Measured, best of ``--repeat``, interleaved:

* the preview, ``om.render(scene, engine="mitsuba")`` (quality="preview": a few samples per pixel,
  fewer bounces, denoised with Intel Open Image Denoise);
* the baseline: what the demo rendered before the preview existed, 64 spp of the path tracer with
  8 bounces, not denoised (``quality="final", spp=64``);
* the preview without its denoiser, to show what the denoiser buys;
* the whole demo (``omnirender demo``: every engine available here), target 10 s or less.

PSNR is computed on the sRGB images as saved (8 bits per channel, every pixel) against a reference
of 1024 spp at quality="final" (8 bounces, not denoised), rendered here once, or read from
``--reference`` (an .npy of the reference's ``image.array``; written there when the file does not
exist yet).  The ratio preview/baseline is the figure to compare between machines; the target is
the preview at 3 s or less at 640x480 on two cores (the baseline took 12 s on a quiet 2-core
machine when the issue was filed) and a PSNR of 32 dB or more.  Images go to ``--out``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

import omnirender as om
from omnirender.demo import demo_scene


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    """PSNR in dB of two uint8 RGB(A) images (RGB only)."""
    diff = a[..., :3].astype(np.float64) - b[..., :3].astype(np.float64)
    mse = float(np.mean(diff * diff))
    return float("inf") if mse == 0 else 10.0 * np.log10(255.0**2 / mse)


def timed(scene: om.Node, size: tuple[int, int], **options: object) -> tuple[float, om.Image]:
    start = time.perf_counter()
    image = om.render(scene, engine="mitsuba", size=size, **options)
    return time.perf_counter() - start, image


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--reference", type=Path, help="an .npy file of the 1024-spp reference (read or written)")
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "omnirender-bench" / "mitsuba")
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    args.out.mkdir(parents=True, exist_ok=True)
    scene = demo_scene()

    if args.reference is not None and args.reference.exists():
        reference = np.load(args.reference)
        print(f"reference: {args.reference}")
    else:
        seconds, ref_image = timed(scene, size, quality="final", spp=1024, seed=7)
        reference = ref_image.array
        ref_image.save(args.out / "reference-1024spp.png")
        if args.reference is not None:
            np.save(args.reference, reference)
        print(f"reference: 1024 spp, quality='final', rendered in {seconds:.1f} s")

    cases = {
        "preview (default)": {},
        "preview, not denoised": {"denoise": False},
        "baseline: 64 spp, 8 bounces": {"quality": "final", "spp": 64},
    }
    best: dict[str, float] = {}
    images: dict[str, om.Image] = {}
    timed(scene, (64, 48))  # load Mitsuba and the denoiser once, outside the timings
    for _ in range(args.repeat):
        for name, options in cases.items():
            seconds, image = timed(scene, size, **options)
            best[name] = min(best.get(name, float("inf")), seconds)
            images[name] = image
    base = best["baseline: 64 spp, 8 bounces"]
    print(f"demo scene, Mitsuba at {size[0]}x{size[1]}, best of {args.repeat}")
    print(f"{'case':30s} {'seconds':>8s} {'ratio':>7s} {'PSNR dB':>8s}  spp, bounces, denoised")
    for name, image in images.items():
        info = image.info
        print(
            f"{name:30s} {best[name]:8.2f} {best[name] / base:7.3f} {psnr(image.array, reference):8.2f}  "
            f"{info['spp']}, {info['max_depth']}, {info['denoised']}"
        )
        image.save(args.out / (name.split(":")[0].replace(" ", "-").replace(",", "").replace("(", "").rstrip(")")
                               + ".png"))  # fmt: skip
    preview = images["preview (default)"].info
    print(
        f"preview stages: build {preview['build_seconds']:.2f} s, trace {preview['render_seconds']:.2f} s, "
        f"denoise {preview['denoise_seconds']:.2f} s, coverage {preview['coverage_seconds']:.2f} s"
    )
    print(f"estimated on a quiet 2-core machine (baseline 12 s there): {12.0 * best['preview (default)'] / base:.1f} s")

    # the whole demo (every engine available here), as `omnirender demo` runs it, against the baseline above
    import contextlib
    import io

    from omnirender.demo import run_demo

    demo_best = float("inf")
    for _ in range(args.repeat):
        start = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()) as out:
            run_demo(args.out / "demo", size=size)
        demo_best = min(demo_best, time.perf_counter() - start)
    print(out.getvalue().rstrip())
    print(f"demo, every engine at {size[0]}x{size[1]}: {demo_best:.2f} s, {demo_best / base:.3f}x the baseline render")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
