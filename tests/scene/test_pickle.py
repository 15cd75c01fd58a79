"""Scenes travel: every component and node pickles and deep-copies to an equal graph.

Like the scene-file test, every registered component type round-trips (built-in
types with the samples of ``test_files``, engine-specific ones by their
qualified names); graphs keep their sharing, parent order and paths; caches
are not sent (a MeshFile travels as its path).
"""

from __future__ import annotations

import copy
import inspect
import pickle

import numpy as np
import pytest
from test_files import OBJ, _params_equal, _samples

import omnirender as om
from omnirender.core.component import RenderingComponent
from omnirender.scene import files


def _engine_components() -> list[RenderingComponent]:
    from test_files_engine_types import SAMPLES

    out = []
    for prefix in ("povray", "gl", "mitsuba", "animation"):
        module = getattr(om, prefix)
        for name in module.__all__:
            cls = getattr(module, name)
            if inspect.isclass(cls) and issubclass(cls, RenderingComponent) and not name.startswith("SDL"):
                make = SAMPLES.get(name)
                out.append(make(module) if make else _default(cls))
    return out


def _default(cls: type) -> RenderingComponent:
    if cls is om.animation.Keyframes:
        return cls(om.Translation(1, 2, 3), "offset", [0, 1], [(0, 0, 0), (1, 2, 3)])
    if cls is om.animation.Orbit:
        return cls(om.Camera.look_at(eye=(4, 3, 6)), seconds=2.0)
    return cls()


def _all_components(tmp_path) -> list[RenderingComponent]:
    samples = _samples(tmp_path)
    builtin = {n: c for n, c in files.registered_types().items() if "." not in n}
    missing = set(builtin) - set(samples)
    assert not missing, f"add samples for {sorted(missing)} to test_files._samples()"
    return [c for name in sorted(builtin) for c in samples[name]] + _engine_components()


@pytest.mark.parametrize("copier", ["pickle", "deepcopy"])
def test_every_registered_type_round_trips(tmp_path, copier):
    originals = _all_components(tmp_path)
    scene = om.Node("scene", [om.Node(f"n{i}", [c]) for i, c in enumerate(originals)])
    again = pickle.loads(pickle.dumps(scene)) if copier == "pickle" else copy.deepcopy(scene)
    got = [child.components[0] for child in again.children]
    assert len(got) == len(originals)
    for a, b in zip(originals, got, strict=True):
        assert type(a) is type(b) and a is not b
        assert _params_equal(a.parameters(), b.parameters()), (type(a).__name__, a.parameters(), b.parameters())
        assert b.version == a.version
        assert b._owners == [again.children[got.index(b)]]  # re-attached to its restored node
    # every class in the list really was reached (engine-specific and animation types included)
    names = {type(c).__name__ for c in got}
    assert {"Camera", "MeshFile", "Finish", "DepthTest", "BSDF", "Animation", "Keyframes"} <= names


def test_unpickled_components_are_live():
    """Owners are restored: changing a parameter reaches the nodes (engines see the change)."""
    scene = om.Node("scene", [om.Node("body", [om.Camera.look_at(eye=(4, 3, 6)), om.Sphere()])])
    again = pickle.loads(pickle.dumps(scene))
    body = again["/scene/body"]
    before = (again.version, body.version)
    body.components[0].eye = (1, 2, 3)
    assert again.version > before[0] and body.version > before[1]
    before = (again.version, body.version)
    body.components[1].radius = 2.0
    assert again.version > before[0] and body.version > before[1]
    assert body.components[0].eye == (1, 2, 3)
    with pytest.raises(ValueError, match="must be > 0"):  # validation is back too
        body.components[1].radius = -1


def _dag() -> om.Node:
    lamp = om.PointLight(position=(5, 5, 5))
    mat = om.Material(diffuse=(1, 0, 0))
    wheel = om.Node("wheel", [mat, om.Torus(1, 0.2)], groups=["parts"])
    late, early = om.Node("late"), om.Node("early")
    root = om.Node("root", [lamp, early, late, om.Node("debug", [mat, om.Sphere()], groups="debug")])
    late.add(om.Translation(2, 0, 0))
    late.add(wheel)  # first parent: 'late', although 'early' comes first in the traversal
    early.add(wheel)
    early.add(om.LightSwitch(False, [lamp]))
    return root


