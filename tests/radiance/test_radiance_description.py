"""The Radiance scene description: primitives, appearance mapping, light units, safety. No Radiance programs needed."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import omnirender as om
from omnirender.attributes.photometry import srgb_to_linear
from omnirender.radiance import RadError, rad, scene_description
from omnirender.radiance.engine import view_arguments
from omnirender.radiance.lights import SOURCE_ANGLE
from omnirender.radiance.picture import picture_bytes, rgbe


def _scene(*items, camera=None):
    s = om.Node("s")
    s.add(camera or om.Camera.look_at(eye=(0, 0, 10), center=(0, 0, 0), fov=40))
    for item in items:
        s.add(item)
    return s


def primitives(text: str) -> list[tuple[str, str, str, list[str], list[float]]]:
    """Parse a description into (modifier, type, id, strings, reals) (comments skipped)."""
    words = [w for line in text.splitlines() if not line.startswith("#") for w in line.split()]
    out, i = [], 0
    while i < len(words):
        mod, kind, ident = words[i : i + 3]
        i += 3
        ns = int(words[i])
        strings = words[i + 1 : i + 1 + ns]
        i += 1 + ns
        assert words[i] == "0"
        nr = int(words[i + 1])
        reals = [float(w) for w in words[i + 2 : i + 2 + nr]]
        i += 2 + nr
        out.append((mod, kind, ident, strings, reals))
    return out


def by_kind(text: str, kind: str) -> list[tuple]:
    return [p for p in primitives(text) if p[1] == kind]


def material_of(text: str, surface: tuple) -> tuple:
    """The primitive named by a surface's modifier."""
    return next(p for p in primitives(text) if p[2] == surface[0])


def test_native_shapes_in_world_coordinates():
    moved = om.Node("moved", [om.Translation(1, 2, 3), om.Rotation(90, (1, 0, 0)), om.Scaling(2)])
    moved.add(om.Sphere(center=(0, 1, 0), radius=0.5))
    moved.add(om.Cylinder(radius=0.5, height=2))
    moved.add(om.Cone(radius=1, height=2))
    moved.add(om.Disk(radius=1.5))
    text, _ = scene_description(_scene(moved))
    sphere = by_kind(text, "sphere")[-1]  # the first spheres are light sources
    assert np.allclose(sphere[4], [1, 2, 5, 1.0])  # y -> z under the rotation, radius scaled
    (cylinder,) = by_kind(text, "cylinder")
    assert np.allclose(cylinder[4], [1, 2, 1, 1, 2, 5, 1.0])
    (cone,) = by_kind(text, "cone")
    assert np.allclose(cone[4], [1, 2, 1, 1, 2, 5, 2.0, 0.0])  # base radius 2, apex radius 0
    rings = by_kind(text, "ring")
    assert len(rings) == 2 + 1 + 1  # cylinder caps, cone base, disk
    disk = rings[-1]
    assert np.allclose(disk[4], [1, 2, 3, 0, 0, 1, 0, 3.0])  # facing +y rotated to +z
    assert np.allclose(rings[0][4][3:6], [0, 0, 1]) and np.allclose(rings[1][4][3:6], [0, 0, -1])  # caps face out


def test_boxes_and_rectangles_are_outward_polygons_under_any_matrix():
    for matrix in (np.diag([2.0, 0.5, 1.0, 1.0]), np.diag([-1.0, 1.0, 1.0, 1.0])):
        text, _ = scene_description(_scene(om.Matrix(matrix), om.Box(size=(1, 2, 3), center=(0.5, 0, 0))))
        polygons = by_kind(text, "polygon")
        assert len(polygons) == 6
        centre = matrix[:3, :3] @ np.array([0.5, 0, 0])
        for p in polygons:
            v = np.array(p[4]).reshape(-1, 3)
            normal = np.cross(v[1] - v[0], v[2] - v[1])
            assert normal @ (v.mean(axis=0) - centre) > 0  # counter-clockwise seen from outside


