"""Example 12: a textured PBR asset through glTF, the same in every engine.

A tiled floor and a bumpy, partly emissive ball get metallic-roughness
materials with texture slots (base colour, metallic-roughness, a normal map
derived from a height field, emissive) and a cut-out alpha mask; the scene
is exported to glTF and read back with ``om.load_gltf`` (every slot, its UV
set and texture transform survive), then rendered by OpenGL, POV-Ray and
Mitsuba side by side.  The engines resolve the materials with the one
appearance model, so the pictures agree in colour, not only in silhouette.

    python examples/12_assets.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om
from omnirender.attributes.texturing import height_to_normal_map


def textures() -> dict[str, om.Texture]:
    n = 64
    y, x = np.mgrid[0:n, 0:n] / n
    tiles = ((np.floor(x * 4) + np.floor(y * 4)) % 2).astype(bool)
    base = np.zeros((n, n, 4), np.uint8)
    base[..., :3] = np.where(tiles[..., None], (200, 190, 170), (90, 70, 60))
    base[..., 3] = 255
    mr = np.zeros((n, n, 4), np.uint8)
    mr[..., 1] = np.where(tiles, 110, 230)  # roughness: light tiles smoother
    mr[..., 2] = np.where(tiles, 255, 0)  # metallic: light tiles metal
    mr[..., 3] = 255
    heights = 0.5 + 0.5 * np.sin(2 * np.pi * 6 * x) * np.sin(2 * np.pi * 3 * y)
    glow = np.zeros((n, n, 4), np.uint8)
    glow[..., 3] = 255
    glow[(np.abs(y - 0.5) < 0.06)] = (255, 255, 255, 255)  # a glowing band around the ball
    leaves = np.zeros((n, n, 4), np.uint8)
    leaves[..., :3] = (60, 150, 60)
    leaves[..., 3] = np.where(np.hypot(x - 0.5, y - 0.5) < 0.45, 255, 0)  # a disc cut out of a square
    return {
        "base": om.Texture(base, scale=(2, 2)),
        "mr": om.Texture(mr, scale=(2, 2)),
        "normal": om.Texture(height_to_normal_map(heights, 0.03)),
        "glow": om.Texture(glow),
        "leaf": om.Texture(leaves),
    }


def asset_scene() -> om.Node:
    t = textures()
    scene = om.Node("asset", [om.Camera.look_at(eye=(2.6, 2.0, 3.4), center=(0, 0.55, 0), fov=40)])
    scene.add(om.Background((0.12, 0.13, 0.16)))
    scene.add(om.PointLight(position=(3, 5, 4), intensity=0.9))
    scene.add(om.DirectionalLight(direction=(1, -0.4, -0.6), intensity=0.3))
    floor = om.PBRMaterial(base_color=(1, 1, 1), base_color_texture=t["base"], metallic=1.0, roughness=1.0,
                           metallic_roughness_texture=t["mr"])  # fmt: skip
    scene.add(om.Node("floor", [floor, om.Rectangle(size=(4, 4))]))
    ball = om.PBRMaterial(base_color=(0.8, 0.35, 0.2), roughness=0.5, normal_texture=t["normal"],
                          emission=(1.0, 0.8, 0.3), emissive_texture=t["glow"])  # fmt: skip
    scene.add(om.Node("ball", [om.Translation(0, 0.6, 0), ball, om.Sphere(radius=0.6)]))
    leaf = om.PBRMaterial(base_color_texture=t["leaf"], alpha_mode="mask", roughness=0.9)
    scene.add(om.Node("leaf", [om.Translation(-1.2, 0.5, -0.8), om.Rotation(90, (1, 0, 0)), leaf,
                               om.Rectangle(size=(1, 1))]))  # fmt: skip
    return scene


def main() -> None:
    out = output_dir()
    om.export(asset_scene(), out / "12-asset.glb")
    again = om.load_gltf(out / "12-asset.glb")  # every material slot comes back
    again.add(om.Background((0.12, 0.13, 0.16)))  # glTF has no background
    images = []
    for name, options in (("gl", {"samples": 4}), ("povray", {"antialias": True}), ("mitsuba", {"spp": 64})):
        ok, why = om.engines()[name]
        if ok:
            images.append(om.render(again, engine=name, size=(320, 240), **options))
        else:
            print(f"{name}: skipped ({why})")
    side_by_side(images).save(out / "12-assets.png")
    print("wrote", out / "12-assets.png")


if __name__ == "__main__":
    main()
