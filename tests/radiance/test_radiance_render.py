"""Rendering with rpict: exact camera, depth, GL brightness, appearance, textures, clipping, lines, export."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import omnirender as om
from omnirender.attributes.photometry import linear_to_srgb, srgb_to_linear

sys.path.insert(0, str(Path(__file__).parents[1] / "povray"))
from raycast import box_mask, pixel_rays, sphere_mask  # noqa: E402

pytestmark = pytest.mark.radiance
SIZE = (160, 100)


def _render(scene, size=SIZE, **kw):
    return om.render(scene, engine="radiance", size=size, **kw)


def _srgb8(linear):
    return np.round(linear_to_srgb(linear) * 255).astype(int)


CAMERAS = [
    om.Camera.look_at(eye=(3, 2, 7), center=(0.3, 0.2, 0), fov=40, far=100),
    om.Camera.orthographic(eye=(3, 2, 7), center=(0.3, 0.2, 0), height=4, far=100),
]


@pytest.mark.parametrize("camera", CAMERAS, ids=["perspective", "orthographic"])
def test_mask_and_depth_match_the_gl_camera_exactly(camera):
    s = om.Node("s")
    s.add(camera)
    s.add(om.Sphere(center=(1, 0.5, 0), radius=0.8))
    moved = s.add(om.Node("moved"))
    moved.add(om.Translation(-1, -0.5, 0.5))
    moved.add(om.Scaling(0.5, 0.25, 1))
    moved.add(om.Box(size=(2, 2, 2)))
    img = _render(s)
    o, d = pixel_rays(camera, SIZE)
    sphere = sphere_mask(o, d, (1, 0.5, 0), 0.8)
    ref = sphere | box_mask(o, d, (-1.5, -0.75, -0.5), (-0.5, -0.25, 1.5))
    assert ref.sum() > 1000
    assert (img.mask != ref).sum() <= 4  # only pixels whose centre is within rounding of an edge
    # eye-space depth along the viewing axis, from rpict's ray lengths
    oc = o - np.array([1, 0.5, 0])
    b = np.sum(oc * d, -1)
    t = -b - np.sqrt(np.maximum(b * b - (np.sum(oc * oc, -1) - 0.64), 0))
    forward = -camera.view_matrix()[2, :3]
    expected = t * (d @ forward) + (o - camera.eye) @ forward
    inside = sphere & img.mask & (expected < img.depth + 0.1)  # not behind the box
    assert inside.sum() > 500
    assert np.abs(img.depth[inside] - expected[inside]).max() < 1e-3
    assert np.all(np.isinf(img.depth[~img.mask]))


def test_brightness_matches_the_gl_lighting_model():
    """Head-on under a directional light of colour 1 plus GL's ambient 0.2: 1.2 * kd, as GL shows it."""
    kd = (0.6, 0.4, 0.2)
    s = om.Node("s")
    s.add(om.Camera.look_at(eye=(0, 0, 5), fov=40))
    s.add(om.DirectionalLight(direction=(0, 0, -1)))
    s.add(om.Material(diffuse=kd, ambient=kd))
    s.add(om.Sphere(radius=1))
    img = _render(s, size=(64, 48))
    expected = 1.2 * srgb_to_linear(kd)
    assert img.hdr[24, 32, :3] == pytest.approx(expected, rel=0.01)
    assert np.abs(np.array(img.pixel(32, 24)[:3]) - _srgb8(expected)).max() <= 1
    assert not img.mask[0, 0] and img.mask[24, 32] and img.pixel(32, 24)[3] == 255  # coverage, opaque sphere
    assert img.engine == "radiance" and "render_seconds" in img.info
    darker = _render(s, size=(64, 48), exposure=0.5)  # the picture is exposed, the radiance stays physical
    assert np.abs(np.array(darker.pixel(32, 24)[:3]) - _srgb8(0.5 * expected)).max() <= 1
    assert darker.hdr[24, 32, :3] == pytest.approx(img.hdr[24, 32, :3])


