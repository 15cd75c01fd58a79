"""Example 19: an OpenUSD stage rendered by OpenGL, POV-Ray, Mitsuba and Radiance.

The stage is written with ``usd-core`` the way a DCC tool or a simulator
would (``pip install omnirender[usd]``): a ground mesh with a texture read by
a ``UsdPreviewSurface`` network, a robot-like model made of gprims (cube,
cylinders, a capsule, a sphere) placed by xform ops, a ``PointInstancer`` of
200 crates, a ``DistantLight``, a ``SphereLight`` and a camera.
``om.load_usd`` turns it into a scene graph (USD paths are node paths), every
engine renders it, and ``om.export`` writes the scene back as a ``.usdz``
package that USD's own validators accept.

    python examples/19_usd.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import math

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om


def write_stage(path) -> None:
    """The stage, authored with usd-core only (no omnirender)."""
    from PIL import Image
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, UsdShade, Vt

    tiles = np.indices((8, 8)).sum(axis=0) % 2
    pixels = np.where(tiles[..., None], (205, 200, 185), (120, 110, 95)).astype(np.uint8)
    Image.fromarray(np.kron(pixels, np.ones((16, 16, 1), np.uint8))).save(path.parent / "tiles.png")

    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    Usd.ModelAPI(world.GetPrim()).SetKind("assembly")

    def surface(name, color, roughness=0.6, metallic=0.0):
        material = UsdShade.Material.Define(stage, f"/World/Looks/{name}")
        shader = UsdShade.Shader.Define(stage, f"/World/Looks/{name}/Surface")
        shader.CreateIdAttr("UsdPreviewSurface")
        shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(roughness)
        shader.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(metallic)
        material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
        if color is not None:
            shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(color)
        return material, shader

    def bind(prim, material):
        UsdShade.MaterialBindingAPI.Apply(prim.GetPrim()).Bind(material)

    camera = UsdGeom.Camera.Define(stage, "/World/Camera")
    camera.AddTranslateOp().Set(Gf.Vec3d(0, 3.2, 8.5))
    camera.AddRotateXOp().Set(-17.0)
    camera.GetFocalLengthAttr().Set(24.0)
    camera.GetVerticalApertureAttr().Set(20.955)
    sun = UsdLux.DistantLight.Define(stage, "/World/Sun")
    sun.AddRotateXYZOp().Set(Gf.Vec3f(-50, 30, 0))
    sun.GetIntensityAttr().Set(0.8 / math.sin(math.radians(0.53 / 2)) ** 2)  # irradiance 0.8 pi
    lamp = UsdLux.SphereLight.Define(stage, "/World/Lamp")
    lamp.AddTranslateOp().Set(Gf.Vec3d(-2.5, 3.0, 2.0))
    lamp.GetRadiusAttr().Set(0.1)
    lamp.GetIntensityAttr().Set(600.0)
    lamp.GetColorAttr().Set((1.0, 0.85, 0.6))

    ground = UsdGeom.Mesh.Define(stage, "/World/Ground")
    ground.GetPointsAttr().Set([(-6, 0, -6), (6, 0, -6), (6, 0, 6), (-6, 0, 6)])
    ground.GetFaceVertexCountsAttr().Set([4])
    ground.GetFaceVertexIndicesAttr().Set([3, 2, 1, 0])
    ground.GetSubdivisionSchemeAttr().Set("none")
    st = UsdGeom.PrimvarsAPI(ground.GetPrim()).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, "vertex")
    st.Set([(0, 1), (1, 1), (1, 0), (0, 0)])  # scaled 3 times by the UsdTransform2d below
    tiled, shader = surface("Tiles", None, roughness=0.9)
    reader = UsdShade.Shader.Define(stage, "/World/Looks/Tiles/St")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
    repeat = UsdShade.Shader.Define(stage, "/World/Looks/Tiles/Repeat")
    repeat.CreateIdAttr("UsdTransform2d")
    repeat.CreateInput("in", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
    repeat.CreateInput("scale", Sdf.ValueTypeNames.Float2).Set((3.0, 3.0))
    image = UsdShade.Shader.Define(stage, "/World/Looks/Tiles/Image")
    image.CreateIdAttr("UsdUVTexture")
    image.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("./tiles.png")
    image.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("repeat")
    image.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(repeat.ConnectableAPI(), "result")
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(image.ConnectableAPI(), "rgb")
    bind(ground, tiled)

    robot = UsdGeom.Xform.Define(stage, "/World/Robot")
    robot.AddTranslateOp().Set(Gf.Vec3d(0.3, 0, 0.5))
    robot.AddRotateYOp().Set(-25.0)
    Usd.ModelAPI(robot.GetPrim()).SetKind("component")
    body_look, _ = surface("Body", (0.75, 0.25, 0.05), roughness=0.4)
    metal, _ = surface("Metal", (0.7, 0.7, 0.75), roughness=0.3, metallic=1.0)
    glass, _ = surface("Eye", (0.05, 0.3, 0.8), roughness=0.2)
    body = UsdGeom.Cube.Define(stage, "/World/Robot/Body")
    body.GetSizeAttr().Set(1.0)
    body.AddTranslateOp().Set(Gf.Vec3d(0, 1.3, 0))
    body.AddScaleOp().Set(Gf.Vec3f(1.2, 1.0, 0.8))
    bind(body, body_look)
    head = UsdGeom.Sphere.Define(stage, "/World/Robot/Head")
    head.AddTranslateOp().Set(Gf.Vec3d(0, 2.25, 0))
    head.GetRadiusAttr().Set(0.45)
    bind(head, glass)
    for side, x in (("Left", -0.35), ("Right", 0.35)):
        leg = UsdGeom.Cylinder.Define(stage, f"/World/Robot/{side}Leg")
        leg.AddTranslateOp().Set(Gf.Vec3d(x, 0.4, 0))
        leg.GetAxisAttr().Set("Y")
        leg.GetRadiusAttr().Set(0.18)
        leg.GetHeightAttr().Set(0.8)
        bind(leg, metal)
        arm = UsdGeom.Capsule.Define(stage, f"/World/Robot/{side}Arm")
        arm.AddTranslateOp().Set(Gf.Vec3d(x * 2.4, 1.35, 0))
        arm.AddRotateZOp().Set(20.0 if x > 0 else -20.0)
        arm.GetAxisAttr().Set("Y")
        arm.GetRadiusAttr().Set(0.14)
        arm.GetHeightAttr().Set(0.7)
        bind(arm, metal)

    crates = UsdGeom.PointInstancer.Define(stage, "/World/Crates")
    crate = UsdGeom.Cube.Define(stage, "/World/Crates/Prototypes/Crate")
    crate.GetSizeAttr().Set(0.35)
    bind(crate, surface("Crate", (0.35, 0.55, 0.2), roughness=0.8)[0])
    crates.CreatePrototypesRel().SetTargets([crate.GetPath()])
    rng = np.random.default_rng(19)
    angles = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    radius = 3.2 + 0.6 * rng.random(200)
    positions = np.stack([radius * np.cos(angles), np.full(200, 0.175), radius * np.sin(angles) - 1.0], 1)
    spin = rng.random(200) * np.pi
    quats = np.stack([np.zeros(200), np.sin(spin / 2), np.zeros(200), np.cos(spin / 2)], 1)  # (i, j, k, real)
    crates.CreateProtoIndicesAttr(Vt.IntArray.FromNumpy(np.zeros(200, np.int32)))
    crates.CreatePositionsAttr(Vt.Vec3fArray.FromNumpy(positions.astype(np.float32)))
    crates.CreateOrientationsAttr(Vt.QuathArray.FromNumpy(quats.astype(np.float16)))
    stage.GetRootLayer().Save()


def main() -> None:
    out = output_dir()
    path = out / "19-robot.usda"
    write_stage(path)
    scene = om.load_usd(path)  # USD paths are node paths: scene["/World/Robot/Head"]
    scene.insert(0, om.Background((0.55, 0.65, 0.8)))
    images = []
    options = {"gl": {"samples": 4}, "povray": {"antialias": True}, "mitsuba": {"spp": 64}, "radiance": {}}
    for name, extra in options.items():
        ok, why = om.engines()[name]
        if ok:
            images.append(om.render(scene, engine=name, size=(320, 240), **extra))
        else:
            print(f"{name}: skipped ({why})")
    side_by_side(images).save(out / "19-usd.png")
    print("wrote", out / "19-usd.png")
    om.export(scene, out / "19-robot-again.usdz")  # back to USD: a package with its texture inside
    print("wrote", out / "19-robot-again.usdz")


if __name__ == "__main__":
    main()
