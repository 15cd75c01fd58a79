"""load_gltf: an animated glTF file (written here with pygltflib, an independent writer) plays as tracks."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import omnirender as om
from omnirender.animation import scene_at
from omnirender.formats.gltf import GLTFImportError

pygltflib = pytest.importorskip("pygltflib")

TETRA = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.uint32)
TIMES = np.array([0.0, 1.0, 2.0], np.float32)
SLIDE = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0]], np.float32)
SPIN = np.array([[0, 0, 0, 1], [0, math.sin(math.pi / 4), 0, math.cos(math.pi / 4)], [0, 1, 0, 0]], np.float32)
GROW = np.array([[1, 1, 1], [2, 2, 2], [3, 3, 3]], np.float32)
# CUBICSPLINE keys: (in-tangent, value, out-tangent) each
HOP = np.array([[0, 0, 0], [0, 0, 0], [0, 4, 0], [0, 0, 0], [0, 1, 0], [0, 0, 0]], np.float32)


def _write(path, *, weights: bool = False, sparse: bool = False, bad_index: bool = False) -> None:
    G = pygltflib
    blobs: list[bytes] = []
    views, accessors = [], []

    def add(array: np.ndarray, kind: str, component: int, target=None, minmax: bool = False) -> int:
        offset = sum(len(b) for b in blobs)
        data = np.ascontiguousarray(array).tobytes()
        blobs.append(data + b"\0" * (-len(data) % 4))
        views.append(G.BufferView(buffer=0, byteOffset=offset, byteLength=len(data), target=target))
        acc = G.Accessor(bufferView=len(views) - 1, componentType=component, count=len(array), type=kind)
        if minmax:
            acc.min, acc.max = array.min(axis=0).tolist(), array.max(axis=0).tolist()
        accessors.append(acc)
        return len(accessors) - 1

    faces = FACES.copy()
    if bad_index:
        faces[0, 0] = 99
    pos = add(TETRA, "VEC3", G.FLOAT, G.ARRAY_BUFFER, minmax=True)
    idx = add(faces.reshape(-1), "SCALAR", G.UNSIGNED_INT, G.ELEMENT_ARRAY_BUFFER)
    times = add(TIMES, "SCALAR", G.FLOAT, minmax=True)
    hop_times = add(TIMES[:2], "SCALAR", G.FLOAT, minmax=True)
    samplers = [
        G.AnimationSampler(input=times, output=add(SLIDE, "VEC3", G.FLOAT), interpolation="LINEAR"),
        G.AnimationSampler(input=times, output=add(SPIN, "VEC4", G.FLOAT), interpolation="LINEAR"),
        G.AnimationSampler(input=times, output=add(GROW, "VEC3", G.FLOAT), interpolation="STEP"),
        G.AnimationSampler(input=hop_times, output=add(HOP, "VEC3", G.FLOAT), interpolation="CUBICSPLINE"),
    ]
    channels = [
        G.AnimationChannel(sampler=0, target=G.AnimationChannelTarget(node=0, path="translation")),
        G.AnimationChannel(sampler=1, target=G.AnimationChannelTarget(node=1, path="rotation")),
        G.AnimationChannel(sampler=2, target=G.AnimationChannelTarget(node=1, path="scale")),
        G.AnimationChannel(sampler=3, target=G.AnimationChannelTarget(node=2, path="translation")),
    ]
    if weights:
        samplers.append(G.AnimationSampler(input=times, output=add(np.zeros((3, 1), np.float32), "SCALAR", G.FLOAT)))
        channels.append(G.AnimationChannel(sampler=4, target=G.AnimationChannelTarget(node=2, path="weights")))
    if sparse:
        accessors[pos].sparse = G.Sparse(count=1, indices={"bufferView": idx, "componentType": G.UNSIGNED_INT},
                                         values={"bufferView": pos})  # fmt: skip
    primitive = G.Primitive(attributes=G.Attributes(POSITION=pos), indices=idx, material=0)
    gltf = G.GLTF2(
        scene=0,
        scenes=[G.Scene(name="stage", nodes=[0, 2, 3])],
        nodes=[
            G.Node(name="rig", translation=[0, 0, 0], children=[1]),
            G.Node(name="arm", mesh=0, rotation=[0, 0, 0, 1]),  # scale is animated but absent: identity
            G.Node(name="hopper", mesh=0, translation=[5, 0, 0]),
            G.Node(name="cam", camera=0, translation=[0, 1, 10]),
        ],
        meshes=[G.Mesh(name="tetra", primitives=[primitive])],
        materials=[G.Material(pbrMetallicRoughness=G.PbrMetallicRoughness(baseColorFactor=[0.2, 0.5, 1.0, 1.0]))],
        cameras=[G.Camera(type="perspective", perspective=G.Perspective(yfov=0.7, znear=0.1, zfar=100))],
        animations=[
            G.Animation(name="move", samplers=samplers, channels=channels),
            G.Animation(name="still", samplers=[samplers[0]], channels=[channels[0]]),
        ],  # fmt: skip
        accessors=accessors,
        bufferViews=views,
        buffers=[G.Buffer(byteLength=sum(len(b) for b in blobs))],
    )
    gltf.set_binary_blob(b"".join(blobs))
    gltf.save_binary(str(path))


@pytest.fixture
def animated(tmp_path):
    path = tmp_path / "animated.glb"
    _write(path)
    return path


def _world_points(scene: om.Node, path: str) -> np.ndarray:
    """The tetrahedron's corners as the engine places them under ``path`` (through om.bounds per corner)."""
    lo, hi = om.bounds(scene[path])
    return np.array([lo, hi])