def test_round_shapes_fall_back_to_meshes_when_radiance_cannot_draw_them():
    cases = {
        "squashed": [om.Scaling(1, 0.5, 1), om.Sphere()],
        "clipped": [om.ClipPlane((0, 1, 0), 0), om.Cylinder()],
        "textured": [om.Texture(np.zeros((2, 2, 3), np.uint8)), om.Disk()],
    }
    for name, items in cases.items():
        text, engine = scene_description(_scene(*items))
        assert not by_kind(text, "cylinder") and not by_kind(text, "ring"), name
        assert not by_kind(text, "sphere"), name
        meshes = by_kind(text, "mesh")
        assert len(meshes) == 1 and len(engine.meshes) == 1, name
        obj = engine.meshes[0].obj
        assert obj.count("\nf ") > 10 and ("vt " in obj) == (name == "textured"), name
    # the clipped cylinder keeps only y >= 0
    _, engine = scene_description(_scene(*cases["clipped"]))
    ys = [float(line.split()[2]) for line in engine.meshes[0].obj.splitlines() if line.startswith("v ")]
    assert min(ys) >= -1e-9 and max(ys) == pytest.approx(1.0)


def test_meshes_have_a_real_modifier_normals_and_world_vertices():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    s = _scene(om.Translation(0, 0, 2), om.Material(diffuse=(1, 0, 0)), om.TriangleSet(vertices=v))
    text, engine = scene_description(s)
    (mesh,) = by_kind(text, "mesh")
    assert mesh[0] != "void" and material_of(text, mesh)[1] == "plastic"
    assert mesh[3] == [engine.meshes[0].name]
    obj = engine.meshes[0].obj
    assert "v 0 0 2\nv 1 0 2\nv 0 1 2\n" in obj and obj.count("vn ") == 3 and "f 1//1 2//2 3//3" in obj
    flat, engine = scene_description(_scene(om.DrawStyle(shading="flat"), om.TriangleSet(vertices=v)))
    assert "vn" not in engine.meshes[0].obj and "f 1 2 3" in engine.meshes[0].obj


def test_vertex_colours_become_one_stored_material_per_face_colour():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    colors = [[1, 0, 0], [1, 0, 0], [1, 0, 0], [0, 0, 1]]
    mesh = om.TriangleSet(vertices=v, indices=[[0, 1, 2], [1, 3, 2]], colors=colors)
    text, engine = scene_description(_scene(mesh))
    (surface,) = by_kind(text, "mesh")
    assert surface[0] == "void"  # the faces name their stored materials
    job = engine.meshes[0]
    names = re.findall(r"usemtl (\S+)", job.obj)
    assert len(names) == 2 and len(set(names)) == 2
    stored = {p[2]: p for p in primitives(job.materials)}
    assert set(names) <= set(stored)
    reds = [stored[n][4][:3] for n in names]
    assert np.allclose(reds[0], [1, 0, 0]) or np.allclose(reds[1], [1, 0, 0])  # all-red face
    mixed = reds[1] if np.allclose(reds[0], [1, 0, 0]) else reds[0]
    assert np.allclose(mixed, srgb_to_linear([2 / 3, 0, 1 / 3]), atol=2e-3)  # the mean of its corners


