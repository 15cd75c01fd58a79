"""om.load_usd: every feature on a small stage written with usd-core itself."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings

import numpy as np
import pytest
from engines import require

import omnirender as om
from omnirender.scene.registry import UntrustedContentError

pytest.importorskip("pxr")
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, UsdShade, Vt  # noqa: E402
from usd_stages import bind, preview_material, srgb  # noqa: E402


def _new(tmp_path, name="s.usda"):
    stage = Usd.Stage.CreateNew(str(tmp_path / name))
    UsdGeom.SetStageUpAxis(stage, "Y")
    return stage


def _save(stage):
    stage.GetRootLayer().Save()
    return stage.GetRootLayer().realPath


def _quad(stage, path, points=((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0))):
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.GetPointsAttr().Set(list(points))
    mesh.GetFaceVertexCountsAttr().Set([4])
    mesh.GetFaceVertexIndicesAttr().Set([0, 1, 2, 3])
    mesh.GetSubdivisionSchemeAttr().Set("none")
    return mesh


def _layer(path, name, schema, child=None, radius=None):
    """A file holding one prim (the default prim) of ``schema``, optionally with a child; returns the prim."""
    stage = Usd.Stage.CreateNew(str(path))
    prim = schema.Define(stage, f"/{name}").GetPrim()
    if radius is not None:
        UsdGeom.Sphere(prim).GetRadiusAttr().Set(radius)
    if child is not None:
        child[1].Define(stage, f"/{name}/{child[0]}")
    stage.SetDefaultPrim(prim)
    stage.GetRootLayer().Save()
    return prim


def _front_camera(stage, path="/World/Camera", z=4.0):
    cam = UsdGeom.Camera.Define(stage, path)
    cam.AddTranslateOp().Set(Gf.Vec3d(0, 0, z))
    cam.GetFocalLengthAttr().Set(35.0)
    return cam


# -- hierarchy and transforms ---------------------------------------------------------------
def test_prim_paths_are_node_paths_and_xform_ops_compose(tmp_path):
    stage = _new(tmp_path)
    arm = UsdGeom.Xform.Define(stage, "/World/Robot/Arm")
    robot = UsdGeom.Xform(stage.GetPrimAtPath("/World/Robot"))
    robot.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    robot.AddRotateYOp().Set(90.0)
    arm.AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
    cube = UsdGeom.Cube.Define(stage, "/World/Robot/Arm/Box")
    cube.GetSizeAttr().Set(1.0)
    cube.AddTranslateOp().Set(Gf.Vec3d(1, 0, 0))
    root = om.load_usd(_save(stage))
    node = root["/World/Robot/Arm/Box"]
    assert node.path == f"/{root.name}/World/Robot/Arm/Box"
    world = UsdGeom.Xformable(stage.GetPrimAtPath("/World/Robot/Arm/Box")).ComputeLocalToWorldTransform(0)
    expected = np.array(world).T @ np.array([0, 0, 0, 1.0])
    lo, hi = om.bounds(root)
    assert np.allclose((np.array(lo) + np.array(hi)) / 2, expected[:3], atol=1e-6)
    assert np.allclose(np.array(hi) - np.array(lo), 2.0, atol=1e-6)  # the unit cube scaled by 2


def test_reset_xform_stack_ignores_the_parent_transform(tmp_path):
    stage = _new(tmp_path)
    parent = UsdGeom.Xform.Define(stage, "/World/Parent")
    parent.AddTranslateOp().Set(Gf.Vec3d(10, 0, 0))
    ball = UsdGeom.Sphere.Define(stage, "/World/Parent/Ball")
    ball.GetRadiusAttr().Set(0.5)
    ball.SetResetXformStack(True)
    ball.AddTranslateOp().Set(Gf.Vec3d(0, 3, 0))
    lo, hi = om.bounds(om.load_usd(_save(stage)))
    assert np.allclose((np.array(lo) + np.array(hi)) / 2, (0, 3, 0), atol=1e-9)


def test_invisible_prims_and_other_purposes_are_left_out_and_kind_is_a_group(tmp_path):
    stage = _new(tmp_path)
    UsdGeom.Xform.Define(stage, "/World")
    Usd.ModelAPI(stage.GetPrimAtPath("/World")).SetKind("assembly")
    UsdGeom.Sphere.Define(stage, "/World/Shown")
    hidden = UsdGeom.Sphere.Define(stage, "/World/Hidden")
    hidden.MakeInvisible()
    guide = UsdGeom.Sphere.Define(stage, "/World/Guide")
    guide.GetPurposeAttr().Set("guide")
    proxy = UsdGeom.Xform.Define(stage, "/World/Proxy")
    proxy.GetPurposeAttr().Set("proxy")
    UsdGeom.Sphere.Define(stage, "/World/Proxy/Inner")
    path = _save(stage)
    root = om.load_usd(path)
    assert [c.name for c in root["/World"].children] == ["Shown"]
    assert "kind:assembly" in root["/World"].groups
    every = om.load_usd(path, purposes=("default", "render", "proxy", "guide"))
    assert {c.name for c in every["/World"].children} == {"Shown", "Guide", "Proxy"}


def test_z_up_stages_are_turned_y_up(tmp_path):
    stage = _new(tmp_path)
    UsdGeom.SetStageUpAxis(stage, "Z")
    ball = UsdGeom.Sphere.Define(stage, "/Ball")
    ball.AddTranslateOp().Set(Gf.Vec3d(0, 0, 5))
    lo, hi = om.bounds(om.load_usd(_save(stage)))
    assert np.allclose((np.array(lo) + np.array(hi)) / 2, (0, 5, 0), atol=1e-9)


# -- meshes ---------------------------------------------------------------------------------
def test_ngons_are_fan_triangulated_and_primvars_of_every_interpolation_are_read(tmp_path):
    stage = _new(tmp_path)
    mesh = UsdGeom.Mesh.Define(stage, "/M")
    mesh.GetPointsAttr().Set([(0, 0, 0), (1, 0, 0), (1.5, 1, 0), (0.5, 1.5, 0), (-0.5, 1, 0), (2, 0, 0), (2, 1, 0)])
    mesh.GetFaceVertexCountsAttr().Set([5, 3])  # a pentagon and a triangle
    mesh.GetFaceVertexIndicesAttr().Set([0, 1, 2, 3, 4, 1, 5, 6])
    mesh.GetSubdivisionSchemeAttr().Set("none")
    mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.uniform).Set([(1, 0, 0), (0, 0, 1)])
    api = UsdGeom.PrimvarsAPI(mesh.GetPrim())
    st = api.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying)
    st.Set([(0, 0), (1, 0), (1, 1)])
    st.SetIndices(Vt.IntArray([0, 1, 2, 2, 1, 0, 1, 2]))  # indexed face-varying
    mesh.GetNormalsAttr().Set([(0, 0, 1)] * 7)
    mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    root = om.load_usd(_save(stage))
    (ts,) = [c for c in root["/M"].components if isinstance(c, om.TriangleSet)]
    assert ts.triangle_count == 4
    colors = ts.color_array()
    assert np.allclose(colors[:9, :3], (1, 0, 0)) and np.allclose(colors[9:, :3], (0, 0, 1))  # per face
    uv = ts.texcoord_array()
    assert np.allclose(uv[3:6], [(0, 0), (1, 1), (1, 1)])  # corners 0, 2, 3 of the pentagon's fan
    assert np.allclose(uv[9:], [(0, 0), (1, 0), (1, 1)])  # the triangle's corners 5, 6, 7
    assert np.allclose(ts.normal_array(), (0, 0, 1))


def test_left_handed_meshes_are_wound_the_other_way(tmp_path):
    stage = _new(tmp_path)
    _quad(stage, "/R")
    left = _quad(stage, "/L")
    left.GetOrientationAttr().Set("leftHanded")
    root = om.load_usd(_save(stage))
    (rh,) = [c for c in root["/R"].components if isinstance(c, om.TriangleSet)]
    (lh,) = [c for c in root["/L"].components if isinstance(c, om.TriangleSet)]
    assert np.allclose(rh.index_array()[:, [0, 2, 1]], lh.index_array())


def test_subdivision_surfaces_are_drawn_as_their_cage_with_one_warning(tmp_path):
    stage = _new(tmp_path)
    for name in ("A", "B"):
        _quad(stage, f"/{name}").GetSubdivisionSchemeAttr().Set("catmullClark")
    with pytest.warns(UserWarning, match=r"2 subdivision surface\(s\) drawn as their control cage \(/A, /B\)"):
        om.load_usd(_save(stage))


def test_geom_subsets_get_their_own_materials(tmp_path):
    require("gl")
    stage = _new(tmp_path)
    _front_camera(stage)
    UsdLux.DistantLight.Define(stage, "/World/Sun").AddRotateXOp().Set(-35.0)  # no mirror highlight at the eye
    mesh = UsdGeom.Mesh.Define(stage, "/World/Two")
    mesh.GetPointsAttr().Set([(-1, -1, 0), (0, -1, 0), (0, 1, 0), (-1, 1, 0), (1, -1, 0), (1, 1, 0)])
    mesh.GetFaceVertexCountsAttr().Set([4, 4])
    mesh.GetFaceVertexIndicesAttr().Set([0, 1, 2, 3, 1, 4, 5, 2])
    mesh.GetSubdivisionSchemeAttr().Set("none")
    bind(mesh.GetPrim(), preview_material(stage, "/World/Looks/Blue", (0.0, 0.0, 0.8)))
    subset = UsdGeom.Subset.CreateGeomSubset(mesh, "left", "face", Vt.IntArray([0]), "materialBind")
    bind(subset.GetPrim(), preview_material(stage, "/World/Looks/Red", (0.8, 0.0, 0.0)))
    root = om.load_usd(_save(stage))
    assert root["/World/Two/left"] is not None
    img = om.render(root, engine="gl", size=(64, 48))
    left, right = img.rgb[24, 22].astype(int), img.rgb[24, 42].astype(int)
    assert left[0] > 100 > left[2] and right[2] > 100 > right[0], (left, right)


def test_textures_with_a_transform_and_their_primvar_reader(tmp_path):
    require("gl")
    from PIL import Image as PILImage

    pixels = np.zeros((16, 16, 4), np.uint8)
    pixels[:, :8] = (255, 0, 0, 255)  # left half red, right half blue
    pixels[:, 8:] = (0, 0, 255, 255)
    PILImage.fromarray(pixels).save(tmp_path / "halves.png")
    stage = _new(tmp_path)
    _front_camera(stage, z=2.5)
    UsdLux.DistantLight.Define(stage, "/World/Sun").AddRotateXOp().Set(-35.0)
    mesh = _quad(stage, "/World/Quad")
    st = UsdGeom.PrimvarsAPI(mesh.GetPrim()).CreatePrimvar("uv", Sdf.ValueTypeNames.TexCoord2fArray, "vertex")
    st.Set([(0, 0), (1, 0), (1, 1), (0, 1)])
    material = UsdShade.Material.Define(stage, "/World/Looks/Tex")
    surface = UsdShade.Shader.Define(stage, "/World/Looks/Tex/Surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    surface.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(1.0)
    reader = UsdShade.Shader.Define(stage, "/World/Looks/Tex/Reader")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.Token).Set("uv")
    transform = UsdShade.Shader.Define(stage, "/World/Looks/Tex/Mirror")
    transform.CreateIdAttr("UsdTransform2d")
    transform.CreateInput("in", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
    transform.CreateInput("scale", Sdf.ValueTypeNames.Float2).Set((-1.0, 1.0))  # u mirrored: blue on the left
    transform.CreateInput("translation", Sdf.ValueTypeNames.Float2).Set((1.0, 0.0))
    texture = UsdShade.Shader.Define(stage, "/World/Looks/Tex/Image")
    texture.CreateIdAttr("UsdUVTexture")
    texture.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("./halves.png")
    texture.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(transform.ConnectableAPI(), "result")
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(texture.ConnectableAPI(), "rgb")
    material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    bind(mesh.GetPrim(), material)
    root = om.load_usd(_save(stage))
    (pbr,) = [c for c in root["/World/Quad"].components if isinstance(c, om.PBRMaterial)]
    assert pbr.base_color_texture is not None and tuple(pbr.base_color_texture.scale) == (-1.0, 1.0)
    img = om.render(root, engine="gl", size=(64, 48))
    left, right = img.rgb[24, 20].astype(int), img.rgb[24, 44].astype(int)
    assert left[2] > 100 > left[0] and right[0] > 100 > right[2], (left, right)


def test_unknown_shading_networks_fall_back_with_a_warning_naming_them(tmp_path):
    stage = _new(tmp_path)
    ball = UsdGeom.Sphere.Define(stage, "/Ball")
    ball.CreateDisplayColorPrimvar().Set([(0.0, 1.0, 0.0)])
    material = UsdShade.Material.Define(stage, "/Looks/Mdl")
    shader = UsdShade.Shader.Define(stage, "/Looks/Mdl/Shader")
    shader.CreateIdAttr("mdl_OmniPBR")
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    bind(ball.GetPrim(), material)
    with pytest.warns(UserWarning, match=r"/Looks/Mdl.*not a UsdPreviewSurface.*mdl_OmniPBR"):
        root = om.load_usd(_save(stage))
    (pbr,) = [c for c in root["/Ball"].components if isinstance(c, om.PBRMaterial)]
    assert pbr.base_color == pytest.approx((0.0, 1.0, 0.0))  # its displayColor


def test_gprims_points_curves_and_capsules(tmp_path):
    stage = _new(tmp_path)
    cyl = UsdGeom.Cylinder.Define(stage, "/Cyl")  # axis z by default
    cyl.GetHeightAttr().Set(4.0)
    cyl.GetRadiusAttr().Set(0.5)
    UsdGeom.Capsule.Define(stage, "/Cap").AddTranslateOp().Set(Gf.Vec3d(5, 0, 0))
    points = UsdGeom.Points.Define(stage, "/Pts")
    points.GetPointsAttr().Set([(0, 5, 0), (1, 5, 0)])
    curves = UsdGeom.BasisCurves.Define(stage, "/Curves")
    curves.GetPointsAttr().Set([(0, -5, 0), (1, -5, 0), (2, -4, 0)])
    curves.GetCurveVertexCountsAttr().Set([3])
    curves.GetTypeAttr().Set("linear")
    root = om.load_usd(_save(stage))
    lo, hi = om.bounds(root["/Cyl"])
    assert np.allclose(np.array(hi) - np.array(lo), (1, 1, 4), atol=0.05)
    lo, hi = om.bounds(root["/Cap"])
    assert np.allclose(np.array(hi) - np.array(lo), (1, 1, 2), atol=0.05)  # height 1 + two radii 0.5, along z
    (pts,) = [c for c in root["/Pts"].components if isinstance(c, om.PointSet)]
    assert len(pts.vertex_array()) == 2
    (lines,) = [c for c in root["/Curves"].components if isinstance(c, om.LineSet)]
    assert lines.index_array().tolist() == [[0, 1], [1, 2]]


# -- lights and cameras ---------------------------------------------------------------------
def test_lights_become_omnirender_lights(tmp_path):
    stage = _new(tmp_path)
    UsdLux.DistantLight.Define(stage, "/Sun").GetIntensityAttr().Set(2.0)
    sphere = UsdLux.SphereLight.Define(stage, "/Bulb")
    sphere.GetRadiusAttr().Set(0.5)
    sphere.GetIntensityAttr().Set(8.0)
    rect = UsdLux.RectLight.Define(stage, "/Panel")
    rect.GetWidthAttr().Set(2.0)
    rect.GetHeightAttr().Set(1.0)
    UsdLux.DiskLight.Define(stage, "/Disk")
    dome = UsdLux.DomeLight.Define(stage, "/Sky")
    dome.GetColorAttr().Set((0.5, 0.5, 0.5))
    dome.GetIntensityAttr().Set(0.3)
    root = om.load_usd(_save(stage))

    def light(path):
        (found,) = [c for c in root[path].components if isinstance(c, om.LightSource)]
        return found

    assert isinstance(light("/Sun"), om.DirectionalLight)
    assert light("/Sun").intensity == pytest.approx(2.0 * math.sin(math.radians(0.53 / 2)) ** 2)
    bulb = light("/Bulb")
    assert isinstance(bulb, om.PointLight) and bulb.intensity == pytest.approx(8.0 * 0.25)
    assert (bulb.constant, bulb.quadratic) == (0.0, 1.0)
    panel = light("/Panel")  # USD's radiance is the area lights' radiance: no factor (issue 26)
    assert isinstance(panel, om.RectLight) and (panel.width, panel.height) == (2.0, 1.0)
    assert panel.intensity == pytest.approx(1.0) and panel.direction == (0.0, 0.0, -1.0)
    disk = light("/Disk")
    assert isinstance(disk, om.DiscLight) and disk.radius == pytest.approx(0.5)
    sky = light("/Sky")
    assert isinstance(sky, om.AmbientLight) and sky.intensity == pytest.approx(0.3)
    assert np.allclose(sky.color, srgb((0.5, 0.5, 0.5)))


def test_the_camera_is_the_first_or_the_one_chosen_by_path(tmp_path):
    stage = _new(tmp_path)
    _front_camera(stage, "/A", z=4.0)
    far = _front_camera(stage, "/B", z=9.0)
    far.GetFocalLengthAttr().Set(50.0)
    path = _save(stage)
    first = [c for n in om.load_usd(path).walk() for c in n.components if isinstance(c, om.Camera)]
    assert len(first) == 2
    chosen = om.load_usd(path, camera="/B")
    (cam,) = [c for n in chosen.walk() for c in n.components if isinstance(c, om.Camera)]
    aperture = far.GetVerticalApertureAttr().Get()  # USD's default film back
    assert cam.fov == pytest.approx(math.degrees(2 * math.atan(aperture / 100.0)))
    with pytest.raises(ValueError, match="no camera at '/C'"):
        om.load_usd(path, camera="/C")


# -- instancing -----------------------------------------------------------------------------
def test_point_instancer_becomes_an_instance_set(tmp_path):
    stage = _new(tmp_path)
    instancer = UsdGeom.PointInstancer.Define(stage, "/Crowd")
    proto = UsdGeom.Cube.Define(stage, "/Crowd/Prototypes/Box")
    proto.GetSizeAttr().Set(1.0)
    instancer.CreatePrototypesRel().SetTargets([proto.GetPath()])
    n = 6
    instancer.CreateProtoIndicesAttr([0] * n)
    instancer.CreatePositionsAttr([(2.0 * i, 0, 0) for i in range(n)])
    half = math.sqrt(0.5)
    instancer.CreateOrientationsAttr([Gf.Quath(half, 0, half, 0)] * n)  # 90 degrees about y
    instancer.CreateScalesAttr([(1, 2, 1)] * n)
    instancer.CreateIdsAttr(list(range(10, 10 + n)))
    instancer.CreateInvisibleIdsAttr([12])
    root = om.load_usd(_save(stage))
    (node,) = root["/Crowd"].children
    (sets,) = [c for c in node.components if isinstance(c, om.InstanceSet)]
    assert len(sets.matrices()) == n
    assert sets.visible_array().tolist() == [True, True, False, True, True, True]
    expected = np.array(instancer.ComputeInstanceTransformsAtTime(0, 0)).transpose(0, 2, 1)  # the visible ones
    assert np.allclose(sets.matrices()[sets.visible_array()], expected, atol=2e-3)  # half-precision quaternions


def test_instanceable_prims_share_one_node(tmp_path):
    _layer(tmp_path / "part.usda", "Part", UsdGeom.Xform, child=("Ball", UsdGeom.Sphere))
    stage = _new(tmp_path)
    for k in range(3):
        prim = stage.DefinePrim(f"/Copy{k}")
        prim.GetReferences().AddReference("./part.usda")
        prim.SetInstanceable(True)
        UsdGeom.Xformable(prim).AddTranslateOp().Set(Gf.Vec3d(3.0 * k, 0, 0))
    root = om.load_usd(_save(stage))
    shared = [root[f"/Copy{k}"].children[0] for k in range(3)]
    assert shared[0] is shared[1] is shared[2]
    lo, hi = om.bounds(root)
    assert np.allclose(lo, (-1, -1, -1)) and np.allclose(hi, (7, 1, 1))


# -- animation ------------------------------------------------------------------------------
def test_time_samples_become_animation_tracks(tmp_path):
    stage = _new(tmp_path)
    stage.SetTimeCodesPerSecond(24)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(49)
    ball = UsdGeom.Sphere.Define(stage, "/Ball")
    op = ball.AddTranslateOp()
    op.Set(Gf.Vec3d(0, 0, 0), 1)
    op.Set(Gf.Vec3d(4, 0, 0), 49)
    blob = UsdGeom.Mesh.Define(stage, "/Blob")  # deforming points are not animated: said, not dropped silently
    blob.GetPointsAttr().Set([(0, 0, 0), (1, 0, 0), (0, 1, 0)], 1)
    blob.GetPointsAttr().Set([(0, 0, 0), (2, 0, 0), (0, 1, 0)], 49)
    blob.GetFaceVertexCountsAttr().Set([3])
    blob.GetFaceVertexIndicesAttr().Set([0, 1, 2])
    blob.GetSubdivisionSchemeAttr().Set("none")
    with pytest.warns(UserWarning, match=r"1 time-sampled attribute\(s\) other than transforms.*/Blob.points"):
        root = om.load_usd(_save(stage))
    (anim,) = [c for c in root.components if isinstance(c, om.Animation)]
    assert anim.duration == pytest.approx(2.0)
    for t in (0.0, 1.0, 2.0):
        at = om.scene_at(root, t)
        lo, hi = om.bounds(om.Node("ball", [at["/Ball"]]))
        assert np.allclose((np.array(lo) + np.array(hi)) / 2, (2.0 * t, 0, 0), atol=1e-6)


# -- composition and the path policy --------------------------------------------------------
def test_composition_inside_the_folder_and_refusal_outside_unless_trusted(tmp_path):
    inside = tmp_path / "project"
    inside.mkdir()
    _layer(inside / "ball.usda", "B", UsdGeom.Sphere, radius=2.0)
    _layer(tmp_path / "secret.usda", "S", UsdGeom.Cube)
    stage = _new(inside)
    stage.DefinePrim("/Ref").GetReferences().AddReference("./ball.usda")
    variants = stage.DefinePrim("/Pick").GetVariantSets().AddVariantSet("size")
    for name, radius in (("small", 0.5), ("large", 3.0)):
        variants.AddVariant(name)
        variants.SetVariantSelection(name)
        with variants.GetVariantEditContext():
            UsdGeom.Sphere.Define(stage, "/Pick/Ball").GetRadiusAttr().Set(radius)
    variants.SetVariantSelection("small")
    path = _save(stage)
    root = om.load_usd(path)
    (ball,) = [c for c in root["/Ref"].components if isinstance(c, om.Sphere)]
    assert ball.radius == 2.0
    (picked,) = [c for c in root["/Pick/Ball"].components if isinstance(c, om.Sphere)]
    assert picked.radius == 0.5
    stage.DefinePrim("/Leak").GetReferences().AddReference("../secret.usda")
    path = _save(stage)
    with pytest.raises(UntrustedContentError, match="outside the stage's folder"):
        om.load_usd(path)
    assert om.load_usd(path, trusted=True)["/Leak"] is not None
    stage.DefinePrim("/Missing").GetReferences().AddReference("./nowhere.usda")
    with pytest.warns(UserWarning, match=r"composition errors: Could not open asset @.*nowhere.usda@"):
        om.load_usd(_save(stage), trusted=True)


# -- other entry points ---------------------------------------------------------------------
def test_mesh_file_reads_usd_files_and_packages(tmp_path):
    stage = _new(tmp_path, "m.usdc")
    _quad(stage, "/Q")
    _save(stage)
    parts = om.MeshFile(tmp_path / "m.usdc").parts()
    assert len(parts) == 1 and parts[0][1].triangle_count == 2
    from pxr import UsdUtils

    assert UsdUtils.CreateNewUsdzPackage(str(tmp_path / "m.usdc"), str(tmp_path / "m.usdz"))
    lo, hi = om.bounds(om.Node("m", [om.MeshFile(tmp_path / "m.usdz")]))
    assert np.allclose(lo, (-1, -1, 0)) and np.allclose(hi, (1, 1, 0))
    gprims = _new(tmp_path, "g.usda")  # spheres, cubes... are tessellated into the mesh's parts
    UsdGeom.Sphere.Define(gprims, "/Ball").AddTranslateOp().Set(Gf.Vec3d(0, 5, 0))
    UsdGeom.Cube.Define(gprims, "/Box")
    lo, hi = om.bounds(om.Node("m", [om.MeshFile(_save(gprims))]))
    assert np.allclose(lo, (-1, -1, -1), atol=0.02) and np.allclose(hi, (1, 6, 1), atol=0.02)


def test_load_usd_takes_a_stage_and_refuses_bad_input(tmp_path):
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.Sphere.Define(stage, "/Ball")
    assert om.load_usd(stage)["/Ball"] is not None
    with pytest.raises(FileNotFoundError, match="no such file"):
        om.load_usd(tmp_path / "missing.usda")
    (tmp_path / "junk.usda").write_text("#usda 1.0\ndef Sphere {{{")
    with pytest.raises(ValueError, match="junk.usda.*cannot open the stage"):
        om.load_usd(tmp_path / "junk.usda")
    bad = _new(tmp_path, "bad.usda")
    mesh = UsdGeom.Mesh.Define(bad, "/M")
    mesh.GetPointsAttr().Set([(0, 0, 0)])
    mesh.GetFaceVertexCountsAttr().Set([3])
    mesh.GetFaceVertexIndicesAttr().Set([0, 1, 2])
    with pytest.raises(ValueError, match="/M: a face vertex index is out of range"):
        om.load_usd(_save(bad))


def test_the_command_line_renders_a_stage(tmp_path):
    require("gl")
    from usd_stages import shapes_stage

    stage = shapes_stage(tmp_path)
    out = tmp_path / "shapes.png"
    done = subprocess.run(
        [sys.executable, "-m", "omnirender.cli", "render", str(stage), "-o", str(out), "--size", "80x60"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    with warnings.catch_warnings():
        img = np.asarray(__import__("PIL.Image", fromlist=["Image"]).open(out))
    assert img.shape[:2] == (60, 80) and img[..., :3].std() > 10


def test_a_point_instancer_draws_as_one_instanced_batch(tmp_path):
    require("gl")
    from omnirender.gl import GLEngine

    calls = []
    for count in (10, 2000):
        stage = _new(tmp_path, f"crowd{count}.usda")
        instancer = UsdGeom.PointInstancer.Define(stage, "/Crowd")
        proto = UsdGeom.Sphere.Define(stage, "/Crowd/Prototypes/Ball")
        instancer.CreatePrototypesRel().SetTargets([proto.GetPath()])
        instancer.CreateProtoIndicesAttr([0] * count)
        instancer.CreatePositionsAttr([(3.0 * (i % 50), 0, 3.0 * (i // 50)) for i in range(count)])
        engine = GLEngine(size=(64, 48), samples=0, shadows=False)
        try:
            engine.render(om.load_usd(_save(stage)), read_depth=False)
            calls.append(engine.stats["draw_calls"])
        finally:
            engine.release()
    assert calls[0] == calls[1], calls


def test_the_command_line_exports_and_animates_stages(tmp_path):
    from usd_stages import shapes_stage

    from omnirender.cli import main

    stage = shapes_stage(tmp_path)
    assert main(["export", str(stage), str(tmp_path / "again.usdc")]) == 0
    assert main(["export", str(tmp_path / "again.usdc"), str(tmp_path / "same.glb")]) == 0
    assert (tmp_path / "same.glb").stat().st_size > 1000
    moving = _new(tmp_path, "moving.usda")
    moving.SetStartTimeCode(0)
    moving.SetEndTimeCode(2)
    moving.SetTimeCodesPerSecond(2)
    op = UsdGeom.Sphere.Define(moving, "/Ball").AddTranslateOp()
    op.Set(Gf.Vec3d(0, 0, 0), 0)
    op.Set(Gf.Vec3d(1, 0, 0), 2)
    frames = tmp_path / "frames" / "%02d.png"
    assert main(["animate", _save(moving), "-o", str(frames), "--size", "32x24", "--workers", "0"]) == 0
    assert len(list((tmp_path / "frames").glob("*.png"))) >= 2
