"""Example 13: renderer trees combining meshes, volumes and light fields (the seed's three figures).

1. A segmented volume (a liver-like organ) with vessel meshes inside it: a plain
   depth group hides the vessels; an occlusion group shows them fully, or
   semi-transparently through the organ.
2. Meshes and a volume (a cloud) in a shadow group, without and with shadows:
   the cloud casts a shadow on the meshes like a mesh does.
3. Two light fields and two meshes in a shadow group: the light fields cast
   shadows on the meshes, and one light field is turned grey by a luminance
   filter in an offscreen depth group.

Writes 13-occlusion.png, 13-shadows.png and 13-light-fields.png.

    python examples/13_renderer_tree.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, side_by_side

import omnirender as om
from omnirender.geometry.matrix import align_y_matrix

C = om.compositing
SIZE = (400, 300)


# --- 1. a segmented volume with meshes inside ----------------------------------------------------
def organ(n: int = 56) -> om.Volume:
    """A lumpy organ: 1 inside, 0 outside, with a soft boundary (a segmentation's label mask, smoothed)."""
    z, y, x = np.mgrid[-1 : 1 : n * 1j, -1 : 1 : n * 1j, -1 : 1 : n * 1j]
    lumps = 0.08 * np.sin(5 * x + 1) * np.sin(4 * y) * np.cos(3 * z)
    r = np.sqrt((x / 0.95) ** 2 + (y / 0.62) ** 2 + (z / 0.72) ** 2) + lumps
    inside = np.clip((1.0 - r) * 12.0, 0.0, 1.0)
    tf = [(0.0, (0.8, 0.45, 0.35, 0.0)), (0.5, (0.85, 0.5, 0.4, 0.05)), (1.0, (0.8, 0.42, 0.32, 0.09))]
    return om.Volume(inside, spacing=2.0 / (n - 1), transfer_function=tf)


def tube(a, b, radius: float) -> om.Node:
    a, b = np.asarray(a, float), np.asarray(b, float)
    length = float(np.linalg.norm(b - a))
    return om.Node("tube", [om.Matrix(align_y_matrix((a + b) / 2, (b - a) / length)), om.Cylinder(radius, length)])


def vessels() -> om.Node:
    """Two vessel trees (portal vein blue, artery red) branching inside the organ."""
    scene = om.Node("vessels", [om.PointLight(position=(2, 4, 5))])
    for color, root, tips in (
        ((0.25, 0.4, 0.95), (-0.7, -0.1, 0.1), [(0.1, 0.35, 0.2), (0.2, -0.3, -0.2), (0.6, 0.1, 0.3)]),
        ((0.95, 0.25, 0.25), (0.75, -0.2, -0.15), [(0.0, 0.25, -0.25), (-0.3, -0.3, 0.25)]),
    ):
        tree = scene.add(om.Node("tree", [om.Material(diffuse=color, specular=(0.4, 0.4, 0.4), shininess=30)]))
        fork = (np.asarray(root) + np.mean(tips, axis=0)) / 2
        tree.add(tube(root, fork, 0.07))
        for tip in tips:
            tree.add(tube(fork, tip, 0.045))
            tree.add(om.Node("end", [om.Sphere(center=tip, radius=0.045)]))
        tree.add(om.Node("joint", [om.Sphere(center=fork, radius=0.07)]))
    return scene


def occlusion_trees() -> list[C.Renderer]:
    liver, inside = C.VolumeRenderer(organ()), C.SceneRenderer(vessels())
    return [
        C.DepthGroup([liver, inside]),
        C.DepthGroup([liver, C.OcclusionGroup([inside], mode="visible")]),
        C.DepthGroup([liver, C.OcclusionGroup([inside], mode="semi-transparent", opacity=0.55)]),
    ]


ORGAN_CAMERA = om.Camera.look_at((0.4, 1.1, 3.2), (0, -0.05, 0), fov=38)


# --- 2. meshes and a volume in a shadow group -------------------------------------------------------
LIGHT = om.PointLight(position=(1.5, 5.0, 2.0))


def cloud(n: int = 40) -> om.Volume:
    z, y, x = np.mgrid[-1 : 1 : n * 1j, -1 : 1 : n * 1j, -1 : 1 : n * 1j]
    density = np.clip(1.0 - np.sqrt(x**2 + (y / 0.7) ** 2 + z**2), 0.0, 1.0) * (0.8 + 0.2 * np.sin(7 * x + 3 * z))
    return om.Volume(
        density, spacing=0.6 / (n - 1), transfer_function=[(0.0, (1, 1, 1, 0)), (0.3, (0.9, 0.95, 1, 0.25))]
    )


def ground_and_torus() -> om.Node:
    scene = om.Node("meshes", [LIGHT])
    scene.add(
        om.Node("floor", [om.Material(diffuse=(0.85, 0.85, 0.8)), om.Box(size=(6, 0.1, 5), center=(0, -0.05, 0))])
    )
    scene.add(om.Node("torus", [om.Translation(0.9, 0.45, 0.3), om.Rotation(70, (1, 0, 0)),
                                om.Material(diffuse=(0.95, 0.6, 0.15)), om.Torus(0.45, 0.15)]))  # fmt: skip
    return scene


def shadow_trees() -> list[C.Renderer]:
    children = [C.SceneRenderer(ground_and_torus()), C.VolumeRenderer(cloud(), om.Translation(-0.7, 1.4, 0))]
    return [C.ShadowGroup(LIGHT, children, enabled=False), C.ShadowGroup(LIGHT, children)]


SHADOW_CAMERA = om.Camera.look_at((0.5, 3.2, 5.5), (0, 0.5, 0), fov=40)


# --- 3. two light fields and two meshes in a shadow group ------------------------------------------
LIGHT_FIELD_CAMERA = om.Camera.look_at((0.2, 2.6, 5.2), (0, 0.5, 0), fov=42)
LF_LIGHT = om.PointLight(position=(3.5, 4.5, 2.5))


def checker(seed: int, cells: int = 6, size: int = 192) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = np.kron(rng.uniform(0.3, 1.0, (cells, cells, 3)), np.ones((size // cells, size // cells, 1)))
    return (img * 255).astype(np.uint8)


def statue(center, seed: int) -> om.Node:
    """A textured object to capture: a sphere on a box."""
    cx, cy, cz = center
    return om.Node("statue", [
        om.PointLight(position=(cx + 2, 5, cz + 4)), om.Texture(checker(seed)), om.Material(diffuse=(1, 1, 1)),
        om.Node("base", [om.Box(size=(0.7, 0.6, 0.7), center=(cx, cy + 0.3, cz))]),
        om.Node("head", [om.Sphere(center=(cx, cy + 0.95, cz), radius=0.38)]),
    ])  # fmt: skip


def light_field_of(center, seed: int, views: int = 18, size=(320, 240)) -> C.LightField:
    """Capture the statue from a cap of cameras around the directions of the camera and the light (16-25 views)."""
    target = np.array([center[0], center[1] + 0.6, center[2]])
    to_camera, to_light = (np.subtract(p, target) for p in (LIGHT_FIELD_CAMERA.eye, LF_LIGHT.position))
    axis = to_camera / np.linalg.norm(to_camera) + to_light / np.linalg.norm(to_light)
    cameras = C.sphere_cap_cameras(target, 4.0, views, cap=28, axis=axis)
    return C.capture_light_field(statue(center, seed), cameras, size=size)


def floor_and_pillar() -> om.Node:
    scene = om.Node("meshes", [LF_LIGHT])
    scene.add(
        om.Node("floor", [om.Material(diffuse=(0.8, 0.82, 0.85)), om.Box(size=(7, 0.1, 5), center=(0, -0.05, 0))])
    )
    scene.add(
        om.Node("pillar", [om.Material(diffuse=(0.3, 0.55, 0.9)), om.Translation(0, 0.8, 0), om.Cylinder(0.25, 1.6)])
    )
    return scene


def light_field_tree() -> C.Renderer:
    left, right = light_field_of((-1.3, 0.0, 0.3), 1), light_field_of((1.2, 0.0, -0.2), 2)
    grey = C.DepthGroup([C.LightFieldRenderer(right), C.LuminanceFilter()], offscreen=True)
    return C.ShadowGroup(LF_LIGHT, [C.SceneRenderer(floor_and_pillar()), C.LightFieldRenderer(left), grey])


if __name__ == "__main__":
    out = output_dir()
    images = [tree.render(SIZE, camera=ORGAN_CAMERA, background=(0.12, 0.12, 0.14)) for tree in occlusion_trees()]
    side_by_side(images).save(out / "13-occlusion.png")
    images = [tree.render(SIZE, camera=SHADOW_CAMERA, background=(0.55, 0.6, 0.7)) for tree in shadow_trees()]
    side_by_side(images).save(out / "13-shadows.png")
    light_field_tree().render((2 * SIZE[0], SIZE[1]), camera=LIGHT_FIELD_CAMERA, background=(0.55, 0.6, 0.7)).save(
        out / "13-light-fields.png"
    )
    print(f"wrote {out / '13-occlusion.png'}, {out / '13-shadows.png'} and {out / '13-light-fields.png'}")
