"""Example 20: a captured-style Gaussian splat scene with a mesh and a volume inserted, in OpenGL and Mitsuba.

A "capture" is generated in code the way a splat trainer would fit one to a
textured room: the surfaces of a tiled floor, a brick wall and a striped
stone ball are sampled, and every sample becomes one flat splat (a disc
along the surface, a hundredth as thick) with the texture's colour and a
little view-dependent colour (degree-1 spherical harmonics).  The cloud is
written as the reference trainer's ``.ply`` and read back with
``om.load_splats`` (log scales, logit opacities, unnormalised quaternions),
then a torus (a mesh) and a smoke blob (an ``om.Volume``) are inserted.  The
GL engine rasterises the splats (sorted, EWA-projected), Mitsuba traces them
as translucent ellipsoid shells; ``om.pick`` names the splat under a pixel,
``om.bounds`` measures the cloud, and the scene is written as glTF
(``KHR_gaussian_splatting``) and USD (``ParticleField3DGaussianSplat``).

    python examples/20_gaussian_splats.py [OUTPUT_FOLDER] [quick]
"""

from __future__ import annotations

import sys

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om

QUICK = "quick" in sys.argv[2:]
SIZE = (240, 180) if QUICK else (480, 360)
SPACING = 0.09 if QUICK else 0.06  # distance between samples (world units)
C0 = 0.28209479177387814
BALL = (-1.0, -0.45, -0.7)  # the striped ball's centre


def tiles(u, v):
    """The floor's texture: warm tiles with dark grout."""
    grout = (np.abs((u * 2.5) % 1 - 0.5) > 0.45) | (np.abs((v * 2.5) % 1 - 0.5) > 0.45)
    checker = ((np.floor(u * 2.5) + np.floor(v * 2.5)) % 2)[..., None]
    tile = checker * np.array([0.85, 0.72, 0.55]) + (1 - checker) * np.array([0.7, 0.5, 0.35])
    return np.where(grout[..., None], np.array([0.25, 0.22, 0.2]), tile)


def bricks(u, v):
    """The wall's texture: running-bond bricks."""
    row = np.floor(v * 6)
    mortar = (np.abs((v * 6) % 1 - 0.5) > 0.42) | (np.abs((u * 3 + 0.5 * row) % 1 - 0.5) > 0.46)
    shade = 0.8 + 0.2 * np.sin(row * 7.1 + np.floor(u * 3 + 0.5 * row) * 3.3)[..., None]
    return np.where(mortar[..., None], np.array([0.78, 0.76, 0.72]), shade * np.array([0.65, 0.28, 0.2]))


def stripes(u, v):
    """The ball's texture: blue and white bands."""
    band = (np.sin(v * 18) > 0)[..., None]
    return np.where(band, np.array([0.2, 0.35, 0.75]), np.array([0.9, 0.9, 0.85]))


def plane_samples(origin, du, dv, texture):
    """Points on the parallelogram origin + s du + t dv (s, t in [0, 1]), jittered, with their normal and colour."""
    du, dv = np.asarray(du, float), np.asarray(dv, float)
    nu, nv = int(np.linalg.norm(du) / SPACING), int(np.linalg.norm(dv) / SPACING)
    s, t = np.meshgrid((np.arange(nu) + 0.5) / nu, (np.arange(nv) + 0.5) / nv)
    rng = np.random.default_rng(nu * 1000 + nv)
    s = np.clip(s + rng.uniform(-0.3, 0.3, s.shape) / nu, 0, 1).ravel()
    t = np.clip(t + rng.uniform(-0.3, 0.3, t.shape) / nv, 0, 1).ravel()
    points = np.asarray(origin, float) + s[:, None] * du + t[:, None] * dv
    normal = np.cross(du, dv)
    return points, np.repeat([normal / np.linalg.norm(normal)], len(points), axis=0), texture(s, t)


def sphere_samples(centre, radius, texture):
    n = int(4 * np.pi * radius**2 / SPACING**2)
    k = np.arange(n) + 0.5  # a Fibonacci sphere: evenly spread samples
    z = 1 - 2 * k / n
    phi = k * np.pi * (3 - np.sqrt(5))
    normal = np.stack([np.sqrt(1 - z * z) * np.cos(phi), z, np.sqrt(1 - z * z) * np.sin(phi)], axis=1)
    return np.asarray(centre) + radius * normal, normal, texture(phi % (2 * np.pi) / (2 * np.pi), np.arccos(z))