def _wall(light, camera):
    """A white wall at z = 1 facing the camera (+z), lit by ``light`` alone."""
    s = om.Node("s", [camera, light, om.Material(diffuse=(1, 1, 1), ambient=(0, 0, 0))])
    s.add(om.Node("wall", [om.Translation(0, 0, 1), om.Rotation(90, (1, 0, 0)), om.Rectangle(size=(6, 6))]))
    return _render(s, size=(40, 40), global_ambient=0.0)


def test_point_and_spot_lights_match_gl_at_the_centre_of_interest():
    camera = om.Camera.look_at(eye=(0, 0, 5), center=(0, 0, 1), fov=30)
    for light in (
        om.PointLight(position=(0, 0, 6)),
        om.SpotLight(position=(0, 0, 6), direction=(0, 0, -1), cutoff=20, exponent=2),
    ):
        img = _wall(light, camera)
        # GL: kd * colour * cos 0 * spot 1 = 1 at the centre of interest, 5 away from the light
        assert img.hdr[19:21, 19:21, 0] == pytest.approx(1.0, rel=0.01), type(light).__name__


def test_spot_lights_have_gls_cone_and_falloff_with_physical_distance():
    spot = om.SpotLight(position=(0, 0, 6), direction=(0, 0, -1), cutoff=10, exponent=20)
    img = _wall(spot, om.Camera.orthographic(eye=(0, 0, 5), center=(0, 0, 1), height=4))

    def expected(row, col):  # spot cos^20, incidence cos and 1 / r^2 relative to the centre of interest (r = 5)
        x, y = (col + 0.5) / 10 - 2, 2 - (row + 0.5) / 10
        c = 5 / math.sqrt(x * x + y * y + 25)
        return c**20 * c * c * c if c >= math.cos(math.radians(10)) else 0.0

    for row, col in ((20, 20), (19, 25), (12, 22), (20, 30)):
        assert img.hdr[row, col, 0] == pytest.approx(expected(row, col), rel=0.02, abs=1e-4), (row, col)
    assert img.hdr[20, 2, 0] == 0.0 and img.mask[20, 2]  # outside the cone


def test_materials_transparency_emission_and_background():
    s = om.Node("s")
    s.add(om.Camera.orthographic(eye=(0, 0, 5), height=2))
    s.add(om.Background((0.0, 0.0, 1.0)))
    s.add(om.DirectionalLight(direction=(0, 0, -1)))
    left = s.add(om.Node("left", [om.Translation(-0.5, 0, 0), om.Rotation(90, (1, 0, 0))]))
    left.add(om.Material(diffuse=(0, 0, 0), emission=(1, 0.5, 0)))
    left.add(om.Rectangle(size=(0.8, 0.8)))
    right = s.add(om.Node("right", [om.Translation(0.5, 0, 0), om.Rotation(90, (1, 0, 0))]))
    right.add(om.Material(diffuse=(1, 1, 1), ambient=(1, 1, 1), opacity=0.5))
    right.add(om.Rectangle(size=(0.8, 0.8)))
    img = _render(s, size=(40, 20), global_ambient=0.0)
    assert img.pixel(15, 10)[:3] == (255, 128, 0)  # emission alone, as GL adds it
    assert img.pixel(1, 1) == (0, 0, 255, 255)  # the background colour
    # half the white surface, half what lies behind: nothing (premultiplied), composited over the blue background
    assert img.hdr[10, 25, :3] == pytest.approx([0.5, 0.5, 0.5], rel=0.02)
    r, g, b, _ = img.pixel(25, 10)
    assert b == 255 and abs(r - g) <= 1 and r == _srgb8(0.5)


def test_metals_reflect_the_ambient_light_like_gl():
    s = om.Node("s", [om.Camera.orthographic(eye=(0, 0, 5), height=2.2)])
    s.add(om.PBRMaterial(base_color=(0.9, 0.7, 0.3), metallic=1.0, roughness=0.5))
    s.add(om.Sphere())
    img = _render(s, size=(40, 40))
    headlight_free = img.hdr[20, 20, :3]  # GL: ambient 0.2 * F0 (= base colour) plus the headlight
    assert headlight_free[0] > 0.2 * srgb_to_linear(0.9) and img.hdr[3, 20, 0] > 0.1


