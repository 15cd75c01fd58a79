"""The distance-visualisation group: colours decode to the analytic distance between two renderers' surfaces."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl
C = om.compositing

SIZE = (128, 96)
CAMERA = om.Camera.look_at((0.3, 0.2, 4.0), (0, 0, 0), fov=45, near=0.5, far=20)
GREY = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))  # display value = distance / range: decodable
FLAT = om.Material(ambient=(0, 0, 0), diffuse=(0, 0, 0), emission=(1, 1, 1))
#: the reference: a plane tilted about y, z = -0.4 - 0.3 x (its normal (0.3, 0, 1))
TILT = np.degrees(np.arctan(0.3))


def surface() -> C.SceneRenderer:
    return C.SceneRenderer(om.Node("surface", [FLAT, om.Box(size=(2.4, 1.8, 0.001), center=(0, 0, 0))]))


def reference(center=(0, 0, -0.4)) -> C.SceneRenderer:
    tilted = [om.Translation(*center), om.Rotation(TILT, (0, 1, 0)), om.Box(size=(3.0, 1.4, 0.001))]
    return C.SceneRenderer(om.Node("reference", [FLAT, *tilted]))


def rays(size):
    """World direction of each pixel centre's ray (unit) and the eye."""
    w, h = size
    to_world = np.linalg.inv(CAMERA.view_matrix())
    t = np.tan(np.radians(CAMERA.fov) / 2)
    ys, xs = np.mgrid[0:h, 0:w] + 0.5
    d = np.stack([(xs / w * 2 - 1) * t * w / h, (1 - ys / h * 2) * t, -np.ones_like(xs)], -1) @ to_world[:3, :3].T
    return d / np.linalg.norm(d, axis=-1, keepdims=True), to_world[:3, 3]


def analytic(size, offset=-0.4):
    """Distance along each ray from the surface plane z = 0 to the reference plane; masks of both."""
    d, o = rays(size)
    t0 = -o[2] / d[..., 2]
    p0 = o + t0[..., None] * d
    on_surface = (np.abs(p0[..., 0]) < 1.2) & (np.abs(p0[..., 1]) < 0.9)
    n = np.array([0.3, 0.0, 1.0])  # plane n . p = offset
    t1 = (offset - o @ n) / (d @ n)
    p1 = o + t1[..., None] * d
    along = p1[..., 0] * np.cos(np.radians(TILT)) + (p1[..., 2] - offset) * np.sin(np.radians(TILT))
    on_reference = (np.abs(along) < 1.5) & (np.abs(p1[..., 1]) < 0.7)
    return t1 - t0, on_surface, on_reference


def test_colours_decode_to_the_distance_between_the_surfaces_along_each_ray():
    group = C.DistanceGroup([surface(), reference()], range=(0.0, 1.0), colormap=GREY, missing=(1, 0, 0))
    image = group.render(SIZE, camera=CAMERA, samples=0, background=(0, 0, 1))
    rgb = image.array[..., :3].astype(float)
    expected, on_surface, on_reference = analytic(SIZE)
    inner = on_surface & on_reference
    inner &= np.roll(inner, 1, 0) & np.roll(inner, -1, 0) & np.roll(inner, 1, 1) & np.roll(inner, -1, 1)
    assert inner.sum() > 2000 and np.ptp(expected[inner]) > 0.4  # distances vary over the image
    measured = rgb[inner, 0] / 255.0
    assert np.abs(measured - expected[inner]).max() <= 2.5 / 255 + 0.002, np.abs(measured - expected[inner]).max()
    missed = on_surface & ~on_reference
    missed &= np.roll(missed, 1, 0) & np.roll(missed, -1, 0) & np.roll(missed, 1, 1) & np.roll(missed, -1, 1)
    assert missed.sum() > 50 and (np.abs(rgb[missed] - (255, 0, 0)).max(-1) <= 1).all()
    outside = ~on_surface
    outside &= np.roll(outside, 1, 0) & np.roll(outside, -1, 0) & np.roll(outside, 1, 1) & np.roll(outside, -1, 1)
    assert (np.abs(rgb[outside] - (0, 0, 255)).max(-1) <= 1).all()  # nothing changes outside the surface
    assert np.isfinite(image.depth[inner]).all()  # the surface's depth (the reference's is not drawn)
    # the default colour map: viridis stops (numpy's distance_colors gives the same colours)
    viridis = C.DistanceGroup([surface(), reference()], range=(0.0, 1.0)).render(SIZE, camera=CAMERA, samples=0)
    from omnirender.compositing.distance import distance_colors

    want = distance_colors(expected[inner], (0.0, 1.0)) * 255
    assert np.abs(viridis.array[inner][:, :3] - want).max() <= 3