@pytest.mark.parametrize("copier", [lambda x: pickle.loads(pickle.dumps(x)), copy.deepcopy])
def test_sharing_parent_order_and_paths_survive(copier):
    root = _dag()
    again = copier(root)
    wheel = again["/root/late/wheel"]
    assert wheel is again["/root/early/wheel"]
    assert wheel.path == "/root/late/wheel" == root["/root/late/wheel"].path
    assert [p.name for p in wheel.parents] == ["late", "early"]
    assert wheel.components[0] is again["/root/debug"].components[0]  # shared material
    assert again["/root/early"].components[0].lights[0] is again.components[0]  # LightSwitch -> the scene's light
    assert wheel.groups == frozenset({"parts"})
    assert [(op, type(o).__name__) for op, o in om.trace(again, mask="!debug")] == [
        (op, type(o).__name__) for op, o in om.trace(root, mask="!debug")
    ]
    assert om.bounds(again)[1].tolist() == om.bounds(root)[1].tolist()


def test_a_pickled_subgraph_comes_back_detached():
    root = _dag()
    early = pickle.loads(pickle.dumps(root["/root/early"]))
    assert early.parent is None and early.path == "/early"
    wheel = early["wheel"]
    assert wheel.parents == (early,)  # the parent outside the pickle ('late') is not dragged along
    assert wheel.path == "/early/wheel"
    # the light the LightSwitch refers to travels with it, owned by nobody in the copy
    assert early.components[0].lights[0]._owners is None


def test_mesh_files_travel_as_paths_and_embed_files_sends_triangles(tmp_path):
    mesh = tmp_path / "tet.obj"
    mesh.write_text(OBJ)
    scene = om.Node("scene", [om.Material(diffuse=(0, 1, 0)), om.MeshFile(mesh)])
    assert scene.components[1].triangle_count == 2  # parsed and cached here
    data = pickle.dumps(scene)
    assert b"tet.obj" in data and len(data) < 1500  # the path, not the parsed triangles
    again = pickle.loads(data)
    assert again.components[1].path == str(mesh) and again.components[1].triangle_count == 2
    mesh.rename(tmp_path / "moved.obj")  # a worker without the file cannot load it ...
    with pytest.raises(FileNotFoundError, match="tet.obj"):
        pickle.loads(data).components[1].parts()
    (tmp_path / "moved.obj").rename(mesh)
    embedded = om.embed_files(scene)  # ... unless the triangles travel with the scene
    assert not any(isinstance(c, om.MeshFile) for n in embedded.walk() for c in n.components)
    assert isinstance(scene.components[1], om.MeshFile)  # the user's graph is untouched
    mesh.unlink()
    far = pickle.loads(pickle.dumps(embedded))
    assert om.statistics(far)["triangles"] == 2
    assert np.allclose(om.bounds(far)[1], (1, 1, 1))


def test_textures_from_files_travel_as_paths_and_embed(tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image as PILImage

    path = tmp_path / "tex.png"
    PILImage.fromarray(np.full((4, 4, 3), 200, np.uint8)).save(path)
    tex = om.Texture(str(path), wrap="clamp")
    tex.image_array()
    data = pickle.dumps(om.Node("s", [tex]))
    assert len(data) < 1000
    embedded = om.embed_files(om.Node("s", [tex, om.Sphere()])).components[0]
    assert embedded.path is None and embedded.wrap == "clamp"
    assert np.array_equal(embedded.image_array(), tex.image_array())


def test_embed_files_names_the_node_of_a_missing_file(tmp_path):
    mesh = tmp_path / "gone.obj"
    mesh.write_text(OBJ)
    scene = om.Node("scene", [om.Node("part", [om.MeshFile(mesh)])])
    mesh.unlink()
    with pytest.raises(FileNotFoundError, match="/scene/part"):
        om.embed_files(scene)


@pytest.mark.gl
def test_an_unpickled_demo_renders_identically():
    from omnirender.demo import demo_scene

    scene = demo_scene()
    a = om.render(scene, engine="gl", size=(160, 120)).array
    b = om.render(pickle.loads(pickle.dumps(scene)), engine="gl", size=(160, 120)).array
    assert np.array_equal(a, b)