def test_vertex_colours_and_texture_orientation():
    s = om.Node("s")
    s.add(om.Camera.orthographic(eye=(0, 0, 5), height=2))
    s.add(om.AmbientLight(intensity=0.8))  # + GL's global ambient 0.2
    s.add(om.Material(ambient=(1, 1, 1), diffuse=(1, 1, 1)))
    quad = s.add(om.Node("quad"))
    quad.add(om.Translation(-1, 0, 0))
    quad.add(
        om.TriangleSet(
            vertices=[[-1, -1, 0], [0, -1, 0], [0, 1, 0], [-1, 1, 0]],
            indices=[[0, 1, 2], [0, 2, 3]],
            colors=[[1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0]],
        )
    )
    tex = np.zeros((2, 2, 3), np.uint8)
    tex[0, :] = (0, 0, 255)  # top row blue
    tex[1, :] = (255, 255, 0)  # bottom row yellow
    textured = s.add(om.Node("textured"))
    textured.add(om.Texture(tex, filter="nearest"))
    textured.add(
        om.TriangleSet(
            vertices=[[0, -1, 0], [1, -1, 0], [1, 1, 0], [0, 1, 0]],
            indices=[[0, 1, 2], [0, 2, 3]],
            texcoords=[[0, 0], [1, 0], [1, 1], [0, 1]],
        )
    )
    img = _render(s, size=(100, 50))
    # Radiance meshes have no vertex colours: each triangle gets the mean of its corners
    lower, upper = img.pixel(20, 40), img.pixel(5, 5)  # below / above the quad's diagonal
    assert lower[:3] == tuple(_srgb8(srgb_to_linear([2 / 3, 1 / 3, 0])))
    assert upper[:3] == tuple(_srgb8(srgb_to_linear([1 / 3, 2 / 3, 0])))
    assert img.pixel(62, 45)[:3] == (255, 255, 0)  # texture coordinate v = 0: the image's bottom row
    assert img.pixel(62, 4)[:3] == (0, 0, 255)


def test_clip_planes_cut_the_geometry_on_the_cpu():
    cam = om.Camera.orthographic(eye=(0, 0, 5), height=3)
    s = om.Node(
        "s", [cam, om.ClipPlane(normal=(1, 0, 0), offset=0.2), om.Sphere(), om.Box(size=0.5, center=(-1, 1, 0))]
    )
    img = _render(s, size=(60, 60))
    o, d = pixel_rays(cam, (60, 60))
    ref = sphere_mask(o, d, (0, 0, 0), 1.0) & (o[..., 0] >= 0.2)
    assert ref.sum() > 300 and (img.mask != ref).sum() <= 8  # tessellated edge of the sphere; the box is gone


def test_lines_points_and_wireframes():
    cam = om.Camera.orthographic(eye=(0, 0, 5), height=2)
    s = om.Node("s", [cam, om.Color(1, 1, 1)])
    s.add(om.Node("lines", [om.DrawStyle(line_width=4), om.LineSet(vertices=[[-1, 0.5, 0], [1, 0.5, 0]])]))
    s.add(om.Node("points", [om.PointSet(vertices=[[0.5, -0.5, 0]], sizes=[10])]))
    wire = om.Node("wire", [om.DrawStyle(mode="wireframe", line_width=2), om.Translation(-0.5, -0.5, 0)])
    wire.add(om.TriangleSet(vertices=[[-0.3, -0.3, 0], [0.3, -0.3, 0], [0, 0.3, 0]]))
    s.add(wire)
    img = _render(s, size=(100, 100))
    rows = np.flatnonzero(img.mask[:, 50])
    assert 3 <= len(rows[rows < 50]) <= 5  # a 4-pixel line across y = 0.5
    assert 8 <= img.mask[75, 65:85].sum() <= 11  # a 10-pixel point
    assert not img.mask[75, 25] and img.mask[:, 10:40].sum() > 40  # the wireframe triangle is hollow