def test_appearance_mapping():
    phong = om.Material(diffuse=(0.5, 0.5, 0.5), specular=(1, 1, 1), shininess=48)
    text, _ = scene_description(_scene(phong, om.Sphere()))
    (_, kind, _, _, reals) = material_of(text, by_kind(text, "sphere")[-1])
    rough = math.sqrt(2 / (4 * 48 + 2))  # shininess is a Phong exponent: Blinn-Phong 4 n, Walter's slope
    spec = 4 * rough * rough
    assert kind == "plastic"
    assert reals[3:] == pytest.approx([spec, rough])
    # Radiance's plastic reflects (1 - spec) of its colour diffusely: the GL diffuse colour is kept
    assert np.array(reals[:3]) * (1 - spec) == pytest.approx(srgb_to_linear([0.5] * 3))

    metal = om.PBRMaterial(base_color=(0.9, 0.7, 0.3), metallic=1.0, roughness=0.4)
    text, _ = scene_description(_scene(metal, om.Sphere()))
    (_, kind, _, _, reals) = material_of(text, by_kind(text, "sphere")[-1])
    assert kind == "metal" and reals == pytest.approx([*srgb_to_linear([0.9, 0.7, 0.3]), 1.0, 0.16])

    dielectric = om.PBRMaterial(base_color=(0.2, 0.4, 0.6), metallic=0.0, roughness=0.5)
    text, _ = scene_description(_scene(dielectric, om.Sphere()))
    assert material_of(text, by_kind(text, "sphere")[-1])[1] == "plastic"

    see_through = om.Material(diffuse=(1, 0, 0), opacity=0.25)
    text, _ = scene_description(_scene(see_through, om.Sphere()))
    mix = material_of(text, by_kind(text, "sphere")[-1])
    assert mix[1] == "mixfunc" and mix[3][1:] == ["void", "0.25", "."]  # the material, a quarter of the time

    glowing = om.Material(diffuse=(0, 0, 0), emission=(1, 0.5, 0))
    text, _ = scene_description(_scene(glowing, om.Sphere()))
    glow = material_of(text, by_kind(text, "sphere")[-1])
    assert glow[1] == "glow" and glow[4] == pytest.approx([*srgb_to_linear([1, 0.5, 0]), 0])

    lit_glow = om.Material(diffuse=(0.5, 0.5, 0.5), emission=(0.2, 0.2, 0.2))
    text, _ = scene_description(_scene(lit_glow, om.Sphere()))
    mix = material_of(text, by_kind(text, "sphere")[-1])
    assert mix[1] == "mixfunc" and mix[3][2:] == ["0.5", "."]
    parts = {p[2]: p for p in primitives(text)}
    assert parts[mix[3][0]][1] == "glow" and parts[mix[3][0]][4][:3] == pytest.approx(2 * srgb_to_linear([0.2] * 3))
    assert parts[mix[3][1]][4][:3] == pytest.approx(2 * srgb_to_linear([0.5] * 3))  # doubled: half of each is kept


def test_a_colour_after_a_material_replaces_its_diffuse_colour():
    text, _ = scene_description(_scene(om.Material(diffuse=(1, 0, 0)), om.Color(0, 1, 0, 0.5), om.Sphere()))
    mix = material_of(text, by_kind(text, "sphere")[-1])
    assert mix[1] == "mixfunc" and mix[3][2] == "0.5"
    inner = next(p for p in primitives(text) if p[2] == mix[3][0])
    assert inner[4][:3] == pytest.approx([0, 1, 0])


def test_textures_become_colorpict_pictures_looked_up_by_the_mesh_coordinates():
    tex = np.zeros((4, 8, 4), np.uint8)
    tex[:2] = (255, 0, 0, 255)  # top rows red
    tex[2:] = (0, 0, 255, 255)
    tex[0, 0, 3] = 0  # a transparent texel: the alpha cuts the surface out
    s = _scene(om.Texture(tex, wrap="clamp", filter="linear"), om.Rectangle(size=(2, 1)))
    text, engine = scene_description(s)
    (mesh,) = by_kind(text, "mesh")
    cutout = material_of(text, mesh)
    assert cutout[1] == "mixpict" and cutout[3][1:3] == ["void", "red"]
    plastic = next(p for p in primitives(text) if p[2] == cutout[3][0])
    pattern = next(p for p in primitives(text) if p[2] == plastic[0])
    assert pattern[1] == "colorpict" and pattern[3][:3] == ["red", "green", "blue"]
    assert pattern[3][5:] == ["bound(0,Lu,0.99999)*2", "bound(0,Lv,0.99999)*1"]  # the picture is 2 x 1 units
    (name, data), (alpha_name, alpha) = engine.pictures
    assert pattern[3][3] == name and cutout[3][3] == alpha_name
    assert data.shape == (4, 8, 3) and np.allclose(data[0, 1], [1, 0, 0]) and np.allclose(data[3, 0], [0, 0, 1])
    assert alpha[0, 0, 0] == 0 and alpha[0, 1, 0] == 1
    nearest = scene_description(_scene(om.Texture(tex[:, :, :3], filter="nearest"), om.Rectangle()))[1]
    assert nearest.pictures[0][1].shape == (256, 512, 3)  # texels repeated: Radiance's lookup blends only seams


