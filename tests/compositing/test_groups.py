"""Occlusion and shadow groups, checked against what the images must be (colours, depths, an analytic shadow)."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

from .scenes import CAMERA, fog_volume

pytestmark = pytest.mark.gl
C = om.compositing
SIZE = (96, 72)

#: A: a wall in front; B: a ball behind it (partly hidden) and a ball in front of it.
WALL = om.Node("wall", [om.Color(0.2, 0.8, 0.2), om.Box(size=(2.0, 2.0, 0.1), center=(0, 0, 0))])
BALLS = om.Node("balls", [om.Color(1.0, 0.2, 0.2), om.Sphere(center=(-0.9, 0, -1.0), radius=0.6),
                          om.Sphere(center=(1.2, 0, 0.8), radius=0.4)])  # fmt: skip


def images(mode: str, opacity: float = 0.5) -> tuple[om.Image, om.Image, om.Image, om.Image]:
    kw = dict(camera=CAMERA, samples=0, background=(0, 0, 0))
    a = C.SceneRenderer(WALL).render(SIZE, **kw)
    b = C.SceneRenderer(BALLS).render(SIZE, **kw)
    plain = C.DepthGroup([C.SceneRenderer(WALL), C.SceneRenderer(BALLS)]).render(SIZE, **kw)
    group = C.DepthGroup(
        [C.SceneRenderer(WALL), C.OcclusionGroup([C.SceneRenderer(BALLS)], mode=mode, opacity=opacity)]
    )
    return a, b, plain, group.render(SIZE, **kw)


def regions(a: om.Image, b: om.Image) -> tuple[np.ndarray, np.ndarray]:
    both = np.isfinite(a.depth) & np.isfinite(b.depth)
    hidden = both & (b.depth > a.depth)
    front = np.isfinite(b.depth) & ~hidden
    return hidden, front


def test_visible_mode_shows_the_hidden_parts_fully_with_their_depth():
    a, b, plain, out = images("visible")
    hidden, front = regions(a, b)
    assert hidden.sum() > 100 and front.sum() > 50
    assert np.abs(plain.array[hidden].astype(int) - a.array[hidden].astype(int)).max() <= 2  # the depth test hides
    assert np.abs(out.array[hidden].astype(int) - b.array[hidden].astype(int)).max() <= 2  # the group shows B
    assert np.allclose(out.depth[hidden], b.depth[hidden], rtol=1e-4)  # ... with B's depth (colour = depth)
    assert np.abs(out.array[front].astype(int) - plain.array[front].astype(int)).max() <= 2
    empty = ~np.isfinite(b.depth)
    assert np.array_equal(out.array[empty], plain.array[empty])  # outside B nothing changes


def test_semi_transparent_mode_mixes_by_opacity_and_keeps_the_front_depth():
    a, b, plain, out = images("semi-transparent", opacity=0.3)
    hidden, front = regions(a, b)
    expected = 0.7 * a.array[hidden][:, :3].astype(float) + 0.3 * b.array[hidden][:, :3].astype(float)
    assert np.abs(out.array[hidden][:, :3] - expected).max() <= 2
    assert np.allclose(out.depth[hidden], a.depth[hidden], rtol=1e-4)  # A still in front there
    assert np.abs(out.array[front].astype(int) - plain.array[front].astype(int)).max() <= 2


def test_meshes_inside_a_volume_are_revealed_by_an_occlusion_group():
    volume = C.VolumeRenderer(fog_volume(alpha=0.5, spacing=1.6))
    inside = C.SceneRenderer(om.Node("inside", [om.Color(0.1, 0.3, 1.0), om.Sphere(radius=0.35)]))
    kw = dict(camera=CAMERA, samples=0, background=(0, 0, 0))
    hidden = C.DepthGroup([volume, inside]).render(SIZE, **kw)
    shown = C.DepthGroup([volume, C.OcclusionGroup([inside])]).render(SIZE, **kw)
    centre = (48, 36)
    assert hidden.pixel(*centre)[2] < 120  # behind the volume's first 5 % opacity: hidden
    assert shown.pixel(*centre)[2] > 200 and shown.pixel(*centre)[0] < 60  # shown fully


def analytic_shadow_scene(light: om.PointLight | om.DirectionalLight):
    """A sphere over a plane seen from above, and the analytic shadow predicate of a world point."""
    center, radius = np.array([0.0, 1.2, 0.0]), 0.8
    plane = om.Node(
        "plane", [light, om.Material(diffuse=(0.8, 0.8, 0.8)), om.Box(size=(8, 0.1, 8), center=(0, -0.05, 0))]
    )
    sphere = om.Node(
        "sphere", [light, om.Material(diffuse=(0.9, 0.4, 0.2)), om.Sphere(center=tuple(center), radius=radius)]
    )
    directional = isinstance(light, om.DirectionalLight)

    def shadowed(points: np.ndarray) -> np.ndarray:
        # towards the light: to its position (a segment), or against its direction (a ray)
        d = -np.broadcast_to(light.direction, points.shape) if directional else np.asarray(light.position) - points
        on_sphere = np.linalg.norm(points - center, axis=1) < radius + 0.02
        facing_away = np.einsum("ij,ij->i", points - center, d) < 0  # the sphere's own shadow
        f = points - center
        a, b, c = (d * d).sum(1), 2 * (f * d).sum(1), (f * f).sum(1) - radius**2
        disc = b * b - 4 * a * c
        root = np.sqrt(np.maximum(disc, 0))
        end_ = np.inf if directional else 1.0
        t1, t2 = (-b - root) / (2 * a), (-b + root) / (2 * a)
        blocked = (disc > 0) & (((t1 > 1e-3) & (t1 < end_)) | ((t2 > 1e-3) & (t2 < end_)))
        return np.where(on_sphere, facing_away, blocked)

    return plane, sphere, shadowed


def world_points(camera: om.Camera, image: om.Image) -> tuple[np.ndarray, np.ndarray]:
    """(pixel mask, world points) of every pixel with a surface, from the image's depth."""
    h, w = image.depth.shape
    mask = np.isfinite(image.depth)
    ys, xs = np.nonzero(mask)
    d = image.depth[ys, xs]
    t = np.tan(np.radians(camera.fov) / 2)
    eye = np.stack([((xs + 0.5) / w * 2 - 1) * t * w / h * d, (1 - (ys + 0.5) / h * 2) * t * d, -d, np.ones_like(d)], 1)
    return mask, (eye @ np.linalg.inv(camera.view_matrix()).T)[:, :3]


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
@pytest.mark.parametrize(
    "light", [om.PointLight(position=(2.0, 6.0, 1.5)), om.DirectionalLight(direction=(-0.3, -1.0, -0.2))], ids=repr
)
def test_the_shadow_group_darkens_the_pixels_an_analytic_shadow_test_predicts(light):
    plane, sphere, shadowed = analytic_shadow_scene(light)
    camera = om.Camera.look_at((0, 4, 7), (0, 0.5, 0), fov=40)
    children = [C.SceneRenderer(plane), C.SceneRenderer(sphere)]
    size = (240, 180)
    lit = C.ShadowGroup(light, children, enabled=False).render(size, camera=camera, samples=0)
    shaded = C.ShadowGroup(light, children).render(size, camera=camera, samples=0)
    ratio = (shaded.array[..., :3].astype(float).sum(2) + 1) / (lit.array[..., :3].astype(float).sum(2) + 1)
    darkened = ratio < 0.7  # darkness 0.6: shadowed pixels keep 40 % of their colour
    mask, points = world_points(camera, lit)
    predicted = np.zeros_like(mask)
    predicted[mask] = shadowed(points)
    agreement = (predicted == darkened)[mask].mean()
    assert agreement >= 0.95, agreement
    assert predicted[mask].mean() > 0.03  # the test is not trivially met by darkening nothing
    assert np.allclose(shaded.depth[mask], lit.depth[mask], rtol=1e-5)  # shadows change colour, not depth


