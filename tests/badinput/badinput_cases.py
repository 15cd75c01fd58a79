"""The bad-input corpus: hostile, malformed, extreme and tricky inputs, each a small function.

Every case runs in its own process (``badinput_runner.py``).  ``kind``:
``"refuse"`` (the default) must raise a clear error whose message contains the
case's ``words``; ``"handle"`` must complete and pass the case's own checks
(``assert``); ``"either"`` may do one or the other.  Categories follow the
bad-input run of issue 17: scene files, components, transforms and cameras,
arrays, nodes, render options and image sizes per engine, the command line,
engine content, deep graphs.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import omnirender as om


@dataclass
class Case:
    id: str
    category: str
    run: Callable[[Path], Any]
    kind: str = "refuse"
    words: tuple[str, ...] = field(default_factory=tuple)
    timeout: float = 30.0


CASES: list[Case] = []


def add(id: str, category: str, run: Callable[[Path], Any], kind: str = "refuse", words=(), timeout: float = 30.0):
    assert all(c.id != id for c in CASES), id
    CASES.append(Case(id, category, run, kind, tuple(words), timeout))


NAN, INF = float("nan"), float("inf")
HUGE_INT = 10**400


def scene(*items: Any) -> om.Node:
    return om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.PointLight(position=(3, 3, 3)), *items])


# -- components: scalar parameters -----------------------------------------------------------------
SCALARS = {
    "Sphere.radius": (om.Sphere, "radius"),
    "Box.size": (om.Box, "size"),
    "Cylinder.radius": (om.Cylinder, "radius"),
    "Cylinder.height": (om.Cylinder, "height"),
    "Cone.height": (om.Cone, "height"),
    "Torus.major_radius": (om.Torus, "major_radius"),
    "Torus.minor_radius": (om.Torus, "minor_radius"),
    "Disk.radius": (om.Disk, "radius"),
    "Rectangle.size": (om.Rectangle, "size"),
    "Text.size": (lambda **k: om.Text("hi", **k), "size"),
    "Material.shininess": (om.Material, "shininess"),
    "PointLight.intensity": (om.PointLight, "intensity"),
}
BAD_SCALARS = {
    "zero": 0,
    "negative": -1,
    "nan": NAN,
    "inf": INF,
    "1e308": 1e308,
    "1e39": 1e39,
    "bigint": HUGE_INT,
    "string": "1",
    "none": None,
    "bool": True,
    "complex": 1j,
}
NONNEGATIVE = {"Material.shininess", "PointLight.intensity"}  # 0 is valid for these
for label, (ctor, param) in SCALARS.items():
    for desc, value in BAD_SCALARS.items():
        if desc == "zero" and label in NONNEGATIVE:
            continue
        if desc == "none" and label.startswith(("Material", "PointLight")):
            continue

        def run(_tmp: Path, ctor=ctor, param=param, value=value) -> None:
            ctor(**{param: value})

        add(f"component/{label}={desc}", "components", run, words=(param,))

# -- components: vectors and colours ---------------------------------------------------------------
VECTORS = {
    "Sphere.center": lambda v: om.Sphere(center=v),
    "Translation.offset": lambda v: om.Translation(offset=v),
    "Scaling.factors": lambda v: om.Scaling(factors=v),
    "Rotation.axis": lambda v: om.Rotation(30, v),
    "PointLight.position": lambda v: om.PointLight(position=v),
    "DirectionalLight.direction": lambda v: om.DirectionalLight(direction=v),
    "Camera.eye": lambda v: om.Camera.look_at(eye=v),
    "Camera.center": lambda v: om.Camera.look_at(eye=(0, 0, 5), center=v),
    "Arrow.end": lambda v: om.Arrow(start=(0, 0, 0), end=v, radius=0.1),
}
VECTOR_WORDS = {
    "Sphere.center": "center",
    "Translation.offset": "offset",
    "Scaling.factors": "factors",
    "Rotation.axis": "axis",
    "PointLight.position": "position",
    "DirectionalLight.direction": "direction",
    "Camera.eye": "eye",
    "Camera.center": "center",
    "Arrow.end": "end",
}
BAD_VECTORS = {
    "nan": (NAN, 0, 0),
    "1e308": (1e308, 0, 0),
    "1e39": (0, 1e39, 0),
    "bigint": (HUGE_INT, 0, 0),
    "strings": ("a", "b", "c"),
    "two": (1, 2),
    "text": "abc",
    "none": None,
}
for label, make in VECTORS.items():
    for desc, value in BAD_VECTORS.items():
        if desc == "none" and label in ("Translation.offset", "Scaling.factors"):
            continue  # offset=None / factors=None mean "not given" (the positional form is used)
        add(f"vector/{label}={desc}", "components", lambda _t, m=make, v=value: m(v), words=(VECTOR_WORDS[label],))
for label, make, word in [
    ("Rotation.axis=zero", lambda: om.Rotation(30, (0, 0, 0)), "axis"),
    ("DirectionalLight.direction=zero", lambda: om.DirectionalLight(direction=(0, 0, 0)), "direction"),
    ("Arrow.zero-length", lambda: om.Arrow(start=(1, 1, 1), end=(1, 1, 1), radius=0.1), "Arrow"),
    ("Rotation.angle=nan", lambda: om.Rotation(NAN, (0, 0, 1)), "angle"),
    ("Rotation.angle=bigint", lambda: om.Rotation(HUGE_INT, (0, 0, 1)), "angle"),
    ("Rotation.angle=string", lambda: om.Rotation("90", (0, 0, 1)), "angle"),
]:
    add(f"vector/{label}", "components", lambda _t, m=make: m(), words=(word,))

COLOURS = {
    "Material.diffuse": lambda c: om.Material(diffuse=c),
    "PBRMaterial.base_color": lambda c: om.PBRMaterial(base_color=c),
    "Background.color": lambda c: om.Background(c),
    "PointLight.color": lambda c: om.PointLight(color=c),
    "Fog.color": lambda c: om.Fog(color=c),
    "Highlight.color": lambda c: om.Highlight(c),
}
BAD_COLOURS = {"above1": (2, 0, 0), "negative": (-0.1, 0, 0), "nan": (NAN, 0, 0), "five": (1, 0, 0, 1, 0), "str": "red"}
for label, make in COLOURS.items():
    for desc, value in BAD_COLOURS.items():
        add(f"colour/{label}={desc}", "components", lambda _t, m=make, v=value: m(v), words=(label.split(".")[1],))
for label, make, word in [
    ("Material.opacity=2", lambda: om.Material(opacity=2), "opacity"),
    ("Material.opacity=nan", lambda: om.Material(opacity=NAN), "opacity"),
    ("PBRMaterial.metallic=-1", lambda: om.PBRMaterial(metallic=-1), "metallic"),
    ("PBRMaterial.roughness=nan", lambda: om.PBRMaterial(roughness=NAN), "roughness"),
    ("Color.a=5", lambda: om.Color(1, 0, 0, 5), "Color"),
    ("Color.rgb=strings", lambda: om.Color("r", "g", "b"), "Color"),
    ("Tessellation.level=99", lambda: om.Tessellation(99), "level"),
    ("Tessellation.level=1.5", lambda: om.Tessellation(1.5), "level"),
    ("DrawStyle.mode=bogus", lambda: om.DrawStyle(mode="bogus"), "mode"),
    ("DrawStyle.line_width=0", lambda: om.DrawStyle(line_width=0), "line_width"),
    ("Fog.start>end", lambda: om.Fog(start=10, end=2), "Fog"),
    ("Fog.density=nan", lambda: om.Fog(density=NAN), "density"),
    ("SpotLight.cutoff=200", lambda: om.SpotLight(cutoff=200), "cutoff"),
    ("PointLight.quadratic=-1", lambda: om.PointLight(quadratic=-1), "quadratic"),
    ("ClipPlane.normal=zero", lambda: om.ClipPlane(normal=(0, 0, 0)), "normal"),
    ("ClipPlane.offset=inf", lambda: om.ClipPlane(offset=INF), "offset"),
    ("Texture.image=empty-path", lambda: om.Texture(""), "image"),
    ("Texture.image=nan", lambda: om.Texture(np.full((2, 2, 3), NAN)), "finite"),
    ("Texture.image=5-channels", lambda: om.Texture(np.zeros((2, 2, 5))), "image"),
    ("Texture.image=above-255", lambda: om.Texture(np.full((2, 2, 3), 300)), "image"),
    ("Texture.image=zero-size", lambda: om.Texture(np.zeros((0, 4, 3), np.uint8)), "image"),
    ("Texture.image=objects", lambda: om.Texture(np.array([[None, 1], [2, 3]], dtype=object)), "image"),
    (
        "Texture.image=100000x100000",
        lambda: om.Texture(np.broadcast_to(np.zeros((1, 1, 4), np.uint8), (100000, 100000, 4))),
        "pixels",
    ),
    ("Texture.wrap=bogus", lambda: om.Texture(np.zeros((2, 2, 3)), wrap="bogus"), "wrap"),
    ("PickId.id=list", lambda: om.PickId([1, 2]), "PickId"),
    ("LightSwitch.lights=strings", lambda: om.LightSwitch(lights=["lamp"]), "LightSwitch"),
]:
    add(f"attribute/{label}", "components", lambda _t, m=make: m(), words=(word,))

# -- transforms and the camera ---------------------------------------------------------------------
for label, make, word in [
    ("Matrix=zeros", lambda: om.Matrix(np.zeros((4, 4))), "singular"),
    ("Matrix=rank2", lambda: om.Matrix(np.diag([1.0, 1.0, 0.0, 1.0])), "singular"),
    ("Matrix=projective", lambda: om.Matrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 0]]), "bottom row"),
    ("Matrix=strings", lambda: om.Matrix([["a"] * 4] * 4), "Matrix"),
    ("Matrix=3x3", lambda: om.Matrix(np.eye(3)), "4x4"),
    ("Matrix=nan", lambda: om.Matrix(np.full((4, 4), NAN)), "finite"),
    ("Matrix=1e39", lambda: om.Matrix(np.diag([1e39, 1.0, 1.0, 1.0])), "Matrix"),
    ("Matrix=ragged", lambda: om.Matrix([[1, 0, 0], [0, 1, 0, 0]]), "Matrix"),
    ("Scaling=0", lambda: om.Scaling(0), "factors"),
    ("Scaling=1e-300", lambda: om.Scaling(1e-300), "factors"),
    ("Scaling=1e308", lambda: om.Scaling(1e308), "factors"),
    ("Translation=1e308", lambda: om.Translation(1e308, 0, 0), "offset"),
    ("Camera.eye=center", lambda: om.Camera.look_at(eye=(1, 1, 1), center=(1, 1, 1)), "center"),
    ("Camera.up-parallel", lambda: om.Camera.look_at(eye=(0, 5, 0), up=(0, 1, 0)), "up"),
    ("Camera.fov=0", lambda: om.Camera.look_at(eye=(0, 0, 5), fov=0), "fov"),
    ("Camera.fov=180", lambda: om.Camera.look_at(eye=(0, 0, 5), fov=180), "fov"),
    ("Camera.fov=nan", lambda: om.Camera.look_at(eye=(0, 0, 5), fov=NAN), "fov"),
    ("Camera.near=0", lambda: om.Camera.look_at(eye=(0, 0, 5), near=0), "near"),
    ("Camera.far<near", lambda: om.Camera.look_at(eye=(0, 0, 5), near=10, far=1), "near"),
    ("Camera.far=1e308", lambda: om.Camera.look_at(eye=(0, 0, 5), far=1e308), "far"),
    ("Camera.near=1e-300", lambda: om.Camera.look_at(eye=(0, 0, 5), near=1e-300), "near"),
    ("Camera.height=-1", lambda: om.Camera.orthographic(eye=(0, 0, 5), height=-1), "height"),
    ("Camera.mask=syntax", lambda: om.Camera.look_at(eye=(0, 0, 5), mask="a &"), "mask"),
    ("Camera.mask=number", lambda: om.Camera.look_at(eye=(0, 0, 5), mask=5), "mask"),
]:
    add(f"transform/{label}", "transforms and camera", lambda _t, m=make: m(), words=(word,))


def _accumulated_overflow(kind: str) -> Callable[[Path], Any]:
    def run(_tmp: Path) -> None:
        deep = om.Node("far", [om.Scaling(1e6), om.Scaling(1e6), om.Scaling(1e6), om.Sphere()])
        s = scene(deep)
        if kind == "bounds":
            om.bounds(s)
        elif kind == "pick":
            om.pick(s, pixel=(4, 3), size=(8, 6))
        elif kind == "glb":
            om.export(s, "x.glb")
        else:
            om.render(s, engine=kind, size=(8, 6))

    return run


for kind in ("bounds", "pick", "glb", "gl", "povray"):
    add(f"transform/accumulated-overflow-{kind}", "transforms and camera", _accumulated_overflow(kind),
        words=("accumulated", "/s/far"))  # fmt: skip

# -- arrays: triangle sets and friends -------------------------------------------------------------
TRI = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
for label, make, word in [
    ("TriangleSet.index-out-of-range", lambda: om.TriangleSet(TRI, indices=[(0, 1, 3)]), "indices"),
    ("TriangleSet.index-negative", lambda: om.TriangleSet(TRI, indices=[(0, 1, -1)]), "indices"),
    ("TriangleSet.index-float", lambda: om.TriangleSet(TRI, indices=[(0, 1, 1.5)]), "indices"),
    ("TriangleSet.index-ragged", lambda: om.TriangleSet(TRI, indices=[(0, 1), (0, 1, 2)]), "indices"),
    ("TriangleSet.index-bigint", lambda: om.TriangleSet(TRI, indices=[(0, 1, HUGE_INT)]), "indices"),
    ("TriangleSet.vertices-nan", lambda: om.TriangleSet([(NAN, 0, 0), (1, 0, 0), (0, 1, 0)]), "vertices"),
    ("TriangleSet.vertices-1e39", lambda: om.TriangleSet([(1e39, 0, 0), (1, 0, 0), (0, 1, 0)]), "vertices"),
    ("TriangleSet.vertices-1e308", lambda: om.TriangleSet([(1e308, 0, 0), (1, 0, 0), (0, 1, 0)]), "vertices"),
    ("TriangleSet.vertices-2d", lambda: om.TriangleSet([(0, 0), (1, 0), (0, 1)]), "vertices"),
    ("TriangleSet.vertices-strings", lambda: om.TriangleSet([("a", "b", "c")] * 3), "vertices"),
    ("TriangleSet.vertices-empty", lambda: om.TriangleSet(np.zeros((0, 3))), "vertices"),
    ("TriangleSet.vertices-not-multiple-of-3", lambda: om.TriangleSet(TRI + [(1, 1, 1)]), "multiple of 3"),
    ("TriangleSet.colors-5", lambda: om.TriangleSet(TRI, colors=[(5, 0, 0)] * 3), "colors"),
    ("TriangleSet.colors-minus1", lambda: om.TriangleSet(TRI, colors=[(-1, 0, 0)] * 3), "colors"),
    ("TriangleSet.colors-count", lambda: om.TriangleSet(TRI, colors=[(1, 0, 0)] * 2), "colors"),
    ("TriangleSet.normals-zero", lambda: om.TriangleSet(TRI, normals=[(0, 0, 0)] * 3), "normals"),
    ("TriangleSet.normals-nan", lambda: om.TriangleSet(TRI, normals=[(NAN, 0, 1)] * 3), "normals"),
    ("TriangleSet.texcoords-3d", lambda: om.TriangleSet(TRI, texcoords=[(0, 0, 0)] * 3), "texcoords"),
    ("TriangleSet.generator-of-strings", lambda: om.TriangleSet(x for x in "abc"), "vertices"),
    ("Polygon.two-vertices", lambda: om.Polygon([(0, 0, 0), (1, 0, 0)]), "Polygon"),
    ("Polygon.self-crossing", lambda: om.Polygon([(0, 0, 0), (1, 1, 0), (1, 0, 0), (0, 1, 0)]), "Polygon"),
    ("Polygon.colinear", lambda: om.Polygon([(0, 0, 0), (1, 0, 0), (2, 0, 0)]), "Polygon"),
    ("LineSet.index-out-of-range", lambda: om.LineSet(TRI, indices=[(0, 5)]), "indices"),
    ("LineSet.one-vertex", lambda: om.LineSet([(0, 0, 0)]), "LineSet"),
    ("Polyline.nan", lambda: om.Polyline([(0, 0, 0), (NAN, 1, 0)]), "vertices"),
    ("PointSet.sizes-negative", lambda: om.PointSet(TRI, sizes=[1, -1, 1]), "sizes"),
    ("PointSet.sizes-count", lambda: om.PointSet(TRI, sizes=[1, 1]), "sizes"),
    ("Heightfield.1d", lambda: om.Heightfield(np.arange(5.0)), "heights"),
    ("Heightfield.nan", lambda: om.Heightfield(np.full((3, 3), NAN)), "heights"),
    ("Heightfield.spacing-0", lambda: om.Heightfield(np.zeros((3, 3)), spacing=0), "spacing"),
    ("Volume.2d", lambda: om.Volume(np.zeros((3, 3))), "Volume"),
    ("Volume.nan", lambda: om.Volume(np.full((3, 3, 3), NAN)), "Volume"),
    ("Volume.spacing-nan", lambda: om.Volume(np.zeros((3, 3, 3)), spacing=(NAN, 1, 1)), "spacing"),
    ("Text.string-number", lambda: om.Text(5), "string"),
    ("MeshFile.missing", lambda: om.MeshFile("no/such/file.obj"), "no such file"),
    ("MeshFile.bad-extension", lambda: (Path("m.xyz").write_text("x"), om.MeshFile("m.xyz")), "extension"),
    ("MeshFile.folder", lambda: (os.makedirs("d.obj", exist_ok=True), om.MeshFile("d.obj")), "not a file"),
    ("MeshFile.nul", lambda: om.MeshFile("a\x00b.obj"), "NUL"),
    ("MeshFile.number", lambda: om.MeshFile(5), "path"),
    ("NURBSSurface.grid-2d", lambda: om.NURBSSurface(np.zeros((4, 3))), "control_points"),
    ("NURBSSurface.nan", lambda: om.NURBSSurface(np.full((4, 4, 3), NAN)), "control_points"),
    ("NURBSSurface.too-few-points", lambda: om.NURBSSurface(np.zeros((3, 4, 3))), "needs more than"),
    ("NURBSSurface.degree-99", lambda: om.NURBSSurface(np.zeros((4, 4, 3)), degree_u=99), "degree"),
    ("NURBSSurface.weights-0", lambda: om.NURBSSurface(np.zeros((4, 4, 3)), weights=np.zeros((4, 4))), "weights"),
    ("NURBSSurface.knots-unclamped", lambda: om.NURBSSurface(np.zeros((4, 4, 3)), knots_u=range(8)), "clamped"),
    ("NURBSSurface.knots-count", lambda: om.NURBSSurface(np.zeros((4, 4, 3)), knots_v=[0, 1]), "knots_v"),
    ("NURBSSurface.trim-line", lambda: om.NURBSSurface(np.zeros((4, 4, 3)), trim=[[(0, 0), (1, 1)]]), "trim loop"),
    (
        "NURBSSurface.trim-huge",
        lambda: om.NURBSSurface(np.zeros((4, 4, 3)), trim=[np.random.rand(10**5, 2)]),
        "sample them more coarsely",
    ),
    ("TrimCurve.weights-negative", lambda: om.TrimCurve([(0, 0), (1, 0), (0, 1)], weights=[1, -1, 1]), "weights"),
]:
    add(f"array/{label}", "arrays", lambda _t, m=make: m(), words=(word,))


def _malformed_mesh(name: str, text: str | bytes) -> Callable[[Path], Any]:
    def run(_tmp: Path) -> None:
        Path(name).write_bytes(text if isinstance(text, bytes) else text.encode())
        om.bounds(om.Node("s", [om.MeshFile(name)]))

    return run


for name, text, word in [
    ("bad-number.obj", "v 0 0 x\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "bad-number.obj"),
    ("bad-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "bad-index.obj"),
    ("no-faces.obj", "v 0 0 0\nv 1 0 0\n", "no-faces.obj"),
    ("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "nan.obj"),
    ("huge.obj", "v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "huge.obj"),
    (
        "binary.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 99999999\nend_header\n\x00\x01",
        "binary.ply",
    ),
    ("garbage.stl", b"\x00" * 80 + b"\xff\xff\xff\x7f", "garbage.stl"),
    ("empty.off", "", "empty.off"),
    ("truncated.glb", b"glTF\x02\x00\x00\x00\xff\xff\x00\x00", "truncated.glb"),
]:
    add(f"array/meshfile-{name}", "arrays", _malformed_mesh(name, text), words=(word,))


def _trimesh_accepted(_tmp: Path) -> None:
    import trimesh

    box = trimesh.creation.box()
    lo, hi = om.bounds(om.Node("s", [om.TriangleSet(box)]))
    assert np.allclose(lo, -0.5) and np.allclose(hi, 0.5)
    lo, hi = om.bounds(om.Node("s", [om.MeshFile(box)]))
    assert np.allclose(lo, -0.5) and np.allclose(hi, 0.5)


add("array/trimesh-objects-accepted", "arrays", _trimesh_accepted, kind="handle")

# -- nodes ------------------------------------------------------------------------------------------
for label, make, word in [
    ("name=NUL", lambda: om.Node("a\x00b"), "name"),
    ("name=newline", lambda: om.Node("a\nb"), "name"),
    ("name=slash", lambda: om.Node("a/b"), "name"),
    ("name=empty", lambda: om.Node(""), "name"),
    ("name=number", lambda: om.Node(5), "name"),
    ("group=space", lambda: om.Node("n", groups=["a b"]), "group"),
    ("group=NUL", lambda: om.Node("n", groups=["a\x00"]), "group"),
    ("group=number", lambda: om.Node("n", groups=5), "group"),
    ("items=component", lambda: om.Node("n", om.Sphere()), "items"),
    ("add=class", lambda: om.Node("n").add(om.Sphere), "Sphere()"),
    ("add=string", lambda: om.Node("n").add("sphere"), "cannot add"),
    ("add=self", lambda: (lambda n: n.add(n))(om.Node("n")), "cycle"),
    ("add=ancestor", lambda: (lambda a: a.children[0].add(a))(om.Node("a", [om.Node("b")])), "cycle"),
    ("path=missing", lambda: om.Node("a", [om.Node("b")])["/a/c"], "no node"),
    ("remove=absent", lambda: om.Node("a").remove(om.Sphere()), "not in this node"),
]:
    add(f"node/{label}", "nodes", lambda _t, m=make: m(), words=(word,))


def _remove_while_iterating(_tmp: Path) -> None:
    node = om.Node("n", [om.Sphere() for _ in range(10)])
    for item in node:
        node.remove(item)
    assert len(node) == 0  # a snapshot is iterated: every item is removed


def _clear_by_children(_tmp: Path) -> None:
    node = om.Node("n", [om.Node(f"c{i}") for i in range(7)])
    for child in node.children:
        node.remove(child)
    for child in node:
        node.remove(child)
    assert len(node) == 0


def _two_backgrounds(engine: str) -> Callable[[Path], Any]:
    def run(_tmp: Path) -> None:
        s = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.Background((1, 0, 0)), om.Background((0, 0, 1))])
        if engine == "declarations":
            found = s.declarations().first(om.Background)
            assert found is not None and found[0].color[:3] == (0.0, 0.0, 1.0)
            return
        image = om.render(s, engine=engine, size=(8, 6))
        assert tuple(image.array[3, 4][:3]) == (0, 0, 255), image.array[3, 4]  # the later one wins

    return run


add("node/iterate-and-remove", "nodes", _remove_while_iterating, kind="handle")
add("node/iterate-children-and-remove", "nodes", _clear_by_children, kind="handle")
for engine in ("declarations", "gl", "povray", "radiance"):
    add(f"node/two-backgrounds-{engine}", "nodes", _two_backgrounds(engine), kind="handle")


# -- scene files ------------------------------------------------------------------------------------
def doc(*contents: Any, **extra: Any) -> str:
    return json.dumps({"format": "omnirender-scene", "version": 1, **extra,
                       "root": {"node": "s", "contents": list(contents)}})  # fmt: skip


def load_text(text: str | bytes, name: str = "scene.json", trusted: bool = False) -> om.Node:
    path = Path(name)
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    return om.load(path, trusted=trusted)


def file_case(id: str, text: str | bytes, words=(), name: str = "scene.json", kind: str = "refuse", **kw: Any):
    add(f"file/{id}", "scene files", lambda _t: load_text(text, name, **kw), kind=kind, words=words)


BOMB = "format: omnirender-scene\nversion: 1\nroot: {node: x}\nbomb:\n  a: &a [x,x,x,x,x,x,x,x,x,x]\n"
for level, prev in zip("bcdefghi", "abcdefgh", strict=True):
    BOMB += f"  {level}: &{level} [{','.join(['*' + prev] * 10)}]\n"

file_case("json-syntax", '{"format": "omnirender-scene",', words=("invalid JSON", "line"))
file_case("yaml-syntax", "format: [unclosed\n", name="s.yaml", words=("invalid YAML",))
file_case("empty-json", "", words=("invalid JSON",))
file_case("empty-yaml", "", name="s.yaml", words=("mapping",))
file_case("top-level-list", "[1, 2]", words=("object",))
file_case("wrong-format", json.dumps({"format": "x", "version": 1, "root": {"node": "a"}}), words=("format",))
file_case("wrong-version", json.dumps({"format": "omnirender-scene", "version": 99, "root": {"node": "a"}}),
          words=("version",))  # fmt: skip
file_case("no-root", json.dumps({"format": "omnirender-scene", "version": 1}), words=("root",))
file_case("unknown-top-key", doc(extra=1), words=("extra",))
file_case("root-is-component", json.dumps({"format": "omnirender-scene", "version": 1, "root": {"type": "Sphere"}}),
          words=("root", "node"))  # fmt: skip
file_case("unknown-type", doc({"type": "Spere"}), words=("Spere",))
file_case("python-type", doc({"type": "os.system", "command": "ls"}), words=("os.system",))
file_case("dunder-type", doc({"type": "__import__"}), words=("__import__",))
file_case("relative-type", doc({"type": "../x"}), words=("type",))
file_case("abstract-type", doc({"type": "Shape"}), words=("Shape",))
file_case("unknown-param", doc({"type": "Sphere", "radus": 1}), words=("radus", "parameters"))
file_case("param-string", doc({"type": "Sphere", "radius": "big"}), words=("radius",))
file_case("param-bigint", doc({"type": "Sphere", "radius": HUGE_INT}), words=("radius",))
file_case("param-1e308", doc({"type": "Sphere", "radius": 1e308}), words=("radius",))
file_case("torus-1e308", doc({"type": "Torus", "major_radius": 1e308}), words=("Torus", "major_radius"))
_PATCH = [[[0, 0, 0], [1, 0, 0]], [[0, 1, 0], [1, 1, 0]]]
file_case("nurbs-knots", doc({"type": "NURBSSurface", "control_points": _PATCH, "degree_u": 1, "degree_v": 1,
                              "knots_u": [0, 1, 0, 1]}),
          words=("NURBSSurface", "root.contents[0].knots_u", "non-decreasing"))  # fmt: skip
file_case("nurbs-trim-curve", doc({"type": "NURBSSurface", "control_points": _PATCH, "degree_u": 1, "degree_v": 1,
                                   "trim": [{"type": "TrimCurve", "points": [[0, 0]]}]}),
          words=("TrimCurve", "root.contents[0].trim[0]", "points"))  # fmt: skip
file_case("vertices-1e39", doc({"type": "TriangleSet", "vertices": [[1e39, 0, 0], [1, 0, 0], [0, 1, 0]]}),
          words=("vertices",))  # fmt: skip
file_case("json-nan", '{"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": '
          '[{"type": "Sphere", "radius": NaN}]}}', words=("NaN",))  # fmt: skip
file_case("yaml-nan", "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  contents:\n"
          "  - {type: Sphere, radius: .nan}\n", name="s.yaml", words=("radius", "finite"))  # fmt: skip
file_case("yaml-inf-in-list", "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  contents:\n"
          "  - {type: Sphere, center: [0, .inf, 0]}\n", name="s.yaml", words=("center", "finite"))  # fmt: skip
file_case("duplicate-key-json", '{"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": '
          '[{"type": "Sphere", "radius": 1, "radius": 2}]}}', words=("duplicate", "radius"))  # fmt: skip
file_case("duplicate-key-yaml", "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  contents:\n"
          "  - type: Sphere\n    radius: 1\n    radius: 2\n", name="s.yaml",
          words=("duplicate", "radius", "root.contents[0].radius"))  # fmt: skip
file_case("duplicate-top-key-yaml", "format: omnirender-scene\nversion: 1\nversion: 1\nroot: {node: s}\n",
          name="s.yaml", words=("duplicate", "version"))  # fmt: skip
file_case("yaml-billion-laughs", BOMB, name="s.yaml", words=("aliases", "$ref"))
file_case("yaml-self-alias", "format: omnirender-scene\nversion: 1\nroot: &r {node: s, contents: [*r]}\n",
          name="s.yaml", words=("alias",))  # fmt: skip
file_case("yaml-undefined-alias", "format: omnirender-scene\nversion: 1\nroot: *nope\n", name="s.yaml",
          words=("alias",))  # fmt: skip
file_case("yaml-python-tag", "format: omnirender-scene\nversion: 1\nroot: !!python/object/apply:os.system [ls]\n",
          name="s.yaml", words=("invalid YAML",))  # fmt: skip
file_case("yaml-timestamp", "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  contents:\n"
          "  - {type: Text, string: 2024-01-01}\n", name="s.yaml", words=("timestamp",))  # fmt: skip
file_case("yaml-binary", "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  contents:\n"
          "  - {type: Text, string: !!binary aGVsbG8=}\n", name="s.yaml", words=("binary",))  # fmt: skip
file_case("yaml-set", "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  groups: !!set {a, b}\n",
          name="s.yaml", words=("set",))  # fmt: skip
file_case("yaml-two-documents", "format: omnirender-scene\n---\nversion: 1\n", name="s.yaml",
          words=("single document",))  # fmt: skip
file_case("yaml-key-on", "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  contents:\n"
          "  - {type: LightSwitch, on: true}\n", name="s.yaml", words=("quote",))  # fmt: skip
file_case("json-deep-300", "[" * 300 + "]" * 300, words=("object",))
file_case("json-deep-100000", "[" * 100000 + "]" * 100000, words=("nested deeper",))
file_case("json-deep-dict", '{"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": '
          '[{"type": "mitsuba.BSDF", "plugin": ' + '{"a": ' * 2000 + "1" + "}" * 2000 + "}]}}",
          words=("nested deeper",))  # fmt: skip
file_case("json-deep-dict-300", '{"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": '
          '[{"type": "mitsuba.BSDF", "plugin": ' + '{"a": ' * 300 + "1" + "}" * 300 + "}]}}",
          words=("nested deeper", "root.contents[0].plugin.a.a"))  # fmt: skip
file_case("json-deep-in-values", doc({"type": "Sphere", "center": "[" * 400 + "]" * 400}), words=("center",))
file_case("yaml-deep-100000", "- " * 1 + "[" * 100000 + "]" * 100000 + "\n", name="s.yaml",
          words=("nested deeper",))  # fmt: skip
file_case("yaml-deep-block", "".join("  " * i + "- \n" for i in range(3000)), name="s.yaml",
          words=("nested deeper",))  # fmt: skip
_nested_nodes = {"node": "n0"}
for _i in range(1, 400):
    _nested_nodes = {"node": f"n{_i}", "contents": [_nested_nodes]}
file_case("node-nesting-400", json.dumps({"format": "omnirender-scene", "version": 1, "root": _nested_nodes}),
          words=("nested deeper", "definitions"))  # fmt: skip
file_case("name-NUL", json.dumps({"format": "omnirender-scene", "version": 1, "root": {"node": "a\x00b"}}),
          words=("root.node", "control"))  # fmt: skip
file_case("name-newline", json.dumps({"format": "omnirender-scene", "version": 1, "root": {"node": "a\nb"}}),
          words=("root.node",))  # fmt: skip
file_case("group-NUL", json.dumps({"format": "omnirender-scene", "version": 1,
          "root": {"node": "a", "groups": ["x\x00"]}}), words=("root.node", "group"))  # fmt: skip
file_case("id-NUL", doc({"type": "Sphere", "$id": "a\x00"}), words=("$id",))
file_case("id-number", doc({"type": "Sphere", "$id": 5}), words=("$id",))
file_case("id-duplicate", doc({"type": "Sphere", "$id": "x"}, {"type": "Box", "$id": "x"}), words=("duplicate id",))
file_case("ref-unknown", doc({"$ref": "nothing"}), words=("unknown id", "nothing"))
file_case("ref-forward", doc({"$ref": "later"}, {"type": "Sphere", "$id": "later"}), words=("unknown id",))
file_case("ref-extra-keys", doc({"type": "Sphere", "$id": "a"}, {"$ref": "a", "radius": 2}), words=("reference",))
file_case("ref-node-in-itself", doc({"node": "a", "$id": "a", "contents": [{"$ref": "a"}]}), words=("cycle",))
file_case("definitions-not-list", doc(definitions=5), words=("definitions",))
file_case("definitions-without-id", doc(definitions=[{"node": "a"}]), words=("definitions[0]", "$id"))
file_case("node-and-type", doc({"node": "a", "type": "Sphere"}), words=("either",))
file_case("entry-number", doc(5), words=("root.contents[0]",))
file_case("contents-not-list", json.dumps({"format": "omnirender-scene", "version": 1,
          "root": {"node": "s", "contents": {"type": "Sphere"}}}), words=("contents",))  # fmt: skip
file_case("array-bad-dtype", doc({"type": "TriangleSet", "vertices": {"$array": [[0, 0, 0]] * 3, "dtype": "object"}}),
          words=("dtype",))  # fmt: skip
file_case("array-ragged", doc({"type": "TriangleSet", "vertices": {"$array": [[0, 0, 0], [1]], "dtype": "float32"}}),
          words=("$array",))  # fmt: skip
file_case("array-strings", doc({"type": "TriangleSet", "vertices": {"$array": [["a"] * 3] * 3, "dtype": "int32"}}),
          words=("$array",))  # fmt: skip
file_case("array-overflow", doc({"type": "TriangleSet", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
          "indices": {"$array": [[0, 1, 300]], "dtype": "uint8"}}), words=("$array",))  # fmt: skip
file_case("base64-invalid", doc({"type": "TriangleSet", "vertices": {"$base64": "!!!", "dtype": "float32",
          "shape": [3, 3]}}), words=("base64",))  # fmt: skip
file_case("base64-length", doc({"type": "TriangleSet", "vertices": {"$base64": "AAAA", "dtype": "float32",
          "shape": [3, 3]}}), words=("bytes",))  # fmt: skip
file_case("base64-shape-negative", doc({"type": "TriangleSet", "vertices": {"$base64": "", "dtype": "float32",
          "shape": [-3, 3]}}), words=("shape",))  # fmt: skip
file_case("base64-shape-huge", doc({"type": "TriangleSet", "vertices": {"$base64": "AAAA", "dtype": "float64",
          "shape": [2**40, 2**40]}}), words=("shape",))  # fmt: skip
file_case("base64-dtype", doc({"type": "TriangleSet", "vertices": {"$base64": "", "dtype": "complex64",
          "shape": [0]}}), words=("dtype",))  # fmt: skip
file_case("base64-nan", doc({"type": "TriangleSet", "vertices": {"$base64": "AADAfw==", "dtype": "float32",
          "shape": [1]}}), words=("finite",))  # fmt: skip
file_case("base64-extra-key", doc({"type": "Sphere", "center": {"$base64": "", "dtype": "float32", "shape": [0],
          "x": 1}}), words=("$base64",))  # fmt: skip
file_case("dict-wrapper-bad", doc({"type": "mitsuba.BSDF", "plugin": {"$dict": 3}}), words=("$dict",))
file_case("non-utf8", b"\xff\xfe{\x00", words=("UTF-8",))
file_case("bad-extension", "{}", name="scene.txt", words=("extension",))


def _folder_scene(_tmp: Path) -> None:
    os.mkdir("folder.json")
    om.load("folder.json")


add("file/folder", "scene files", _folder_scene, words=("folder",))
add("file/missing", "scene files", lambda _t: om.load("missing.yaml"), words=("does not exist",))


# path policy and side-car arrays
def _outside(kind: str, trusted: bool = False) -> Callable[[Path], Any]:
    def run(tmp: Path) -> None:
        inner = tmp / "inner"
        inner.mkdir()
        mesh = tmp / "m.obj"
        mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
        png = tmp / "t.png"
        from PIL import Image

        Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(png)
        np.save(tmp / "a.npy", np.zeros((3, 3), np.float32))
        entries = {
            "mesh-dotdot": {"type": "MeshFile", "path": "../m.obj"},
            "mesh-absolute": {"type": "MeshFile", "path": str(mesh)},
            "texture-dotdot": {"type": "Texture", "image": "../t.png"},
            "texture-etc-passwd": {"type": "Texture", "image": "/etc/passwd"},
            "npy-dotdot": {"type": "TriangleSet", "vertices": {"$file": "../a.npy"}},
        }
        if kind == "mesh-symlink":
            os.symlink(mesh, inner / "link.obj")
            entry = {"type": "MeshFile", "path": "link.obj"}
        else:
            entry = entries[kind]
        (inner / "s.json").write_text(doc(entry))
        loaded = om.load(inner / "s.json", trusted=trusted)
        if trusted:
            assert loaded.components[2:] or loaded.components, loaded

    return run


for kind in ("mesh-dotdot", "mesh-absolute", "texture-dotdot", "texture-etc-passwd", "npy-dotdot", "mesh-symlink"):
    add(f"file/path-policy-{kind}", "scene files", _outside(kind), words=("folder", "trusted=True"))
add("file/path-policy-trusted-allows", "scene files", _outside("mesh-dotdot", trusted=True), kind="handle")


def _npz_case(kind: str) -> Callable[[Path], Any]:
    def run(_tmp: Path) -> None:
        np.savez("side.npz", v=np.zeros((3, 3), np.float32), bad=np.full((3, 3), np.nan))
        np.save("objects.npy", np.array([None, 1], dtype=object), allow_pickle=True)
        Path("corrupt.npz").write_bytes(b"PK\x03\x04garbage")
        entry = {
            "missing-key": {"$file": "side.npz", "key": "nope"},
            "no-key": {"$file": "side.npz"},
            "nan": {"$file": "side.npz", "key": "bad"},
            "pickle": {"$file": "objects.npy"},
            "corrupt": {"$file": "corrupt.npz", "key": "v"},
            "missing-file": {"$file": "gone.npz", "key": "v"},
            "wrong-extension": {"$file": "side.txt", "key": "v"},
        }[kind]
        load_text(doc({"type": "TriangleSet", "vertices": entry}))

    return run


for kind in ("missing-key", "no-key", "nan", "pickle", "corrupt", "missing-file", "wrong-extension"):
    add(f"file/sidecar-{kind}", "scene files", _npz_case(kind), words=("vertices",))

for engine_type in ("povray.Raw", "radiance.Raw"):
    file_case(f"trusted-only-{engine_type}", doc({"type": engine_type, "text": "// x"}), words=("trusted",))
file_case("trusted-only-nested", doc({"node": "n", "contents": [{"type": "povray.Raw", "text": "x"}]}),
          words=("root.contents[0].contents[0]", "trusted"))  # fmt: skip


def _round_trip(kind: str) -> Callable[[Path], Any]:
    def run(tmp: Path) -> None:
        rng = np.random.default_rng(1)
        points = rng.normal(size=(5000, 3)).astype(np.float32)
        s = om.Node("s", [om.PointSet(points), om.Background((0.1, 0.2, 0.3)), om.Node("a\u00e9\u4e2d")])
        fmt = "yaml" if kind.endswith("yaml") else "json"
        path = tmp / f"r.{fmt}"
        om.save(s, path, arrays="npz" if kind.startswith("npz") else "auto")
        back = om.load(path)
        assert np.array_equal(back.components[0].vertex_array(), points)
        assert back.children[0].name == "a\u00e9\u4e2d"

    return run


for kind in ("base64-json", "base64-yaml", "npz-json", "npz-yaml"):
    add(f"file/round-trip-{kind}", "scene files", _round_trip(kind), kind="handle")


def _alias_within_limit(_tmp: Path) -> None:
    text = (
        "format: omnirender-scene\nversion: 1\nroot:\n  node: s\n  contents:\n"
        "  - &m {type: Material, diffuse: [1, 0, 0]}\n  - {node: a, contents: [*m]}\n  - {node: b, contents: [*m]}\n"
    )
    loaded = load_text(text, "s.yaml")
    a, b = loaded["/s/a"].components[0], loaded["/s/b"].components[0]  # an alias repeats the data
    assert a.diffuse == b.diffuse == (1.0, 0.0, 0.0)


add("file/yaml-alias-within-limit", "scene files", _alias_within_limit, kind="handle")


# -- render options, image sizes ------------------------------------------------------------------------
def _render(engine: str, size: Any = (8, 6), **options: Any) -> Callable[[Path], Any]:
    def run(_tmp: Path) -> None:
        om.render(scene(om.Sphere()), engine=engine, size=size, **options)

    return run


ENGINES = ("gl", "povray", "mitsuba", "radiance")
for engine in ENGINES:
    timeout = 60.0 if engine == "mitsuba" else 30.0
    for label, size in [("100000x100000", (100000, 100000)), ("40000x40000", (40000, 40000)),
                        ("nan", (NAN, 5)), ("zero", (0, 5)), ("negative", (-5, 5)), ("strings", ("8", "6")),
                        ("three", (8, 6, 1)), ("fraction", (8.5, 6)), ("bool", (True, 6))]:  # fmt: skip
        add(f"options/{engine}-size-{label}", "render options and sizes", _render(engine, size), words=("size",),
            timeout=timeout)  # fmt: skip
    add(f"options/{engine}-unknown-option", "render options and sizes", _render(engine, bogus=1), words=("bogus",),
        timeout=timeout)  # fmt: skip
    add(f"options/{engine}-mask-syntax", "render options and sizes", _render(engine, mask="a & | b"),
        words=("mask",), timeout=timeout)  # fmt: skip
    add(f"options/{engine}-on-missing", "render options and sizes", _render(engine, on_missing="ignore"),
        words=("on_missing",), timeout=timeout)  # fmt: skip
for label, options, word in [
    ("gl-samples-3", {"samples": 3}, "samples"),
    ("gl-samples-nan", {"samples": NAN}, "samples"),
    ("gl-samples-huge-size", {"samples": 16, "size": (16384, 16384)}, "samples"),
    ("gl-background-bad", {"background": (2, 0, 0)}, "background"),
    ("gl-background-string", {"background": "red"}, "background"),
    ("povray-timeout-nan", {"timeout": NAN}, "timeout"),
    ("povray-timeout-string", {"timeout": "1"}, "timeout"),
    ("povray-timeout-negative", {"timeout": -1}, "timeout"),
    ("povray-timeout-inf", {"timeout": INF}, "timeout"),
    ("povray-timeout-bool", {"timeout": True}, "timeout"),
    ("povray-quality-12", {"quality": 12}, "quality"),
    ("povray-antialias-nan", {"antialias": NAN}, "antialias"),
    ("povray-threads-0", {"threads": 0}, "threads"),
    ("mitsuba-spp-nan", {"spp": NAN}, "spp"),
    ("mitsuba-spp-zero", {"spp": 0}, "spp"),
    ("mitsuba-spp-string", {"spp": "64"}, "spp"),
    ("mitsuba-spp-2pow64", {"spp": 2**64}, "spp"),
    ("mitsuba-seed-2pow64", {"seed": 2**64}, "seed"),
    ("mitsuba-seed-negative", {"seed": -1}, "seed"),
    ("mitsuba-seed-nan", {"seed": NAN}, "seed"),
    ("mitsuba-global-ambient-nan", {"global_ambient": NAN}, "global_ambient"),
    ("mitsuba-global-ambient-negative", {"global_ambient": -1}, "global_ambient"),
    ("mitsuba-integrator-string", {"integrator": "path"}, "integrator"),
    ("radiance-timeout-nan", {"timeout": NAN}, "timeout"),
    ("radiance-timeout-string", {"timeout": "1"}, "timeout"),
    ("radiance-oversample-0", {"oversample": 0}, "oversample"),
    ("radiance-oversample-100", {"oversample": 100}, "oversample"),
    ("radiance-exposure-nan", {"exposure": NAN}, "exposure"),
    ("radiance-global-ambient-nan", {"global_ambient": NAN}, "global_ambient"),
    ("radiance-oversample-rays", {"oversample": 8, "size": (4096, 4096)}, "rays"),
]:
    engine = label.split("-")[0]
    size = options.pop("size", (8, 6))
    add(f"options/{label}", "render options and sizes", _render(engine, size, **options), words=(word,),
        timeout=60.0 if engine == "mitsuba" else 30.0)  # fmt: skip
for label, run, word in [
    ("unknown-engine", _render("vulkan"), "vulkan"),
    ("engine-case", _render("GL"), "GL"),
    ("scene-none", lambda _t: om.render(None), "scene"),
    ("scene-number", lambda _t: om.render(5), "scene"),
    ("scene-string", lambda _t: om.render("scene.yaml"), "scene"),
    ("scene-list-of-strings", lambda _t: om.render(["sphere"]), "scene[0]"),
    ("scene-generator-of-strings", lambda _t: om.render(x for x in ["a", "b"]), "str"),
    ("trace-generator-of-strings", lambda _t: om.trace(x for x in ["a", "b"]), "str"),
    ("bounds-generator-of-strings", lambda _t: om.bounds(x for x in ["a"]), "str"),
    ("pick-pixel-outside", lambda _t: om.pick(scene(om.Sphere()), pixel=(50, 50), size=(8, 6)), "pixel"),
    ("pick-pixel-nan", lambda _t: om.pick(scene(om.Sphere()), pixel=(NAN, 1), size=(8, 6)), "pixel"),
    ("pick-no-size", lambda _t: om.pick(scene(om.Sphere()), pixel=(1, 1)), "size"),
    ("pick-ray-nan", lambda _t: om.pick(scene(om.Sphere()), ray=((NAN, 0, 0), (0, 0, -1))), "ray"),
    ("pick-ray-zero-direction", lambda _t: om.pick(scene(om.Sphere()), ray=((0, 0, 5), (0, 0, 0))), "direction"),
    ("export-unknown-extension", lambda _t: om.export(scene(om.Sphere()), "x.vrml"), "extension"),
    ("export-missing-folder", lambda _t: om.export(scene(om.Sphere()), "no/such/dir/x.glb"), "folder"),
    ("save-missing-folder", lambda _t: om.save(scene(om.Sphere()), "no/such/dir/x.json"), "folder"),
    ("save-bad-extension", lambda _t: om.save(scene(om.Sphere()), "x.txt"), "extension"),
    ("save-arrays-bogus", lambda _t: om.save(scene(om.Sphere()), "x.json", arrays="zip"), "arrays"),
    ("save-callable-param", lambda _t: om.save(om.Node("s", [om.Technique(service=print)]), "x.json"), "service"),
    ("viewer-size-nan", lambda _t: om.Viewer(size=(NAN, 5), engine=om.Engine()), "size"),
    ("viewer-mask-syntax", lambda _t: setattr(om.Viewer(engine=om.Engine()), "mask", "a &"), "mask"),
    ("viewer-background-nan", lambda _t: om.Viewer(engine=om.Engine(), background=(NAN, 0, 0)), "background"),
]:
    add(f"api/{label}", "render options and sizes", run, words=(word,))


# -- the command line ---------------------------------------------------------------------------------
def cli(*args: str) -> tuple[int, str]:
    from omnirender.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(list(args))
    return code, err.getvalue()


class CLIError(ValueError):
    """A command-line refusal: its one error line (classified like any refusal)."""


def cli_case(id: str, args: list[str], code: int, words=(), setup: Callable[[Path], Any] | None = None):
    def run(tmp: Path) -> None:
        if setup is not None:
            setup(tmp)
        got, err = cli(*args)
        lines = [ln for ln in err.splitlines() if "error:" in ln]
        if got == 0:
            return  # accepted: silent for a refusal case
        if got != code:
            raise AssertionError(f"exit code {got}, expected {code}: {err.strip()[:300]}")
        if len(lines) != 1 or "Traceback" in err:
            raise AssertionError(f"expected one error line, got: {err.strip()[:300]}")
        raise CLIError(lines[0])  # classified by its text like any refusal

    add(f"cli/{id}", "command line", run, words=words)


def _good_scene(tmp: Path) -> None:
    om.save(scene(om.Sphere()), tmp / "good.json")


def _raw_scene(tmp: Path) -> None:
    (tmp / "raw.json").write_text(doc({"type": "povray.Raw", "text": "// x"}))


def _outside_scene(tmp: Path) -> None:
    (tmp / "sub").mkdir()
    (tmp / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (tmp / "sub" / "s.json").write_text(doc({"type": "MeshFile", "path": "../m.obj"}))


cli_case("missing-scene", ["render", "missing.json"], 2, ("not found",))
cli_case("bad-scene-extension", ["render", "scene.txt"], 2, ("extension",))
cli_case("missing-mesh", ["view", "bunny.obj"], 2, ("not found",))
cli_case("unknown-engine", ["render", "good.json", "-e", "vulkan"], 2, ("vulkan",), _good_scene)
cli_case("bad-output-extension", ["render", "good.json", "-o", "x.txt"], 2, ("x.txt",), _good_scene)
cli_case("bad-size", ["render", "good.json", "--size", "nanxnan"], 2, ("size",), _good_scene)
cli_case("huge-size", ["render", "good.json", "--size", "100000x100000"], 2, ("size",), _good_scene)
cli_case("zero-spp", ["render", "good.json", "--spp", "0"], 2, ("spp",), _good_scene)
cli_case("bad-mask", ["render", "good.json", "--mask", "a &"], 2, ("mask",), _good_scene)
cli_case("unknown-command", ["paint", "good.json"], 2, ("paint",), _good_scene)
cli_case("trusted-only", ["render", "raw.json", "-e", "povray", "-o", "x.png"], 1, ("--trusted",), _raw_scene)
cli_case("outside-folder", ["render", "sub/s.json", "-o", "x.png"], 1, ("--trusted", "folder"), _outside_scene)
cli_case("malformed-scene", ["info", "bad.json"], 1, ("invalid JSON",),
         lambda t: (t / "bad.json").write_text("{"))  # fmt: skip
cli_case("malformed-mesh", ["render", "bad.obj", "-o", "x.png"], 1, ("bad.obj",),
         lambda t: (t / "bad.obj").write_text("v 0 0 x\nf 1 2 3\n"))  # fmt: skip
cli_case("export-unknown", ["export", "good.json", "x.vrml"], 2, ("x.vrml",), _good_scene)
cli_case("animate-no-animation", ["animate", "good.json", "--workers", "0"], 2, ("animation",), _good_scene)
cli_case("animate-bad-frames", ["animate", "good.json", "--frames", "a-b"], 2, ("frames",), _good_scene)
cli_case("schema-missing-folder", ["schema", "-o", "no/such/dir/x.json"], 1, ("folder",))


def _cli_mesh_render(tmp: Path) -> None:
    (tmp / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    code, err = cli("render", str(tmp / "tri.obj"), "-o", str(tmp / "tri.png"), "--size", "32x24")
    assert code == 0, err
    from PIL import Image

    pixels = np.asarray(Image.open(tmp / "tri.png"))
    assert pixels.shape == (24, 32, 4) and len(np.unique(pixels.reshape(-1, 4), axis=0)) > 1


add("cli/render-mesh-file", "command line", _cli_mesh_render, kind="handle")


# -- engine content -------------------------------------------------------------------------------------
def _hostile_strings(engine: str) -> Callable[[Path], Any]:
    def run(_tmp: Path) -> None:
        evil = 'x" } #include "/etc/passwd" #declare A = 1; !rm -rf ~'
        s = om.Node(evil.replace("/", "_"), [om.Camera.look_at(eye=(0, 0, 5)), om.Text(evil, size=10), om.Sphere()])
        if engine.startswith("."):
            om.export(s, f"out{engine}")
            text = Path(f"out{engine}").read_bytes()
            assert b'/etc/passwd"\n' not in text
        else:
            om.render(s, engine=engine, size=(16, 12))

    return run


for engine in ("gl", "povray", "radiance", ".pov", ".rib", ".rad", ".glb", ".html"):
    add(f"content/hostile-strings-{engine}", "engine content", _hostile_strings(engine), kind="handle")


def _degenerate(kind: str) -> Callable[[Path], Any]:
    def run(_tmp: Path) -> None:
        flat = om.TriangleSet([(0, 0, 0), (1, 0, 0), (2, 0, 0)])  # zero area
        same = om.TriangleSet([(0, 0, 0)] * 3)
        far = om.Sphere(center=(0, 0, -1e12), radius=1e11)
        s = scene(flat, same, far, om.Sphere(radius=1e-12))
        if kind == "bounds":
            lo, hi = om.bounds(s)
            assert np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))
        elif kind == "pick":
            om.pick(s, pixel=(4, 3), size=(8, 6))
        elif kind.startswith("."):
            om.export(s, f"out{kind}")
        else:
            om.render(s, engine=kind, size=(8, 6))

    return run


for kind in ("bounds", "pick", "gl", "povray", "radiance", ".glb", ".rib"):
    add(f"content/degenerate-{kind}", "engine content", _degenerate(kind), kind="handle")


def _povray_killed(tmp: Path) -> None:
    fake = tmp / "bin"
    fake.mkdir()
    program = fake / "povray"
    program.write_text("#!/bin/sh\necho 'Configuration warning: cannot open povray.conf' >&2\nkill -9 $$\n")
    program.chmod(0o755)
    os.environ["PATH"] = f"{fake}{os.pathsep}{os.environ.get('PATH', '')}"
    om.render(scene(om.Sphere()), engine="povray", size=(8, 6))


add("content/povray-killed-by-signal", "engine content", _povray_killed, words=("killed by signal 9", "SIGKILL"))


# -- deep graphs --------------------------------------------------------------------------------------
def _deep(levels: int, op: str) -> Callable[[Path], Any]:
    def run(tmp: Path) -> None:
        node = om.Node("n0", [om.Sphere(radius=0.5)])
        for i in range(1, levels):
            node = om.Node(f"n{i}", [om.Translation(0.0001, 0, 0), node])  # bottom-up: linear to build
        root = om.Node("root", [om.Camera.look_at(eye=(0, 0, 20)), node])
        if op in ("json", "yaml"):
            om.save(root, tmp / f"deep.{op}")
            back = om.load(tmp / f"deep.{op}")
            depth, n = 0, back
            while n.children:
                n, depth = n.children[0], depth + 1
            assert depth == levels
        elif op == "info":
            from omnirender.cli import scene_report

            assert "not listed" in scene_report(root, engines=False)
        else:
            lo, hi = om.bounds(root)
            assert abs(lo[0] - (-0.5 + 0.0001 * (levels - 1))) < 1e-6

    return run


# (100,000 levels are tested in tests/scene/test_deep_graphs.py and measured by bench/soak.py)
add("deep/10000-levels-json", "deep graphs", _deep(10000, "json"), kind="handle", timeout=60)
add("deep/2000-levels-yaml", "deep graphs", _deep(2000, "yaml"), kind="handle", timeout=60)
add("deep/2000-levels-info", "deep graphs", _deep(2000, "info"), kind="handle", timeout=60)
add("deep/2000-levels-bounds", "deep graphs", _deep(2000, "bounds"), kind="handle", timeout=60)

if __name__ == "__main__":
    from collections import Counter

    print(len(CASES), Counter(c.category for c in CASES))