def test_radiance_material_and_options_are_used_and_checked():
    user = om.radiance.Material("glass", (0.9, 0.9, 0.9))
    text, engine = scene_description(
        _scene(om.Material(diffuse=(1, 0, 0)), user, om.Sphere(), om.radiance.Options(ab=2))
    )
    glass = material_of(text, by_kind(text, "sphere")[-1])
    assert glass[:2] == ("void", "glass") and glass[4] == [0.9, 0.9, 0.9]
    assert engine.options.arguments() == ["-ab", "2", "-dt", "0", "-dc", "1", "-dj", "0"]
    full = om.radiance.Options(ab=1, ad=512, as_=128, aa=0.1, ar=64, lw=0.001, lr=8)
    assert " ".join(full.arguments()).startswith("-ab 1 -ad 512 -as 128 -aa 0.1 -ar 64 -lw 0.001 -lr 8")
    with pytest.raises(ValueError, match="takes 5 real arguments"):
        om.radiance.Material("plastic", (1, 1, 1))
    with pytest.raises(ValueError, match="did you mean 'plastic'"):
        om.radiance.Material("plastik", (1, 1, 1, 0, 0))
    for bad in (dict(ab=-1), dict(ab=1.5), dict(aa=float("nan")), dict(lw=2.0), dict(ad=0), dict(dt=float("inf"))):
        with pytest.raises(ValueError, match="Options"):
            om.radiance.Options(**bad)


def test_light_units_match_gl_brightness():
    """A directional light of colour c gives irradiance pi*c; point lights are matched at the centre of interest."""
    sun = om.DirectionalLight(direction=(0, -1, 0), color=(1, 0.5, 0.25), intensity=2)
    lamp = om.PointLight(position=(0, 0, 4), color=(1, 1, 1), intensity=1.5)
    physical = om.PointLight(position=(3, 0, 0), intensity=2, constant=0, quadratic=1)
    spot = om.SpotLight(position=(0, 5, 0), direction=(0, -1, 0), cutoff=30, exponent=4)
    text, _ = scene_description(_scene(sun, lamp, physical, spot))
    prims = {p[2]: p for p in primitives(text)}
    (source,) = [p for p in by_kind(text, "source") if prims[p[0]][1] == "light"]
    assert source[4] == pytest.approx([0, 1, 0, SOURCE_ANGLE])  # towards the light
    omega = 2 * math.pi * (1 - math.cos(math.radians(SOURCE_ANGLE) / 2))
    assert np.array(prims[source[0]][4]) * omega == pytest.approx(math.pi * np.array([2, 1, 0.5]))
    spheres = {tuple(p[4][:3]): p for p in by_kind(text, "sphere")}

    def intensity(position):
        sphere = spheres[position]
        material = prims[sphere[0]]
        assert material[1] == "illum"  # a source that camera rays pass through, like GL's invisible lights
        return np.array(material[4]) * math.pi * sphere[4][3] ** 2

    assert intensity((0, 0, 4)) == pytest.approx([1.5 * math.pi * 16] * 3, rel=1e-6)  # matched 4 away (the origin)
    assert intensity((3, 0, 0)) == pytest.approx([2 * math.pi] * 3, rel=1e-6)  # inverse-square: pi * c everywhere
    pattern = prims[prims[spheres[(0, 5, 0)][0]][0]]
    assert pattern[1] == "brightfunc"
    expr = pattern[3][0]
    value = _calc(expr, d=(0, 1, 0))  # a ray arriving from straight below the spot
    assert value == pytest.approx(1.0)
    cos20 = math.cos(math.radians(20))
    assert _calc(expr, d=(math.sin(math.radians(20)), cos20, 0)) == pytest.approx(cos20**4, rel=1e-6)
    assert _calc(expr, d=(math.sin(math.radians(40)), math.cos(math.radians(40)), 0)) == 0.0


def _calc(expr: str, d) -> float:
    """Evaluate a generated calcomp expression in Python (if(a,b,c), ^, Dx/Dy/Dz)."""

    def if_(a, b, c):
        return b if a > 0 else c

    py = expr.replace("^", "**").replace("if(", "if_(")
    return float(eval(py, {"if_": if_, "Dx": d[0], "Dy": d[1], "Dz": d[2]}))  # noqa: S307 - our own text


