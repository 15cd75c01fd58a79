"""Small USD stages written with usd-core itself (one feature each), and the omnirender scenes they mean.

The builders return the path of the written ``.usda``; ``equivalent_*`` build
the same scene directly with omnirender, following the documented mapping
(linear USD colours as sRGB display values, UsdPreviewSurface as PBRMaterial,
a DistantLight of intensity I as a DirectionalLight of intensity I).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

import omnirender as om
from omnirender.attributes.photometry import linear_to_srgb

FOCAL = 35.0
APERTURE = 20.955
FOV = math.degrees(2 * math.atan(APERTURE / (2 * FOCAL)))
EYE = (0.0, 1.5, 7.0)
SUN_ROTATION = -40.0  # about x: the distant light leans towards -z and down
#: the radiance of a 0.53 degree sun disc whose irradiance is pi: omnirender's DirectionalLight of intensity 1
SUN = 1.0 / math.sin(math.radians(0.53 / 2)) ** 2


def srgb(c):
    return tuple(float(v) for v in np.clip(linear_to_srgb(np.asarray(c, np.float64)), 0, 1))


def _stage(path: Path):
    from pxr import Gf, Usd, UsdGeom, UsdLux

    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    cam = UsdGeom.Camera.Define(stage, "/World/Camera")
    cam.AddTranslateOp().Set(Gf.Vec3d(*EYE))
    cam.GetFocalLengthAttr().Set(FOCAL)
    cam.GetVerticalApertureAttr().Set(APERTURE)
    cam.GetHorizontalApertureAttr().Set(APERTURE * 4 / 3)
    cam.GetClippingRangeAttr().Set(Gf.Vec2f(0.1, 100))
    sun = UsdLux.DistantLight.Define(stage, "/World/Sun")
    sun.AddRotateXOp().Set(SUN_ROTATION)
    sun.GetIntensityAttr().Set(SUN)
    return stage


def preview_material(stage, path: str, diffuse, roughness=0.8, metallic=0.0, opacity=None):
    from pxr import Sdf, UsdShade

    material = UsdShade.Material.Define(stage, path)
    shader = UsdShade.Shader.Define(stage, path + "/Surface")
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(tuple(diffuse))
    shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(roughness)
    shader.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(metallic)
    if opacity is not None:
        shader.CreateInput("opacity", Sdf.ValueTypeNames.Float).Set(opacity)
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    return material


def bind(prim, material) -> None:
    from pxr import UsdShade

    UsdShade.MaterialBindingAPI.Apply(prim).Bind(material)


RED, GREEN, BLUE, GREY = (0.8, 0.05, 0.05), (0.05, 0.6, 0.1), (0.05, 0.1, 0.8), (0.5, 0.5, 0.5)


def shapes_stage(folder: Path) -> Path:
    """Camera, sun, a floor mesh (a quad and a pentagon), a sphere, a cube, a cylinder and a cone (axis y)."""
    from pxr import Gf, UsdGeom

    path = folder / "shapes.usda"
    stage = _stage(path)
    floor = UsdGeom.Mesh.Define(stage, "/World/Floor")
    floor.GetPointsAttr().Set([(-3, 0, -3), (3, 0, -3), (3, 0, 3), (-3, 0, 3), (0, 0, -4)])
    floor.GetFaceVertexCountsAttr().Set([4])
    floor.GetFaceVertexIndicesAttr().Set([3, 2, 1, 0])
    floor.GetSubdivisionSchemeAttr().Set("none")
    bind(floor.GetPrim(), preview_material(stage, "/World/Looks/Grey", GREY))
    items = [
        ("Ball", UsdGeom.Sphere, (-1.6, 0.7, 0.0), RED),
        ("Crate", UsdGeom.Cube, (0.0, 0.5, 0.0), GREEN),
        ("Drum", UsdGeom.Cylinder, (1.6, 0.5, 0.0), BLUE),
        ("Peak", UsdGeom.Cone, (0.0, 0.6, -1.8), RED),
    ]
    for name, schema, offset, color in items:
        prim = schema.Define(stage, f"/World/{name}")
        prim.AddTranslateOp().Set(Gf.Vec3d(*offset))
        if schema is UsdGeom.Sphere:
            prim.GetRadiusAttr().Set(0.7)
        elif schema is UsdGeom.Cube:
            prim.GetSizeAttr().Set(1.0)
        else:
            prim.GetRadiusAttr().Set(0.5)
            prim.GetHeightAttr().Set(1.0 if schema is UsdGeom.Cylinder else 1.2)
            prim.GetAxisAttr().Set("Y")
        bind(prim.GetPrim(), preview_material(stage, f"/World/Looks/{name}", color))
    stage.GetRootLayer().Save()
    return path


def equivalent_shapes() -> om.Node:
    """The scene of :func:`shapes_stage`, built with omnirender."""

    def pbr(c):
        return om.PBRMaterial(base_color=srgb(c), metallic=0.0, roughness=0.8)

    scene = om.Node("shapes")
    scene.add(om.Node("Camera", [om.Translation(*EYE), om.Camera(eye=(0, 0, 0), center=(0, 0, -1), fov=FOV, near=0.1,
                                                                  far=100)]))  # fmt: skip
    scene.add(om.Node("Sun", [om.Rotation(SUN_ROTATION, (1, 0, 0)), om.DirectionalLight(direction=(0, 0, -1))]))
    floor = np.array([(-3, 0, -3), (3, 0, -3), (3, 0, 3), (-3, 0, 3)], np.float64)
    scene.add(om.Node("Floor", [pbr(GREY), om.TriangleSet(floor, [[3, 2, 1], [3, 1, 0]])]))
    scene.add(om.Node("Ball", [om.Translation(-1.6, 0.7, 0.0), pbr(RED), om.Sphere(radius=0.7)]))
    scene.add(om.Node("Crate", [om.Translation(0.0, 0.5, 0.0), pbr(GREEN), om.Box(size=1.0)]))
    scene.add(om.Node("Drum", [om.Translation(1.6, 0.5, 0.0), pbr(BLUE), om.Cylinder(radius=0.5, height=1.0)]))
    scene.add(om.Node("Peak", [om.Translation(0.0, 0.6, -1.8), pbr(RED), om.Cone(radius=0.5, height=1.2)]))
    return scene


def crowd_stage(folder: Path) -> Path:
    """Camera, a sphere light (radius 0.2), a dome light, a floor and a PointInstancer of 12 turned, scaled boxes
    coloured per instance (displayColor), one of them hidden by invisibleIds."""
    from pxr import Gf, UsdGeom, UsdLux, Vt

    path = folder / "crowd.usda"
    stage = _stage(path)
    stage.RemovePrim("/World/Sun")
    lamp = UsdLux.SphereLight.Define(stage, "/World/Lamp")
    lamp.AddTranslateOp().Set(Gf.Vec3d(*LAMP))
    lamp.GetRadiusAttr().Set(0.2)
    lamp.GetIntensityAttr().Set(LAMP_RADIANCE)
    dome = UsdLux.DomeLight.Define(stage, "/World/Sky")
    dome.GetIntensityAttr().Set(0.2)
    floor = UsdGeom.Cube.Define(stage, "/World/Floor")
    floor.AddTranslateOp().Set(Gf.Vec3d(0, -0.05, 0))
    floor.AddScaleOp().Set(Gf.Vec3f(8, 0.1, 8))
    floor.GetSizeAttr().Set(1.0)
    bind(floor.GetPrim(), preview_material(stage, "/World/Looks/Grey", GREY))
    crowd = UsdGeom.PointInstancer.Define(stage, "/World/Crowd")
    box = UsdGeom.Cube.Define(stage, "/World/Crowd/Prototypes/Box")
    box.GetSizeAttr().Set(0.5)
    bind(box.GetPrim(), preview_material(stage, "/World/Looks/White", (0.8, 0.8, 0.8)))
    crowd.CreatePrototypesRel().SetTargets([box.GetPath()])
    t, q, s, c = crowd_arrays()
    crowd.CreateProtoIndicesAttr([0] * len(t))
    crowd.CreatePositionsAttr(Vt.Vec3fArray.FromNumpy(t.astype(np.float32)))
    crowd.CreateOrientationsfAttr(Vt.QuatfArray.FromNumpy(q[:, [1, 2, 3, 0]].astype(np.float32)))  # (i, j, k, r)
    crowd.CreateScalesAttr(Vt.Vec3fArray.FromNumpy(s.astype(np.float32)))
    colors = UsdGeom.PrimvarsAPI(crowd.GetPrim()).CreatePrimvar(
        "displayColor", __import__("pxr").Sdf.ValueTypeNames.Color3fArray, "vertex"
    )
    colors.Set(Vt.Vec3fArray.FromNumpy(c.astype(np.float32)))
    crowd.CreateIdsAttr(list(range(len(t))))
    crowd.CreateInvisibleIdsAttr([5])
    stage.GetRootLayer().Save()
    return path


LAMP = (1.0, 3.0, 2.0)
LAMP_RADIANCE = 250.0


def crowd_arrays():
    """Translations, unit quaternions (w, x, y, z), scales and linear colours of the 12 instances."""
    k = np.arange(12)
    angle = 2 * np.pi * k / 12
    t = np.stack([2.2 * np.cos(angle), np.full(12, 0.4), 2.2 * np.sin(angle) - 0.5], 1)
    half = angle / 2
    q = np.stack([np.cos(half), np.zeros(12), np.sin(half), np.zeros(12)], 1)
    s = np.stack([np.ones(12), 1 + k / 12, np.ones(12)], 1)
    c = np.stack([0.1 + 0.8 * k / 11, 0.3 * np.ones(12), 0.9 - 0.8 * k / 11], 1)
    return t, q, s, c


def equivalent_crowd() -> om.Node:
    """The scene of :func:`crowd_stage`, built with omnirender (the documented light mapping)."""
    from omnirender.geometry.trs import compose_trs

    scene = om.Node("crowd")
    scene.add(om.Node("Camera", [om.Translation(*EYE), om.Camera(eye=(0, 0, 0), center=(0, 0, -1), fov=FOV, near=0.1,
                                                                  far=100)]))  # fmt: skip
    scene.add(om.PointLight(position=LAMP, intensity=LAMP_RADIANCE * 0.2**2, constant=0.0, quadratic=1.0))
    scene.add(om.AmbientLight(color=srgb((1, 1, 1)), intensity=0.2))
    grey = om.PBRMaterial(base_color=srgb(GREY), metallic=0.0, roughness=0.8)
    scene.add(om.Node("Floor", [om.Translation(0, -0.05, 0), om.Scaling(8, 0.1, 8), grey, om.Box(size=1.0)]))
    t, q, s, c = crowd_arrays()
    matrices = compose_trs(t, q[:, [1, 2, 3, 0]], s)
    visible = np.ones(12, bool)
    visible[5] = False
    white = om.PBRMaterial(base_color=srgb((0.8, 0.8, 0.8)), metallic=0.0, roughness=0.8)
    colors = np.array([srgb(row) for row in c])
    scene.add(om.Node("Crowd", [white, om.InstanceSet(om.Box(size=0.5), matrices, colors=colors, visible=visible)]))
    return scene
