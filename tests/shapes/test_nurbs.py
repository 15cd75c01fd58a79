"""NURBS surfaces: evaluation, Bézier patches, trimming, meshes, GPU tessellation and agreement between engines."""

from __future__ import annotations

import math

import numpy as np
import pytest
from engines import marks, require

import omnirender as om
from omnirender.geometry import nurbs


def cylinder_quarter() -> om.NURBSSurface:
    """A quarter of a unit cylinder (exact: a rational quadratic arc swept along y)."""
    arc = np.array([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    cp = np.zeros((3, 2, 3))
    for i, (x, z) in enumerate(arc):
        cp[i, :, 0], cp[i, :, 2] = x, z
        cp[i, :, 1] = (-1.0, 1.0)
    w = np.array([[1.0, 1.0], [np.sqrt(0.5)] * 2, [1.0, 1.0]])
    return om.NURBSSurface(cp, weights=w, degree_u=2, degree_v=1)


def bumpy(trim: list | None = None) -> om.NURBSSurface:
    u, v = np.linspace(-1.5, 1.5, 6), np.linspace(-1.0, 1.0, 5)
    cp = np.zeros((6, 5, 3))
    cp[..., 0], cp[..., 2] = u[:, None], v[None, :]
    cp[..., 1] = 0.6 * np.sin(2 * u[:, None]) * np.cos(2 * v[None, :])
    return om.NURBSSurface(cp, trim=trim or ())


def hole(cx: float = 0.5, cy: float = 0.5, r: float = 0.2, n: int = 48) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([cx + r * np.cos(t), cy - r * np.sin(t)])  # clockwise: a hole


def test_rational_surface_is_exact():
    s = cylinder_quarter()
    u, v = np.meshgrid(np.linspace(0, 1, 17), np.linspace(0, 1, 5))
    p = s.evaluate(u, v)
    assert np.allclose(np.hypot(p[..., 0], p[..., 2]), 1.0, atol=1e-12)  # on the unit cylinder
    assert np.allclose(p[..., 1], -1.0 + 2.0 * v)
    assert s.rational and s.bounds()[1][0] == 1.0


def test_bezier_patches_reproduce_the_surface():
    s = bumpy()
    patches, domains = s.bezier_patches()
    assert patches.shape == (6, 4, 4, 4)  # 3 spans along u, 2 along v
    for patch, (u0, u1, v0, v1) in zip(patches, domains, strict=True):
        for a, b in ((0.3, 0.7), (0.0, 1.0), (0.9, 0.1)):
            bu = [math.comb(3, i) * a**i * (1 - a) ** (3 - i) for i in range(4)]
            bv = [math.comb(3, j) * b**j * (1 - b) ** (3 - j) for j in range(4)]
            h = np.einsum("i,j,ijk->k", bu, bv, patch)
            expected = s.evaluate(np.array([u0 + a * (u1 - u0)]), np.array([v0 + b * (v1 - v0)]))[0]
            assert np.allclose(h[:3] / h[3], expected, atol=1e-12)


def test_trimming_keeps_by_the_winding_rule():
    inner = hole()
    square = np.array([[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9]])  # counter-clockwise: keep inside
    points = np.array([[0.5, 0.5], [0.05, 0.05], [0.2, 0.5]])
    assert nurbs.trim_kept(points, [inner]).tolist() == [False, True, True]  # a clockwise loop cuts a hole
    assert nurbs.trim_kept(points, [square]).tolist() == [True, False, True]
    assert nurbs.trim_kept(points, [square, inner]).tolist() == [False, False, True]


def test_trimmed_mesh_follows_the_loop():
    s = bumpy([hole()])
    mesh = s.tessellate((24, 20))
    uv = mesh["texcoords"]
    inscribed = 0.2 * np.cos(np.pi / 48)  # the loop is a 48-gon in the circle
    assert len(np.unique(mesh["indices"])) == len(uv)  # every vertex is used
    assert np.all(np.linalg.norm(uv - 0.5, axis=1) >= inscribed - 1e-4)  # nothing inside the hole
    centroids = uv[mesh["indices"]].mean(axis=1)
    assert np.all(np.linalg.norm(centroids - 0.5, axis=1) > inscribed - 0.01)  # chords of the cut cells at most
    on_loop = np.abs(np.linalg.norm(uv - 0.5, axis=1) - 0.2) < 2e-3
    assert on_loop.sum() > 30  # the cut runs along the loop
    e1, e2 = (
        uv[mesh["indices"][:, 1]] - uv[mesh["indices"][:, 0]],
        uv[mesh["indices"][:, 2]] - uv[mesh["indices"][:, 0]],
    )
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
    assert abs(area - (1.0 - np.pi * 0.2**2)) < 0.01


def test_trim_curves_and_validation():
    circle = om.TrimCurve([[0.5, 0.3], [0.3, 0.3], [0.3, 0.5], [0.3, 0.7], [0.5, 0.7], [0.7, 0.7], [0.7, 0.5],
                           [0.7, 0.3], [0.5, 0.3]],
                          weights=[1, 0.5**0.5, 1, 0.5**0.5, 1, 0.5**0.5, 1, 0.5**0.5, 1],
                          knots=[0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4])  # fmt: skip
    line = circle.polyline(64)
    assert np.allclose(np.linalg.norm(line - 0.5, axis=1), 0.2)
    s = bumpy([circle])
    assert len(s.trim_loops()) == 1
    with pytest.raises(ValueError, match="clamped"):
        om.NURBSSurface(np.zeros((4, 4, 3)), knots_u=[0, 0.1, 0.2, 0.3, 1, 1, 1, 1])
    with pytest.raises(ValueError, match="needs more than"):
        om.NURBSSurface(np.zeros((3, 4, 3)))
    with pytest.raises(ValueError, match="weights must be"):
        om.NURBSSurface(np.zeros((4, 4, 3)), weights=-np.ones((4, 4)))
    with pytest.raises(ValueError, match="trim loop 0"):
        om.NURBSSurface(np.zeros((4, 4, 3)), trim=[[0, 1]])


def test_analysis_engines_use_the_mesh():
    s = bumpy()
    lo, hi = om.bounds(om.Node("n", [s]))
    assert np.allclose(lo[[0, 2]], (-1.5, -1.0)) and np.allclose(hi[[0, 2]], (1.5, 1.0))
    hits = om.pick(om.Node("n", [s]), ray=((0.3, 5.0, 0.2), (0, -1, 0)))
    u, v = np.meshgrid(np.linspace(0, 1, 401), np.linspace(0, 1, 401))
    grid = s.evaluate(u, v).reshape(-1, 3)
    nearest = grid[np.argmin(np.hypot(grid[:, 0] - 0.3, grid[:, 2] - 0.2))]
    assert hits and abs(hits[0].point[1] - nearest[1]) < 5e-3
    assert not om.pick(om.Node("n", [bumpy([hole()])]), ray=((0.0, 5.0, 0.0), (0, -1, 0)))  # through the hole
    # collisions: a small ball touching the surface's highest bump collides, one above it does not
    top = grid[np.argmax(grid[:, 1])]
    for lift, expected in ((0.0, True), (0.3, False)):
        ball = om.Node("ball", [om.Translation(*(top + (0, lift + 0.1, 0))), om.Sphere(radius=0.15)])
        scene = om.Node("scene", [om.Collidable(True), om.Node("surface", [s]), ball])
        assert bool(om.collisions(scene)) == expected, lift


# -- rendering ------------------------------------------------------------------------------------------------
def scene(shape: om.Component, level: int | None = None) -> om.Node:
    items = [om.Camera.look_at((0, 3, 4), (0, 0, 0), fov=45), om.PointLight(position=(2, 4, 3)),
             om.Material(diffuse=(0.9, 0.5, 0.2))]  # fmt: skip
    if level is not None:
        items.append(om.Tessellation(level))
    return om.Node("s", [*items, shape])


def fine_mesh(s: om.NURBSSurface, cells: int = 192) -> om.TriangleSet:
    m = s.tessellate((cells, cells))
    return om.TriangleSet(m["vertices"], m["indices"], normals=m["normals"], texcoords=m["texcoords"])


def boundary_distance(mask: np.ndarray, where: np.ndarray) -> np.ndarray:
    """Pixel distance from each pixel of ``where`` to the nearest pixel on the other side of ``mask``'s edge."""
    edge = mask & ~(np.roll(mask, 1, 0) & np.roll(mask, -1, 0) & np.roll(mask, 1, 1) & np.roll(mask, -1, 1))
    ey, ex = np.nonzero(edge)
    py, px = np.nonzero(where)
    if not len(py):
        return np.zeros(0)
    return np.sqrt((py[:, None] - ey[None, :]) ** 2 + (px[:, None] - ex[None, :]) ** 2).min(axis=1)


EYE, FOV = (0.0, 3.0, 4.0), 45.0  # scene()'s camera


def screen_error(s: om.NURBSSurface, depth: np.ndarray) -> np.ndarray:
    """Per drawn pixel, how far (in pixels) the drawn point is from the exact surface on screen.

    The pixel's point (unprojected from the eye-space depth) is matched to its nearest point of the exact
    surface (a dense grid, then Gauss-Newton on (u, v)); the error is the distance between the projections.
    """
    from scipy.spatial import cKDTree

    from omnirender.core.camera import look_at_matrix, perspective_matrix

    h, w = depth.shape
    view, proj = look_at_matrix(EYE, (0, 0, 0), (0, 1, 0)), perspective_matrix(FOV, w / h, 0.1, 1000.0)
    ys, xs = np.nonzero(np.isfinite(depth))
    z = depth[ys, xs].astype(np.float64)
    t = math.tan(math.radians(FOV) / 2)
    ndc = np.column_stack([(xs + 0.5) / w * 2 - 1, 1 - (ys + 0.5) / h * 2])
    eye = np.column_stack([ndc[:, 0] * t * w / h * z, ndc[:, 1] * t * z, -z, np.ones_like(z)])
    world = (np.linalg.inv(view) @ eye.T).T[:, :3]
    g = np.linspace(0, 1, 301)
    gu, gv = np.meshgrid(g, g, indexing="ij")
    _, nearest = cKDTree(s.evaluate(gu, gv).reshape(-1, 3)).query(world)
    u, v = gu.ravel()[nearest], gv.ravel()[nearest]
    for _ in range(8):  # minimise |S(u, v) - point|^2
        p = s.evaluate(u, v)
        du = (s.evaluate(np.minimum(u + 1e-6, 1), v) - s.evaluate(np.maximum(u - 1e-6, 0), v)) / (
            np.minimum(u + 1e-6, 1) - np.maximum(u - 1e-6, 0))[:, None]  # fmt: skip
        dv = (s.evaluate(u, np.minimum(v + 1e-6, 1)) - s.evaluate(u, np.maximum(v - 1e-6, 0))) / (
            np.minimum(v + 1e-6, 1) - np.maximum(v - 1e-6, 0))[:, None]  # fmt: skip
        r = world - p
        a11, a12, a22 = (du * du).sum(1), (du * dv).sum(1), (dv * dv).sum(1)
        b1, b2 = (du * r).sum(1), (dv * r).sum(1)
        det = a11 * a22 - a12 * a12
        u = np.clip(u + (a22 * b1 - a12 * b2) / det, 0, 1)
        v = np.clip(v + (a11 * b2 - a12 * b1) / det, 0, 1)
    clip = (proj @ view @ np.column_stack([s.evaluate(u, v), np.ones(len(u))]).T).T
    px = (clip[:, 0] / clip[:, 3] + 1) / 2 * w
    py = (1 - clip[:, 1] / clip[:, 3]) / 2 * h
    return np.hypot(px - (xs + 0.5), py - (ys + 0.5))


@pytest.mark.gl
def test_gpu_tessellation_stays_within_its_error_bound():
    """Every pixel the GPU-tessellated surface covers lies within the screen-space bound of the exact surface
    (measured on its depth against the exactly evaluated surface; a fine mesh measures the method's own error),
    and the silhouette agrees with a fine mesh's."""
    from omnirender.gl import GLEngine
    from omnirender.gl.painters.nurbs import error_bound

    s = bumpy([hole()])
    engine = GLEngine(size=(240, 180), samples=0, shadows=False)
    try:
        exact = engine.render(scene(fine_mesh(s)))
        assert screen_error(s, exact.depth).max() < 0.01  # the measurement itself
        previous = None
        for level in (1, 3, 4):
            gpu = engine.render(scene(s, level))
            error = screen_error(s, gpu.depth)
            assert error.max() <= error_bound(level) + 0.01, (level, error.max())
            assert previous is None or error.mean() < previous  # a finer level is closer
            previous = error.mean()
            off = exact.mask ^ gpu.mask
            assert off.mean() < 0.01 and boundary_distance(exact.mask, off).max(initial=0.0) <= error_bound(level) + 1
    finally:
        engine.release()


@pytest.mark.slow
@pytest.mark.parametrize(
    "trimmed", [pytest.param(t, marks=marks("gl", "povray", "mitsuba", "radiance")) for t in (False, True)]
)
def test_silhouettes_agree_in_every_engine(trimmed, tmp_path):
    """GPU tessellation (forward and deferred), POV-Ray (bicubic_patch when untrimmed), Mitsuba, Radiance and the
    mesh."""
    for name in ("gl", "povray", "mitsuba", "radiance"):
        require(name)
    s = bumpy([hole()] if trimmed else None)
    pov = tmp_path / "s.pov"
    om.export(scene(s), pov)
    assert ("bicubic_patch" in pov.read_text()) != trimmed  # native patches for the untrimmed surface only
    reference = om.render(scene(fine_mesh(s)), engine="gl", size=(160, 120)).mask
    masks = {
        "gl": om.render(scene(s), engine="gl", size=(160, 120)).mask,
        "gl deferred": om.render(scene(s), engine="gl", size=(160, 120), pipeline="deferred").mask,
        "povray": om.render(scene(s), engine="povray", size=(160, 120)).mask,
        "mitsuba": om.render(scene(s), engine="mitsuba", size=(160, 120), spp=8).mask,
        "radiance": om.render(scene(s), engine="radiance", size=(160, 120)).mask,
    }
    for name, mask in masks.items():
        off = mask ^ reference
        share = off.sum() / (mask | reference).sum()
        distance = boundary_distance(reference, off).max(initial=0.0)
        assert share < 0.05 and distance <= 1.5, f"{name}: {share:.2%} of the silhouette differs, up to {distance} px"


@pytest.mark.gl
def test_gpu_patches_shade_like_the_mesh_in_both_pipelines():
    from omnirender.colorimetry import cielab, delta_e2000
    from omnirender.gl import GLEngine

    s = bumpy([hole()])
    clipped = om.Node("c", [om.ClipPlane(normal=(1, 0, 0), offset=-0.8), s])
    for pipeline in ("forward", "deferred"):
        engine = GLEngine(size=(200, 150), pipeline=pipeline)
        try:
            mesh, gpu = engine.render(scene(fine_mesh(s), 5)), engine.render(scene(s, 5))
            de = delta_e2000(cielab(mesh.array[..., :3]), cielab(gpu.array[..., :3]))
            assert np.percentile(de, 99) < 3.0, pipeline
            cut = engine.render(scene(clipped, 5)).mask
            xs = np.nonzero(cut.any(axis=0))[0]
            assert cut.sum() < 0.8 * gpu.mask.sum() and xs.min() > np.nonzero(gpu.mask.any(axis=0))[0].min() + 10
        finally:
            engine.release()