def test_ambient_light_and_headlight():
    text, engine = scene_description(_scene(om.AmbientLight(intensity=0.3), om.Sphere()))
    assert engine.ambient_value() == pytest.approx([0.5] * 3)  # GL's global 0.2 plus the light
    assert "-av 0.5 0.5 0.5" in text.splitlines()[1]
    glows = [p for p in by_kind(text, "source") if p[4][3] == 360]
    assert len(glows) == 1  # the environment that metals reflect
    assert "headlight" not in text  # any light turns the headlight off, as in GL
    text, engine = scene_description(_scene(om.Sphere()))
    assert "headlight" in text and engine.ambient_value() == pytest.approx([0.2] * 3)


def test_view_reproduces_the_gl_projection():
    cam = om.Camera.look_at(eye=(3, 2, 7), center=(0.3, 0.2, 0), fov=40, near=0.5, far=50)
    args = view_arguments(cam, cam.view_matrix(), (320, 160))

    def flag(name, n=1):
        i = args.index(name)
        return [float(x) for x in args[i + 1 : i + 1 + n]]

    assert args[0] == "-vtv" and flag("-vv") == [40]
    assert math.tan(math.radians(flag("-vh")[0]) / 2) == pytest.approx(2 * math.tan(math.radians(20)))
    assert flag("-vo") + flag("-va") == [0.5, 50]
    forward = np.array([0.3, 0.2, 0]) - [3, 2, 7]
    assert flag("-vp", 3) == [3, 2, 7] and flag("-vd", 3) == pytest.approx(forward / np.linalg.norm(forward))
    ortho = om.Camera.orthographic(eye=(0, 0, 5), height=3)
    args = view_arguments(ortho, ortho.view_matrix(), (300, 100))
    assert args[0] == "-vtl" and flag("-vh") == [9] and flag("-vv") == [3]


def test_names_paths_and_strings_cannot_inject_anything(tmp_path):
    with pytest.raises(ValueError, match="control characters"):  # newlines never reach the description
        om.Node('x"\n!rm -rf ~\n#void light')
    evil = 'x" !rm -rf ~ #void light'
    s = om.Node(evil)
    s.add(om.Camera.look_at(eye=(0, 0, 5)))
    child = s.add(om.Node('b"! c d'))
    img = tmp_path / 'bad"name\n!x.png'
    from PIL import Image as PILImage

    PILImage.fromarray(np.zeros((2, 2, 3), np.uint8)).save(img, format="PNG")
    child.add(om.Texture(str(img)))
    child.add(om.Sphere())
    text, engine = scene_description(s)
    for line in text.splitlines():
        assert not line.lstrip().startswith("!"), line
        if line.startswith("#"):
            assert re.fullmatch(r"# [A-Za-z0-9_./\- :]*", line), line
    assert all(line.startswith("# ") for line in text.splitlines() if "rm -rf" in line)  # only as a comment
    assert "bad" not in text and "passwd" not in text
    assert [name for name, _ in engine.pictures] == ["om_pic0.hdr"]
    primitives(text)  # still well formed
    for bad in ("a b", "x\n!ls", 'q"', "#c", "!x", "", "a" * 600, "/etc/passwd", "../../secret.cal"):
        with pytest.raises(RadError):
            om.radiance.Material("plasfunc", (1, 1, 1, 0, 0), strings=(bad, "."))
    with pytest.raises(RadError):
        om.radiance.RadianceEngine(resource_prefix="x y")
    with pytest.raises(RadError):
        rad.number(float("nan"))
    with pytest.raises(RadError):
        rad.primitive("void", "plastic", "a b")


def test_overflowing_transforms_are_refused_before_anything_is_written(tmp_path):
    with pytest.raises(ValueError, match="at most 1e\\+15"):
        om.Scaling(1e200)
    deep = [om.Scaling(1e6), om.Scaling(1e6), om.Scaling(1e6), om.Box()]  # each fine, together 1e18
    s = _scene(om.Node("far", deep))
    with pytest.raises(ValueError, match="accumulated model matrix exceeds.*in node /s/far"):
        om.export(s, tmp_path / "x.rad")
    assert list(tmp_path.iterdir()) == []


def test_flattening_transforms_are_refused():
    with pytest.raises(ValueError, match="singular"):
        om.Matrix(np.diag([1.0, 0.0, 1.0, 1.0]))
    with pytest.raises(ValueError, match="non-zero"):
        om.Scaling(1, 0, 1)


