"""Proof that the engines agree (issues 5 and 15): one scene, GL, POV-Ray, Mitsuba and Radiance, the same pixels.

The test scene (camera, floor box, sphere, torus, a triangle mesh, point light)
is rendered at 320x240 by every available engine, seen through a perspective
and through an orthographic camera.  The foreground masks (alpha or finite
depth) must agree on at least 98% of the pixels between every pair of
engines, and each engine must agree with an analytic reference mask: rays
through the pixel centres built from the core camera matrices, intersected
exactly with the sphere and box, by sphere tracing with the torus and with
the mesh's triangles.  This checks cameras, transforms and tessellations.
Engines also agree on meaning: diffuse patches of several colours under a
directional light and the ambient light have the GL engine's colours in every
engine (CIELAB distance below 2).

``docs/make_images.py`` renders this scene for the README's side-by-side figure.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np
import pytest
from engines import marks, require

import omnirender as om

SIZE = (320, 240)
ENGINES = ("gl", "povray", "mitsuba", "radiance")
VIEWS = ("perspective", "orthographic")
THRESHOLD = 0.98

TORUS_MATRIX = om.Translation(1.0, 0.45, -0.7).matrix @ om.Rotation(60, (1, 0, 0)).matrix
MESH_MATRIX = om.Translation(0.9, 0.0, 1.3).matrix @ om.Scaling(0.55).matrix
SPHERE = ((-1.1, 0.6, 0.6), 0.6)
FLOOR = ((0.0, -0.05, 0.0), (5.0, 0.1, 5.0))
TORUS = (0.6, 0.2)


def octahedron() -> tuple[np.ndarray, np.ndarray]:
    """A pointy octahedron standing on y = 0 (model coordinates)."""
    v = np.array([[1, 1, 0], [-1, 1, 0], [0, 1, 1], [0, 1, -1], [0, 2.4, 0], [0, 0, 0]], dtype=np.float64)
    f = np.array([[4, 0, 3], [4, 3, 1], [4, 1, 2], [4, 2, 0], [5, 3, 0], [5, 1, 3], [5, 2, 1], [5, 0, 2]])
    return v, f


def camera(view: str = "perspective") -> om.Camera:
    eye, center = (3.3, 2.5, 4.9), (0.0, 0.45, 0.1)
    if view == "orthographic":
        return om.Camera.orthographic(eye=eye, center=center, height=4.6)
    return om.Camera.look_at(eye=eye, center=center, fov=40)


def make_scene(view: str = "perspective") -> om.Node:
    scene = om.Node("scene")
    scene.add(camera(view))
    scene.add(om.PointLight(position=(4.0, 6.0, 3.0)))
    scene.add(om.AmbientLight(intensity=0.25))
    floor = scene.add(om.Node("floor"))
    floor.add(om.Material(diffuse=(0.75, 0.75, 0.72)))
    floor.add(om.Box(size=FLOOR[1], center=FLOOR[0]))
    ball = scene.add(om.Node("ball"))
    ball.add(om.Material(diffuse=(0.9, 0.25, 0.2), specular=(0.5, 0.5, 0.5), shininess=50))
    ball.add(om.Sphere(center=SPHERE[0], radius=SPHERE[1]))
    ring = scene.add(om.Node("ring"))
    ring.add(om.Matrix(TORUS_MATRIX))
    ring.add(om.Material(diffuse=(0.2, 0.45, 0.9)))
    ring.add(om.Torus(major_radius=TORUS[0], minor_radius=TORUS[1]))
    gem = scene.add(om.Node("gem"))
    gem.add(om.Matrix(MESH_MATRIX))
    gem.add(om.Material(diffuse=(0.95, 0.75, 0.2)))
    v, f = octahedron()
    gem.add(om.TriangleSet(vertices=v, indices=f))
    return scene


# -- the analytic reference --------------------------------------------------
def pixel_rays(camera: om.Camera, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """World-space rays (origins, unit directions) through the pixel centres, row 0 at the top."""
    w, h = size
    inv = np.linalg.inv(camera.view_matrix())
    x, y = np.meshgrid((np.arange(w) + 0.5) / w * 2 - 1, 1 - (np.arange(h) + 0.5) / h * 2)
    if camera.is_orthographic:  # parallel rays from the image plane through the eye
        half = camera.height / 2
        o = np.stack([x * half * w / h, y * half, np.zeros_like(x)], axis=-1) @ inv[:3, :3].T + inv[:3, 3]
        d = np.broadcast_to(inv[:3, :3] @ np.array([0.0, 0.0, -1.0]), o.shape)
        return o, d
    t = math.tan(math.radians(camera.fov) / 2)
    d = np.stack([x * t * w / h, y * t, -np.ones_like(x)], axis=-1) @ inv[:3, :3].T
    return np.broadcast_to(inv[:3, 3], d.shape), d / np.linalg.norm(d, axis=-1, keepdims=True)


def _local(o: np.ndarray, d: np.ndarray, matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    inv = np.linalg.inv(matrix)
    return o @ inv[:3, :3].T + inv[:3, 3], d @ inv[:3, :3].T  # t stays a world-ray parameter


def hit_sphere(o, d, center, radius):
    oc = o - np.asarray(center)
    b = np.sum(oc * d, -1)
    disc = b * b - (np.sum(oc * oc, -1) - radius * radius)
    return (disc >= 0) & (-b + np.sqrt(np.maximum(disc, 0)) > 0)


def hit_box(o, d, center, size):
    lo, hi = np.asarray(center) - np.asarray(size) / 2, np.asarray(center) + np.asarray(size) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (lo - o) / d, (hi - o) / d
    tmin, tmax = np.nanmax(np.minimum(t1, t2), -1), np.nanmin(np.maximum(t1, t2), -1)
    return (tmax >= tmin) & (tmax > 0)


def hit_torus(o, d, major, minor, steps=200):
    """Sphere tracing of the torus distance field (rays in its local frame, directions normalised)."""
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    d = d / n
    t = np.zeros(o.shape[:-1])
    hit = np.zeros(o.shape[:-1], dtype=bool)
    for _ in range(steps):
        p = o + t[..., None] * d
        q = np.hypot(np.hypot(p[..., 0], p[..., 2]) - major, p[..., 1])
        dist = q - minor
        hit |= dist < 1e-5
        t = np.where(hit, t, t + np.maximum(dist, 1e-5))
        if np.all(hit | (t > 50)):
            break
    return hit


def hit_triangles(o, d, vertices, faces):
    hit = np.zeros(o.shape[:-1], dtype=bool)
    for a, b, c in vertices[faces]:
        e1, e2 = b - a, c - a
        p = np.cross(d, e2)
        det = p @ e1
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o - a
            u = np.sum(s * p, -1) * inv
            q = np.cross(s, e1)
            v = np.sum(d * q, -1) * inv
            t = (q @ e2) * inv
        hit |= (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return hit


def analytic_mask(size: tuple[int, int] = SIZE, view: str = "perspective") -> np.ndarray:
    o, d = pixel_rays(camera(view), size)
    o = np.ascontiguousarray(o)
    mask = hit_box(o, d, *FLOOR) | hit_sphere(o, d, *SPHERE)
    mask |= hit_torus(*_local(o, d, TORUS_MATRIX), *TORUS)
    v, f = octahedron()
    mask |= hit_triangles(*_local(o, d, MESH_MATRIX), v, f)
    return mask


# -- rendering ------------------------------------------------------------------


@functools.cache
def rendered(name: str, view: str = "perspective") -> om.Image:
    options = {"povray": {"threads": 2}, "mitsuba": {"spp": 16}}.get(name, {})
    return om.render(make_scene(view), engine=name, size=SIZE, **options)


@functools.cache
def reference(view: str = "perspective") -> np.ndarray:
    return analytic_mask(view=view)


def agreement(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.mean(a == b))


@pytest.mark.parametrize("view", VIEWS)
@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ENGINES])
def test_engine_matches_the_analytic_mask(name, view):
    require(name)
    img = rendered(name, view)
    ref = reference(view)
    assert img.size == SIZE
    assert 0.25 < ref.mean() < 0.75  # the reference itself is sensible
    score = agreement(img.mask, ref)
    assert score >= THRESHOLD, f"{name} ({view}) agrees with the analytic mask on only {score:.2%} of pixels"


@pytest.mark.parametrize("view", VIEWS)
@pytest.mark.parametrize(
    "a,b", [pytest.param(a, b, marks=marks(a, b), id=f"{a}-{b}") for a, b in itertools.combinations(ENGINES, 2)]
)
def test_engines_agree_pairwise(a, b, view):
    require(a)
    require(b)
    score = agreement(rendered(a, view).mask, rendered(b, view).mask)
    assert score >= THRESHOLD, f"{a} and {b} masks ({view}) agree on only {score:.2%} of pixels"


# -- shading -------------------------------------------------------------------
PATCH_COLORS = [(0.8, 0.2, 0.2), (0.2, 0.7, 0.3), (0.2, 0.3, 0.9), (0.9, 0.8, 0.3), (0.5, 0.5, 0.5), (0.1, 0.1, 0.1)]
MAX_DELTA_E = 2.0


def patches_scene() -> om.Node:
    """Six diffuse squares facing an orthographic camera, lit by a slanted directional light (and GL's ambient)."""
    s = om.Node("patches", [om.Camera.orthographic(eye=(0, 0, 5), height=2)])
    s.add(om.DirectionalLight(direction=(0.3, -0.2, -1), intensity=0.8))
    for i, c in enumerate(PATCH_COLORS):
        patch = s.add(om.Node(f"p{i}", [om.Translation(-2.5 + i, 0, 0), om.Rotation(90, (1, 0, 0))]))
        patch.add(om.Material(diffuse=c, ambient=c))  # ambient = diffuse: physically based engines reflect so
        patch.add(om.Rectangle(size=(0.8, 0.8)))
    return s


def cielab(rgb8: np.ndarray) -> np.ndarray:
    """sRGB (0..255) to CIELAB (D65)."""
    c = np.asarray(rgb8, np.float64) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    m = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    xyz = lin @ m.T / np.array([0.9505, 1.0, 1.089])
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1)


def patch_colours(name: str) -> np.ndarray:
    options = {"mitsuba": {"spp": 64}}.get(name, {})
    img = om.render(patches_scene(), engine=name, size=(240, 80), **options)
    return np.array([img.rgb[35:45, 40 * i + 15 : 40 * i + 25].reshape(-1, 3).mean(0) for i in range(6)])


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks("gl", n)) for n in ENGINES if n != "gl"])
def test_lit_colours_agree_with_gl(name):
    require("gl")
    require(name)
    delta = np.linalg.norm(cielab(patch_colours(name)) - cielab(patch_colours("gl")), axis=1)
    assert delta.max() < MAX_DELTA_E, f"{name}: CIELAB distances to GL {np.round(delta, 2)}"