def _rot_y(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _box(points: np.ndarray) -> np.ndarray:
    return np.array([points.min(axis=0), points.max(axis=0)])


def test_the_hierarchy_meshes_materials_and_camera_are_imported(animated):
    scene = om.load_gltf(animated)
    assert scene.name == "stage"
    assert [n.path for n in scene.walk()][:4] == ["/stage", "/stage/rig", "/stage/rig/arm", "/stage/rig/arm/tetra"]
    arm = scene["/stage/rig/arm"]
    assert [type(c).__name__ for c in arm.components] == ["Rotation", "Scaling"]
    tetra = arm.children[0]
    material, mesh = tetra.components
    assert isinstance(mesh, om.TriangleSet) and mesh.triangle_count == 4
    assert material.base_color == pytest.approx((0.4845, 0.7353, 1.0), abs=1e-3)  # linear -> display values
    assert scene["/stage/hopper"].children[0] is tetra  # one mesh used twice is one shared node
    camera, world = scene.preevaluate()[1]
    assert np.allclose(world[:3, 3], (0, 1, 10)) and camera.fov == pytest.approx(math.degrees(0.7))
    # the static pose agrees with trimesh's own reading of the file (which flattens the hierarchy)
    trimesh = pytest.importorskip("trimesh")
    assert np.allclose(om.bounds(scene), trimesh.load(animated).bounds, atol=1e-6)


def test_translation_rotation_and_scale_channels_play(animated):
    scene = om.load_gltf(animated)
    (animation,) = [c for c in scene.components if isinstance(c, om.Animation)]
    assert animation.duration == 2.0
    for t in (0.0, 0.5, 1.0, 1.25, 1.5, 2.0, 3.0):
        u = min(t, 2.0)
        offset = np.interp(u, TIMES, SLIDE[:, 0]), np.interp(u, TIMES, SLIDE[:, 1]), 0.0
        angle = 90.0 * u  # slerp: uniform turn about +y, 0 -> 90 -> 180 degrees
        scale = GROW[min(int(u), 2), 0]  # STEP keeps the key before t
        corners = TETRA * scale @ _rot_y(angle).T + offset
        got = _world_points(scene_at(scene, t), "/stage/rig/arm")
        assert np.allclose(got, _box(corners), atol=1e-5), t


def test_cubic_spline_channels_use_the_files_tangents(animated):
    scene = om.load_gltf(animated)
    for t in (0.0, 0.25, 0.5, 0.8, 1.0):
        # Hermite from (value 0, out-tangent 4) to (value 1, in-tangent 0) over one second
        h10 = t**3 - 2 * t**2 + t
        h01 = -2 * t**3 + 3 * t**2
        y = 4 * h10 + 1 * h01
        later = scene_at(scene, t)
        later.remove(later["/stage/rig"])  # the tetrahedron node is shared: measure the hopper's alone
        got = np.array(om.bounds(later))
        # the channel replaces the node's own translation (5, 0, 0), as glTF specifies
        assert np.allclose(got, _box(TETRA + (0.0, y, 0.0)), atol=1e-5), t


def test_choosing_an_animation(animated):
    assert not [c for c in om.load_gltf(animated, animation=None).components if isinstance(c, om.Animation)]
    (still,) = [c for c in om.load_gltf(animated, animation="still").components if isinstance(c, om.Animation)]
    assert len(still.tracks) == 1
    both = [c for c in om.load_gltf(animated, animation="all").components if isinstance(c, om.Animation)]
    assert [len(a.tracks) for a in both] == [4, 1]
    with pytest.raises(GLTFImportError, match=r"no animation named 'walk' \(animations: \['move', 'still'\]\)"):
        om.load_gltf(animated, animation="walk")
    with pytest.raises(GLTFImportError, match="no animation 5"):
        om.load_gltf(animated, animation=5)


def test_unsupported_and_broken_files_are_reported(tmp_path):
    path = tmp_path / "weights.glb"
    _write(path, weights=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = om.load_gltf(path)
    assert any("animates morph weights" in str(w.message) and "skipped" in str(w.message) for w in caught)
    assert len([c for c in scene.components if isinstance(c, om.Animation)][0].tracks) == 4
    _write(tmp_path / "sparse.glb", sparse=True)
    sparse = om.load_gltf(tmp_path / "sparse.glb")  # sparse accessors are read (tests/test_assets_gltf.py)
    assert np.allclose(om.bounds(sparse)[1], om.bounds(om.load_gltf(path))[1])
    _write(tmp_path / "index.glb", bad_index=True)
    with pytest.raises(GLTFImportError, match=r"meshes\[0\].primitives\[0\]: an index is out of range"):
        om.load_gltf(tmp_path / "index.glb")
    (tmp_path / "junk.glb").write_bytes(b"glTF\x02\x00\x00\x00\xff\xff\x00\x00")
    with pytest.raises(GLTFImportError, match="truncated"):
        om.load_gltf(tmp_path / "junk.glb")
    with pytest.raises(FileNotFoundError):
        om.load_gltf(tmp_path / "missing.glb")


def test_the_demo_exported_by_omnirender_loads_back(tmp_path):
    """Our own glTF exporter's output (text glTF too) reads back with the same bounds and materials."""
    from omnirender.demo import demo_scene

    scene = demo_scene()
    om.export(scene, tmp_path / "demo.glb")
    again = om.load_gltf(tmp_path / "demo.glb")
    assert np.allclose(om.bounds(again), om.bounds(scene), atol=1e-4)
    assert om.statistics(again)["triangles"] == om.statistics(scene)["triangles"]


@pytest.mark.gl
def test_an_animated_gltf_file_renders_as_frames(animated, tmp_path):
    report = om.render_frames(animated, "0-2", engine="gl", size=(48, 36), fps=1, out=tmp_path / "f" / "%d.png",
                              workers=0)  # fmt: skip
    assert report.written == [0, 1, 2]
    from PIL import Image

    frames = [np.asarray(Image.open(p).convert("RGB")).astype(int) for p in report.files]
    assert np.abs(frames[0] - frames[2]).max() > 50  # the parts moved