def test_lines_and_points_are_cylinders_and_spheres_sized_in_pixels():
    cam = om.Camera.orthographic(eye=(0, 0, 5), height=2)
    lines = om.LineSet(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0]])  # the second is degenerate
    points = om.PointSet(vertices=[[0, 0, 0], [0.5, 0.5, 0]], sizes=[2, 4])
    text, _ = scene_description(_scene(om.DrawStyle(line_width=3), lines, points, camera=cam), (200, 200))
    (cyl,) = by_kind(text, "cylinder")
    assert cyl[4] == pytest.approx([0, 0, 0, 1, 0, 0, 1.5 * 2 / 200])
    spheres = by_kind(text, "sphere")
    assert [p[4][3] for p in spheres] == pytest.approx([1 * 2 / 200, 2 * 2 / 200])


def test_other_engines_ignore_radiance_attributes_and_radiance_ignores_theirs():
    items = [
        om.radiance.Material("metal", (0.8, 0.8, 0.8, 0.9, 0.05)),
        om.radiance.Options(ab=1),
        om.radiance.Sky(intensity=10),
        om.radiance.Raw("void plastic extra 0 0 5 1 1 1 0 0\n"),
        om.povray.Finish(phong=0.8),
        om.mitsuba.BSDF({"type": "diffuse"}),
        om.Sphere(),
    ]
    text, _ = scene_description(_scene(*items))
    assert "void plastic extra" in text and "phong" not in text
    from omnirender.povray import scene_sdl

    sdl, _ = scene_sdl(_scene(*items))
    assert "phong 0.8" in sdl and "metal" not in sdl and "extra" not in sdl


def test_rgbe_pictures_round_trip_in_numpy():
    rgb = np.array([[[1.0, 0.5, 0.25], [0.0, 0.0, 0.0], [1e-3, 2e-3, 0.0], [100.0, 1.0, 0.0]]] * 2)
    encoded = rgbe(rgb)
    m, e = encoded[..., :3].astype(float), encoded[..., 3:].astype(float)
    decoded = np.where(e > 0, (m + 0.5) * np.exp2(e - 136), 0.0)
    step = rgb.max(axis=2, keepdims=True) / 128  # one shared exponent: 8 bits below the largest channel
    assert np.all(np.abs(decoded - rgb) <= step)
    wide = picture_bytes(np.ones((3, 300, 3)))
    assert wide.startswith(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3 +X 300\n")
    line = wide[len(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3 +X 300\n") :][: 4 + 4 * (300 + 3)]
    assert line[:4] == bytes([2, 2, 1, 44]) and line[4] == 128 and line[4 + 129] == 128 and line[4 + 258] == 44


def test_engine_micro_program_and_reuse():
    e = om.radiance.RadianceEngine((320, 240))
    mat, move, sphere = om.Material(diffuse=(1, 0, 0)), om.Translation(0, 2, 0), om.Sphere(radius=0.5)
    e.push(mat)
    e.push(move)
    e.eval(sphere)
    e.pop(move.category)
    e.pop(mat.category)
    e.eval(om.Sphere())
    text = e.description()
    spheres = by_kind(text, "sphere")
    assert [s[4] for s in spheres] == [[0, 2, 0, 0.5], [0, 0, 0, 1]]
    assert material_of(text, spheres[0])[4][:3] == [1, 0, 0] and material_of(text, spheres[1])[1] == "plastic"
    assert e.context.is_empty()
    scene = _scene(om.PointLight(position=(1, 2, 3)), om.Torus())
    e.run(scene)
    first = e.description()
    e.run(scene)  # the engine persists: a second traversal starts afresh and writes the same description
    assert e.description() == first and len(e.meshes) == 1


def test_a_light_switch_is_ignored_with_a_warning_naming_the_node():
    a = om.PointLight(position=(5, 0, 3))
    s = _scene(a, om.Node("only_a", [om.LightSwitch(on=False), om.Sphere(), om.Node("deeper", [om.LightSwitch()])]))
    with pytest.warns(UserWarning, match="LightSwitch in node /s/only_a is ignored") as caught:
        text, _ = scene_description(s)
    assert len(caught) == 1 and len(by_kind(text, "sphere")) == 2  # the light and the shape