def test_fog_and_oversampling():
    s = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5), fov=40), om.DirectionalLight(direction=(0, 0, -1))])
    s.add(om.Fog(color=(1, 0, 0), mode="linear", start=0, end=8))
    s.add(om.Material(diffuse=(0, 0, 1), ambient=(0, 0, 1)))
    s.add(om.Sphere())
    img = _render(s, size=(40, 40), global_ambient=0.0)
    depth = img.depth[20, 20]
    distance = depth * math.sqrt(1 + 2 * (0.5 / 20 * math.tan(math.radians(20))) ** 2)
    f = (8 - distance) / 8
    assert img.hdr[20, 20, :3] == pytest.approx([1 - f, 0, f * 1.0], rel=0.02, abs=0.01)  # GL's mix with the fog
    assert not img.mask[0, 0]  # the background is not fogged
    smooth = _render(s, size=(40, 40), oversample=3, global_ambient=0.0)
    edge = (smooth.coverage > 0) & (smooth.coverage < 1)
    assert edge.sum() > 20 and (smooth.mask != img.mask).sum() <= 6
    assert smooth.info["oversample"] == 3 and smooth.hdr.shape == (40, 40, 4)


def test_a_scene_with_povray_and_radiance_attributes_renders_in_both():
    s = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5), fov=40), om.PointLight(position=(2, 2, 5))])
    s.add(om.povray.Finish(phong=0.8))
    s.add(om.radiance.Material("metal", (0.9, 0.2, 0.2, 0.9, 0.1)))
    s.add(om.radiance.Options(ab=1, ad=64, as_=0, aa=0))
    s.add(om.Sphere())
    rad = _render(s, size=(40, 40))
    assert rad.mask[20, 20] and rad.pixel(20, 20)[0] > rad.pixel(20, 20)[1]  # its own red metal
    assert "-ab 1 -ad 64" in rad.info["options"]


def test_export_writes_a_description_radiance_accepts(tmp_path):
    from omnirender.radiance.runner import run

    tex = np.full((4, 4, 3), 200, np.uint8)
    s = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.PointLight(position=(1, 1, 4))])
    s.add(om.Node("torus", [om.Texture(tex), om.Torus()]))
    target = tmp_path / "my scene.rad"
    assert om.export(s, target) == target
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["my scene.rad", "my_scene_mesh0.rtm", "my_scene_pic0.hdr"]
    text = target.read_text()
    assert "1 my_scene_mesh0.rtm" in text and "my_scene_pic0.hdr" in text and text.startswith("# omnirender")
    run("oconv", ["my scene.rad"], tmp_path, stdout="check.oct")  # Radiance reads it in its folder
    (tmp_path / "rays.txt").write_text("0 5 0 1 -5 0\n0 5 0 0 -1 0\n")  # at the torus tube, through its hole
    run("rtrace", ["-h", "-ov", "-ab", "0", "check.oct"], tmp_path, stdin="rays.txt", stdout="values.txt")
    tube, hole = np.loadtxt(tmp_path / "values.txt")
    assert hole == pytest.approx([0.2] * 3)  # the ambient environment (GL's global ambient)
    assert tube.min() > 0.01 and not np.allclose(tube, hole)  # the textured tube


def test_hostile_export_names_give_safe_file_names(tmp_path):
    evil = tmp_path / 'ev il"\n!x.rad'
    om.export(om.Node("s", [om.Torus()]), evil)
    assert sorted(p.name for p in tmp_path.iterdir()) == [evil.name, "ev_il___x_mesh0.rtm"]
    assert "\n1 ev_il___x_mesh0.rtm\n" in evil.read_text()
    om.export(om.Node("s", [om.Torus()]), tmp_path / "1.rad")  # a Radiance name must not start with a digit
    assert (tmp_path / "om_1_mesh0.rtm").is_file()