@pytest.mark.slow  # 20-90 s on a software rasteriser (the softpipe and GL 4.1 jobs of .ci/run leave it out)
def test_a_volume_casts_a_shadow_on_meshes():
    light = om.PointLight(position=(0, 6, 0))
    floor = C.SceneRenderer(om.Node("floor", [light, om.Material(diffuse=(0.8, 0.8, 0.8)),
                                              om.Box(size=(6, 0.1, 6), center=(0, -1.5, 0))]))  # fmt: skip
    cloud = C.VolumeRenderer(fog_volume(alpha=0.4), om.Translation(0, 0.6, 0))
    camera = om.Camera.look_at((0, 3, 6), (0, -0.5, 0), fov=45)
    lit = C.ShadowGroup(light, [floor, cloud], enabled=False).render(SIZE, camera=camera, samples=0)
    shaded = C.ShadowGroup(light, [floor, cloud]).render(SIZE, camera=camera, samples=0)
    darker = shaded.array[..., :3].sum(2) < 0.7 * lit.array[..., :3].sum(2)
    # the shadow lies on the floor below the cloud: the floor pixels whose world point is under it
    mask, points = world_points(camera, lit)
    below = np.zeros_like(mask)
    below[mask] = (np.hypot(points[:, 0], points[:, 2]) < 0.5) & (points[:, 1] < -1.4)
    assert below.sum() > 20
    assert darker[below].mean() > 0.9
    far = np.zeros_like(mask)
    far[mask] = (np.hypot(points[:, 0], points[:, 2]) > 2.0) & (points[:, 1] < -1.4)
    assert darker[far].mean() < 0.02
