"""Instance sets and levels of detail mean the same in every engine (issue 18).

GL draws an ``om.InstanceSet`` as one instanced call; POV-Ray, Mitsuba and
Radiance see one node per visible instance through its default simplifier.
Both must give the spheres where the arrays put them (masks against an
analytic reference: ray-sphere intersections through the pixel centres) with
the instances' own colours (CIELAB against GL at each sphere's brightest
point).  A ``LevelOfDetail`` shows, in GL, the level its eye distance selects;
offline engines take the finest level unless told ``offline="distance"``.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from engines import marks, require
from test_engines_agree import cielab, hit_sphere, pixel_rays

import omnirender as om

SIZE = (160, 120)
ENGINES = ("gl", "povray", "mitsuba", "radiance")
RADIUS = 0.35
OFFSET = np.array([0.3, 0.0, -0.2])  # the translation of the node holding the set
THRESHOLD = 0.98
MAX_DELTA_E = 2.0


def arrays() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nine instances on a 3x3 grid: positions, colours, scales, and the middle one hidden."""
    i = np.arange(9)
    positions = np.stack([(i % 3 - 1) * 1.2, np.zeros(9), (i // 3 - 1) * 1.2], axis=1)
    hues = np.array([(0.9, 0.2, 0.2), (0.2, 0.8, 0.3), (0.2, 0.3, 0.9)])
    colors = np.concatenate([hues[i % 3] * (0.6 + 0.2 * (i // 3))[:, None], np.ones((9, 1))], axis=1)
    scales = 0.7 + 0.1 * (i % 4)
    visible = i != 4
    return positions, colors, scales, visible


def camera() -> om.Camera:
    return om.Camera.look_at(eye=(0.0, 4.5, 3.5), center=(0.3, 0.0, -0.2), fov=45)


def scene() -> om.Node:
    positions, colors, scales, visible = arrays()
    s = om.Node("scene", [camera(), om.DirectionalLight(direction=(0.0, -1.0, -0.6), intensity=0.9)])
    s.add(om.AmbientLight(intensity=0.2))
    s.add(
        om.Node(
            "set",
            [om.Translation(*OFFSET), om.InstanceSet(om.Sphere(radius=RADIUS), positions, colors, scales, visible)],
        )
    )
    return s


def analytic_mask() -> np.ndarray:
    positions, _, scales, visible = arrays()
    o, d = pixel_rays(camera(), SIZE)
    o = np.ascontiguousarray(o)
    mask = np.zeros(d.shape[:-1], bool)
    for p, s in zip(positions[visible], scales[visible], strict=True):
        mask |= hit_sphere(o, d, p + OFFSET, RADIUS * s)
    return mask


@functools.cache
def rendered(name: str) -> om.Image:
    options = {"povray": {"threads": 2}, "mitsuba": {"spp": 32}}.get(name, {})
    return om.render(scene(), engine=name, size=SIZE, **options)


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ENGINES])
def test_instances_are_where_the_arrays_put_them(name):
    require(name)
    ref = analytic_mask()
    assert 0.05 < ref.mean() < 0.5
    score = float(np.mean(rendered(name).mask == ref))
    assert score >= THRESHOLD, f"{name}: the instance set's mask agrees with the analytic one on {score:.2%}"


def _sphere_colours(image: om.Image) -> np.ndarray:
    """Mean colour of a small patch at the top of each visible sphere (facing the light)."""
    positions, _, scales, visible = arrays()
    cam = camera()
    out = []
    for p, s in zip(positions[visible], scales[visible], strict=True):
        top = np.append(p + OFFSET + (0.0, RADIUS * s * 0.8, 0.0), 1.0)
        clip = cam.projection_matrix(SIZE[0] / SIZE[1]) @ cam.view_matrix() @ top
        x = int((clip[0] / clip[3] * 0.5 + 0.5) * SIZE[0])
        y = int((0.5 - clip[1] / clip[3] * 0.5) * SIZE[1])
        out.append(image.rgb[y - 1 : y + 2, x - 1 : x + 2].reshape(-1, 3).mean(0))
    return np.array(out)


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks("gl", n)) for n in ENGINES if n != "gl"])
def test_instances_have_their_own_colours_in_every_engine(name):
    require("gl")
    require(name)
    gl = _sphere_colours(rendered("gl"))
    lab = cielab(gl)
    assert np.ptp(lab[:, 1:], axis=0).max() > 40  # the instances' colours really differ
    delta = np.linalg.norm(cielab(_sphere_colours(rendered(name))) - lab, axis=1)
    assert delta.max() < MAX_DELTA_E, f"{name}: CIELAB distances to GL per instance {np.round(delta, 2)}"


# -- levels of detail ---------------------------------------------------------------


def lod_scene(eye_distance: float, offline: str = "finest") -> om.Node:
    near = om.Node("near", [om.Color(0.9, 0.1, 0.1), om.Sphere(radius=1.0)])
    far = om.Node("far", [om.Color(0.1, 0.8, 0.1), om.Box(size=1.6)])
    lod = om.LevelOfDetail([near, far], distances=[10.0], center=(0.0, 0.0, 0.0), offline=offline)
    cam = om.Camera.look_at(eye=(0.0, 0.0, eye_distance), center=(0.0, 0.0, 0.0), fov=30)
    return om.Node("scene", [cam, om.DirectionalLight(direction=(0, 0, -1)), om.Node("thing", [lod])])


def _centre(image: om.Image) -> str:
    r, g, _ = image.rgb[image.rgb.shape[0] // 2, image.rgb.shape[1] // 2].astype(int)
    return "near" if r > 2 * g else "far" if g > 2 * r else "none"


@pytest.mark.gl
def test_gl_shows_the_level_of_the_eye_distance_and_follows_the_transforms():
    from omnirender.gl import GLEngine

    require("gl")
    with GLEngine(size=(48, 48), samples=0) as e:
        assert _centre(e.render(lod_scene(6.0))) == "near"
        assert _centre(e.render(lod_scene(14.0))) == "far"
        s = lod_scene(6.0)
        assert _centre(e.render(s)) == "near"
        move = om.Translation(0.0, 0.0, -6.0)  # the object moves away: 12 units from the eye
        s["/scene/thing"].insert(0, move)
        assert _centre(e.render(s)) == "far"
        move.offset = (0.0, 0.0, 0.0)  # moved back on the in-place path
        assert _centre(e.render(s)) == "near" and e.stats["compiled"] is False


@pytest.mark.povray
def test_offline_engines_take_the_finest_level_unless_told_the_distance():
    require("povray")
    far_away = 14.0
    assert _centre(om.render(lod_scene(far_away), engine="povray", size=(32, 32))) == "near"
    assert _centre(om.render(lod_scene(far_away, offline="distance"), engine="povray", size=(32, 32))) == "far"
    assert _centre(om.render(lod_scene(6.0, offline="distance"), engine="povray", size=(32, 32))) == "near"


def test_analysis_engines_choose_as_the_renderers_do():
    """Bounds see the level POV-Ray draws: the finest, or with offline="distance" the camera's."""

    def size(s: om.Node) -> float:
        lo, hi = om.bounds(s)
        return float((hi - lo)[0])

    assert size(lod_scene(14.0)) == pytest.approx(2.0, abs=0.05)  # the unit sphere
    assert size(lod_scene(14.0, offline="distance")) == pytest.approx(1.6, abs=1e-6)  # the box
    no_camera = lod_scene(14.0, offline="distance")
    no_camera.remove(no_camera.items[0])
    assert size(no_camera) == pytest.approx(2.0, abs=0.05)  # no camera, no distance: the finest


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"levels": [], "distances": []}, "at least one level"),
        ({"levels": [om.Sphere(), om.Box()], "distances": [1.0, 2.0]}, "2 levels need 1 switching distances"),
        ({"levels": [om.Sphere(), om.Box(), om.Cone()], "distances": [3.0, 2.0]}, "positive and increasing"),
        ({"levels": [om.Sphere(), "box"], "distances": [1.0]}, "level 1 must be a shape or an om.Node"),
        ({"levels": [om.Sphere()], "distances": [], "offline": "nearest"}, "offline must be one of"),
    ],
)
def test_bad_levels_of_detail_are_refused(kwargs, message):
    with pytest.raises(ValueError, match="LevelOfDetail: ") as info:
        om.LevelOfDetail(**kwargs)
    assert message in str(info.value)


def test_instance_sets_have_the_bounds_of_their_instances():
    positions, _, scales, visible = arrays()
    lo, hi = om.bounds(scene())
    r = (RADIUS * scales[visible])[:, None]
    expected_lo = (positions[visible] + OFFSET - r).min(axis=0)
    expected_hi = (positions[visible] + OFFSET + r).max(axis=0)
    assert np.allclose(lo, expected_lo, atol=1e-6) and np.allclose(hi, expected_hi, atol=1e-6)