def quaternions_to(normals):
    """(w, x, y, z) rotations taking the splat's local z axis to each normal."""
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(z, normals)
    w = 1.0 + normals @ z
    q = np.concatenate([w[:, None], axis], axis=1)
    flip = w < 1e-6  # normal = -z: a half turn about x
    q[flip] = (0.0, 1.0, 0.0, 0.0)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def captured_cloud() -> om.GaussianSplats:
    parts = [
        plane_samples((-2, -1, 1.5), (4, 0, 0), (0, 0, -3.5), tiles),  # floor (normal +y)
        plane_samples((-2, -1, -2), (4, 0, 0), (0, 2.6, 0), bricks),  # back wall (normal +z)
        sphere_samples(BALL, 0.55, stripes),  # the stone ball
    ]
    points = np.concatenate([p for p, _, _ in parts])
    normals = np.concatenate([n for _, n, _ in parts])
    colours = np.concatenate([c for _, _, c in parts])
    n = len(points)
    rng = np.random.default_rng(20)
    sh = np.zeros((n, 4, 3), np.float32)
    sh[:, 0] = (colours - 0.5) / C0
    sh[:, 1:] = rng.normal(scale=0.04, size=(n, 3, 3))  # a faint sheen that changes with the view
    s = 0.55 * SPACING
    scales = np.tile([s, s, 0.01 * s], (n, 1)) * np.exp(rng.normal(scale=0.1, size=(n, 3)))
    return om.GaussianSplats(
        points.astype(np.float32),
        quaternions_to(normals).astype(np.float32),
        scales.astype(np.float32),
        rng.uniform(0.75, 0.95, n).astype(np.float32),
        sh,
    )


def smoke() -> om.Volume:
    n = 40
    z, y, x = np.mgrid[-1 : 1 : n * 1j, -1 : 1 : n * 1j, -1 : 1 : n * 1j]
    density = np.clip(1.2 - np.sqrt(x**2 + (y * 1.3) ** 2 + z**2) * 1.4 + 0.15 * np.sin(6 * x) * np.cos(5 * z), 0, 1)
    tf = [(0.0, (0.6, 0.8, 0.9, 0.0)), (0.4, (0.55, 0.75, 0.95, 0.04)), (1.0, (0.9, 0.95, 1.0, 0.12))]
    return om.Volume(density, spacing=1.2 / (n - 1), transfer_function=tf)


def main() -> None:
    out = output_dir()
    # the "capture": written as a trainer .ply, read back as a splat file
    om.save_splats(captured_cloud(), out / "20-capture.ply")
    cloud = om.load_splats(out / "20-capture.ply")
    camera = om.Camera.look_at((0.6, 0.55, 3.3), (0, -0.35, -0.6), fov=50)
    scene = om.Node(
        "room",
        [
            camera,
            om.Background((0.05, 0.05, 0.07)),
            om.DirectionalLight(direction=(-0.4, -1, -0.6)),
            om.Node("capture", [cloud]),
            om.Node("torus", [om.Translation(0.45, -0.72, 0.1), om.Color(0.9, 0.25, 0.15), om.Torus(0.35, 0.12)]),
            om.Node("smoke", [om.Translation(1.15, -0.35, -0.9), smoke()]),
        ],
    )
    lo, hi = om.bounds([cloud])  # the box of the splats' 3-sigma ellipsoids
    print(
        f"{cloud.count} splats (degree {cloud.sh_degree}) from {np.round(lo, 2).tolist()} to {np.round(hi, 2).tolist()}"
    )
    eye, ball = np.array([0.6, 0.55, 3.3]), np.array(BALL)
    (hit,) = om.pick(scene, ray=(eye, ball - eye), nearest=True)  # the ray to the ball's centre meets its splats
    print(f"the ray to the ball hits {hit.path} splat {hit.splat} at {np.round(hit.point, 2).tolist()}")
    images = []
    for engine in ("gl", "mitsuba"):
        image = om.render(scene, engine=engine, size=SIZE)
        image.save(out / f"20-{engine}.png")
        images.append(image)
    side_by_side(images).save(out / "20-gaussian-splats.png")
    om.export(scene, out / "20-room.glb")
    om.export(scene, out / "20-room.usda")
    print(f"wrote {out / '20-gaussian-splats.png'} (GL | Mitsuba), 20-room.glb and 20-room.usda")


if __name__ == "__main__":
    main()