def test_signed_distances_tell_in_front_from_behind():
    # the reference crosses the surface: left of x ~ -0.2 it lies in front (negative), right behind
    crossing = reference(center=(0, 0, 0.06))
    group = C.DistanceGroup([surface(), crossing], range=0.5, signed=True, colormap=GREY)
    rgb = group.render(SIZE, camera=CAMERA, samples=0).array[..., 0].astype(float)
    expected, on_surface, on_reference = analytic(SIZE, offset=0.06)
    inner = on_surface & on_reference & (np.abs(expected) > 0.02)
    inner &= np.roll(inner, 2, 1) & np.roll(inner, -2, 1) & np.roll(inner, 2, 0) & np.roll(inner, -2, 0)
    decoded = rgb[inner] / 255.0 * 1.0 - 0.5  # GREY over -0.5 .. 0.5
    assert (expected[inner] < 0).sum() > 300 and (expected[inner] > 0).sum() > 300
    assert np.abs(decoded - expected[inner]).max() <= 0.015


def test_distance_group_input_is_validated_with_the_fix():
    with pytest.raises(ValueError, match="range must be"):
        C.DistanceGroup([surface(), reference()], range=(1, 1))
    with pytest.raises(ValueError, match="colormap must be 2 to 16 RGB"):
        C.DistanceGroup([surface(), reference()], colormap=[(1, 0, 0)])
    with pytest.raises(ValueError, match="DistanceGroup: missing values must be in \\[0, 1\\]"):
        C.DistanceGroup([surface(), reference()], missing=(2, 0, 0))
    one = C.DistanceGroup([surface()])
    with pytest.raises(ValueError, match="needs two children"):
        one.render((32, 24), camera=CAMERA)
    problems = C.check_tree(C.DepthGroup([one]))
    assert [(p.guideline, p.path) for p in problems] == [("distance-pair", "DepthGroup/[0]DistanceGroup")]
    filtered = C.DepthGroup([C.DistanceGroup([surface(), C.LuminanceFilter()])])
    assert ("distance-pair", "DepthGroup/[0]DistanceGroup/[1]LuminanceFilter") in {
        (p.guideline, p.path) for p in C.check_tree(filtered)
    }


def test_the_thickness_of_a_ball_is_the_distance_from_its_front_to_its_back_faces():
    """The docstring's shell thickness: the surface is a ball's front faces, the reference the same ball's back
    faces (drawn with front faces culled); the colour gives the chord length 2 sqrt(r^2 - b^2) of each ray."""
    ball = om.Sphere(radius=1.0)
    fine = om.Tessellation(5)  # 128 segments around: chords within 0.1 % of the sphere's
    front = C.SceneRenderer(om.Node("front", [FLAT, fine, ball]))
    back = C.SceneRenderer(om.Node("back", [FLAT, fine, om.gl.CullFace("front"), ball]))
    camera = om.Camera.look_at((0, 0, 5), (0, 0, 0), fov=40, near=0.5, far=20)
    image = C.DistanceGroup([front, back], range=(0.0, 2.0), colormap=GREY).render(SIZE, camera=camera, samples=0)
    w, h = SIZE
    to_world = np.linalg.inv(camera.view_matrix())
    t = np.tan(np.radians(camera.fov) / 2)
    ys, xs = np.mgrid[0:h, 0:w] + 0.5
    d = np.stack([(xs / w * 2 - 1) * t * w / h, (1 - ys / h * 2) * t, -np.ones_like(xs)], -1) @ to_world[:3, :3].T
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = to_world[:3, 3]
    b = d @ o
    disc = b * b - (o @ o - 1.0)
    chord = 2 * np.sqrt(np.maximum(disc, 0))
    inside = disc > 0.05  # away from the silhouette (a tessellated sphere's chords differ most there)
    measured = image.array[..., 0].astype(float) / 255 * 2.0
    assert inside.sum() > 1000
    err = np.abs(measured - chord)[inside]  # 8-bit colours: 2/255 = 0.008 per step
    assert err.mean() <= 0.004 and err.max() <= 0.012, (err.mean(), err.max())
