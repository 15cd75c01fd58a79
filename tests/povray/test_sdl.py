"""The POV-Ray engine's SDL writer (no povray program needed)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import omnirender as om
from omnirender.povray import POVRayEngine, scene_sdl, sdl
from omnirender.povray.mesh import mesh2_text
from omnirender.povray.runner import POVRayError, error_lines


def _scene(*items, name="scene"):
    s = om.Node(name)
    s.add(om.Camera.look_at(eye=(0, 0, 5), center=(0, 0, 0), fov=40))
    for item in items:
        s.add(item)
    return s


def test_matrix_is_transposed_for_row_vectors():
    m = om.Translation(1, 2, 3).matrix @ om.Scaling(2, 3, 4).matrix
    text = sdl.matrix(m)
    values = [float(v) for v in text[len("matrix <") : -1].split(",")]
    assert values == [2, 0, 0, 0, 3, 0, 0, 0, 4, 1, 2, 3]
    r = om.Rotation(90, (0, 0, 1)).matrix  # x axis -> y axis
    values = [float(v) for v in sdl.matrix(r)[len("matrix <") : -1].split(",")]
    assert np.allclose(values[:3], [0, 1, 0], atol=1e-12)  # image of the x axis is the first row


def test_numbers_must_be_finite():
    with pytest.raises(sdl.SDLError, match="non-finite"):
        sdl.vector([1.0, math.nan, 0.0])


def test_camera_vectors_reproduce_the_gl_projection():
    cam = om.Camera.look_at(eye=(0, 0, 5), center=(0, 0, 0), fov=40)
    text = om.povray.engine.camera_sdl(cam, cam.view_matrix(), (400, 200))
    up = [float(v) for v in re.search(r"up <([^>]*)>", text).group(1).split(",")]
    right = [float(v) for v in re.search(r"right <([^>]*)>", text).group(1).split(",")]
    direction = [float(v) for v in re.search(r"direction <([^>]*)>", text).group(1).split(",")]
    assert np.allclose(direction, [0, 0, -1])
    assert np.allclose(up, [0, 2 * math.tan(math.radians(20)), 0])
    assert np.allclose(right, [4 * math.tan(math.radians(20)), 0, 0])  # aspect 2, +x to the right
    ortho = om.Camera.orthographic(eye=(0, 0, 5), height=3)
    text = om.povray.engine.camera_sdl(ortho, ortho.view_matrix(), (300, 200))
    assert "orthographic" in text and "up <0,3,0>" in text and "right <4.5,0,0>" in text


def test_primitives_materials_and_povray_attributes():
    body = om.Node("body")
    body.add(om.Translation(0, 1, 0))
    body.add(om.Material(diffuse=(1, 0, 0), specular=(1, 1, 1), shininess=40))
    body.add(om.povray.Finish(phong=0.8, reflection={"metallic": True, "falloff": 2}))
    body.add(om.povray.Interior(ior=1.5))
    body.add(om.Torus(major_radius=1, minor_radius=0.3))
    body.add(om.Cylinder(radius=0.5, height=2))
    body.add(om.Cone(radius=0.5, height=2))
    body.add(om.Disk(radius=2))
    body.add(om.Rectangle(size=(2, 4)))
    text, engine = scene_sdl(_scene(om.PointLight(position=(5, 5, 5)), body))
    assert "torus { 1, 0.3 }" in text
    assert "cylinder { <0,-1,0>, <0,1,0>, 0.5 }" in text
    assert "cone { <0,-1,0>, 0.5, <0,1,0>, 0 }" in text
    assert "disc { <0,0,0>, <0,1,0>, 2 }" in text
    assert "polygon { 4, <-1,0,-2>, <1,0,-2>, <1,0,2>, <-1,0,2> }" in text
    assert text.count("matrix <1,0,0,0,1,0,0,0,1,0,1,0>") == 5
    assert "phong 0.8 reflection { metallic falloff 2 }" in text
    assert "interior { ior 1.5 }" in text
    # red stays red after sRGB -> linear (black channels are lifted to 1e-4 to carry the grey ambient term)
    pigment = [float(v) for v in re.search(r"pigment \{ rgb <([^>]*)> \}", text).group(1).split(",")]
    assert pigment[0] == 1 and max(pigment[1:]) <= 1e-4
    assert "light_source { <5,5,5> rgb <1,1,1> }" in text
    assert text.count("#declare OM_T") == 1  # one texture shared by all five objects


def test_other_engines_ignore_povray_attributes():
    from omnirender.core import Engine

    class Counting(Engine):
        service = "count"

    seen = []

    class Count(om.ShapePainter):
        service = "count"
        target = om.Sphere

        def exec(self, shape, engine):
            seen.append(shape)

    e = Counting()
    e.install(Count())
    e.evaluate([om.povray.Finish(phong=1), om.povray.Pigment(color=(1, 0, 0)), om.povray.Raw("x"), om.Sphere()])
    assert len(seen) == 1


def test_light_conversions():
    lights = [
        om.PointLight(position=(0, 4, 0), constant=1, quadratic=0.25),
        om.SpotLight(position=(0, 4, 0), direction=(0, -1, 0), cutoff=30, exponent=2),
        om.DirectionalLight(direction=(0, -1, 0), color=(1, 0.5, 0.25)),
        om.AmbientLight(color=(1, 1, 1), intensity=0.2),
    ]
    text, _ = scene_sdl(_scene(*lights, om.Sphere()))
    # 1/(1 + 0.25 d^2) == 0.5 * 2 / (1 + (d/2)^2)
    assert "light_source { <0,4,0> rgb <0.5,0.5,0.5> fade_distance 2 fade_power 2 }" in text
    assert "spotlight point_at <0,3,0>" in text and "falloff 30 tightness 2" in text
    assert "light_source { <0,100000,0> rgb <1,0.5,0.25> parallel point_at <0,0,0> }" in text
    assert "ambient_light rgb <0.4,0.4,0.4>" in text  # GL's global ambient 0.2 + the ambient light
    assert "headlight" not in text


def test_a_scene_without_lights_gets_the_gl_headlight():
    text, _ = scene_sdl(_scene(om.Sphere()))
    m = re.search(r"light_source \{ <([^>]*)> rgb <1,1,1> parallel point_at <0,0,0> shadowless \} // headlight", text)
    towards = np.array([float(v) for v in m.group(1).split(",")])
    assert np.allclose(
        towards / np.linalg.norm(towards), np.array([-0.25, 0.35, 1.0]) / np.linalg.norm([-0.25, 0.35, 1])
    )
    assert "ambient_light rgb <0.2,0.2,0.2>" in text


def test_mesh2_is_complete_and_vectorised():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=np.float32)
    i = np.array([[0, 1, 2], [1, 3, 2]])
    c = np.array([[1, 0, 0, 1], [0, 1, 0, 1], [1, 0, 0, 0.5], [1, 0, 0, 1]])
    text = mesh2_text(v, i, normals=np.tile([0, 0, 1], (4, 1)), texcoords=v[:, :2], colors=c, finish="F")
    assert "vertex_vectors { 4,\n<0,0,0>,\n<1,0,0>,\n<0,1,0>,\n<1,1,0>\n}" in text
    assert "normal_vectors { 4," in text and "uv_vectors { 4," in text
    assert "texture_list { 3," in text  # distinct colours only
    assert re.search(r"face_indices \{ 2,\n<0,1,2>,\d,\d,\d,\n<1,3,2>,\d,\d,\d\n\}", text)
    with pytest.raises(sdl.SDLError, match="out of range"):
        mesh2_text(v, np.array([[0, 1, 7]]))


def test_triangle_set_with_vertex_colours_and_flat_shading():
    mesh = om.TriangleSet(
        vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], indices=[[0, 1, 2]], colors=[[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    )
    text, _ = scene_sdl(_scene(om.DrawStyle(shading="flat"), mesh))
    assert "mesh2 {" in text and "texture_list { 3," in text and "normal_vectors" not in text
    assert "#declare OM_F0 = finish" in text


def test_names_and_paths_cannot_inject_directives(tmp_path):
    with pytest.raises(ValueError, match="control characters"):  # newlines never reach the SDL
        om.Node('x"\n#include "passwd"\n#declare A = 1;')
    evil = 'x" #include "passwd" #declare A = 1;'
    s = om.Node(evil)
    s.add(om.Camera.look_at(eye=(0, 0, 5)))
    child = s.add(om.Node('b"#c'))
    img = tmp_path / 'bad"name\n#x.png'
    from PIL import Image as PILImage

    PILImage.fromarray(np.zeros((2, 2, 3), np.uint8)).save(img, format="PNG")
    child.add(om.Color(1, 1, 1))  # a white base colour: the texture's file is used as it is
    child.add(om.Texture(str(img)))
    child.add(om.Sphere())
    text, engine = scene_sdl(s)
    directives = [ln for ln in text.splitlines() if ln.lstrip().startswith("#")]
    assert all(ln.startswith(("#version", "#declare OM_")) for ln in directives), directives
    assert 'passwd"' not in text and "#include" not in text
    assert '"om_tex0.png"' in text and engine.resources == [("om_tex0.png", str(img))]
    for bad in ("phong 1 } #declare", "a b"):
        with pytest.raises(sdl.SDLError):
            om.povray.Finish(**{bad: 1})
    with pytest.raises(sdl.SDLError):
        om.povray.Pigment(pattern='checker }\n#include "x"')
    with pytest.raises(sdl.SDLError):
        om.povray.Finish(phong="0.5 } #include")
    with pytest.raises(sdl.SDLError):
        sdl.file_name('a"b')


def test_export_writes_sdl_and_texture_images(tmp_path):
    tex = np.zeros((4, 4, 3), np.uint8)
    tex[:, :2] = 255
    s = _scene(om.Texture(tex), om.Rectangle(size=(2, 2)))
    path = om.export(s, tmp_path / "scene.pov")
    text = path.read_text()
    assert text.startswith("// omnirender scene for POV-Ray 3.7\n#version 3.7;")
    # named with the export folder, so the file renders from any working folder
    assert f'"{tmp_path.resolve()}/scene_tex0.png"' in text and (tmp_path / "scene_tex0.png").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.pov", "scene_tex0.png"]  # no temp files left


@pytest.mark.povray
def test_an_exported_pov_file_renders_standalone_from_another_folder(tmp_path):
    import subprocess

    from omnirender.povray.runner import find_povray

    tex = np.zeros((4, 4, 3), np.uint8)
    tex[:, :2] = (255, 0, 0)
    s = _scene(om.Background((0.2, 0.6, 0.3)), om.Color(1, 1, 1), om.Texture(tex, filter="nearest"))
    s.add(om.Rectangle(size=(0.5, 0.5)))
    (tmp_path / "out").mkdir()
    path = om.export(s, tmp_path / "out" / "scene.pov")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    cmd = [find_povray(), f"+I{path}", f"+O{elsewhere / 'image.png'}", "+W64", "+H48", "-D", "-V", "+FN"]
    subprocess.run(cmd, cwd=elsewhere, capture_output=True, timeout=60, check=True)
    from PIL import Image as PILImage

    img = np.asarray(PILImage.open(elsewhere / "image.png").convert("RGB"))
    assert tuple(img[2, 2]) == pytest.approx((51, 153, 77), abs=3)  # the scene's background, opaque


def test_clip_planes_and_raw_text():
    s = _scene(
        om.ClipPlane(normal=(0, 1, 0), offset=0.5),
        om.povray.Raw("no_shadow", placement="object"),
        om.povray.Raw("#declare Trusted = 1;"),
        om.povray.GlobalSettings(radiosity={"count": 50}, max_trace_level=7),
        om.Background((0.2, 0.3, 0.4)),
        om.Fog(color=(1, 1, 1), mode="exp", density=0.1),
        om.Sphere(),
    )
    text, _ = scene_sdl(s)
    assert "clipped_by { plane { <0,-1,0>, -0.5 } }" in text
    assert "  no_shadow\n" in text and "#declare Trusted = 1;" in text
    assert "radiosity { count 50 } max_trace_level 7" in text
    assert "fog { fog_type 1 distance 10 " in text


def test_missing_program_says_how_to_install(monkeypatch):
    monkeypatch.setenv("PATH", "/nonexistent")
    ok, why = om.povray.available()
    assert not ok and "apt-get install povray" in why
    with pytest.raises(POVRayError, match="apt-get install povray"):
        om.render(_scene(om.Sphere()), engine="povray", size=(8, 8))


def test_error_lines_are_extracted_and_unwrapped():
    output = (
        "==== [Parsing...] ====\nFile 'scene.pov' line 12: Parse Error: No matching } in 'texture', undeclared\n"
        " identifier 'finsh' found instead\nFatal error in parser: Cannot parse input.\nRender failed\n"
    )
    lines = error_lines(output)
    assert lines[0] == (
        "File 'scene.pov' line 12: Parse Error: No matching } in 'texture', undeclared identifier 'finsh' found instead"
    )
    assert "Fatal error in parser: Cannot parse input." in lines


def test_engine_rejects_bad_size():
    with pytest.raises(ValueError, match="size"):
        POVRayEngine((0, 10))


def test_textured_primitives_are_tessellated_with_uvs():
    text, engine = scene_sdl(_scene(om.Texture(np.zeros((2, 2, 3), np.uint8)), om.Sphere(), om.Box()))
    assert text.count("mesh2 {") == 2 and text.count("uv_vectors") == 2
    assert 'uv_mapping image_map { png "om_tex0.png" interpolate 2 }' in text
    assert "sphere {" not in text and len(engine.resources) == 1  # one image shared by both


def test_component_lists_and_unknown_options():
    text, _ = scene_sdl([om.Camera.look_at(eye=(0, 0, 5)), om.Sphere(radius=2)])
    assert "sphere { <0,0,0>, 2 }" in text
    with pytest.raises(TypeError, match="unknown option"):
        scene_sdl([om.Sphere()], spp=3)
    s = _scene(om.Node("a", [om.Sphere()], groups=["debug"]), om.Node("b", [om.Box()]))
    text, _ = scene_sdl(s, mask="!debug")
    assert "sphere" not in text and "box" in text


def test_light_switch_makes_light_groups():
    a, b = om.PointLight(position=(5, 0, 0)), om.PointLight(position=(-5, 0, 0))
    only_a = om.Node("only_a", [om.LightSwitch(on=True, lights=[a]), om.Sphere()])
    dark = om.Node("dark", [om.LightSwitch(on=False), om.Box()])
    text, _ = scene_sdl(_scene(a, b, only_a, dark, om.Cylinder()))
    groups = re.findall(r"light_group \{\n(.*?)global_lights off\n\}", text, re.S)
    assert len(groups) == 2
    assert "<5,0,0>" in groups[0] and "<-5,0,0>" not in groups[0] and "sphere" in groups[0]
    assert "light_source" not in groups[1] and "box" in groups[1]
    assert "cylinder" not in "".join(groups)  # unswitched objects see every light


def test_engine_micro_program():
    e = POVRayEngine((320, 240))
    mat, rot, torus = om.Material(diffuse=(1, 0, 0)), om.Rotation(180, (0, 1, 0)), om.Torus()
    e.push(mat)
    e.push(rot)
    e.eval(torus)
    e.pop(rot.category)
    e.pop(mat.category)
    e.eval(om.Sphere())
    text = e.sdl()
    assert "torus { 1, 0.25 }" in text and re.search(r"matrix <-1,0,[-0-9.e]+,0,1,0,[-0-9.e]+,0,-1,0,0,0>", text)
    assert text.count("#declare OM_T") == 2  # red for the torus, the default grey for the sphere
    assert e.context.is_empty()


def test_blocks_with_arguments_and_bare_argument_values_are_rejected():
    media = {"absorption": (0.2, 0.4, 0.6), "scattering": om.povray.Block(1, (0.1, 0.1, 0.1), extinction=0.5)}
    interior = om.povray.Interior(ior=1.3, media=media)
    assert interior.sdl() == (
        "interior { ior 1.3 media { absorption <0.2,0.4,0.6> scattering { 1, <0.1,0.1,0.1> extinction 0.5 } } }"
    )
    with pytest.raises(sdl.SDLError, match=r"scattering is a POV-Ray block with arguments.*om\.povray\.Block"):
        om.povray.Interior(media={"scattering": (1, 0.1)})
    with pytest.raises(sdl.SDLError, match="not a valid POV-Ray keyword"):
        om.povray.Interior(media={"scattering": om.povray.Block(1, "x } #include")})
    with pytest.raises(sdl.SDLError, match="block argument"):
        om.povray.Interior(media={"scattering": om.povray.Block(1, {"a": 1})})
    with pytest.raises(sdl.SDLError, match="not a valid POV-Ray keyword"):
        om.povray.Finish(**{"$args": [1]})  # arguments only inside nested blocks
    # a Block is plain data: it survives a scene-file round trip and writes the same SDL
    from omnirender.scene import files

    loaded = files.loads(files.dumps(om.Node("s", [interior]))).components[0]
    assert loaded.sdl() == interior.sdl()


def test_node_at_line_maps_sdl_lines_to_the_node_that_wrote_them():
    bad = om.Node("bad", [om.Material(diffuse=(1, 0, 0)), om.povray.Raw("sphere { 0, 1 finsh { } }")])
    s = _scene(om.Node("good", [om.Sphere()]), bad, om.Node("after", [om.Box()]))
    text, _ = scene_sdl(s)
    lines = text.splitlines()
    raw_line = next(i for i, ln in enumerate(lines, start=1) if "finsh" in ln)
    box_line = next(i for i, ln in enumerate(lines, start=1) if ln.strip().startswith("box {"))
    assert om.povray.api.node_at_line(text, raw_line) == "/scene/bad"
    assert om.povray.api.node_at_line(text, box_line) == "/scene/after"
    assert om.povray.api.node_at_line(text, 1) is None  # the header belongs to no node
    declared = next(i for i, ln in enumerate(lines, start=1) if ln.startswith("#declare OM_T"))
    assert om.povray.api.node_at_line(text, declared) == "/scene/good"


def test_missing_texture_files_name_the_node_and_the_fix(tmp_path):
    for name in ("gone.png", "gone.bmp"):  # a format POV-Ray reads itself, and one converted to PNG
        s = _scene(om.Node("box", [om.Texture(str(tmp_path / name)), om.Box()]))
        with pytest.raises(FileNotFoundError, match=r"in node /scene/box does not exist; check the path or pass"):
            scene_sdl(s)
        with pytest.raises(FileNotFoundError, match="/scene/box"):
            om.export(s, tmp_path / "x.pov")
        assert list(tmp_path.iterdir()) == []


def _textured_scene():
    a = np.zeros((4, 4, 3), np.uint8)
    b = np.full((4, 4, 3), 200, np.uint8)
    return _scene(
        om.Node("a", [om.Texture(a), om.Rectangle(size=(2, 2))]),
        om.Node("b", [om.Texture(b), om.Rectangle(size=(1, 1))]),
    )


def test_export_is_all_or_nothing_when_a_texture_fails_midway(tmp_path, monkeypatch):
    from omnirender.povray import api

    target = tmp_path / "scene.pov"
    target.write_text("old scene")
    (tmp_path / "scene_tex0.png").write_bytes(b"old texture")
    real = api._write_resource
    calls = []

    def failing(data, tmp):
        calls.append(tmp)
        if len(calls) == 2:  # the second image: half written, then the disk is full
            tmp.write_bytes(b"half")
            raise OSError(28, "No space left on device")
        real(data, tmp)

    monkeypatch.setattr(api, "_write_resource", failing)
    with pytest.raises(OSError, match="No space"):
        om.export(_textured_scene(), target)
    assert target.read_text() == "old scene" and (tmp_path / "scene_tex0.png").read_bytes() == b"old texture"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.pov", "scene_tex0.png"]  # no temp files, no tex1


def test_export_is_atomic_when_the_sdl_write_fails_midway(tmp_path, monkeypatch):
    import builtins

    from omnirender.povray import api

    target = tmp_path / "scene.pov"
    target.write_text("old scene")

    class Half:
        def __init__(self, fh):
            self.fh = fh

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.fh.close()

        def write(self, text):
            self.fh.write(text[: len(text) // 2])
            self.fh.flush()
            raise OSError(28, "No space left on device")

    monkeypatch.setattr(api, "open", lambda *a, **k: Half(builtins.open(*a, **k)), raising=False)
    with pytest.raises(OSError, match="No space"):
        om.export(_textured_scene(), target)
    assert target.read_text() == "old scene"
    assert [p.name for p in tmp_path.iterdir()] == ["scene.pov"]


def test_povray_runs_with_home_set_to_its_temporary_folder(tmp_path, monkeypatch):
    from omnirender import process
    from omnirender.povray import runner

    seen = {}

    def fake_popen(args, cwd=None, env=None, **kw):
        seen.update(cwd=cwd, home=env["HOME"])
        raise OSError("stop here")

    monkeypatch.setenv("HOME", "/root")
    monkeypatch.setattr(runner, "find_povray", lambda: "/usr/bin/povray")
    monkeypatch.setattr(process.subprocess, "Popen", fake_popen)
    with pytest.raises(POVRayError, match="cannot start"):
        runner.run_povray(["+Iscene.pov"], tmp_path, progress=False)
    assert seen == {"cwd": tmp_path, "home": str(tmp_path)}
