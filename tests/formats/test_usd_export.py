"""om.export to USD: the written stages pass USD's validators and read back as the same GL image."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from engines import require

import omnirender as om

pytest.importorskip("pxr")
from pxr import Usd, UsdGeom, UsdLux, UsdShade  # noqa: E402

from omnirender.demo import demo_scene  # noqa: E402
from omnirender.formats.usd.writer import validate  # noqa: E402

SIZE = (160, 120)
SCENES = Path(__file__).resolve().parents[2] / "examples" / "scenes"


def _diff(a: om.Node, b: om.Node, size=SIZE) -> float:
    x = om.render(a, engine="gl", size=size).rgb.astype(np.float64)
    y = om.render(b, engine="gl", size=size).rgb.astype(np.float64)
    return float(np.abs(x - y).mean())


def feature_scene() -> om.Node:
    """PBR and Phong materials, a texture with a transform, vertex colours, an instance set, lines, points,
    every light type, a background and an animated transform."""
    checker = np.kron((np.indices((4, 4)).sum(axis=0) % 2)[..., None] * 200 + 40, np.ones((8, 8, 1)))
    pixels = np.concatenate([checker.repeat(3, axis=2), np.full((32, 32, 1), 255)], axis=2).astype(np.uint8)
    scene = om.Node("features", [om.Camera.look_at(eye=(3, 4, 9), center=(0, 0.5, 0), fov=40)])
    scene.add(om.Background((0.2, 0.25, 0.3)))
    scene.add(om.DirectionalLight(direction=(-0.4, -1, -0.3), intensity=0.7))
    scene.add(om.PointLight(position=(2, 3, 2), intensity=0.4, constant=1.0, linear=0.1))
    scene.add(om.SpotLight(position=(-2, 4, 1), direction=(0.3, -1, 0), cutoff=35, exponent=4, intensity=0.5))
    scene.add(om.AmbientLight(intensity=0.15))
    floor = scene.add(
        om.Node("floor", [om.Texture(pixels, scale=(2, 2), rotation=15), om.Material(diffuse=(0.9, 0.9, 0.9))])
    )
    floor.add(om.Box(size=(8, 0.2, 8), center=(0, -0.1, 0)))
    ball = scene.add(om.Node("ball", [om.Translation(-1.5, 0.8, 0)]))
    ball.add(om.PBRMaterial(base_color=(0.9, 0.3, 0.1), metallic=0.3, roughness=0.4))
    ball.add(om.Sphere(radius=0.8))
    spin = scene.add(om.Node("spin", [om.Translation(1.5, 0.6, 0)]))
    turn = spin.add(om.Rotation(0, (0, 1, 0)))
    spin.add(om.Material(diffuse=(0.2, 0.5, 0.9), specular=(1, 1, 1), shininess=50))
    spin.add(om.Cone(radius=0.5, height=1.2))
    spin.add(om.Node("drum", [om.Translation(0, 1.2, 0), om.Cylinder(radius=0.3, height=0.6)]))
    scene.add(om.Animation([om.Keyframes(turn, "angle", [0.0, 2.0], [0.0, 180.0])], fps=12))
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float64)
    scene.add(
        om.Node("tri", [om.Translation(0, 0.2, 2), om.TriangleSet(tri, colors=[(1, 0, 0), (0, 1, 0), (0, 0, 1)])])
    )
    positions = np.array([[x, 0.15, -2.5] for x in np.linspace(-3, 3, 7)])
    crowd = om.InstanceSet(om.Box(size=0.3), positions, colors=np.tile([0.9, 0.9, 0.2], (7, 1)))
    scene.add(om.Node("crowd", [om.Color(0.5, 0.5, 0.5), crowd]))
    lines = om.LineSet(np.array([[-3, 2, -3], [3, 2, -3], [3, 2, -3], [3, 3, -3]], np.float64))
    scene.add(om.Node("lines", [om.Color(1, 1, 0), lines, om.PointSet(np.array([[0, 3, -3.0]]))]))
    return scene


@pytest.mark.parametrize("suffix", [".usda", ".usdc", ".usdz"])
def test_the_demo_scene_round_trips_and_validates(tmp_path, suffix):
    require("gl")
    scene = demo_scene()
    path = om.export(scene, tmp_path / f"demo{suffix}")
    assert path.is_file()
    assert validate(path) == []
    diff = _diff(scene, om.load_usd(path))
    assert diff <= 2.0, f"mean |diff| {diff:.3f}/255"


@pytest.mark.parametrize("name", ["demo.yaml", "features.yaml"])
def test_example_scene_files_round_trip(tmp_path, name):
    require("gl")
    pytest.importorskip("yaml")
    scene = om.load(SCENES / name)
    path = om.export(scene, tmp_path / "scene.usda")
    assert validate(path) == []
    diff = _diff(scene, om.load_usd(path))
    assert diff <= 2.0, f"{name}: mean |diff| {diff:.3f}/255"


def test_every_feature_round_trips_validates_and_animates(tmp_path):
    require("gl")
    scene = feature_scene()
    path = om.export(scene, tmp_path / "features.usda")
    assert validate(path) == []
    assert (tmp_path / "features_textures").is_dir()
    back = om.load_usd(path)
    for t in (0.0, 1.0):
        diff = _diff(om.scene_at(scene, t), om.scene_at(back, t))
        assert diff <= 2.0, f"t={t}: mean |diff| {diff:.3f}/255"


def test_the_written_stage_is_plain_usd(tmp_path):
    """What other USD tools see: prims of the right schemas, a PreviewSurface network, lights, a camera."""
    path = om.export(feature_scene(), tmp_path / "f.usdc")
    stage = Usd.Stage.Open(str(path))
    assert stage.GetDefaultPrim().GetName() == "features"
    assert UsdGeom.GetStageUpAxis(stage) == "Y"
    types = {str(p.GetTypeName()) for p in stage.Traverse()}
    assert {"Xform", "Cube", "Sphere", "Cone", "Cylinder", "Mesh", "PointInstancer", "BasisCurves", "Points",
            "Camera", "DistantLight", "SphereLight", "DomeLight", "Material", "Shader"} <= types  # fmt: skip
    instancer = UsdGeom.PointInstancer(next(p for p in stage.Traverse() if p.GetTypeName() == "PointInstancer"))
    assert len(instancer.GetPositionsAttr().Get()) == 7
    shaders = [UsdShade.Shader(p) for p in stage.Traverse() if p.GetTypeName() == "Shader"]
    assert {"UsdPreviewSurface", "UsdUVTexture", "UsdPrimvarReader_float2", "UsdTransform2d"} <= {
        s.GetIdAttr().Get() for s in shaders
    }
    spin = [p for p in stage.Traverse() if UsdGeom.Xformable(p) and UsdGeom.Xformable(p).TransformMightBeTimeVarying()]
    assert spin and stage.GetEndTimeCode() == pytest.approx(24.0)
    sun = UsdLux.DistantLight(next(p for p in stage.Traverse() if p.GetTypeName() == "DistantLight"))
    assert sun.GetIntensityAttr().Get() == pytest.approx(0.7 * math.pi)


def test_export_refuses_an_unknown_suffix_and_writes_atomically(tmp_path):
    from omnirender.formats.usd.writer import export

    with pytest.raises(ValueError, match="must end in one of"):
        export(om.Node("s", [om.Sphere()]), tmp_path / "x.usdx")
    path = om.export(om.Node("s", [om.Sphere()]), tmp_path / "x.usda")
    assert [p.name for p in tmp_path.iterdir()] == ["x.usda"]  # no temporary files left
    assert "def Sphere" in path.read_text()


def test_without_omnirender_attributes_the_plain_usd_mapping_looks_alike(tmp_path):
    """What another USD tool sees (UsdPreviewSurface, physical UsdLux units) reads back close to the original."""
    require("gl")
    from omnirender.colorimetry import cielab, delta_e2000

    scene = demo_scene()
    path = om.export(scene, tmp_path / "plain.usda")
    stage = Usd.Stage.Open(str(path))
    for prim in stage.Traverse():
        for attr in prim.GetAttributes():
            if attr.GetName().startswith("omnirender:"):
                prim.RemoveProperty(attr.GetName())
    stage.GetRootLayer().Save()
    a = om.render(scene, engine="gl", size=SIZE)
    b = om.render(om.load_usd(path), engine="gl", size=SIZE)
    assert float(np.mean(a.mask == b.mask)) >= 0.98
    both = a.mask & b.mask
    de = delta_e2000(cielab(a.rgb[both].astype(np.float64)), cielab(b.rgb[both].astype(np.float64)))
    assert float(np.median(de)) <= 8.0, f"median CIEDE2000 {np.median(de):.1f}"


def test_area_lights_round_trip_as_usdlux_rect_and_disk_lights(tmp_path):
    """om.RectLight / om.DiscLight -> UsdLux RectLight / DiskLight (radiance L) -> the same lights (issue 26)."""
    from pxr import Usd, UsdLux

    root = om.Node("scene", [om.Camera.look_at((0, 3, 6), (0, 0, 0))])
    lamp = root.add(om.Node("lamp", [om.Translation((0, 2, 0)), om.Scaling(2.0)]))
    lamp.add(om.RectLight(direction=(0, -1, 0), width=1.0, height=0.5, intensity=3.0, two_sided=True))
    root.add(
        om.Node("disc", [om.DiscLight(position=(1, 2, 0), direction=(0, -1, 0), radius=0.25, casts_shadows=False)])
    )
    root.add(om.Node("box", [om.Box()]))
    path = tmp_path / "area.usda"
    om.export(root, path)
    stage = Usd.Stage.Open(str(path))
    rects = [UsdLux.RectLight(p) for p in stage.Traverse() if p.IsA(UsdLux.RectLight)]
    disks = [UsdLux.DiskLight(p) for p in stage.Traverse() if p.IsA(UsdLux.DiskLight)]
    assert len(rects) == 1 and len(disks) == 1
    assert (rects[0].GetWidthAttr().Get(), rects[0].GetHeightAttr().Get()) == pytest.approx((2.0, 1.0))
    assert rects[0].GetIntensityAttr().Get() == pytest.approx(3.0)
    assert disks[0].GetRadiusAttr().Get() == pytest.approx(0.25)
    back = om.load_usd(path)
    found = {type(c).__name__: c for node in back.walk() for c in node.components if isinstance(c, om.LightSource)}
    assert found["RectLight"].two_sided and found["RectLight"].intensity == pytest.approx(3.0)
    assert not found["DiscLight"].casts_shadows
    # placed by the prims' transforms: the same picture as the original lights give
    img_a = om.render(root, engine="gl", size=(48, 36), samples=0)
    img_b = om.render(back, engine="gl", size=(48, 36), samples=0)
    assert np.abs(img_a.array.astype(int) - img_b.array.astype(int)).mean() < 1.0
