"""RenderMan RIB export: parse the output back with a small tokenizer and check its structure."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import omnirender as om
from omnirender.formats import rib

_TOKEN = re.compile(
    r'"([^"]*)"|(\[)|(\])|([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|([A-Za-z_][A-Za-z0-9_]*)|(#[^\n]*)|(\S)'
)


def tokenize(text: str) -> list[tuple[str, object]]:
    """RIB tokens: ("str", s), ("[", None), ("]", None), ("num", float), ("req", name); comments dropped."""
    out: list[tuple[str, object]] = []
    for m in _TOKEN.finditer(text):
        s, lb, rb, num, name, comment, other = m.groups()
        if comment is not None:
            continue
        if other is not None:
            raise AssertionError(f"unexpected character {other!r} in RIB")
        if s is not None:
            out.append(("str", s))
        elif lb:
            out.append(("[", None))
        elif rb:
            out.append(("]", None))
        elif num is not None:
            out.append(("num", float(num)))
        else:
            out.append(("req", name))
    return out


def parse(text: str) -> list[tuple[str, list]]:
    """Requests with their arguments; arrays become Python lists."""
    requests: list[tuple[str, list]] = []
    array: list | None = None
    for kind, value in tokenize(text):
        if kind == "req":
            assert array is None, f"request {value} inside an array"
            requests.append((value, []))
        elif kind == "[":
            assert array is None, "nested array"
            array = []
        elif kind == "]":
            assert array is not None, "unbalanced ]"
            requests[-1][1].append(array)
            array = None
        elif array is not None:
            array.append(value)
        else:
            requests[-1][1].append(value)
    assert array is None, "unterminated array"
    return requests


def _balanced(requests) -> None:
    stack = []
    for name, _ in requests:
        if name.endswith("Begin"):
            stack.append(name[:-5])
        elif name.endswith("End"):
            assert stack and stack.pop() == name[:-3], f"unbalanced {name}"
    assert not stack


def _scene() -> om.Node:
    scene = om.Node("scene")
    scene.add(om.Camera.look_at(eye=(4, 3, 6), center=(0, 0, 0), fov=35))
    scene.add(om.PointLight(position=(5, 5, 5)))
    scene.add(om.DirectionalLight(direction=(0, -1, 0)))
    scene.add(om.SpotLight(position=(0, 4, 0), direction=(0, -1, 0), cutoff=20))
    scene.add(om.AmbientLight(intensity=0.2))
    floor = scene.add(om.Node("floor", [om.Material(diffuse=(0.8, 0.8, 0.8)), om.Box(size=(10, 0.1, 10))]))
    assert floor
    body = scene.add(om.Node("body"))
    body.add(om.Translation(0, 1, 0))
    body.add(om.Material(diffuse=(1, 0.4, 0.6), specular=(1, 1, 1), shininess=40, opacity=0.5))
    body.add(om.Torus(major_radius=1, minor_radius=0.3))
    body.add(om.Sphere(center=(0, 1, 0), radius=0.5))
    parts = body.add(om.Node("parts"))
    parts.add(om.Translation(2, 0, 0))
    parts.add(om.rib.Surface("wood", Kd=0.7, ringscale=[10], **{"uniform string mapname": "grain.tex"}))
    parts.add(om.Cylinder(radius=0.3, height=1))
    parts.add(om.Cone(radius=0.4, height=0.8))
    parts.add(om.Disk(radius=0.5))
    parts.add(om.Rectangle(size=(1, 2)))
    parts.add(om.TriangleSet(vertices=[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], indices=[(0, 1, 2), (0, 2, 3)]))
    parts.add(om.LineSet(vertices=[(0, 0, 0), (1, 1, 1)]))
    parts.add(om.PointSet(vertices=[(0, 0, 0), (1, 1, 1), (2, 2, 2)]))
    return scene


def test_rib_structure(tmp_path):
    path = om.export(_scene(), tmp_path / "scene.rib", size=(400, 300))
    requests = parse(path.read_text())
    names = [n for n, _ in requests]
    _balanced(requests)
    assert names.index("Projection") < names.index("WorldBegin") < names.index("WorldEnd") == len(names) - 1
    args = dict(requests)
    assert args["Format"] == [400.0, 300.0, 1.0]
    assert args["Projection"] == ["perspective", "fov", [35.0]]
    assert args["Display"][0] == "scene.tif"
    assert names.count("AttributeBegin") == names.count("AttributeEnd")
    # one block per node (scene, floor, body, parts) and one per shape
    identifiers = [a[2][0] for n, a in requests if n == "Attribute" and a[0] == "identifier"]
    assert identifiers == ["scene", "floor", "body", "parts"]
    for quadric in ("Sphere", "Torus", "Cylinder", "Cone", "Polygon", "Curves", "Points"):
        assert names.count(quadric) == 1, quadric
    assert names.count("Disk") == 2 + 1 + 1  # cylinder caps, cone base, the disk
    assert names.count("LightSource") == 4
    lights = sorted(a[0] for n, a in requests if n == "LightSource")
    assert lights == ["ambientlight", "distantlight", "pointlight", "spotlight"]
    spot = next(a for n, a in requests if n == "LightSource" and a[0] == "spotlight")
    assert spot[spot.index("coneangle") + 1] == [pytest.approx(math.radians(20), rel=1e-6)]
    for name, a in requests:
        if name in ("ConcatTransform", "Transform"):
            assert len(a) == 1 and len(a[0]) == 16 and a[0][15] == 1.0
        if name == "PointsPolygons":
            nverts, verts = a[0], a[1]
            assert set(nverts) == {3.0} and len(verts) == 3 * len(nverts)
            p = a[a.index("P") + 1]
            assert len(p) % 3 == 0 and max(verts) < len(p) // 3
            n = a[a.index("N") + 1]
            assert len(n) == len(p)
    surfaces = [a for n, a in requests if n == "Surface"]
    assert ["matte", "Ka", [0.25], "Kd", [1.0]] in surfaces
    assert any(s[0] == "plastic" and s[s.index("roughness") + 1] == [pytest.approx(1 / 40)] for s in surfaces)
    wood = [s for s in surfaces if s[0] == "wood"]
    assert len(wood) == 7 and wood[0] == [
        "wood",
        "Kd",
        [0.7],
        "ringscale",
        [10.0],
        "uniform string mapname",
        ["grain.tex"],
    ]
    assert ["Opacity", [[0.5, 0.5, 0.5]]] == [n_a for n_a in ([n, a] for n, a in requests) if n_a[0] == "Opacity"][0]


def test_camera_transform_maps_the_eye_to_the_origin_and_the_centre_onto_plus_z():
    requests = parse(rib.to_text(_scene()))
    m = np.array(dict(requests)["Transform"][0]).reshape(4, 4).T  # row-vector order back to ours
    eye = m @ np.array([4, 3, 6, 1.0])
    centre = m @ np.array([0, 0, 0, 1.0])
    np.testing.assert_allclose(eye[:3], 0, atol=1e-6)
    np.testing.assert_allclose(centre[:3], (0, 0, np.sqrt(61)), atol=1e-5)  # RenderMan looks down +z
    up = m @ np.array([0, 10, 0, 1.0])
    assert up[1] > centre[1]  # world up is camera up


def test_quadrics_are_turned_from_z_up_to_y_up():
    requests = parse(rib.to_text(om.Node("s", [om.Translation(1, 2, 3), om.Cylinder(radius=0.5, height=2)])))
    names = [n for n, _ in requests]
    m = np.array(requests[names.index("Cylinder") - 3][1][0]).reshape(4, 4).T
    # the cylinder's axis (RenderMan z) ends up along world +y, at the translation
    np.testing.assert_allclose(m[:3, :3] @ (0, 0, 1), (0, 1, 0), atol=1e-12)
    np.testing.assert_allclose(m[:3, 3], (1, 2, 3))
    assert dict(requests)["Cylinder"] == [0.5, -1.0, 1.0, 360.0]


def test_orthographic_camera_and_tall_images():
    ortho = om.Node("s", [om.Camera.orthographic(eye=(0, 0, 5), height=4), om.Sphere()])
    args = dict(parse(rib.to_text(ortho, size=(200, 100))))
    assert args["Projection"] == ["orthographic"] and args["ScreenWindow"] == [-4.0, 4.0, -2.0, 2.0]
    tall = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5), fov=40), om.Sphere()])
    fov = dict(parse(rib.to_text(tall, size=(100, 200))))["Projection"][2][0]
    assert fov == pytest.approx(math.degrees(2 * math.atan(math.tan(math.radians(20)) * 0.5)), rel=1e-6)


def test_strings_cannot_inject_requests():
    with pytest.raises(ValueError, match="quote"):
        om.rib.Surface('wood" WorldEnd "')
    with pytest.raises(ValueError, match="parameter name"):
        om.rib.Surface("wood", **{"Kd]": 1})
    with pytest.raises(ValueError, match="quote"):
        om.rib.Surface("wood", mapname='a"b')
    with pytest.raises(ValueError, match="quote"):
        rib.to_text(om.Node("s", [om.Sphere()]), display='x" "y')


def test_om_rib_is_the_surface_attribute():
    assert om.rib.Surface is rib.Surface
    s = om.rib.Surface("metal", Ks=0.9)
    assert s.parameters() == {"name": "metal", "Ks": 0.9}
    assert s.rib() == 'Surface "metal" "Ks" [0.9]'


def test_color_after_material_replaces_its_colour():
    scene = om.Node("s", [om.Material(diffuse=(1, 0, 0), opacity=0.5), om.Color(0, 0, 1), om.Sphere()])
    args = dict(parse(rib.to_text(scene)))
    assert args["Color"] == [[0.0, 0.0, 1.0]] and args["Opacity"] == [[0.5, 0.5, 0.5]]
    assert args["Surface"][0] == "matte"


def test_odd_node_names_are_sanitised_not_refused():
    scene = om.Node('scene"\\WorldEnd', [om.Node('a"b\\c"d\\', [om.Sphere()])])
    text = rib.to_text(scene)
    requests = [name for name, _ in parse(text)]
    assert requests.count("WorldEnd") == 1 and requests[-1] == "WorldEnd"  # nothing injected
    names = [args[2] for name, args in parse(text) if name == "Attribute" and args[:2] == ["identifier", "name"]]
    assert names == [["scene__WorldEnd"], ["a_b_c_d_"]]
    with pytest.raises(ValueError, match="control characters"):  # newlines and NULs never reach an exporter
        om.Node("scene\nWorldEnd")
    assert 'Display "scene__WorldEnd.tif"' in text
    assert "# scene__WorldEnd: written by omnirender" in text


class _Blob(om.Shape):
    """A shape no engine knows (no painter, no simplifier)."""

    __slots__ = ()


def test_unknown_shapes_raise_by_default_and_warn_on_request():
    scene = om.Node("s", [om.Node("odd", [_Blob()])])
    with pytest.raises(om.NoHandlerError):
        rib.to_text(scene)
    with pytest.warns(UserWarning):
        rib.to_text(scene, on_missing="warn")


def test_a_write_failing_midway_leaves_the_existing_file_unchanged(tmp_path, monkeypatch):
    import contextlib

    target = tmp_path / "scene.rib"
    target.write_text("old file")
    real = rib.atomic_write

    @contextlib.contextmanager
    def half_then_full_disk(path, mode="w", **kw):
        with real(path, mode, **kw) as fh:

            class Half:
                def write(self, data):
                    fh.write(data[: len(data) // 2])
                    fh.flush()
                    raise OSError(28, "No space left on device")

            yield Half()

    monkeypatch.setattr(rib, "atomic_write", half_then_full_disk)
    with pytest.raises(OSError, match="No space"):
        om.export(om.Node("s", [om.Sphere()]), target)
    assert target.read_text() == "old file"
    assert [p.name for p in tmp_path.iterdir()] == ["scene.rib"]


# -- ClipPlane: a ClippingPlane option for the whole scene, clipped geometry for a subgraph --------------

CLIP_CAMERA = om.Camera.look_at(eye=(0, 1, 6), center=(0, 0, 0))


def _world_geometry(requests) -> list[tuple[str, np.ndarray]]:
    """(request, world points (K, 3)) of every PointsPolygons / Curves / Points, following the block transforms."""
    out = []
    stack, current = [], np.eye(4)
    world = False
    for name, args in requests:
        if name == "WorldBegin":
            world = True
        if not world:
            continue
        if name == "AttributeBegin":
            stack.append(current)
        elif name == "AttributeEnd":
            current = stack.pop()
        elif name == "ConcatTransform":
            current = current @ np.array(args[0]).reshape(4, 4).T  # RIB row-vector order back to ours
        elif name in ("PointsPolygons", "Curves", "Points"):
            p = np.array(args[args.index("P") + 1], np.float64).reshape(-1, 3)
            out.append((name, p @ current[:3, :3].T + current[:3, 3]))
    return out


def _renderman_keeps(args, points) -> np.ndarray:
    """RI spec: ClippingPlane x y z nx ny nz removes the points on the side the normal points to."""
    p0, n = np.array(args[:3]), np.array(args[3:])
    return (np.asarray(points) - p0) @ n <= 1e-9


def test_a_plane_for_the_whole_scene_is_a_clipping_plane_option_keeping_the_same_side():
    clip = om.ClipPlane((1, 2, 0), 0.3)
    scene = om.Node("scene", [CLIP_CAMERA, om.Translation(0, 0.5, 0), om.Rotation(40, (0, 0, 1)), clip])
    scene.add(om.Node("ball", [om.Sphere(radius=1.0)]))
    requests = parse(rib.to_text(scene))
    _balanced(requests)
    names = [n for n, _ in requests]
    assert names.count("ClippingPlane") == 1
    assert names.index("Transform") < names.index("ClippingPlane") < names.index("WorldBegin")  # an option, in world
    assert "Sphere" in names and "PointsPolygons" not in names  # the quadric stays a quadric
    args = dict(requests)["ClippingPlane"]
    # the same half-space as the GL engine's: world plane of the model matrix where the plane was added
    m = om.Translation(0, 0.5, 0).matrix @ om.Rotation(40, (0, 0, 1)).matrix
    samples = np.random.default_rng(1).uniform(-3, 3, (500, 3))
    local = samples @ np.linalg.inv(m)[:3, :3].T + np.linalg.inv(m)[:3, 3]
    assert np.array_equal(_renderman_keeps(args, samples), clip.keeps(local))
    assert abs(np.linalg.norm(args[3:]) - 1.0) < 1e-6


def test_a_plane_in_a_subgraph_clips_the_geometry_there_only():
    cut = om.Node("cut", [om.Translation(1, 0, 0), om.ClipPlane((0, 1, 0), 0.2), om.Scaling(0.5)])
    cut.add(om.Sphere(radius=1.0))
    cut.add(om.LineSet(vertices=[(0, -1, 0), (0, 1, 0), (-1, 0.8, 0), (1, 0.8, 0)]))
    cut.add(om.PointSet(vertices=[(0, -1, 0), (0, 1, 0)]))
    cut.add(om.Node("gone", [om.Translation(0, -3, 0), om.Cylinder()]))  # entirely below the plane
    scene = om.Node("scene", [CLIP_CAMERA, om.Node("free", [om.Sphere(radius=0.3)]), cut, om.Torus()])
    text = rib.to_text(scene)
    requests = parse(text)
    _balanced(requests)
    names = [n for n, _ in requests]
    assert "ClippingPlane" not in names  # not expressible as an option: it must not clip "free" or the torus
    assert names.count("Sphere") == 1 and names.count("Torus") == 1  # the unclipped quadrics stay quadrics
    assert "Cylinder" not in names and names.count("Disk") == 0  # clipped away entirely: nothing written
    assert "# ClipPlane normal [0 1 0] offset 0.2 (world)" in text
    geometry = dict(_world_geometry(requests))
    # the plane y >= 0.2 sits under Translation(1, 0, 0) only: world y >= 0.2; the scaling came after it
    sphere = geometry["PointsPolygons"]
    assert sphere[:, 1].min() == pytest.approx(0.2, abs=1e-6) and sphere[:, 1].max() == pytest.approx(0.5, abs=1e-3)
    radii = np.linalg.norm(sphere - (1, 0, 0), axis=1)  # cut points lie on chords of the tessellation
    assert radii.max() <= 0.5 + 1e-6 and radii.min() > 0.49
    curves = geometry["Curves"]
    assert curves[:, 1].min() == pytest.approx(0.2) and len(curves) == 4  # the vertical one is shortened
    np.testing.assert_allclose(geometry["Points"], [(1, 0.5, 0)])  # the point below the plane is dropped
    polygons = next(a for n, a in requests if n == "PointsPolygons")
    assert len(polygons[polygons.index("N") + 1]) == len(polygons[polygons.index("P") + 1])  # normals follow


def test_a_plane_added_after_shapes_clips_only_what_follows():
    scene = om.Node("scene", [CLIP_CAMERA, om.Sphere(radius=0.5), om.ClipPlane((0, -1, 0), 0.0), om.Sphere(radius=1.0)])
    requests = parse(rib.to_text(scene))
    names = [n for n, _ in requests]
    assert "ClippingPlane" not in names  # an option would also clip the first sphere
    assert names.count("Sphere") == 1
    assert dict(_world_geometry(requests))["PointsPolygons"][:, 1].max() <= 1e-9  # y <= 0 kept


def test_triangle_sets_keep_colours_and_texture_coordinates_when_clipped():
    tri = om.TriangleSet(
        vertices=[(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)],
        indices=[(0, 1, 2), (0, 2, 3)],
        colors=[(1, 0, 0, 1), (1, 0, 0, 1), (0, 0, 1, 1), (0, 0, 1, 1)],
        texcoords=[(0, 0), (1, 0), (1, 1), (0, 1)],
    )
    scene = om.Node("scene", [CLIP_CAMERA, om.Node("n", [om.ClipPlane((0, 1, 0), 0.0), tri])])
    requests = parse(rib.to_text(scene))
    args = next(a for n, a in requests if n == "PointsPolygons")
    p = np.array(args[args.index("P") + 1]).reshape(-1, 3)
    cs = np.array(args[args.index("Cs") + 1]).reshape(-1, 3)
    st = np.array(args[args.index("st") + 1]).reshape(-1, 2)
    assert len(p) == len(cs) == len(st) == 5 and p[:, 1].min() == 0.0
    on_cut = np.isclose(p[:, 1], 0.0)
    np.testing.assert_allclose(cs[on_cut], [[0.5, 0, 0.5]] * 3)  # half way from red to blue
    np.testing.assert_allclose(st[on_cut, 1], 0.5)  # t flipped for RenderMan: 1 - 0.5


def test_removing_a_whole_scene_plane_before_more_shapes_is_refused():
    clip = om.ClipPlane((0, 1, 0), 0.0)
    engine = rib.RIBEngine()
    engine.on_enter(om.Node("scene"))  # inside the root node, before any shape: a whole-scene plane
    engine.add(clip)
    assert len(engine.global_clips) == 1
    engine.remove(clip)
    with pytest.raises(ValueError, match="ClipPlane in a node around the shapes"):
        engine.eval(om.Sphere())


def test_area_lights_are_area_light_sources_on_their_polygon(tmp_path):
    root = om.Node("scene", [om.Camera.look_at((0, 3, 6), (0, 0, 0))])
    root.add(om.RectLight(position=(0, 2, 0), direction=(0, -1, 0), width=2.0, height=1.0, intensity=3.0))
    root.add(om.DiscLight(position=(1, 2, 0), direction=(0, -1, 0), radius=0.25, two_sided=True))
    root.add(om.Box())
    text = om.export(root, tmp_path / "area.rib").read_text()
    assert text.count('AreaLightSource "arealight"') == 2 and "Sides 2" in text
    block = text[text.index('AreaLightSource "arealight" 1') :]
    block = block[block.index('Polygon "P" [') + len('Polygon "P" [') :]
    corners = np.array([float(v) for v in block[: block.index("]")].split()]).reshape(-1, 3)
    assert corners.shape == (4, 3) and np.allclose(corners[:, 1], 2.0)
    assert np.ptp(corners[:, 0]) == pytest.approx(2.0) and np.ptp(corners[:, 2]) == pytest.approx(1.0)
