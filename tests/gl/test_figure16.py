"""The VRS paper's Figure 16 scenes (examples/07_techniques.py): each technique's effect where it belongs.

(a) silhouette pixels lie on the outlines of the styled shapes only, and the
    nested Phong-highlight technique still adds its highlights;
(b) the haloed wire-frame breaks a line only where it passes behind another;
(c) the mirrored ball appears in the floor mirror, below the ball;
(d) the ball's shadow on the wall is seen inside the reflection.
"""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

from .test_techniques import _dilate, load_example

pytestmark = pytest.mark.gl

SIZE = (240, 180)


@pytest.fixture(scope="module")
def ex():
    return load_example("07_techniques.py")


def render(scene, **options):
    return om.render(scene, engine="gl", size=SIZE, samples=0, **options)


def strip_techniques(node: om.Node) -> om.Node:
    """A copy of the graph without GL techniques (what other engines evaluate)."""
    out = om.Node(node.name)
    for c in node.items:
        if isinstance(c, om.Node):
            out.add(strip_techniques(c))
        elif not isinstance(c, om.gl.GLTechnique):
            out.add(c)
    return out


def test_a_silhouettes_lie_on_the_outlines_and_nest_with_highlights(ex):
    styled = render(ex.build_scene("a"))
    plain = render(strip_techniques(ex.build_scene("a")))
    outlines = np.zeros(styled.array.shape[:2], bool)
    for name in ("ball", "ring"):
        only = strip_techniques(ex.build_scene("a"))
        keep = om.Node("scene", [c for c in only.items if not isinstance(c, om.Node)])
        keep.add(next(n for n in only.walk() if n.name == name))
        mask = render(keep, background=(0, 0, 0, 0)).mask
        outlines |= _dilate(mask, 3) & ~_erode(mask, 3)
    dark = styled.array[..., :3].max(axis=2) < 50
    lines = dark & (plain.array[..., :3].max(axis=2) >= 50)
    assert lines.sum() > 200, "silhouettes were drawn"
    assert (lines & outlines).sum() >= 0.97 * lines.sum(), "silhouette pixels lie on the outlines only"
    bright = styled.array[..., :3].min(axis=2) > 235
    assert (bright & ~(plain.array[..., :3].min(axis=2) > 235)).sum() > 20, "the nested highlight pass adds highlights"


def _erode(mask: np.ndarray, r: int) -> np.ndarray:
    return ~_dilate(~mask, r)


def test_b_haloed_lines_break_only_where_they_pass_behind_another(ex):
    scene = ex.build_scene("b")
    haloed = render(scene).array[..., :3].max(axis=2) < 128
    wire = scene["/wire"].items[0]
    wire.halo = 0.0
    plain = render(scene).array[..., :3].max(axis=2) < 128
    gaps = plain & ~haloed
    assert gaps.sum() > 20, "halos cut the lines behind"
    # where two projected edges of the octahedron cross (one behind the other) the gaps must be
    crossings, corners = _octahedron_crossings(ex, scene)
    assert len(crossings) >= 2
    yy, xx = np.nonzero(gaps)
    gem = xx < SIZE[0] // 2  # the octahedron is the left half; the ring's own crossings are on the right
    xx, yy = xx[gem], yy[gem]

    def near(points: np.ndarray, r: float) -> np.ndarray:
        return np.min(np.hypot(xx[:, None] - points[:, 0], yy[:, None] - points[:, 1]), axis=1) <= r

    # a line breaks where it passes behind another, nowhere else (not where edges meet at a corner)
    assert near(crossings, 8).mean() >= 0.97, "the gem's lines break only at crossings"
    assert not near(corners, 3).any(), "edges meeting at a corner are not cut"
    assert all((np.hypot(xx - x, yy - y) <= 8).any() for x, y in crossings), "every crossing has a gap"


def _octahedron_crossings(ex, scene) -> tuple[np.ndarray, np.ndarray]:
    """Pixel positions where two projected octahedron edges without a common vertex cross, and its corners."""
    camera = next(c for c in scene.items if isinstance(c, om.Camera))
    gem = scene["/wire/gem"]
    tri = next(c for c in gem.items if isinstance(c, om.TriangleSet))
    model = np.eye(4)
    for c in gem.items:
        if isinstance(c, om.Transform):
            model = model @ c.matrix
    v = tri.vertex_array().astype(np.float64) @ model[:3, :3].T + model[:3, 3]
    clip = np.c_[v, np.ones(len(v))] @ (camera.projection_matrix(SIZE[0] / SIZE[1]) @ camera.view_matrix()).T
    ndc = clip[:, :2] / clip[:, 3:]
    px = np.c_[(ndc[:, 0] + 1) / 2 * SIZE[0], (1 - ndc[:, 1]) / 2 * SIZE[1]]
    f = tri.index_array()
    edges = {tuple(sorted((int(a), int(b)))) for t in f for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    out = []
    edges = sorted(edges)
    for i, (a, b) in enumerate(edges):
        for c, d in edges[i + 1 :]:
            if len({a, b, c, d}) < 4:
                continue
            p, r, q, s = px[a], px[b] - px[a], px[c], px[d] - px[c]
            den = r[0] * s[1] - r[1] * s[0]
            if abs(den) < 1e-9:
                continue
            t = ((q - p)[0] * s[1] - (q - p)[1] * s[0]) / den
            u = ((q - p)[0] * r[1] - (q - p)[1] * r[0]) / den
            if 0.05 < t < 0.95 and 0.05 < u < 0.95:
                out.append(p + t * r)
    return np.array(out), px


def test_c_the_mirrored_ball_is_below_the_ball_in_the_floor(ex):
    scene = ex.build_scene("c")
    with_ball = render(scene).array[..., :3].astype(int)
    ball = next(n for n in scene.walk() if n.name == "ball")
    ball_mask = render(om.Node("only", [*(c for c in scene.items if not isinstance(c, om.Node)), ball]),
                       background=(0, 0, 0, 0)).mask  # fmt: skip
    scene.remove(ball)
    without = render(scene).array[..., :3].astype(int)
    changed = (np.abs(with_ball - without).max(axis=2) > 40) & ~_dilate(ball_mask, 2)
    reflected = changed & (with_ball[..., 0] > with_ball[..., 2] + 40)  # red: the ball's colour
    assert reflected.sum() > 300
    ys_ball = np.nonzero(ball_mask)[0]
    ys_ref = np.nonzero(reflected)[0]
    assert ys_ref.min() > ys_ball.mean() and ys_ref.mean() > ys_ball.max(), "the reflection is below the ball"


def test_d_the_shadow_on_the_wall_is_seen_in_the_reflection(ex):
    scene = ex.build_scene("d")
    shadowed = render(scene).array[..., :3].astype(int)
    plain = render(scene, shadows=False).array[..., :3].astype(int)
    floor_only = om.Node("only", [*(c for c in scene.items if not isinstance(c, om.Node)), scene["/floor"]])
    floor = render(floor_only, background=(0, 0, 0, 0)).mask
    darker = (plain - shadowed).max(axis=2) > 30
    assert (darker & ~floor).sum() > 300, "shadows on the wall and the floor"
    assert (darker & floor).sum() > 300, "and shadows inside the mirror's reflection"
